/* test_api.c: the control API end to end over real sockets. A server on 127.0.0.1, port 0, runs
 * with fake ops backed by a tiny in-test model (a list of trials and a "running" flag, under a
 * mutex as the real runner's will be), and every route is driven through the libcurl client.
 * A raw-socket helper (no curl) covers what the client cannot or should not send: malformed
 * JSON, requests split across several writes, chunked uploads, and reading reply headers. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "api.h"
#include "api_route.h" /* the room's own routes' grammar, tested here */

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

/* ---------------------------------------------------------------- fake model and ops */

#define FAKE_MAX 16
#define FAKE_PNG_LEN 200000

typedef struct fake_trial {
    int64_t id;
    char scene[64];
    char note[128];
    const char *status; /* "running", "aborted" */
} fake_trial;

typedef struct fake_model {
    pthread_mutex_t lock;
    fake_trial trials[FAKE_MAX];
    int count;
    int running; /* index of the running trial, or -1 */
    int ops_called;
} fake_model;

static json_t *trial_json(const fake_trial *t)
{
    return json_pack("{s:I, s:s, s:s, s:s}", "id", (json_int_t)t->id, "scene", t->scene, "note", t->note, "status",
                     t->status);
}

static int fake_status(void *user, json_t **out, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    fake_model *m = user;
    pthread_mutex_lock(&m->lock);
    m->ops_called++;
    *out = json_pack("{s:s, s:i}", "state", m->running >= 0 ? "running" : "idle", "trials", m->count);
    pthread_mutex_unlock(&m->lock);
    return 0;
}

static int fake_start(void *user, const json_t *body, json_t **out, int *http_status, char *why, size_t why_len)
{
    fake_model *m = user;
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)body, key, v)
    {
        if (strcmp(key, "scene") == 0 || strcmp(key, "note") == 0) {
            if (!json_is_string(v)) {
                snprintf(why, why_len, "field '%s' must be a string", key);
                *http_status = 400;
                return -1;
            }
        } else if (strcmp(key, "set") == 0) {
            if (!json_is_array(v)) {
                snprintf(why, why_len, "field 'set' must be an array of strings");
                *http_status = 400;
                return -1;
            }
        } else {
            snprintf(why, why_len, "unknown field '%s'", key);
            *http_status = 400;
            return -1;
        }
    }
    pthread_mutex_lock(&m->lock);
    m->ops_called++;
    if (m->running >= 0) {
        snprintf(why, why_len, "trial %lld is running; abort it first", (long long)m->trials[m->running].id);
        pthread_mutex_unlock(&m->lock);
        *http_status = 409;
        return -1;
    }
    if (m->count == FAKE_MAX) {
        pthread_mutex_unlock(&m->lock);
        snprintf(why, why_len, "fake model is full");
        *http_status = 500;
        return -1;
    }
    fake_trial *t = &m->trials[m->count];
    t->id = m->count + 1;
    const char *scene = json_string_value(json_object_get(body, "scene"));
    const char *note = json_string_value(json_object_get(body, "note"));
    snprintf(t->scene, sizeof t->scene, "%s", scene ? scene : "default");
    snprintf(t->note, sizeof t->note, "%s", note ? note : "");
    t->status = "running";
    m->running = m->count++;
    *out = trial_json(t);
    pthread_mutex_unlock(&m->lock);
    return 0; /* *http_status stays 201 */
}

static int fake_abort(void *user, json_t **out, int *http_status, char *why, size_t why_len)
{
    fake_model *m = user;
    pthread_mutex_lock(&m->lock);
    m->ops_called++;
    if (m->running < 0) {
        pthread_mutex_unlock(&m->lock);
        snprintf(why, why_len, "no trial is running");
        *http_status = 409;
        return -1;
    }
    fake_trial *t = &m->trials[m->running];
    t->status = "aborted";
    m->running = -1;
    *out = trial_json(t);
    pthread_mutex_unlock(&m->lock);
    return 0;
}

static int fake_list(void *user, json_t **out, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    fake_model *m = user;
    pthread_mutex_lock(&m->lock);
    m->ops_called++;
    json_t *a = json_array();
    for (int i = 0; i < m->count; i++)
        json_array_append_new(a, trial_json(&m->trials[i]));
    pthread_mutex_unlock(&m->lock);
    *out = a;
    return 0;
}

static int fake_show(void *user, int64_t id, json_t **out, int *http_status, char *why, size_t why_len)
{
    fake_model *m = user;
    pthread_mutex_lock(&m->lock);
    m->ops_called++;
    if (id < 1 || id > m->count) {
        pthread_mutex_unlock(&m->lock);
        snprintf(why, why_len, "no trial %lld", (long long)id);
        *http_status = 404;
        return -1;
    }
    *out = trial_json(&m->trials[id - 1]);
    pthread_mutex_unlock(&m->lock);
    return 0;
}

/* The fake "PNG": the signature, then every byte value including NUL, CR and LF. */
static unsigned char fake_png_byte(size_t i)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    return i < 8 ? sig[i] : (unsigned char)((i * 31u + (i >> 8)) & 0xffu);
}

static int fake_report(void *user, int64_t id, unsigned char **png, size_t *len, int *http_status, char *why,
                       size_t why_len)
{
    fake_model *m = user;
    pthread_mutex_lock(&m->lock);
    m->ops_called++;
    int count = m->count;
    pthread_mutex_unlock(&m->lock);
    if (id < 1 || id > count) {
        snprintf(why, why_len, "no trial %lld", (long long)id);
        *http_status = 404;
        return -1;
    }
    unsigned char *p = malloc(FAKE_PNG_LEN);
    if (p == NULL) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    for (size_t i = 0; i < FAKE_PNG_LEN; i++)
        p[i] = fake_png_byte(i);
    *png = p;
    *len = FAKE_PNG_LEN;
    return 0;
}

