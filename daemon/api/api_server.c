/* api_server.c: the control API's HTTP side (libmicrohttpd), see api_server.h for the routes and
 * the threading and ownership contracts.
 *
 * Request life cycle. libmicrohttpd calls on_request() several times per request:
 *   1. once when the headers are in (no body yet): we allocate the per-request state and run
 *      every check that needs no body, in this order: token (401), path (404, 400 bad id),
 *      method (405), two Content-Length headers that disagree (400), Content-Length against the
 *      limit (413). A failed check answers at once, before any body is read; a client that sent
 *      "Expect: 100-continue" never uploads it. Otherwise the body's deadline is armed.
 *   2. zero or more times with a chunk of body: appended to the request's buffer, which never
 *      grows past max_body_bytes (a chunked upload that goes past it is drained and answered 413).
 *      A chunk after the deadline, or none before it, is answered 408 (body_deadline_arm).
 *   3. once with no data: the body is complete; parse it, call the op, queue the reply.
 * The per-request state is freed in on_completed(), which libmicrohttpd calls for every request
 * however it ended (reply sent, client gone, timeout, shutdown).
 *
 * Design choices. One internal polling thread (MHD_USE_AUTO picks epoll on Linux, so file
 * descriptors above FD_SETSIZE are fine in a daemon that also holds a camera, serial ports and a
 * database); the ops therefore never run concurrently. libmicrohttpd binds the socket itself;
 * its log messages are captured only while api_server_start runs so a failure to start names the
 * reason ("Address already in use"), and dropped afterwards (library code prints nothing). Reply
 * bodies are serialised into our own malloc'ed buffer and handed over with MHD_RESPMEM_MUST_FREE,
 * so the server does not depend on jansson's allocator. The token is compared in constant time.
 *
 * Connections (see api_server.h): api_guard accepts and waits for the headers; take_connection()
 * sorts a complete head into the control pool (MHD internal polling thread, as above) or the
 * stream pool (a second libmicrohttpd daemon, one thread per stream, so a stream's read may wait
 * for the live bus without stalling anyone), counting open connections per pool through
 * libmicrohttpd's connection notifications. Neither daemon listens: the guard hands sockets over
 * with MHD_add_connection. */
#include "api_server.h"

#include "api_guard.h"
#include "api_head.h"
#include "api_route.h"

#include <arpa/inet.h>
#include <errno.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define API_WHY_MAX 512
#define API_STREAM_IDLE_S 60 /* a stream client that reads nothing for this long is dropped, s */

typedef struct api_pool {
    struct api_server *s;
    int stream;                /* 1: the stream pool */
    unsigned idle_s;           /* libmicrohttpd's idle timeout of this pool's connections, s */
    atomic_int open;           /* connections handed over and not yet closed */
} api_pool;

struct api_server {
    struct MHD_Daemon *mhd;    /* control pool */
    struct MHD_Daemon *smhd;   /* stream pool */
    api_guard *guard;
    api_pool pool[2];          /* [0] control, [1] stream */
    unsigned max_control, max_streams;
    api_asset *assets;
    size_t n_assets;
    api_ops ops;
    void *user;
    char token[API_TOKEN_MAX + 1]; /* "" = no token */
    size_t token_len;
    size_t max_body;
    unsigned body_timeout_ms;
    unsigned port;

    /* libmicrohttpd log capture during start-up only (see the file comment). The polling thread
     * may log while start returns, hence the mutex. */
    pthread_mutex_t log_lock;
    bool log_capture;
    char log[256];
};

/* Per-request state, owned by libmicrohttpd's *con_cls between on_request and on_completed. */
typedef struct api_request {
    api_route route;
    int64_t id;
    char path[API_CAMPAIGN_PATH_MAX]; /* a campaign route's path (the op sorts it) */
    bool answered;  /* a reply was queued (before the body was read, or after all of it), or the
                       408 of a late body was written */
    bool too_big;   /* the body went past max_body: drained, answered 413 */
    uint64_t started_ms; /* headers in (monotonic), for the body deadline */
    char *body;
    size_t len, cap;
} api_request;

api_server_config api_server_config_default(void)
{
    api_server_config c = {
        .listen = "127.0.0.1",
        .port = 8377,
        .token = NULL,
        .max_body_bytes = 64 * 1024,
        .connection_timeout_s = 30,
        .max_connections = 64,
        .max_streams = 32,
        .header_timeout_ms = 5000,
        .pending_max = 256,
        .body_timeout_ms = API_BODY_TIMEOUT_MS,
    };
    return c;
}

/* ---------------------------------------------------------------- replies */

/* Queue a reply whose body is buf[0..len), malloc'ed; ownership passes to libmicrohttpd. xname
 * (may be NULL) is one more header, with the value xvalue. */
