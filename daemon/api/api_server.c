/* api_server.c: the control API's HTTP side (libmicrohttpd), see api_server.h for the routes and
 * the threading and ownership contracts.
 *
 * Request life cycle. libmicrohttpd calls on_request() several times per request:
 *   1. once when the headers are in (no body yet): we allocate the per-request state and run
 *      every check that needs no body, in this order: token (401), path (404, 400 bad id),
 *      method (405), Content-Length against the limit (413). A failed check answers at once,
 *      before any body is read; a client that sent "Expect: 100-continue" never uploads it.
 *   2. zero or more times with a chunk of body: appended to the request's buffer, which never
 *      grows past max_body_bytes (a chunked upload that goes past it is drained and answered 413).
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
 * so the server does not depend on jansson's allocator. The token is compared in constant time. */
#include "api_server.h"

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
#include <sys/socket.h>

#define API_TOKEN_MAX 256
#define API_WHY_MAX 512

struct api_server {
    struct MHD_Daemon *mhd;
    api_ops ops;
    void *user;
    char token[API_TOKEN_MAX + 1]; /* "" = no token */
    size_t token_len;
    size_t max_body;
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
    bool answered;  /* a reply was queued before the body was read */
    bool too_big;   /* the body went past max_body: drained, answered 413 */
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
    };
    return c;
}

/* ---------------------------------------------------------------- replies */

/* Queue a reply whose body is buf[0..len), malloc'ed; ownership passes to libmicrohttpd. */
static enum MHD_Result reply_buffer(struct MHD_Connection *c, int status, const char *ctype, void *buf,
                                    size_t len, const char *allow)
{
    struct MHD_Response *r = MHD_create_response_from_buffer(len, buf, MHD_RESPMEM_MUST_FREE);
    if (r == NULL) {
        free(buf);
        return MHD_NO; /* out of memory: libmicrohttpd closes the connection */
    }
    enum MHD_Result ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    if (ok == MHD_YES)
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    if (ok == MHD_YES && allow != NULL)
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_ALLOW, allow);
    if (ok == MHD_YES && status == MHD_HTTP_UNAUTHORIZED)
        ok = MHD_add_response_header(r, MHD_HTTP_HEADER_WWW_AUTHENTICATE, "Bearer realm=\"ribbond\"");
    if (ok == MHD_YES)
        ok = MHD_queue_response(c, (unsigned)status, r);
    MHD_destroy_response(r);
    return ok;
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

/* {"error": msg, "status": status}, with an Allow header for 405. */
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

/* Constant-time comparison: the time taken does not tell how many leading bytes were right. */
static bool same_secret(const char *a, size_t alen, const char *b, size_t blen)
{
    unsigned char diff = (unsigned char)(alen != blen);
    size_t n = alen < blen ? alen : blen;
    for (size_t i = 0; i < n; i++)
        diff |= (unsigned char)(a[i] ^ b[i]);
    return diff == 0;
}

/* 0 when the request carries the right bearer token (or none is configured), else a reason. */
static int check_token(const api_server *s, struct MHD_Connection *c, char *why, size_t n)
{
    if (s->token_len == 0)
        return 0;
    const char *h = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_AUTHORIZATION);
    if (h == NULL) {
        snprintf(why, n, "this daemon requires a token: send \"Authorization: Bearer TOKEN\" "
                         "(the token is [api] token in the rig file)");
        return -1;
    }
    if (strncasecmp(h, "Bearer ", 7) != 0) {
        snprintf(why, n, "Authorization header must be \"Bearer TOKEN\"");
        return -1;
    }
    const char *t = h + 7;
    while (*t == ' ')
        t++;
    size_t len = strlen(t);
    while (len > 0 && (t[len - 1] == ' ' || t[len - 1] == '\t'))
        len--;
    if (!same_secret(t, len, s->token, s->token_len)) {
        snprintf(why, n, "wrong token");
        return -1;
    }
    return 0;
}