/* The fake samples CSV of trial id: a header and one row naming the id (a comma and a quote in a
 * text cell, as the store writes them). */
static int fake_samples_csv(void *user, int64_t id, char **csv, size_t *len, int *http_status, char *why,
                            size_t why_len)
{
    fake_model *m = user;
    pthread_mutex_lock(&m->lock);
    m->ops_called++;
    int count = m->count;
    pthread_mutex_unlock(&m->lock);
    if (id < 1 || id > count) {
        snprintf(why, why_len, "trial %lld does not exist", (long long)id);
        *http_status = 404;
        return -1;
    }
    char text[200];
    int n = snprintf(text, sizeof text, "seq,t_s,reason\n%lld,0.5,\"low, \"\"quality\"\"\"\n", (long long)id);
    *csv = malloc((size_t)n + 1);
    if (!*csv) return -1;
    memcpy(*csv, text, (size_t)n + 1);
    *len = (size_t)n;
    return 0;
}

/* The fake phase report: FAKE_PNG_LEN bytes as fake_report, with the map's state. */
static int fake_phase_png(void *user, unsigned char **png, size_t *len, char *map, size_t map_len, int *http_status,
                          char *why, size_t why_len)
{
    (void)http_status;
    if (fake_report(user, 1, png, len, http_status, why, why_len) != 0) return -1;
    snprintf(map, map_len, "computing 3/30\n"); /* the line break is sent as '?' */
    return 0;
}

static const api_ops fake_ops = {
    .samples_csv = fake_samples_csv,
    .phase_png = fake_phase_png,
    .status = fake_status,
    .start = fake_start,
    .abort_current = fake_abort,
    .list = fake_list,
    .show = fake_show,
    .report_png = fake_report,
};

/* ---------------------------------------------------------------- fixture */

#define TOKEN "s3cret-token"

typedef struct fixture {
    fake_model m;
    api_server *srv;
    char url[64];
    api_client_config cc;
} fixture;

static int fixture_up(void **state, const char *token, const api_ops *ops)
{
    fixture *f = calloc(1, sizeof *f);
    assert_non_null(f);
    pthread_mutex_init(&f->m.lock, NULL);
    f->m.running = -1;
    api_server_config cfg = api_server_config_default();
    cfg.port = 0;
    cfg.token = token;
    char why[512] = "";
    int rc = api_server_start(&cfg, ops, &f->m, &f->srv, why, sizeof why);
    if (rc != 0)
        fail_msg("api_server_start: %s", why);
    assert_true(api_server_port(f->srv) > 0);
    snprintf(f->url, sizeof f->url, "http://127.0.0.1:%u", api_server_port(f->srv));
    f->cc = api_client_config_default();
    f->cc.base_url = f->url;
    f->cc.token = token;
    f->cc.timeout_s = 10;
    *state = f;
    return 0;
}

static int setup(void **state) { return fixture_up(state, NULL, &fake_ops); }
static int setup_token(void **state) { return fixture_up(state, TOKEN, &fake_ops); }

static int teardown(void **state)
{
    fixture *f = *state;
    api_server_stop(f->srv);
    pthread_mutex_destroy(&f->m.lock);
    free(f);
    return 0;
}

/* One request through the client; fails the test when the exchange itself fails. Returns the
 * HTTP status; *out (if given) gets the JSON reply, why the error message. */
static int req(const fixture *f, const char *method, const char *path, const json_t *body, json_t **out, char *why,
               size_t why_len)
{
    int status = 0;
    json_t *j = NULL;
    int rc = api_client_request(&f->cc, method, path, body, &status, &j, NULL, NULL, why, why_len);
    if (rc != 0)
        fail_msg("%s %s: %s", method, path, why);
    assert_non_null(j);
    /* Every reply of this API is JSON; every error reply is {"error", "status"} with the status. */
    if (status >= 400) {
        assert_true(json_is_string(json_object_get(j, "error")));
        assert_int_equal(json_integer_value(json_object_get(j, "status")), status);
        assert_string_equal(why, json_string_value(json_object_get(j, "error")));
    }
    if (out)
        *out = j;
    else
        json_decref(j);
    return status;
}

/* ---------------------------------------------------------------- raw socket helper */

/* Connect to 127.0.0.1:port, send parts one write() each with pause_ms between them, read the
 * whole reply (requests carry "Connection: close"). Returns the reply length, NUL-terminated. */
static size_t raw_exchange(unsigned port, const char *const *parts, const size_t *lens, size_t nparts, int pause_ms,
                           char *reply, size_t cap)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct timeval tv = {.tv_sec = 10};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    assert_int_equal(connect(fd, (struct sockaddr *)&a, sizeof a), 0);
    for (size_t i = 0; i < nparts; i++) {
        size_t len = lens ? lens[i] : strlen(parts[i]);
        size_t off = 0;
        while (off < len) {
            ssize_t w = send(fd, parts[i] + off, len - off, MSG_NOSIGNAL);
            if (w < 0)
                break; /* the server may answer (413) and close before everything is sent */
            off += (size_t)w;
        }
        if (pause_ms > 0 && i + 1 < nparts) {
            struct timespec ts = {.tv_sec = 0, .tv_nsec = pause_ms * 1000000L};
            nanosleep(&ts, NULL);
        }
    }
    size_t got = 0;
    for (;;) {
        assert_true(got + 1 < cap);
        ssize_t r = recv(fd, reply + got, cap - 1 - got, 0);
        if (r <= 0)
            break;
        got += (size_t)r;
    }
    close(fd);
    reply[got] = '\0';
    return got;
}