static enum MHD_Result reply_buffer_x(struct MHD_Connection *c, int status, const char *ctype, void *buf,
                                      size_t len, const char *allow, const char *xname, const char *xvalue)
{
    struct MHD_Response *r = MHD_create_response_from_buffer(len, buf, MHD_RESPMEM_MUST_FREE);
    if (r == NULL) {
        free(buf);
        return MHD_NO; /* out of memory: libmicrohttpd closes the connection */
    }
    enum MHD_Result ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    if (ok == MHD_YES)
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    if (ok == MHD_YES) /* one request per control connection: a slot is never held idle */
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CONNECTION, "close");
    if (ok == MHD_YES && allow != NULL)
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_ALLOW, allow);
    if (ok == MHD_YES && status == MHD_HTTP_UNAUTHORIZED)
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_WWW_AUTHENTICATE, "Bearer realm=\"ribbond\"");
    if (ok == MHD_YES && xname != NULL)
        ok = MHD_add_response_header(r, xname, xvalue);
    if (ok == MHD_YES)
        ok = MHD_queue_response(c, (unsigned)status, r);
    MHD_destroy_response(r);
    return ok;
}

static enum MHD_Result reply_buffer(struct MHD_Connection *c, int status, const char *ctype, void *buf,
                                    size_t len, const char *allow)
{
    return reply_buffer_x(c, status, ctype, buf, len, allow, NULL, NULL);
}

/* Serialise j (compact, one trailing newline) into a malloc'ed buffer. NULL on failure. */
static char *json_text(const json_t *j, size_t *len)
{
    size_t need = json_dumpb(j, NULL, 0, JSON_COMPACT | JSON_ENCODE_ANY);
    if (need == 0)
        return NULL;
    char *buf = malloc(need + 1);
    if (buf == NULL)
        return NULL;
    if (json_dumpb(j, buf, need, JSON_COMPACT | JSON_ENCODE_ANY) != need) {
        free(buf);
        return NULL;
    }
    buf[need] = '\n';
    *len = need + 1;
    return buf;
}

/* A JSON string of msg. Messages may quote bytes from the request (a path segment) that are not
 * UTF-8; jansson refuses those, so such a message is sent with non-ASCII bytes as '?'. */
static json_t *message_string(const char *msg)
{
    json_t *s = json_string(msg);
    if (s != NULL)
        return s;
    char clean[API_WHY_MAX];
    size_t i = 0;
    for (; msg[i] != '\0' && i + 1 < sizeof clean; i++) {
        unsigned char b = (unsigned char)msg[i];
        clean[i] = (b < 0x20 || b >= 0x7f) ? '?' : (char)b;
    }
    clean[i] = '\0';
    return json_string(clean);
}

/* {"error": msg, "status": status}, with an Allow header for 405 and Retry-After: 1 for 503 (an op
 * busy with something that will end soon: GET /campaign/phase while the boundary is traced). */
static enum MHD_Result reply_error(struct MHD_Connection *c, int status, const char *msg, const char *allow)
{
    json_t *j = json_object();
    if (j == NULL || json_object_set_new(j, "error", message_string(msg)) != 0 ||
        json_object_set_new(j, "status", json_integer(status)) != 0) {
        json_decref(j);
        return MHD_NO;
    }
    size_t len = 0;
    char *text = json_text(j, &len);
    json_decref(j);
    if (text == NULL)
        return MHD_NO;
    if (status == MHD_HTTP_SERVICE_UNAVAILABLE)
        return reply_buffer_x(c, status, "application/json", text, len, allow, MHD_HTTP_HEADER_RETRY_AFTER, "1");
    return reply_buffer(c, status, "application/json", text, len, allow);
}

static enum MHD_Result reply_errorf(struct MHD_Connection *c, int status, const char *allow, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static enum MHD_Result reply_errorf(struct MHD_Connection *c, int status, const char *allow, const char *fmt, ...)
{
    char msg[API_WHY_MAX];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return reply_error(c, status, msg, allow);
}

/* Reply with j (stolen). */
static enum MHD_Result reply_json(struct MHD_Connection *c, int status, json_t *j)
{
    size_t len = 0;
    char *text = json_text(j, &len);
    json_decref(j);
    if (text == NULL)
        return reply_error(c, MHD_HTTP_INTERNAL_SERVER_ERROR, "could not encode the reply as JSON", NULL);
    return reply_buffer(c, status, "application/json", text, len, NULL);
}

/* Turn an op's result into a reply, enforcing the contract of api_server.h. out is stolen. */
static enum MHD_Result finish_op(struct MHD_Connection *c, const char *op, int rc, json_t *out, int status,
                                 const char *why)
{
    if (rc == 0) {
        if (out == NULL)
            return reply_errorf(c, 500, NULL, "internal error: ops->%s succeeded without a reply", op);
        if (status < 200 || status > 299) {
            json_decref(out);
            return reply_errorf(c, 500, NULL, "internal error: ops->%s succeeded with status %d", op, status);
        }
        return reply_json(c, status, out);
    }
    json_decref(out);
    if (status < 400 || status > 599)
        status = 500;
    if (why[0] == '\0')
        return reply_errorf(c, status, NULL, "%s failed (no reason given)", op);
    return reply_error(c, status, why, NULL);
}

/* ---------------------------------------------------------------- checks */

static uint64_t mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

static const api_asset *find_asset(const api_server *s, const char *url)
{
    for (size_t i = 0; i < s->n_assets; i++)
        if (strcmp(s->assets[i].path, url) == 0)
            return &s->assets[i];
    return NULL;
}

static enum MHD_Result reply_asset(struct MHD_Connection *c, const api_asset *a)
{
    struct MHD_Response *r = MHD_create_response_from_buffer(a->len, (void *)a->data, MHD_RESPMEM_PERSISTENT);
    if (r == NULL)
        return MHD_NO;
    enum MHD_Result ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, a->content_type);
    if (ok == MHD_YES)
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-cache");
    if (ok == MHD_YES)
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CONNECTION, "close");
    if (ok == MHD_YES)
        ok = MHD_queue_response(c, MHD_HTTP_OK, r);
    MHD_destroy_response(r);
    return ok;
}