/* Headers are in: run every check that needs no body. Returns MHD_YES to go on reading. */
static enum MHD_Result on_headers(api_server *s, struct MHD_Connection *c, const char *url, const char *method,
                                  api_request *req)
{
    char why[API_WHY_MAX] = "";
    if (check_token(s, c, why, sizeof why) != 0) {
        req->answered = true;
        return reply_error(c, MHD_HTTP_UNAUTHORIZED, why, NULL);
    }
    req->route = api_route_parse(url, &req->id, why, sizeof why);
    if (req->route == API_ROUTE_NONE) {
        req->answered = true;
        return reply_errorf(c, MHD_HTTP_NOT_FOUND, NULL,
                            "no such path: %.200s (paths: /status, /trials, /trials/current/abort, /trials/ID, "
                            "/trials/ID/report.png)",
                            url);
    }
    if (req->route == API_ROUTE_BAD_ID) {
        req->answered = true;
        return reply_error(c, MHD_HTTP_BAD_REQUEST, why, NULL);
    }
    if (!api_route_method_ok(req->route, method)) {
        const char *allow = api_route_allow(req->route);
        req->answered = true;
        return reply_errorf(c, MHD_HTTP_METHOD_NOT_ALLOWED, allow, "method %.20s not allowed on %.200s (allowed: %s)",
                            method, url, allow);
    }
    const char *cl = MHD_lookup_connection_value(c, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
    if (cl != NULL) {
        char *end = NULL;
        errno = 0;
        unsigned long long v = strtoull(cl, &end, 10);
        if (end != cl && errno == 0 && v > s->max_body) {
            req->answered = true;
            return reply_errorf(c, MHD_HTTP_CONTENT_TOO_LARGE, NULL,
                                "request body of %llu bytes is larger than the limit of %zu bytes", v, s->max_body);
        }
    }
    return MHD_YES;
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

/* The body as a JSON object: {} when empty or blank. NULL with a reason on error. */
static json_t *body_object(const api_request *req, char *why, size_t n)
{
    size_t i = 0;
    while (i < req->len && (req->body[i] == ' ' || req->body[i] == '\t' || req->body[i] == '\r' || req->body[i] == '\n'))
        i++;
    if (i == req->len)
        return json_object();
    json_error_t err;
    json_t *j = json_loadb(req->body, req->len, JSON_REJECT_DUPLICATES, &err);
    if (j == NULL) {
        snprintf(why, n, "malformed JSON body at line %d, column %d: %s", err.line, err.column, err.text);
        return NULL;
    }
    if (!json_is_object(j)) {
        static const char *const names[] = {"an object", "an array", "a string", "a number", "a number",
                                            "true", "false", "null"};
        int t = (int)json_typeof(j);
        snprintf(why, n, "request body must be a JSON object, got %s",
                 t >= 0 && t < (int)(sizeof names / sizeof names[0]) ? names[t] : "something else");
        json_decref(j);
        return NULL;
    }
    return j;
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
            json_t *body = body_object(req, why, sizeof why);
            if (body == NULL)
                return reply_error(c, MHD_HTTP_BAD_REQUEST, why, NULL);
            status = MHD_HTTP_CREATED;
            rc = ops->start(s->user, body, &out, &status, why, sizeof why);
            json_decref(body);
            return finish_op(c, "start", rc, out, status, why);
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

    case API_ROUTE_NONE:
    case API_ROUTE_BAD_ID:
        return reply_error(c, 500, "internal error: request reached dispatch without a route", NULL);
    }
    return reply_error(c, MHD_HTTP_NOT_IMPLEMENTED, "this daemon does not serve that request yet", NULL);
}

/* ---------------------------------------------------------------- libmicrohttpd callbacks */

static enum MHD_Result on_request(void *cls, struct MHD_Connection *c, const char *url, const char *method,
                                  const char *version, const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    (void)version;
    api_server *s = cls;
    api_request *req = *con_cls;
    if (req == NULL) {
        req = calloc(1, sizeof *req);
        if (req == NULL)
            return MHD_NO;
        *con_cls = req;
        enum MHD_Result ok = on_headers(s, c, url, method, req);
        if (ok != MHD_YES || req->answered || *upload_data_size == 0)
            return ok;
    }
    if (*upload_data_size != 0) {
        if (!req->answered)
            body_append(s, req, upload_data, *upload_data_size);
        *upload_data_size = 0;
        return MHD_YES;
    }
    if (req->answered)
        return MHD_YES;
    req->answered = true;
    if (req->too_big)
        return reply_errorf(c, MHD_HTTP_CONTENT_TOO_LARGE, NULL, "request body is larger than the limit of %zu bytes",
                            s->max_body);
    return dispatch(s, c, method, req);
}

static void on_completed(void *cls, struct MHD_Connection *c, void **con_cls, enum MHD_RequestTerminationCode toe)
{
    (void)cls;
    (void)c;
    (void)toe;
    api_request *req = *con_cls;
    if (req != NULL) {
        free(req->body);
        free(req);
        *con_cls = NULL;
    }
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

/* Parse a numeric listen address into sa; tell whether it is a loopback address. */
static int parse_listen(const char *listen, struct sockaddr_storage *sa, bool *v6, bool *loopback, char *why, size_t n)
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
    snprintf(why, n, "listen address '%.100s' is not a numeric IPv4 or IPv6 address (e.g. 127.0.0.1, ::1, 0.0.0.0)",
             listen);
    return -1;
}

static int check_config(const api_server_config *cfg, char *why, size_t n)
{
    if (cfg->port > 65535) {
        snprintf(why, n, "api port %u is out of range (0 = any free port, or 1..65535)", cfg->port);
        return -1;
    }
    if (cfg->max_body_bytes < 1024 || cfg->max_body_bytes > 16u * 1024 * 1024) {
        snprintf(why, n, "api max_body_bytes %zu is out of range (1024 .. 16777216)", cfg->max_body_bytes);
        return -1;
    }
    if (cfg->connection_timeout_s < 1 || cfg->connection_timeout_s > 3600) {
        snprintf(why, n, "api connection_timeout_s %u is out of range (1 .. 3600)", cfg->connection_timeout_s);
        return -1;
    }
    if (cfg->max_connections < 1 || cfg->max_connections > 1000) {
        snprintf(why, n, "api max_connections %u is out of range (1 .. 1000)", cfg->max_connections);
        return -1;
    }
    if (cfg->token != NULL) {
        size_t len = strlen(cfg->token);
        if (len > API_TOKEN_MAX) {
            snprintf(why, n, "api token is %zu characters long; at most %d", len, API_TOKEN_MAX);
            return -1;
        }
        for (size_t i = 0; i < len; i++) {
            unsigned char b = (unsigned char)cfg->token[i];
            if (b <= 0x20 || b >= 0x7f) {
                snprintf(why, n, "api token character %zu is not visible ASCII (no spaces or control characters)",
                         i + 1);
                return -1;
            }
        }
    }
    return 0;
}

int api_server_start(const api_server_config *cfg_in, const api_ops *ops, void *user, api_server **out, char *why,
                     size_t n)
{
    api_server_config cfg = cfg_in ? *cfg_in : api_server_config_default();
    if (out == NULL || ops == NULL) {
        snprintf(why, n, "api_server_start: ops and out must not be NULL");
        return -1;
    }
    *out = NULL;
    const char *listen = cfg.listen ? cfg.listen : "127.0.0.1";
    if (check_config(&cfg, why, n) != 0)
        return -1;
    struct sockaddr_storage sa;
    bool v6 = false, loopback = false;
    if (parse_listen(listen, &sa, &v6, &loopback, why, n) != 0)
        return -1;
    bool has_token = cfg.token != NULL && cfg.token[0] != '\0';
    if (!loopback && !has_token) {
        snprintf(why, n,
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
        snprintf(why, n, "out of memory");
        return -1;
    }
    s->ops = *ops;
    s->user = user;
    if (has_token) {
        s->token_len = strlen(cfg.token);
        memcpy(s->token, cfg.token, s->token_len + 1);
    }
    s->max_body = cfg.max_body_bytes;
    if (pthread_mutex_init(&s->log_lock, NULL) != 0) {
        free(s);
        snprintf(why, n, "could not create a mutex");
        return -1;
    }
    s->log_capture = true;

    unsigned flags = MHD_USE_AUTO_INTERNAL_THREAD | MHD_USE_ITC | MHD_USE_ERROR_LOG;
    if (v6)
        flags |= MHD_USE_IPv6;
    errno = 0;
    s->mhd = MHD_start_daemon(flags, (uint16_t)cfg.port, NULL, NULL, on_request, s,
                              MHD_OPTION_EXTERNAL_LOGGER, on_log, s,
                              MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&sa,
                              MHD_OPTION_NOTIFY_COMPLETED, on_completed, s,
                              MHD_OPTION_CONNECTION_TIMEOUT, cfg.connection_timeout_s,
                              MHD_OPTION_CONNECTION_LIMIT, cfg.max_connections,
                              MHD_OPTION_END);
    int err = errno;
    pthread_mutex_lock(&s->log_lock);
    s->log_capture = false;
    pthread_mutex_unlock(&s->log_lock);
    if (s->mhd == NULL) {
        const char *reason = s->log[0] ? s->log : err ? strerror(err) : "libmicrohttpd gave no reason";
        snprintf(why, n, "cannot serve the API on %s port %u: %s", listen, cfg.port, reason);
        pthread_mutex_destroy(&s->log_lock);
        free(s);
        return -1;
    }
    const union MHD_DaemonInfo *info = MHD_get_daemon_info(s->mhd, MHD_DAEMON_INFO_BIND_PORT);
    s->port = info ? info->port : cfg.port;
    if (s->port == 0) {
        snprintf(why, n, "cannot tell which port the API listens on");
        api_server_stop(s);
        return -1;
    }
    *out = s;
    return 0;
}

unsigned api_server_port(const api_server *s)
{
    return s ? s->port : 0;
}

void api_server_stop(api_server *s)
{
    if (s == NULL)
        return;
    if (s->mhd)
        MHD_stop_daemon(s->mhd);
    pthread_mutex_destroy(&s->log_lock);
    free(s);
}