static int raw_status(const char *reply)
{
    int status = 0;
    if (sscanf(reply, "HTTP/1.%*d %d", &status) != 1)
        fail_msg("not an HTTP reply: %.80s", reply);
    return status;
}

static const char *raw_body(const char *reply)
{
    const char *p = strstr(reply, "\r\n\r\n");
    assert_non_null(p);
    return p + 4;
}

/* ---------------------------------------------------------------- tests: routes */

static void test_route_table(void **state)
{
    (void)state;
    int64_t id = 0;
    char why[256] = "";
    assert_int_equal(api_route_parse("/status", &id, why, sizeof why), API_ROUTE_STATUS);
    assert_int_equal(api_route_parse("/trials", &id, why, sizeof why), API_ROUTE_TRIALS);
    assert_int_equal(api_route_parse("/trials/current/abort", &id, why, sizeof why), API_ROUTE_ABORT);
    assert_int_equal(api_route_parse("/trials/42", &id, why, sizeof why), API_ROUTE_TRIAL);
    assert_int_equal(id, 42);
    assert_int_equal(api_route_parse("/trials/9223372036854775807/report.png", &id, why, sizeof why),
                     API_ROUTE_REPORT);
    assert_int_equal(id, INT64_MAX);
    assert_int_equal(api_route_parse("/trials/9223372036854775808", &id, why, sizeof why), API_ROUTE_BAD_ID);
    assert_non_null(strstr(why, "too large"));
    const char *bad[] = {"/trials/0", "/trials/-1", "/trials/1x", "/trials/", "/trials/current",
                         "/trials/abc/report.png"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        assert_int_equal(api_route_parse(bad[i], &id, why, sizeof why), API_ROUTE_BAD_ID);
    /* Outside the grammar [A-Za-z0-9._/-] (escapes are not decoded, so '%' itself is refused). */
    const char *bad_path[] = {"", "status", "/trials/+1", "/trials/ 1", "/trials/1%00/report.png",
                              "/status%00garbage", "/trials%00/1", "/trials/current/abort%00zz", "/status?x",
                              "/st\x01tus", "/trials/1\xff"};
    for (size_t i = 0; i < sizeof bad_path / sizeof bad_path[0]; i++)
        assert_int_equal(api_route_parse(bad_path[i], &id, why, sizeof why), API_ROUTE_BAD_PATH);
    assert_int_equal(api_route_parse("/status%00garbage", &id, why, sizeof why), API_ROUTE_BAD_PATH);
    assert_non_null(strstr(why, "'%' at offset 7"));
    assert_int_equal(api_route_parse("/trials/17/samples.csv", &id, why, sizeof why), API_ROUTE_SAMPLES_CSV);
    assert_int_equal(id, 17);
    assert_int_equal(api_route_parse("/trials/0/samples.csv", &id, why, sizeof why), API_ROUTE_BAD_ID);
    assert_int_equal(api_route_parse("/trials/x/samples.csv", &id, why, sizeof why), API_ROUTE_BAD_ID);
    assert_int_equal(api_route_parse("/phase.png", &id, why, sizeof why), API_ROUTE_PHASE);
    /* The campaign's paths go to one op, which sorts them (daemon/campaign/campaign_routes.c). */
    assert_int_equal(api_route_parse("/specimens", &id, why, sizeof why), API_ROUTE_CAMPAIGN);
    assert_int_equal(api_route_parse("/specimens/S-12/retire", &id, why, sizeof why), API_ROUTE_CAMPAIGN);
    assert_int_equal(api_route_parse("/queue", &id, why, sizeof why), API_ROUTE_CAMPAIGN);
    assert_int_equal(api_route_parse("/queue/3/confirm", &id, why, sizeof why), API_ROUTE_CAMPAIGN);
    assert_int_equal(api_route_parse("/queues", &id, why, sizeof why), API_ROUTE_NONE);
    assert_int_equal(api_route_parse("/specimensX", &id, why, sizeof why), API_ROUTE_NONE);
    assert_true(api_route_method_ok(API_ROUTE_CAMPAIGN, "POST") && api_route_method_ok(API_ROUTE_CAMPAIGN, "GET"));
    assert_false(api_route_method_ok(API_ROUTE_CAMPAIGN, "DELETE"));
    assert_string_equal(api_route_allow(API_ROUTE_SAMPLES_CSV), "GET");
    assert_string_equal(api_route_allow(API_ROUTE_PHASE), "GET");
    assert_false(api_route_method_ok(API_ROUTE_SAMPLES_CSV, "POST"));
    assert_int_equal(api_route_parse("/live/events", &id, why, sizeof why), API_ROUTE_EVENTS);
    assert_int_equal(api_route_parse("/live/camera.jpg", &id, why, sizeof why), API_ROUTE_CAMERA);
    assert_int_equal(api_route_parse("/live/prediction", &id, why, sizeof why), API_ROUTE_PREDICTION);
    const char *none[] = {"/", "/statu", "/status/", "/trials/1/report.jpg", "/trials/1/report.png/x",
                          "/trials/1/samples.csv/x", "/trials/1/samples", "/phase.png/", "/phase",
                          "/trialsx", "/trials/current/abort/", "/live", "/live/events/"};
    for (size_t i = 0; i < sizeof none / sizeof none[0]; i++)
        assert_int_equal(api_route_parse(none[i], &id, why, sizeof why), API_ROUTE_NONE);
    assert_string_equal(api_route_allow(API_ROUTE_TRIALS), "GET, POST");
    assert_true(api_route_method_ok(API_ROUTE_TRIALS, "POST"));
    assert_false(api_route_method_ok(API_ROUTE_STATUS, "POST"));
    assert_false(api_route_method_ok(API_ROUTE_ABORT, "GET"));
}

static void test_status(void **state)
{
    fixture *f = *state;
    char why[512];
    json_t *j = NULL;
    assert_int_equal(req(f, "GET", "/status", NULL, &j, why, sizeof why), 200);
    assert_string_equal(json_string_value(json_object_get(j, "state")), "idle");
    json_decref(j);
}

static void test_start_list_show(void **state)
{
    fixture *f = *state;
    char why[512];
    json_t *j = NULL;
    json_t *body = json_pack("{s:s, s:[s], s:s}", "scene", "paper-gamma013.ini", "set", "protocol.compression=0.4",
                             "note", "first \xce\x94W run");
    assert_int_equal(req(f, "POST", "/trials", body, &j, why, sizeof why), 201);
    json_decref(body);
    assert_int_equal(json_integer_value(json_object_get(j, "id")), 1);
    assert_string_equal(json_string_value(json_object_get(j, "status")), "running");
    assert_string_equal(json_string_value(json_object_get(j, "note")), "first \xce\x94W run");
    json_decref(j);

    assert_int_equal(req(f, "GET", "/status", NULL, &j, why, sizeof why), 200);
    assert_string_equal(json_string_value(json_object_get(j, "state")), "running");
    json_decref(j);

    assert_int_equal(req(f, "GET", "/trials", NULL, &j, why, sizeof why), 200);
    assert_true(json_is_array(j));
    assert_int_equal(json_array_size(j), 1);
    json_decref(j);

    assert_int_equal(req(f, "GET", "/trials/1", NULL, &j, why, sizeof why), 200);
    assert_string_equal(json_string_value(json_object_get(j, "scene")), "paper-gamma013.ini");
    json_decref(j);
}

static void test_start_empty_body(void **state)
{
    fixture *f = *state;
    char why[512];
    json_t *j = NULL;
    /* No body at all: the op gets {}. */
    assert_int_equal(req(f, "POST", "/trials", NULL, &j, why, sizeof why), 201);
    assert_string_equal(json_string_value(json_object_get(j, "scene")), "default");
    json_decref(j);
}

static void test_start_while_running_is_409(void **state)
{
    fixture *f = *state;
    char why[512];
    assert_int_equal(req(f, "POST", "/trials", NULL, NULL, why, sizeof why), 201);
    assert_int_equal(req(f, "POST", "/trials", NULL, NULL, why, sizeof why), 409);
    assert_non_null(strstr(why, "trial 1 is running"));
    assert_int_equal(f->m.count, 1);
}

static void test_start_bad_field_is_400(void **state)
{
    fixture *f = *state;
    char why[512];
    json_t *body = json_pack("{s:i}", "scene", 3);
    assert_int_equal(req(f, "POST", "/trials", body, NULL, why, sizeof why), 400);
    json_decref(body);
    assert_non_null(strstr(why, "'scene'"));
    /* A body that is JSON but not an object is the server's 400. */
    body = json_pack("[i]", 1);
    assert_int_equal(req(f, "POST", "/trials", body, NULL, why, sizeof why), 400);
    json_decref(body);
    assert_non_null(strstr(why, "must be a JSON object, got an array"));
}

static void test_abort(void **state)
{
    fixture *f = *state;
    char why[512];
    json_t *j = NULL;
    assert_int_equal(req(f, "POST", "/trials/current/abort", NULL, NULL, why, sizeof why), 409);
    assert_string_equal(why, "no trial is running");
    assert_int_equal(req(f, "POST", "/trials", NULL, NULL, why, sizeof why), 201);
    assert_int_equal(req(f, "POST", "/trials/current/abort", NULL, &j, why, sizeof why), 200);
    assert_string_equal(json_string_value(json_object_get(j, "status")), "aborted");
    json_decref(j);
    assert_int_equal(req(f, "POST", "/trials/current/abort", NULL, NULL, why, sizeof why), 409);
    /* Idle again: a new trial may start. */
    assert_int_equal(req(f, "POST", "/trials", NULL, &j, why, sizeof why), 201);
    assert_int_equal(json_integer_value(json_object_get(j, "id")), 2);
    json_decref(j);
}

static void test_unknown_trial_and_path_are_404(void **state)
{
    fixture *f = *state;
    char why[512];
    assert_int_equal(req(f, "GET", "/trials/7", NULL, NULL, why, sizeof why), 404);
    assert_string_equal(why, "no trial 7");
    assert_int_equal(req(f, "GET", "/trials/7/report.png", NULL, NULL, why, sizeof why), 404);
    assert_int_equal(req(f, "GET", "/nope", NULL, NULL, why, sizeof why), 404);
    assert_non_null(strstr(why, "no such path: /nope"));
    assert_int_equal(req(f, "GET", "/trials/1/video", NULL, NULL, why, sizeof why), 404);
    assert_int_equal(req(f, "GET", "/", NULL, NULL, why, sizeof why), 404);
}

static void test_bad_id_is_400(void **state)
{
    fixture *f = *state;
    char why[512];
    const char *paths[] = {"/trials/abc", "/trials/0", "/trials/-3", "/trials/99999999999999999999",
                           "/trials/x/report.png", "/trials/current"};
    for (size_t i = 0; i < sizeof paths / sizeof paths[0]; i++)
        assert_int_equal(req(f, "GET", paths[i], NULL, NULL, why, sizeof why), 400);
    assert_int_equal(req(f, "GET", "/trials/abc", NULL, NULL, why, sizeof why), 400);
    assert_non_null(strstr(why, "'abc' is not a positive integer"));
    assert_int_equal(f->m.ops_called, 0);
}

static void test_wrong_method_is_405(void **state)
{
    fixture *f = *state;
    char why[512];
    assert_int_equal(req(f, "DELETE", "/trials", NULL, NULL, why, sizeof why), 405);
    assert_non_null(strstr(why, "allowed: GET, POST"));
    assert_int_equal(req(f, "POST", "/status", NULL, NULL, why, sizeof why), 405);
    assert_int_equal(req(f, "GET", "/trials/current/abort", NULL, NULL, why, sizeof why), 405);
    assert_int_equal(req(f, "PUT", "/trials/1", NULL, NULL, why, sizeof why), 405);
    assert_int_equal(f->m.ops_called, 0);

    /* The Allow header, read off the wire. */
    char reply[4096];
    const char *parts[] = {"DELETE /trials HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n"};
    raw_exchange(api_server_port(f->srv), parts, NULL, 1, 0, reply, sizeof reply);
    assert_int_equal(raw_status(reply), 405);
    assert_non_null(strstr(reply, "\r\nAllow: GET, POST\r\n"));
    assert_non_null(strstr(reply, "\r\nContent-Type: application/json\r\n"));
}

static void test_malformed_json_is_400(void **state)
{
    fixture *f = *state;
    char reply[4096];
    const char *body = "{\"scene\": \"a\",\n \"note\": }";
    char head[256];
    snprintf(head, sizeof head,
             "POST /trials HTTP/1.1\r\nHost: t\r\nContent-Type: application/json\r\nContent-Length: %zu\r\n"
             "Connection: close\r\n\r\n",
             strlen(body));
    const char *parts[] = {head, body};
    raw_exchange(api_server_port(f->srv), parts, NULL, 2, 0, reply, sizeof reply);
    assert_int_equal(raw_status(reply), 400);
    json_error_t err;
    json_t *j = json_loads(raw_body(reply), 0, &err);
    assert_non_null(j);
    const char *msg = json_string_value(json_object_get(j, "error"));
    assert_non_null(msg);
    assert_non_null(strstr(msg, "malformed JSON body at line 2, column"));
    assert_int_equal(json_integer_value(json_object_get(j, "status")), 400);
    json_decref(j);
    assert_int_equal(f->m.count, 0);
}

static void test_oversized_body_is_413(void **state)
{
    fixture *f = *state;
    char why[512];
    /* Through the client: Content-Length is over the limit, refused before the upload. */
    size_t big = 70 * 1024;
    char *note = malloc(big + 1);
    assert_non_null(note);
    memset(note, 'x', big);
    note[big] = '\0';
    json_t *body = json_pack("{s:s}", "note", note);
    free(note);
    assert_int_equal(req(f, "POST", "/trials", body, NULL, why, sizeof why), 413);
    json_decref(body);
    assert_non_null(strstr(why, "larger than the limit of 65536 bytes"));

    /* Chunked upload (no Content-Length): drained, then 413. */
    enum { CHUNK = 16 * 1024, NCHUNK = 6 };
    static char chunk[CHUNK + 32];
    int hl = snprintf(chunk, sizeof chunk, "%x\r\n", CHUNK);
    memset(chunk + hl, ' ', CHUNK);
    memcpy(chunk + hl + CHUNK, "\r\n", 2);
    const char *parts[NCHUNK + 2];
    size_t lens[NCHUNK + 2];
    parts[0] = "POST /trials HTTP/1.1\r\nHost: t\r\nTransfer-Encoding: chunked\r\nConnection: close\r\n\r\n";
    lens[0] = strlen(parts[0]);
    for (int i = 0; i < NCHUNK; i++) {
        parts[1 + i] = chunk;
        lens[1 + i] = (size_t)hl + CHUNK + 2;
    }
    parts[NCHUNK + 1] = "0\r\n\r\n";
    lens[NCHUNK + 1] = 5;
    char reply[4096];
    raw_exchange(api_server_port(f->srv), parts, lens, NCHUNK + 2, 0, reply, sizeof reply);
    assert_int_equal(raw_status(reply), 413);

    /* Content-Length over the limit with the body sent at once (no Expect): the reply still
     * arrives whole. */
    static char whole[80 * 1024];
    int wl = snprintf(whole, sizeof whole,
                      "POST /trials HTTP/1.1\r\nHost: t\r\nContent-Length: %d\r\nConnection: close\r\n\r\n",
                      70 * 1024);
    memset(whole + wl, ' ', 70 * 1024);
    const char *one[] = {whole};
    size_t one_len[] = {(size_t)wl + 70 * 1024};
    raw_exchange(api_server_port(f->srv), one, one_len, 1, 0, reply, sizeof reply);
    assert_int_equal(raw_status(reply), 413);
    assert_non_null(strstr(raw_body(reply), "\"status\":413"));
    assert_int_equal(f->m.count, 0);
}

static void test_token_required(void **state)
{
    fixture *f = *state;
    char why[512];
    json_t *j = NULL;
    api_client_config good = f->cc;
    f->cc.token = NULL;
    assert_int_equal(req(f, "GET", "/status", NULL, NULL, why, sizeof why), 401);
    assert_non_null(strstr(why, "requires a token"));
    /* Even an unknown path says 401 first: nothing is revealed without the token. */
    assert_int_equal(req(f, "GET", "/nope", NULL, NULL, why, sizeof why), 401);
    f->cc.token = "s3cret-tokeN";
    assert_int_equal(req(f, "POST", "/trials", NULL, NULL, why, sizeof why), 401);
    assert_string_equal(why, "wrong token");
    json_t *body = json_pack("{s:s}", "note", "refused before the op sees it");
    assert_int_equal(req(f, "POST", "/trials", body, NULL, why, sizeof why), 401);
    json_decref(body);
    f->cc.token = "s3cret-token-and-more";
    assert_int_equal(req(f, "GET", "/status", NULL, NULL, why, sizeof why), 401);
    assert_int_equal(f->m.ops_called, 0);
    f->cc = good;
    assert_int_equal(req(f, "GET", "/status", NULL, &j, why, sizeof why), 200);
    json_decref(j);
    assert_int_equal(req(f, "POST", "/trials", NULL, NULL, why, sizeof why), 201);

    /* A wrong scheme, and the WWW-Authenticate header, off the wire. */
    char reply[4096];
    const char *parts[] = {"GET /status HTTP/1.1\r\nHost: t\r\nAuthorization: Basic czNjcmV0\r\n"
                           "Connection: close\r\n\r\n"};
    raw_exchange(api_server_port(f->srv), parts, NULL, 1, 0, reply, sizeof reply);
    assert_int_equal(raw_status(reply), 401);
    assert_non_null(strstr(reply, "\r\nWWW-Authenticate: Bearer"));
}

static void test_listen_beyond_loopback_needs_token(void **state)
{
    (void)state;
    fake_model m = {.running = -1};
    pthread_mutex_init(&m.lock, NULL);
    api_server_config cfg = api_server_config_default();
    cfg.port = 0;
    cfg.listen = "0.0.0.0";
    api_server *s = NULL;
    char why[512] = "";
    assert_int_equal(api_server_start(&cfg, &fake_ops, &m, &s, why, sizeof why), -1);
    assert_null(s);
    assert_non_null(strstr(why, "without a token"));
    cfg.token = "";
    assert_int_equal(api_server_start(&cfg, &fake_ops, &m, &s, why, sizeof why), -1);

    cfg.token = TOKEN;
    if (api_server_start(&cfg, &fake_ops, &m, &s, why, sizeof why) != 0)
        fail_msg("0.0.0.0 with a token: %s", why);
    assert_true(api_server_port(s) > 0);
    api_server_stop(s);

    /* Bad addresses and bad settings are refused with the reason. */
    cfg.listen = "ribbon.example.org";
    assert_int_equal(api_server_start(&cfg, &fake_ops, &m, &s, why, sizeof why), -1);
    assert_non_null(strstr(why, "not a numeric"));
    cfg.listen = "127.0.0.1";
    cfg.token = "has space";
    assert_int_equal(api_server_start(&cfg, &fake_ops, &m, &s, why, sizeof why), -1);
    assert_non_null(strstr(why, "token"));
    cfg.token = NULL;
    cfg.max_body_bytes = 10;
    assert_int_equal(api_server_start(&cfg, &fake_ops, &m, &s, why, sizeof why), -1);
    assert_non_null(strstr(why, "max_body_bytes"));
    pthread_mutex_destroy(&m.lock);
}

static void test_port_in_use_names_reason(void **state)
{
    fixture *f = *state;
    api_server_config cfg = api_server_config_default();
    cfg.port = api_server_port(f->srv);
    api_server *s = NULL;
    char why[512] = "";
    assert_int_equal(api_server_start(&cfg, &fake_ops, &f->m, &s, why, sizeof why), -1);
    assert_null(s);
    assert_non_null(strstr(why, "cannot serve the API on 127.0.0.1 port"));
}

static void test_ipv6_loopback(void **state)
{
    (void)state;
    fake_model m = {.running = -1};
    pthread_mutex_init(&m.lock, NULL);
    api_server_config cfg = api_server_config_default();
    cfg.port = 0;
    cfg.listen = "::1";
    api_server *s = NULL;
    char why[512] = "";
    if (api_server_start(&cfg, &fake_ops, &m, &s, why, sizeof why) != 0) {
        pthread_mutex_destroy(&m.lock);
        print_message("no IPv6 loopback here (%s); skipped\n", why);
        skip();
    }
    char url[64];
    snprintf(url, sizeof url, "http://[::1]:%u", api_server_port(s));
    api_client_config cc = api_client_config_default();
    cc.base_url = url;
    int status = 0;
    json_t *j = NULL;
    int rc = api_client_request(&cc, "GET", "/status", NULL, &status, &j, NULL, NULL, why, sizeof why);
    api_server_stop(s);
    pthread_mutex_destroy(&m.lock);
    if (rc != 0)
        fail_msg("GET over ::1: %s", why);
    assert_int_equal(status, 200);
    json_decref(j);
}

static void test_report_png_bytes(void **state)
{
    fixture *f = *state;
    char why[512];
    assert_int_equal(req(f, "POST", "/trials", NULL, NULL, why, sizeof why), 201);

    int status = 0;
    json_t *j = NULL;
    unsigned char *png = NULL;
    size_t len = 0;
    int rc = api_client_request(&f->cc, "GET", "/trials/1/report.png", NULL, &status, &j, &png, &len, why, sizeof why);
    if (rc != 0)
        fail_msg("report.png: %s", why);
    assert_int_equal(status, 200);
    assert_null(j);
    assert_non_null(png);
    assert_int_equal(len, FAKE_PNG_LEN);
    for (size_t i = 0; i < len; i++)
        if (png[i] != fake_png_byte(i))
            fail_msg("byte %zu differs: %02x != %02x", i, png[i], fake_png_byte(i));
    free(png);

    /* The error of the same route is JSON, in why and in json_out. */
    rc = api_client_request(&f->cc, "GET", "/trials/2/report.png", NULL, &status, &j, &png, &len, why, sizeof why);
    assert_int_equal(rc, 0);
    assert_int_equal(status, 404);
    assert_null(png);
    assert_string_equal(why, "no trial 2");
    assert_non_null(j);
    json_decref(j);

    /* Content type and bytes off the wire. */
    size_t cap = FAKE_PNG_LEN + 4096;
    char *reply = malloc(cap);
    assert_non_null(reply);
    const char *parts[] = {"GET /trials/1/report.png HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n"};
    size_t got = raw_exchange(api_server_port(f->srv), parts, NULL, 1, 0, reply, cap);
    assert_int_equal(raw_status(reply), 200);
    assert_non_null(strstr(reply, "\r\nContent-Type: image/png\r\n"));
    const char *body = raw_body(reply);
    assert_int_equal(got - (size_t)(body - reply), FAKE_PNG_LEN);
    for (size_t i = 0; i < FAKE_PNG_LEN; i++)
        assert_int_equal((unsigned char)body[i], fake_png_byte(i));
    free(reply);

    /* A caller that expects JSON only is told the reply is not JSON. */
    rc = api_client_request(&f->cc, "GET", "/trials/1/report.png", NULL, &status, &j, NULL, NULL, why, sizeof why);
    assert_int_equal(rc, -1);
    assert_null(j);
    assert_non_null(strstr(why, "is not JSON (content type image/png)"));
}

/* GET /trials/{id}/samples.csv: the op's text as text/csv with its file name, byte for byte; an
 * unknown trial 404 (JSON), a bad id 400 before any op, POST 405. GET /phase.png: the op's PNG
 * with the map's state as X-Phase-Map (control bytes sent as '?'). */
static void test_samples_csv_and_phase_png(void **state)
{
    fixture *f = *state;
    char why[512];
    assert_int_equal(req(f, "POST", "/trials", NULL, NULL, why, sizeof why), 201);
    int calls = f->m.ops_called;
    assert_int_equal(req(f, "GET", "/trials/2/samples.csv", NULL, NULL, why, sizeof why), 404);
    assert_string_equal(why, "trial 2 does not exist");
    assert_int_equal(req(f, "GET", "/trials/0/samples.csv", NULL, NULL, why, sizeof why), 400);
    assert_int_equal(req(f, "POST", "/trials/1/samples.csv", NULL, NULL, why, sizeof why), 405);
    assert_int_equal(f->m.ops_called, calls + 1); /* only the 404 reached the op */

    char reply[4096];
    const char *parts[] = {"GET /trials/1/samples.csv HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n"};
    raw_exchange(api_server_port(f->srv), parts, NULL, 1, 0, reply, sizeof reply);
    assert_int_equal(raw_status(reply), 200);
    assert_non_null(strstr(reply, "\r\nContent-Type: text/csv; charset=utf-8\r\n"));
    assert_non_null(strstr(reply, "\r\nContent-Disposition: attachment; filename=\"trial-1-samples.csv\"\r\n"));
    assert_string_equal(raw_body(reply), "seq,t_s,reason\n1,0.5,\"low, \"\"quality\"\"\"\n");

    size_t cap = FAKE_PNG_LEN + 4096;
    char *big = malloc(cap);
    assert_non_null(big);
    const char *phase[] = {"GET /phase.png HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n"};
    size_t got = raw_exchange(api_server_port(f->srv), phase, NULL, 1, 0, big, cap);
    assert_int_equal(raw_status(big), 200);
    assert_non_null(strstr(big, "\r\nContent-Type: image/png\r\n"));
    assert_non_null(strstr(big, "\r\nX-Phase-Map: computing 3/30?\r\n"));
    assert_int_equal(got - (size_t)(raw_body(big) - big), FAKE_PNG_LEN);
    free(big);
}

static void test_client_when_nothing_listens(void **state)
{
    (void)state;
    /* A port that was free a moment ago: bind, read the port, close. */
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct sockaddr_in a = {.sin_family = AF_INET};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t al = sizeof a;
    assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof a), 0);
    assert_int_equal(getsockname(fd, (struct sockaddr *)&a, &al), 0);
    close(fd);
    char url[64];
    snprintf(url, sizeof url, "http://127.0.0.1:%u", ntohs(a.sin_port));
    api_client_config cc = api_client_config_default();
    cc.base_url = url;
    cc.timeout_s = 5;
    int status = -1;
    json_t *j = NULL;
    char why[512] = "";
    assert_int_equal(api_client_request(&cc, "GET", "/status", NULL, &status, &j, NULL, NULL, why, sizeof why), -1);
    assert_null(j);
    assert_int_equal(status, 0);
    char want[256];
    snprintf(want, sizeof want, "cannot reach ribbond at %s: connection refused; is it running? (ribbond --config FILE)",
             url);
    assert_string_equal(why, want);

    /* Bad client settings are refused before any network traffic. */
    cc.base_url = "ftp://127.0.0.1";
    assert_int_equal(api_client_request(&cc, "GET", "/status", NULL, &status, &j, NULL, NULL, why, sizeof why), -1);
    assert_non_null(strstr(why, "http://"));
}