/* Collects a request's headers into a growing array (api_header_list). */
typedef struct api_header_list {
    api_header *h;
    size_t n, cap;
    bool failed;
} api_header_list;

static enum MHD_Result collect_header(void *cls, enum MHD_ValueKind kind, const char *key, const char *value)
{
    (void)kind;
    api_header_list *l = cls;
    if (l->n == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 16;
        api_header *h = realloc(l->h, cap * sizeof *h);
        if (h == NULL) {
            l->failed = true;
            return MHD_NO;
        }
        l->h = h;
        l->cap = cap;
    }
    l->h[l->n++] = (api_header){.name = key, .value = value};
    return MHD_YES;
}

/* Headers are in: serve a page asset, or run every check that needs no body (api_head_check, on
 * the headers as libmicrohttpd parsed them). Returns MHD_YES to go on reading. */
static enum MHD_Result on_headers(api_server *s, int stream_pool, struct MHD_Connection *c, const char *url,
                                  const char *method, api_request *req)
{
    char why[API_WHY_MAX] = "";
    req->started_ms = mono_ms();
    const api_asset *asset = stream_pool ? NULL : find_asset(s, url);
    if (asset != NULL && strcmp(method, "GET") == 0) { /* the page's own files: no data, no token */
        req->answered = true;
        return reply_asset(c, asset);
    }
    api_header_list headers = {0};
    MHD_get_connection_values(c, MHD_HEADER_KIND, collect_header, &headers);
    if (headers.failed) {
        free(headers.h);
        return MHD_NO; /* out of memory: libmicrohttpd closes the connection */
    }
    api_head_policy policy = {.token = s->token, .token_len = s->token_len, .max_body = s->max_body};
    api_head_verdict v;
    api_head_check(&policy, stream_pool != 0, method, url, headers.h, headers.n, &v, why, sizeof why);
    free(headers.h);
    req->route = v.route;
    req->id = v.id;
    if (v.route == API_ROUTE_CAMPAIGN || v.route == API_ROUTE_RAIL)
        snprintf(req->path, sizeof req->path, "%s", url);
    if (v.status == 0)
        return MHD_YES;
    req->answered = true;
    return reply_error(c, v.status, why, v.allow);
}

/* Append a chunk of body, or mark the request too big and drop the chunk. */
static void body_append(const api_server *s, api_request *req, const char *data, size_t size)
{
    if (req->too_big)
        return;
    if (size > s->max_body - req->len) {
        req->too_big = true;
        free(req->body);
        req->body = NULL;
        req->len = req->cap = 0;
        return;
    }
    if (req->len + size > req->cap) {
        size_t cap = req->cap ? req->cap : 1024;
        while (cap < req->len + size)
            cap *= 2;
        if (cap > s->max_body)
            cap = s->max_body;
        char *p = realloc(req->body, cap);
        if (p == NULL) { /* treat as too big: the reply says so, and nothing is half-parsed */
            req->too_big = true;
            free(req->body);
            req->body = NULL;
            req->len = req->cap = 0;
            return;
        }
        req->body = p;
        req->cap = cap;
    }
    memcpy(req->body + req->len, data, size);
    req->len += size;
}

/* ---------------------------------------------------------------- streams */

static ssize_t stream_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    (void)pos;
    api_stream *st = cls;
    long n = st->read(st->ctx, buf, max);
    if (n <= 0)
        return MHD_CONTENT_READER_END_OF_STREAM;
    return (ssize_t)n;
}

static void stream_free(void *cls)
{
    api_stream *st = cls;
    if (st->close)
        st->close(st->ctx);
    free(st);
}

/* An unending text/event-stream reply pulled from st (copied; closed when the stream ends). */
static enum MHD_Result reply_stream(struct MHD_Connection *c, const api_stream *st_in)
{
    api_stream *st = malloc(sizeof *st);
    if (st == NULL) {
        if (st_in->close)
            st_in->close(st_in->ctx);
        return MHD_NO;
    }
    *st = *st_in;
    struct MHD_Response *r = MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16384, stream_read, st, stream_free);
    if (r == NULL) {
        stream_free(st);
        return MHD_NO;
    }
    enum MHD_Result ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, "text/event-stream");
    if (ok == MHD_YES)
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    if (ok == MHD_YES)
        ok = MHD_queue_response(c, MHD_HTTP_OK, r);
    MHD_destroy_response(r);
    return ok;
}

/* ---------------------------------------------------------------- dispatch */

static enum MHD_Result dispatch(api_server *s, struct MHD_Connection *c, const char *method, api_request *req)
{
    const api_ops *ops = &s->ops;
    char why[API_WHY_MAX] = "";
    json_t *out = NULL;
    int status = MHD_HTTP_OK;
    int rc;

    switch (req->route) {
    case API_ROUTE_STATUS:
        if (ops->status == NULL)
            break;
        rc = ops->status(s->user, &out, why, sizeof why);
        return finish_op(c, "status", rc, out, rc == 0 ? MHD_HTTP_OK : MHD_HTTP_INTERNAL_SERVER_ERROR, why);

    case API_ROUTE_TRIALS:
        if (strcmp(method, "GET") == 0) {
            if (ops->list == NULL)
                break;
            rc = ops->list(s->user, &out, why, sizeof why);
            return finish_op(c, "list", rc, out, rc == 0 ? MHD_HTTP_OK : MHD_HTTP_INTERNAL_SERVER_ERROR, why);
        } else {
            if (ops->start == NULL)
                break;
            json_t *body = api_body_object(req->body, req->len, why, sizeof why);
            if (body == NULL)
                return reply_error(c, MHD_HTTP_BAD_REQUEST, why, NULL);
            status = MHD_HTTP_CREATED;
            rc = ops->start(s->user, body, &out, &status, why, sizeof why);
            json_decref(body);
            return finish_op(c, "start", rc, out, status, why);
        }

    case API_ROUTE_RAIL: {
        if (ops->rail == NULL)
            break;
        json_t *body = api_body_object(req->body, req->len, why, sizeof why);
        if (body == NULL)
            return reply_error(c, MHD_HTTP_BAD_REQUEST, why, NULL);
        rc = ops->rail(s->user, req->path, body, &out, &status, why, sizeof why);
        json_decref(body);
        return finish_op(c, "rail", rc, out, status, why);
    }

    case API_ROUTE_ABORT:
        if (ops->abort_current == NULL)
            break;
        rc = ops->abort_current(s->user, &out, &status, why, sizeof why);
        return finish_op(c, "abort_current", rc, out, status, why);

    case API_ROUTE_TRIAL:
        if (ops->show == NULL)
            break;
        rc = ops->show(s->user, req->id, &out, &status, why, sizeof why);
        return finish_op(c, "show", rc, out, status, why);

    case API_ROUTE_REPORT: {
        if (ops->report_png == NULL)
            break;
        unsigned char *png = NULL;
        size_t len = 0;
        rc = ops->report_png(s->user, req->id, &png, &len, &status, why, sizeof why);
        if (rc == 0 && png != NULL && len > 0 && status >= 200 && status <= 299)
            return reply_buffer(c, status, "image/png", png, len, NULL);
        free(png);
        if (rc == 0)
            return reply_error(c, 500, "internal error: ops->report_png succeeded without an image", NULL);
        return finish_op(c, "report_png", rc, NULL, status, why);
    }

    case API_ROUTE_SAMPLES_CSV: {
        if (ops->samples_csv == NULL)
            break;
        char *csv = NULL;
        size_t len = 0;
        rc = ops->samples_csv(s->user, req->id, &csv, &len, &status, why, sizeof why);
        if (rc == 0 && csv != NULL && len > 0 && status >= 200 && status <= 299) {
            char disposition[96];
            snprintf(disposition, sizeof disposition, "attachment; filename=\"trial-%lld-samples.csv\"",
                     (long long)req->id);
            return reply_buffer_x(c, status, "text/csv; charset=utf-8", csv, len, NULL, "Content-Disposition",
                                  disposition);
        }
        free(csv);
        if (rc == 0)
            return reply_error(c, 500, "internal error: ops->samples_csv succeeded without a body", NULL);
        return finish_op(c, "samples_csv", rc, NULL, status, why);
    }

    case API_ROUTE_PHASE: {
        if (ops->phase_png == NULL)
            break;
        unsigned char *png = NULL;
        size_t len = 0;
        char map[API_WHY_MAX] = "";
        rc = ops->phase_png(s->user, &png, &len, map, sizeof map, &status, why, sizeof why);
        if (rc == 0 && png != NULL && len > 0 && status >= 200 && status <= 299) {
            for (char *p = map; *p; p++) /* a header value: visible ASCII and spaces only */
                if ((unsigned char)*p < 0x20 || (unsigned char)*p >= 0x7f)
                    *p = '?';
            return reply_buffer_x(c, status, "image/png", png, len, NULL, "X-Phase-Map", map[0] ? map : "-");
        }
        free(png);
        if (rc == 0)
            return reply_error(c, 500, "internal error: ops->phase_png succeeded without an image", NULL);
        return finish_op(c, "phase_png", rc, NULL, status, why);
    }

    case API_ROUTE_EVENTS: {
        if (ops->events == NULL)
            break;
        api_stream st = {0};
        if (ops->events(s->user, &st, why, sizeof why) != 0 || st.read == NULL)
            return reply_error(c, 500, why[0] ? why : "events failed (no reason given)", NULL);
        return reply_stream(c, &st);
    }

    case API_ROUTE_CAMERA: {
        if (ops->camera_jpeg == NULL)
            break;
        unsigned char *jpg = NULL;
        size_t len = 0;
        rc = ops->camera_jpeg(s->user, &jpg, &len, &status, why, sizeof why);
        if (rc == 0 && jpg != NULL && len > 0 && status >= 200 && status <= 299)
            return reply_buffer(c, status, "image/jpeg", jpg, len, NULL);
        free(jpg);
        if (rc == 0)
            return reply_error(c, 500, "internal error: ops->camera_jpeg succeeded without an image", NULL);
        return finish_op(c, "camera_jpeg", rc, NULL, status, why);
    }

    case API_ROUTE_PREDICTION:
        if (ops->prediction == NULL)
            break;
        rc = ops->prediction(s->user, &out, &status, why, sizeof why);
        return finish_op(c, "prediction", rc, out, status, why);

    case API_ROUTE_CAMPAIGN: {
        if (ops->campaign == NULL)
            break;
        json_t *body = NULL;
        if (strcmp(method, "POST") == 0 && (body = api_body_object(req->body, req->len, why, sizeof why)) == NULL)
            return reply_error(c, MHD_HTTP_BAD_REQUEST, why, NULL);
        rc = ops->campaign(s->user, method, req->path, body, &out, &status, why, sizeof why);
        json_decref(body);
        return finish_op(c, "campaign", rc, out, status, why);
    }

    case API_ROUTE_NONE:
    case API_ROUTE_BAD_ID:
    case API_ROUTE_BAD_PATH:
        return reply_error(c, 500, "internal error: request reached dispatch without a route", NULL);
    }
    return reply_error(c, MHD_HTTP_NOT_IMPLEMENTED, "this daemon does not serve that request yet", NULL);
}