static void test_partial_writes(void **state)
{
    fixture *f = *state;
    unsigned port = api_server_port(f->srv);
    char reply[4096];
    /* A GET whose request line and headers arrive in pieces. */
    const char *get[] = {"GET /sta", "tus HTTP/1.1\r\nHo", "st: t\r\nConnec", "tion: close\r\n", "\r\n"};
    raw_exchange(port, get, NULL, 5, 30, reply, sizeof reply);
    assert_int_equal(raw_status(reply), 200);
    assert_non_null(strstr(raw_body(reply), "\"state\":\"idle\""));

    /* A POST whose body arrives in three writes, one splitting a UTF-8 character. */
    const char *body = "{\"scene\": \"paper.ini\", \"note\": \"split \xce\x94W body\"}";
    size_t blen = strlen(body);
    char head[256];
    snprintf(head, sizeof head,
             "POST /trials HTTP/1.1\r\nHost: t\r\nContent-Type: application/json\r\nContent-Length: %zu\r\n"
             "Connection: close\r\n\r\n",
             blen);
    const char *post[] = {head, body, body + 10, body + 40};
    size_t lens[] = {strlen(head), 10, 30, blen - 40};
    raw_exchange(port, post, lens, 4, 30, reply, sizeof reply);
    assert_int_equal(raw_status(reply), 201);
    json_error_t err;
    json_t *j = json_loads(raw_body(reply), 0, &err);
    assert_non_null(j);
    assert_string_equal(json_string_value(json_object_get(j, "note")), "split \xce\x94W body");
    json_decref(j);
}