/* ---------------------------------------------------------------- the body's deadline */

/* The body must be in body_timeout_ms after the headers (issue 33, item 7: the deadline used to
 * be checked only when more data arrived, so a body that stopped coming held its slot until
 * libmicrohttpd's idle timeout, 30 s, and was closed without a word). libmicrohttpd's per-
 * connection timeout counts idle seconds from the last data received; set to the whole seconds
 * left before the deadline at the headers and again at every chunk, it fires at the deadline
 * (at most a second after it) whether or not data keeps coming. Returns 0 while the deadline is
 * ahead, -1 once it has passed. */
static int body_deadline_arm(const api_server *s, struct MHD_Connection *c, const api_request *req)
{
    uint64_t now = mono_ms(), end = req->started_ms + s->body_timeout_ms;
    if (now > end)
        return -1;
    unsigned left_s = (unsigned)((end - now + 999) / 1000);
    MHD_set_connection_option(c, MHD_CONNECTION_OPTION_TIMEOUT, left_s ? left_s : 1u);
    return 0;
}

/* Answer a body that missed its deadline with 408, as the guard answers a late head. The bytes
 * are written on the socket itself: libmicrohttpd queues a reply only before a body is read or
 * after all of it, and this request has neither. Nothing was sent on the connection before
 * (but perhaps "100 Continue"), and it is closed right after (on a timeout, libmicrohttpd calls
 * on_completed before it shuts the socket down). */
static void reply_body_late(const api_server *s, struct MHD_Connection *c, api_request *req)
{
    req->answered = true;
    const union MHD_ConnectionInfo *ci = MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
    if (ci == NULL)
        return;
    char msg[160], reply[1024];
    snprintf(msg, sizeof msg, "request body not complete within %u ms of the headers", s->body_timeout_ms);
    size_t len = api_guard_reply(reply, sizeof reply, 408, msg);
    if (len > 0) {
        ssize_t w = send(ci->connect_fd, reply, len, MSG_NOSIGNAL | MSG_DONTWAIT);
        (void)w; /* a small reply fits the socket buffer; a client that cannot take it loses it */
    }
}

/* ---------------------------------------------------------------- libmicrohttpd callbacks */

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url, const char *method,
                                  const char *version, const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    (void)version;
    api_pool *pool = cls;
    api_server *s = pool->s;
    api_request *req = *con_cls;
    if (req == NULL) {
        req = calloc(1, sizeof *req);
        if (req == NULL)
            return MHD_NO;
        *con_cls = req;
        enum MHD_Result ok = on_headers(s, pool->stream, c, url, method, req);
        if (ok == MHD_YES && !req->answered)
            body_deadline_arm(s, c, req);
        if (ok != MHD_YES || req->answered || *upload_data_size == 0)
            return ok;
    }
    if (*upload_data_size != 0) {
        if (!req->answered && body_deadline_arm(s, c, req) != 0) {
            reply_body_late(s, c, req); /* a body trickled in past its deadline */
            return MHD_NO;              /* the slot goes back to the pool */
        }
        if (!req->answered)
            body_append(s, req, upload_data, *upload_data_size);
        *upload_data_size = 0;
        return MHD_YES;
    }
    if (req->answered)
        return MHD_YES;
    req->answered = true;
    MHD_set_connection_option(c, MHD_CONNECTION_OPTION_TIMEOUT, pool->idle_s); /* the reply's own time */
    if (req->too_big)
        return reply_errorf(c, MHD_HTTP_CONTENT_TOO_LARGE, NULL, "request body is larger than the limit of %zu bytes",
                            s->max_body);
    return dispatch(s, c, method, req);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls, enum MHD_RequestTerminationCode toe)
{
    api_server *s = cls;
    api_request *req = *con_cls;
    if (req != NULL && !req->answered && toe == MHD_REQUEST_TERMINATED_TIMEOUT_REACHED)
        reply_body_late(s, c, req); /* nothing more came before the body's deadline */
    if (req != NULL) {
        free(req->body);
        free(req);
        *con_cls = NULL;
    }
}

static void on_connection(void *cls, struct MHD_Connection *c, void **socket_ctx, enum MHD_ConnectionNotificationCode code)
{
    (void)c;
    (void)socket_ctx;
    api_pool *pool = cls;
    if (code == MHD_CONNECTION_NOTIFY_CLOSED)
        atomic_fetch_sub(&pool->open, 1);
}

/* Percent-escapes stay as they were sent (the path grammar refuses '%'): nothing is decoded, so
 * nothing can be truncated by a decoded NUL. */
static size_t keep_escapes(void *cls, struct MHD_Connection *c, char *s)
{
    (void)cls;
    (void)c;
    return strlen(s);
}

/* api_guard's take: sort a complete head into a pool (api_head_sort_raw), or refuse with 503. */
static int take_connection(void *user, int fd, const struct sockaddr *peer, socklen_t peer_len, const char *head,
                           size_t len, char *why, size_t why_len)
{
    api_server *s = user;
    api_head_sort sort;
    api_head_sort_raw(head, len, &sort);
    int stream = sort.stream;
    api_pool *pool = &s->pool[stream];
    unsigned limit = stream ? s->max_streams : s->max_control;
    if (sort.control)
        limit += API_RESERVED_CONTROL;
    if (atomic_load(&pool->open) >= (int)limit) {
        snprintf(why, why_len, stream ? "too many live streams open (%u); close a page and retry"
                                : "the API is busy (%u connections in use); retry",
                 limit);
        return 503;
    }
    /* Counted here, on the only thread that hands sockets over, so the count is never behind;
     * libmicrohttpd's own limit is set above ours and never reached (reaching it made
     * libmicrohttpd 0.9.75 hang at stop). On failure libmicrohttpd has closed the socket. */
    atomic_fetch_add(&pool->open, 1);
    if (MHD_add_connection(stream ? s->smhd : s->mhd, fd, peer, peer_len) != MHD_YES)
        atomic_fetch_sub(&pool->open, 1);
    return 0;
}

static void on_log(void *cls, const char *fmt, va_list ap)
{
    api_server *s = cls;
    pthread_mutex_lock(&s->log_lock);
    if (s->log_capture) {
        vsnprintf(s->log, sizeof s->log, fmt, ap);
        size_t len = strlen(s->log);
        while (len > 0 && (s->log[len - 1] == '\n' || s->log[len - 1] == '.'))
            s->log[--len] = '\0';
    }
    pthread_mutex_unlock(&s->log_lock);
}

/* ---------------------------------------------------------------- start / stop */

static int listen_on(int fd)
{
    return listen(fd, 1024);
}

/* Parse a numeric listen address into sa; tell whether it is a loopback address. */
static int parse_listen(const char *listen, struct sockaddr_storage *sa, bool *v6, bool *loopback, char *why, size_t why_len)
{
    memset(sa, 0, sizeof *sa);
    if (strcmp(listen, "localhost") == 0)
        listen = "127.0.0.1";
    struct sockaddr_in *a4 = (struct sockaddr_in *)sa;
    struct sockaddr_in6 *a6 = (struct sockaddr_in6 *)sa;
    if (inet_pton(AF_INET, listen, &a4->sin_addr) == 1) {
        a4->sin_family = AF_INET;
        *v6 = false;
        *loopback = (ntohl(a4->sin_addr.s_addr) >> 24) == 127;
        return 0;
    }
    if (inet_pton(AF_INET6, listen, &a6->sin6_addr) == 1) {
        a6->sin6_family = AF_INET6;
        *v6 = true;
        const unsigned char *b = a6->sin6_addr.s6_addr;
        *loopback = IN6_IS_ADDR_LOOPBACK(&a6->sin6_addr) || (IN6_IS_ADDR_V4MAPPED(&a6->sin6_addr) && b[12] == 127);
        return 0;
    }
    snprintf(why, why_len, "listen address '%.100s' is not a numeric IPv4 or IPv6 address (e.g. 127.0.0.1, ::1, 0.0.0.0)",
             listen);
    return -1;
}