/* ---------------------------------------------------------------- op contract */

static int broken_status(void *user, json_t **out, char *why, size_t why_len)
{
    (void)user;
    (void)out;
    (void)why;
    (void)why_len;
    return 0; /* success without a reply: a bug in the op */
}

static int failing_list(void *user, json_t **out, char *why, size_t why_len)
{
    (void)user;
    (void)out;
    snprintf(why, why_len, "store is locked");
    return -1;
}

static int setup_partial_ops(void **state)
{
    static const api_ops ops = {.status = broken_status, .list = failing_list};
    return fixture_up(state, NULL, &ops);
}

static void test_op_contract(void **state)
{
    fixture *f = *state;
    char why[512];
    assert_int_equal(req(f, "GET", "/status", NULL, NULL, why, sizeof why), 500);
    assert_non_null(strstr(why, "ops->status succeeded without a reply"));
    assert_int_equal(req(f, "GET", "/trials", NULL, NULL, why, sizeof why), 500);
    assert_string_equal(why, "store is locked");
    assert_int_equal(req(f, "POST", "/trials", NULL, NULL, why, sizeof why), 501);
    assert_int_equal(req(f, "GET", "/trials/1/report.png", NULL, NULL, why, sizeof why), 501);
    assert_int_equal(req(f, "GET", "/trials/1/samples.csv", NULL, NULL, why, sizeof why), 501);
    assert_int_equal(req(f, "GET", "/phase.png", NULL, NULL, why, sizeof why), 501);
}