static int check_config(const api_server_config *cfg, char *why, size_t why_len)
{
    if (cfg->port > 65535) {
        snprintf(why, why_len, "api port %u is out of range (0 = any free port, or 1..65535)", cfg->port);
        return -1;
    }
    if (cfg->max_body_bytes < 1024 || cfg->max_body_bytes > 16u * 1024 * 1024) {
        snprintf(why, why_len, "api max_body_bytes %zu is out of range (1024 .. 16777216)", cfg->max_body_bytes);
        return -1;
    }
    if (cfg->connection_timeout_s < 1 || cfg->connection_timeout_s > 3600) {
        snprintf(why, why_len, "api connection_timeout_s %u is out of range (1 .. 3600)", cfg->connection_timeout_s);
        return -1;
    }
    if (cfg->max_connections < 1 || cfg->max_connections > 1000) {
        snprintf(why, why_len, "api max_connections %u is out of range (1 .. 1000)", cfg->max_connections);
        return -1;
    }
    if (cfg->max_streams < 1 || cfg->max_streams > 256) {
        snprintf(why, why_len, "api max_streams %u is out of range (1 .. 256)", cfg->max_streams);
        return -1;
    }
    if (cfg->header_timeout_ms < 100 || cfg->header_timeout_ms > 60000) {
        snprintf(why, why_len, "api header_timeout_ms %u is out of range (100 .. 60000)", cfg->header_timeout_ms);
        return -1;
    }
    if (cfg->pending_max < 16 || cfg->pending_max > 4096) {
        snprintf(why, why_len, "api pending_max %u is out of range (16 .. 4096)", cfg->pending_max);
        return -1;
    }
    if (cfg->body_timeout_ms < 1000 || cfg->body_timeout_ms > 60000) {
        snprintf(why, why_len, "api body_timeout_ms %u is out of range (1000 .. 60000)", cfg->body_timeout_ms);
        return -1;
    }
    if (cfg->token != NULL) {
        size_t len = strlen(cfg->token);
        if (len > API_TOKEN_MAX) {
            snprintf(why, why_len, "api token is %zu characters long; at most %d", len, API_TOKEN_MAX);
            return -1;
        }
        for (size_t i = 0; i < len; i++) {
            unsigned char b = (unsigned char)cfg->token[i];
            if (b <= 0x20 || b >= 0x7f) {
                snprintf(why, why_len, "api token character %zu is not visible ASCII (no spaces or control characters)",
                         i + 1);
                return -1;
            }
        }
    }
    return 0;
}