static int group_setup(void **state)
{
    (void)state;
    char why[256];
    if (api_client_global_init(why, sizeof why) != 0) {
        fprintf(stderr, "%s\n", why);
        return -1;
    }
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    api_client_global_cleanup();
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_route_table),
        cmocka_unit_test_setup_teardown(test_status, setup, teardown),
        cmocka_unit_test_setup_teardown(test_start_list_show, setup, teardown),
        cmocka_unit_test_setup_teardown(test_start_empty_body, setup, teardown),
        cmocka_unit_test_setup_teardown(test_start_while_running_is_409, setup, teardown),
        cmocka_unit_test_setup_teardown(test_start_bad_field_is_400, setup, teardown),
        cmocka_unit_test_setup_teardown(test_abort, setup, teardown),
        cmocka_unit_test_setup_teardown(test_unknown_trial_and_path_are_404, setup, teardown),
        cmocka_unit_test_setup_teardown(test_bad_id_is_400, setup, teardown),
        cmocka_unit_test_setup_teardown(test_wrong_method_is_405, setup, teardown),
        cmocka_unit_test_setup_teardown(test_malformed_json_is_400, setup, teardown),
        cmocka_unit_test_setup_teardown(test_oversized_body_is_413, setup, teardown),
        cmocka_unit_test_setup_teardown(test_token_required, setup_token, teardown),
        cmocka_unit_test(test_listen_beyond_loopback_needs_token),
        cmocka_unit_test_setup_teardown(test_port_in_use_names_reason, setup, teardown),
        cmocka_unit_test(test_ipv6_loopback),
        cmocka_unit_test_setup_teardown(test_report_png_bytes, setup, teardown),
        cmocka_unit_test_setup_teardown(test_samples_csv_and_phase_png, setup, teardown),
        cmocka_unit_test(test_client_when_nothing_listens),
        cmocka_unit_test_setup_teardown(test_partial_writes, setup, teardown),
        cmocka_unit_test_setup_teardown(test_op_contract, setup_partial_ops, teardown),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