int api_server_start(const api_server_config *cfg_in, const api_ops *ops, void *user, api_server **out, char *why,
                     size_t why_len)
{
    api_server_config cfg = cfg_in ? *cfg_in : api_server_config_default();
    if (out == NULL || ops == NULL) {
        snprintf(why, why_len, "api_server_start: ops and out must not be NULL");
        return -1;
    }
    *out = NULL;
    const char *listen = cfg.listen ? cfg.listen : "127.0.0.1";
    if (check_config(&cfg, why, why_len) != 0)
        return -1;
    struct sockaddr_storage sa;
    bool v6 = false, loopback = false;
    if (parse_listen(listen, &sa, &v6, &loopback, why, why_len) != 0)
        return -1;
    bool has_token = cfg.token != NULL && cfg.token[0] != '\0';
    if (!loopback && !has_token) {
        snprintf(why, why_len,
                 "refusing to listen on %s without a token: anyone who can reach this address could move the "
                 "rails; set [api] token, or listen on 127.0.0.1",
                 listen);
        return -1;
    }
    if (v6)
        ((struct sockaddr_in6 *)&sa)->sin6_port = htons((uint16_t)cfg.port);
    else
        ((struct sockaddr_in *)&sa)->sin_port = htons((uint16_t)cfg.port);

    api_server *s = calloc(1, sizeof *s);
    if (s == NULL) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    s->ops = *ops;
    s->user = user;
    if (has_token) {
        s->token_len = strlen(cfg.token);
        memcpy(s->token, cfg.token, s->token_len + 1);
    }
    s->max_body = cfg.max_body_bytes;
    s->body_timeout_ms = cfg.body_timeout_ms;
    if (pthread_mutex_init(&s->log_lock, NULL) != 0) {
        free(s);
        snprintf(why, why_len, "could not create a mutex");
        return -1;
    }
    s->log_capture = true;

    s->pool[0].s = s->pool[1].s = s;
    s->pool[1].stream = 1;
    s->pool[0].idle_s = cfg.connection_timeout_s;
    s->pool[1].idle_s = API_STREAM_IDLE_S;
    s->max_control = cfg.max_connections;
    s->max_streams = cfg.max_streams;
    if (cfg.n_assets > 0) {
        s->assets = calloc(cfg.n_assets, sizeof *s->assets);
        if (s->assets == NULL) {
            snprintf(why, why_len, "out of memory");
            goto fail;
        }
        memcpy(s->assets, cfg.assets, cfg.n_assets * sizeof *s->assets);
        s->n_assets = cfg.n_assets;
    }

    /* The listening socket is ours (the guard's): bound here so a failure names its reason. */
    int lfd = socket(v6 ? AF_INET6 : AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (lfd < 0) {
        snprintf(why, why_len, "cannot serve the API on %s port %u: socket: %s", listen, cfg.port, strerror(errno));
        goto fail;
    }
    int one = 1;
    setsockopt(lfd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (v6)
        setsockopt(lfd, IPPROTO_IPV6, IPV6_V6ONLY, &one, sizeof one);
    socklen_t salen = v6 ? sizeof(struct sockaddr_in6) : sizeof(struct sockaddr_in);
    if (bind(lfd, (struct sockaddr *)&sa, salen) != 0 || listen_on(lfd) != 0) {
        snprintf(why, why_len, "cannot serve the API on %s port %u: %s", listen, cfg.port, strerror(errno));
        close(lfd);
        goto fail;
    }
    struct sockaddr_storage bound;
    socklen_t blen = sizeof bound;
    if (getsockname(lfd, (struct sockaddr *)&bound, &blen) != 0) {
        snprintf(why, why_len, "cannot tell which port the API listens on: %s", strerror(errno));
        close(lfd);
        goto fail;
    }
    s->port = ntohs(v6 ? ((struct sockaddr_in6 *)&bound)->sin6_port : ((struct sockaddr_in *)&bound)->sin_port);

    errno = 0;
    s->mhd = MHD_start_daemon(MHD_USE_AUTO_INTERNAL_THREAD | MHD_USE_ITC | MHD_USE_ERROR_LOG | MHD_USE_NO_LISTEN_SOCKET,
                              0, NULL, NULL, on_request, &s->pool[0],
                              MHD_OPTION_EXTERNAL_LOGGER, on_log, s,
                              MHD_OPTION_NOTIFY_COMPLETED, on_completed, s,
                              MHD_OPTION_NOTIFY_CONNECTION, on_connection, &s->pool[0],
                              MHD_OPTION_UNESCAPE_CALLBACK, keep_escapes, NULL,
                              MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)(4 * API_HEAD_MAX),
                              MHD_OPTION_CONNECTION_TIMEOUT, cfg.connection_timeout_s,
                              MHD_OPTION_CONNECTION_LIMIT, cfg.max_connections + API_RESERVED_CONTROL + 16,
                              MHD_OPTION_END);
    if (s->mhd != NULL)
        s->smhd = MHD_start_daemon(MHD_USE_THREAD_PER_CONNECTION | MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_ITC |
                                       MHD_USE_ERROR_LOG | MHD_USE_NO_LISTEN_SOCKET,
                                   0, NULL, NULL, on_request, &s->pool[1],
                                   MHD_OPTION_EXTERNAL_LOGGER, on_log, s,
                                   MHD_OPTION_NOTIFY_COMPLETED, on_completed, s,
                                   MHD_OPTION_NOTIFY_CONNECTION, on_connection, &s->pool[1],
                                   MHD_OPTION_UNESCAPE_CALLBACK, keep_escapes, NULL,
                                   MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)(4 * API_HEAD_MAX),
                                   /* a client that reads nothing for this long is dropped */
                                   MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)API_STREAM_IDLE_S,
                                   MHD_OPTION_CONNECTION_LIMIT, cfg.max_streams + 16,
                                   MHD_OPTION_END);
    int err = errno;
    pthread_mutex_lock(&s->log_lock);
    s->log_capture = false;
    pthread_mutex_unlock(&s->log_lock);
    if (s->mhd == NULL || s->smhd == NULL) {
        const char *reason = s->log[0] ? s->log : err ? strerror(err) : "libmicrohttpd gave no reason";
        snprintf(why, why_len, "cannot serve the API on %s port %u: %s", listen, cfg.port, reason);
        close(lfd);
        goto fail;
    }
    api_guard_config gc = {
        .listen_fd = lfd,
        .header_timeout_ms = cfg.header_timeout_ms,
        .pending_max = cfg.pending_max,
        .line_max = API_LINE_MAX,
        .head_max = API_HEAD_MAX,
        .take = take_connection,
        .user = s,
    };
    if (api_guard_start(&gc, &s->guard, why, why_len) != 0) {
        close(lfd);
        goto fail;
    }
    *out = s;
    return 0;
fail:
    api_server_stop(s);
    return -1;
}

unsigned api_server_port(const api_server *s)
{
    return s ? s->port : 0;
}

void api_server_stop(api_server *s)
{
    if (s == NULL)
        return;
    api_guard_stop(s->guard); /* first: no new connection reaches the pools */
    if (s->smhd)
        MHD_stop_daemon(s->smhd);
    if (s->mhd)
        MHD_stop_daemon(s->mhd);
    pthread_mutex_destroy(&s->log_lock);
    free(s->assets);
    free(s);
}
