/* test_api_connections.c: the API under hostile connections (issue 17, defects 1, 10 and 12): slow
 * and silent sockets by the thousand, bodies that never come, oversized request lines and heads,
 * percent-escaped NULs in paths, and the stream pool's budget; issue 33, items 6-8: heads of
 * blank lines only, the body deadline answered 408 when nothing more arrives, two conflicting
 * Content-Length headers. A server on 127.0.0.1 port 0 with small fake ops; every exchange is a
 * raw socket with a receive timeout, so nothing here can hang. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "api_head.h"   /* the room's own token comparison, tested here */
#include "api_server.h"

#include <arpa/inet.h>
#include <errno.h>
#include <jansson.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#define TOKEN "s3cret-token"

typedef struct fake {
    atomic_int aborts, starts;
} fake;

static int f_status(void *user, json_t **out, char *why, size_t why_len)
{
    (void)user, (void)why, (void)why_len;
    *out = json_pack("{s:s}", "state", "running");
    return 0;
}

static int f_start(void *user, const json_t *body, json_t **out, int *st, char *why, size_t why_len)
{
    (void)body, (void)st, (void)why, (void)why_len;
    atomic_fetch_add(&((fake *)user)->starts, 1);
    *out = json_pack("{s:i}", "id", 1);
    return 0;
}

static int f_abort(void *user, json_t **out, int *st, char *why, size_t why_len)
{
    (void)st, (void)why, (void)why_len;
    atomic_fetch_add(&((fake *)user)->aborts, 1);
    *out = json_pack("{s:s}", "abort", "requested");
    return 0;
}

/* A stream that sends one message every 50 ms for ever. */
static long beat_read(void *ctx, char *buf, size_t max)
{
    (void)ctx;
    struct timespec ts = {0, 50 * 1000000L};
    nanosleep(&ts, NULL);
    return snprintf(buf, max, "data: {\"type\":\"beat\"}\n\n");
}

static int f_events(void *user, api_stream *out, char *why, size_t why_len)
{
    (void)user, (void)why, (void)why_len;
    out->read = beat_read;
    out->close = NULL;
    out->ctx = NULL;
    return 0;
}

static int f_list(void *user, json_t **out, char *why, size_t why_len)
{
    (void)user, (void)why, (void)why_len;
    *out = json_array();
    return 0;
}

static const api_ops ops = {
    .status = f_status, .start = f_start, .abort_current = f_abort, .events = f_events, .list = f_list};

typedef struct fixture {
    fake m;
    api_server *srv;
    unsigned port;
    const char *token;
} fixture;

static int up_with(void **state, const char *token, unsigned max_streams, unsigned header_timeout_ms,
                   unsigned body_timeout_ms)
{
    fixture *f = calloc(1, sizeof *f);
    api_server_config cfg = api_server_config_default();
    cfg.port = 0;
    cfg.token = token;
    cfg.max_streams = max_streams;
    if (header_timeout_ms) cfg.header_timeout_ms = header_timeout_ms;
    if (body_timeout_ms) cfg.body_timeout_ms = body_timeout_ms;
    char why[512] = "";
    if (api_server_start(&cfg, &ops, &f->m, &f->srv, why, sizeof why) != 0) fail_msg("start: %s", why);
    f->port = api_server_port(f->srv);
    f->token = token;
    *state = f;
    return 0;
}
static int up(void **state, const char *token, unsigned max_streams)
{
    return up_with(state, token, max_streams, 0, 0);
}
static int setup(void **state) { return up(state, NULL, 32); }
/* Short deadlines, so that the tests of what happens at them wait about a second. */
static int setup_short_deadlines(void **state) { return up_with(state, NULL, 32, 1000, 1000); }
static int setup_token(void **state) { return up(state, TOKEN, 32); }
static int setup_streams4(void **state) { return up(state, NULL, 4); }
static int teardown(void **state)
{
    fixture *f = *state;
    api_server_stop(f->srv);
    free(f);
    return 0;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int dial(unsigned port)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct timeval tv = {.tv_sec = 5};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, (struct sockaddr *)&a, sizeof a) != 0) {
        close(fd);
        return -1;
    }
    return fd;
}

static void send_all(int fd, const char *p, size_t len)
{
    size_t off = 0;
    while (off < len) {
        ssize_t w = send(fd, p + off, len - off, MSG_NOSIGNAL);
        if (w <= 0) return; /* the server may answer and close before all is sent */
        off += (size_t)w;
    }
}

/* Read until the server closes (or cap, or the 5 s timeout). */
static size_t read_reply(int fd, char *buf, size_t cap)
{
    size_t got = 0;
    while (got + 1 < cap) {
        ssize_t r = recv(fd, buf + got, cap - 1 - got, 0);
        if (r <= 0) break;
        got += (size_t)r;
    }
    buf[got] = '\0';
    return got;
}

/* One request on a fresh socket; the reply's status, body in *body (points into buf). */
static int exchange(unsigned port, const char *request, size_t len, char *buf, size_t cap, const char **body)
{
    int fd = dial(port);
    assert_true(fd >= 0);
    send_all(fd, request, len);
    read_reply(fd, buf, cap);
    close(fd);
    int status = 0;
    if (sscanf(buf, "HTTP/1.%*d %d", &status) != 1) return -1;
    const char *b = strstr(buf, "\r\n\r\n");
    *body = b ? b + 4 : "";
    return status;
}

/* The reply is the API's JSON error object with that status. */
static void assert_json_error(const char *reply, const char *body, int status)
{
    assert_non_null(strstr(reply, "Content-Type: application/json"));
    json_error_t e;
    json_t *j = json_loads(body, 0, &e);
    if (!j) fail_msg("not JSON: %.200s", body);
    assert_true(json_is_string(json_object_get(j, "error")));
    assert_int_equal(json_integer_value(json_object_get(j, "status")), status);
    json_decref(j);
}

static int simple(const fixture *f, const char *method, const char *path, double *secs)
{
    char rq[512], buf[4096];
    int n = snprintf(rq, sizeof rq, "%s %s HTTP/1.1\r\nHost: x\r\n%s%s%sConnection: close\r\n\r\n", method, path,
                     f->token ? "Authorization: Bearer " : "", f->token ? f->token : "", f->token ? "\r\n" : "");
    const char *body;
    double t0 = now_s();
    int st = exchange(f->port, rq, (size_t)n, buf, sizeof buf, &body);
    if (secs) *secs = now_s() - t0;
    return st;
}

/* ---------------------------------------------------------------- defect 10: %00 */

static void test_percent_nul_is_400(void **state)
{
    fixture *f = *state;
    const char *paths[][2] = {{"GET", "/trials/1%00/report.png"}, {"GET", "/status%00garbage"},
                              {"GET", "/trials%00/1"},           {"POST", "/trials/current/abort%00zz"},
                              {"GET", "/status%2Fx"},             {"GET", "/st%61tus"}};
    for (size_t i = 0; i < sizeof paths / sizeof paths[0]; i++) {
        char rq[256], buf[4096];
        int n = snprintf(rq, sizeof rq, "%s %s HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n", paths[i][0],
                         paths[i][1]);
        const char *body;
        int st = exchange(f->port, rq, (size_t)n, buf, sizeof buf, &body);
        if (st != 400) fail_msg("%s %s answered %d, expected 400", paths[i][0], paths[i][1], st);
        assert_json_error(buf, body, 400);
        assert_non_null(strstr(body, "outside the API's path grammar"));
    }
    assert_int_equal(atomic_load(&f->m.aborts), 0);
}

/* ---------------------------------------------------------------- item 12: 414 / 431 as JSON */

static void test_oversized_line_and_head_are_json(void **state)
{
    fixture *f = *state;
    size_t big = 40000;
    char *rq = malloc(big + 256), *buf = malloc(8192);
    const char *body;
    /* A request line (URL) of 40 000 bytes. */
    int n = sprintf(rq, "GET /");
    memset(rq + n, 'a', big);
    n += (int)big;
    n += sprintf(rq + n, " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
    int st = exchange(f->port, rq, (size_t)n, buf, 8192, &body);
    assert_int_equal(st, 414);
    assert_json_error(buf, body, 414);
    /* A header of 40 000 bytes. */
    n = sprintf(rq, "GET /status HTTP/1.1\r\nHost: x\r\nX-Big: ");
    memset(rq + n, 'b', big);
    n += (int)big;
    n += sprintf(rq + n, "\r\nConnection: close\r\n\r\n");
    st = exchange(f->port, rq, (size_t)n, buf, 8192, &body);
    assert_int_equal(st, 431);
    assert_json_error(buf, body, 431);
    free(rq);
    free(buf);
}

/* ---------------------------------------------------------------- defect 1: slow sockets */

#define SLOW 1000

/* SLOW sockets that each sent the start of a request and never finish it (one more header line
 * each second while the test runs): abort and /status still answer within 1 s. */
static void slow_headers_case(fixture *f)
{
    struct rlimit rl;
    getrlimit(RLIMIT_NOFILE, &rl);
    if (rl.rlim_cur < SLOW + 200) {
        rlim_t want = SLOW + 200;
        if (rl.rlim_max != RLIM_INFINITY && rl.rlim_max < want) skip(); /* cannot open that many here */
        rl.rlim_cur = want;
        assert_int_equal(setrlimit(RLIMIT_NOFILE, &rl), 0);
    }
    int *fds = malloc(SLOW * sizeof *fds);
    int opened = 0;
    for (int i = 0; i < SLOW; i++) {
        fds[i] = dial(f->port);
        if (fds[i] < 0) continue;
        opened++;
        static const char part[] = "GET /status HTTP/1.1\r\nHost: x\r\n";
        send_all(fds[i], part, sizeof part - 1);
    }
    assert_int_equal(opened, SLOW);
    double worst = 0;
    for (int round = 0; round < 3; round++) {
        for (int i = 0; i < SLOW; i++) send_all(fds[i], "X-Slow: 1\r\n", 11); /* keep them "alive" */
        double t_abort = 0, t_status = 0;
        int a = simple(f, "POST", "/trials/current/abort", &t_abort);
        int s = simple(f, "GET", "/status", &t_status);
        assert_int_equal(a, 200);
        assert_int_equal(s, 200);
        if (t_abort > worst) worst = t_abort;
        if (t_status > worst) worst = t_status;
        struct timespec ts = {0, 300 * 1000000L};
        nanosleep(&ts, NULL);
    }
    printf("# %d slow sockets: slowest abort or status answer %.3f s\n", SLOW, worst);
    assert_true(worst < 1.0);
    assert_int_equal(atomic_load(&f->m.aborts), 3);
    for (int i = 0; i < SLOW; i++)
        if (fds[i] >= 0) close(fds[i]);
    free(fds);
}

static void test_slow_headers_do_not_lock_out(void **state) { slow_headers_case(*state); }
/* With a token: the slow sockets send none, the client with the right token still gets through. */
static void test_slow_headers_with_token(void **state) { slow_headers_case(*state); }

/* 100 requests whose body never comes hold every ordinary control slot: a new ordinary request is
 * told 503 (JSON), but abort and /status (no body) use the reserved slots and still answer. */
static void test_bodies_that_never_come(void **state)
{
    fixture *f = *state;
    enum { N = 100 };
    int fds[N];
    for (int i = 0; i < N; i++) {
        fds[i] = dial(f->port);
        assert_true(fds[i] >= 0);
        static const char head[] = "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 1000\r\n\r\n{";
        send_all(fds[i], head, sizeof head - 1);
    }
    struct timespec ts = {0, 300 * 1000000L}; /* let the server take them all */
    nanosleep(&ts, NULL);
    char buf[4096];
    const char *body;
    static const char start[] = "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\nConnection: close\r\n\r\n{}";
    int st = exchange(f->port, start, sizeof start - 1, buf, sizeof buf, &body);
    assert_int_equal(st, 503);
    assert_json_error(buf, body, 503);
    double t = 0;
    assert_int_equal(simple(f, "POST", "/trials/current/abort", &t), 200);
    assert_true(t < 1.0);
    assert_int_equal(simple(f, "GET", "/status", &t), 200);
    assert_true(t < 1.0);
    assert_int_equal(atomic_load(&f->m.starts), 0);
    for (int i = 0; i < N; i++) close(fds[i]);
}

/* ---------------------------------------------------------------- the stream pool */

static int open_stream(unsigned port, char *buf, size_t cap)
{
    int fd = dial(port);
    assert_true(fd >= 0);
    static const char rq[] = "GET /live/events HTTP/1.1\r\nHost: x\r\n\r\n";
    send_all(fd, rq, sizeof rq - 1);
    ssize_t r = recv(fd, buf, cap - 1, 0);
    buf[r > 0 ? r : 0] = '\0';
    return fd;
}

static void test_stream_budget(void **state)
{
    fixture *f = *state; /* max_streams = 4 */
    int fds[4];
    char buf[4096];
    for (int i = 0; i < 4; i++) {
        fds[i] = open_stream(f->port, buf, sizeof buf);
        assert_non_null(strstr(buf, "200"));
        assert_non_null(strstr(buf, "text/event-stream"));
    }
    /* Full: the fifth is told so, as JSON. Streams never take control slots. */
    int fd = open_stream(f->port, buf, sizeof buf);
    close(fd);
    int status = 0;
    sscanf(buf, "HTTP/1.%*d %d", &status);
    assert_int_equal(status, 503);
    assert_json_error(buf, strstr(buf, "\r\n\r\n") + 4, 503);
    double t = 0;
    for (int k = 0; k < 5; k++) {
        assert_int_equal(simple(f, "GET", "/status", &t), 200);
        assert_true(t < 1.0);
    }
    /* A stream that is read keeps receiving while the others never read. */
    size_t got = 0;
    double t0 = now_s();
    while (now_s() - t0 < 1.0) {
        ssize_t r = recv(fds[0], buf, sizeof buf, 0);
        if (r <= 0) break;
        got += (size_t)r;
    }
    assert_true(got > 100);
    for (int i = 0; i < 4; i++) close(fds[i]);
    /* Closed streams give their slots back (libmicrohttpd notices within a beat). */
    int ok = 0;
    for (int k = 0; k < 40 && !ok; k++) {
        fd = open_stream(f->port, buf, sizeof buf);
        close(fd);
        ok = strncmp(buf, "HTTP/1.1 200", 12) == 0;
        if (!ok) nanosleep(&(struct timespec){0, 100 * 1000000L}, NULL);
    }
    assert_true(ok);
}

/* ---------------------------------------------------------------- item 12: token comparison */

static void test_token_equal(void **state)
{
    (void)state;
    assert_true(api_token_equal(TOKEN, strlen(TOKEN), TOKEN, strlen(TOKEN)));
    assert_false(api_token_equal("s3cret", 6, TOKEN, strlen(TOKEN)));           /* a prefix */
    assert_false(api_token_equal(TOKEN "x", strlen(TOKEN) + 1, TOKEN, strlen(TOKEN))); /* longer */
    assert_false(api_token_equal("", 0, TOKEN, strlen(TOKEN)));
    assert_false(api_token_equal("s3cret-tokem", 12, TOKEN, strlen(TOKEN)));   /* last byte */
    /* Bytes past the end are not compared as data: "a\0" of length 1 is not "a\0" of length 2. */
    assert_false(api_token_equal("a\0", 2, "a", 1));
    char longer[600];
    memset(longer, 'x', sizeof longer);
    assert_false(api_token_equal(longer, sizeof longer, longer, API_TOKEN_MAX)); /* longer than any token */
    assert_true(api_token_equal(longer, API_TOKEN_MAX, longer, API_TOKEN_MAX));
}

/* ---------------------------------------------------------------- issue 33 item 6: blank lines */

/* The status of the reply waiting on fd (read until the server closes, or the 5 s timeout). */
static int reply_status(int fd, char *buf, size_t cap)
{
    read_reply(fd, buf, cap);
    int status = 0;
    if (sscanf(buf, "HTTP/1.%*d %d", &status) != 1) return -1;
    return status;
}

/* 70 connections that send "\r\n\r\n" and nothing else (more than the 64 control slots) are no
 * request: the guard holds them until its header timeout (1 s here) and answers 408, and /trials
 * answers meanwhile. Blank lines before a real request are skipped, and the request goes to its
 * pool (a stream after blank lines is still a stream). */
static void test_blank_lines_hold_no_slot(void **state)
{
    fixture *f = *state; /* header_timeout_ms = 1000, max_connections = 64 */
    enum { N = 70 };
    int fds[N];
    double t0 = now_s();
    for (int i = 0; i < N; i++) {
        fds[i] = dial(f->port);
        assert_true(fds[i] >= 0);
        send_all(fds[i], "\r\n\r\n", 4);
    }
    struct timespec ts = {0, 200 * 1000000L}; /* let the server take them, as it would a request */
    nanosleep(&ts, NULL);
    double t = 0;
    int st = simple(f, "GET", "/trials", &t);
    if (st != 200) fail_msg("GET /trials answered %d behind %d blank-line connections", st, N);
    assert_true(t < 1.0);
    static const char post[] = "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\nConnection: close\r\n\r\n{}";
    char buf[4096];
    const char *body;
    assert_int_equal(exchange(f->port, post, sizeof post - 1, buf, sizeof buf, &body), 201);
    /* Blank lines before a request line are not a request of their own (RFC 9112, 2.2). */
    static const char lead[] = "\r\n\n\r\nGET /status HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n";
    assert_int_equal(exchange(f->port, lead, sizeof lead - 1, buf, sizeof buf, &body), 200);
    int sfd = dial(f->port);
    assert_true(sfd >= 0);
    static const char lead_stream[] = "\r\nGET /live/events HTTP/1.1\r\nHost: x\r\n\r\n";
    send_all(sfd, lead_stream, sizeof lead_stream - 1);
    ssize_t r = recv(sfd, buf, sizeof buf - 1, 0);
    buf[r > 0 ? r : 0] = '\0';
    close(sfd);
    if (strncmp(buf, "HTTP/1.1 200", 12) != 0) fail_msg("a stream after a blank line: %.80s", buf);
    /* The silent ones are answered 408 by the guard at its header timeout. */
    int timed_out = 0;
    for (int i = 0; i < N; i++) {
        if (reply_status(fds[i], buf, sizeof buf) == 408) timed_out++;
        close(fds[i]);
    }
    double waited = now_s() - t0;
    printf("# %d blank-line connections: /trials in %.3f s, %d answered 408, all within %.2f s\n", N, t, timed_out,
           waited);
    assert_int_equal(timed_out, N);
    assert_true(waited < 4.0);
}

/* ---------------------------------------------------------------- issue 33 item 7: body deadline */

/* A body that stops coming is answered 408 at the body deadline (1 s here), as JSON, whether
 * nothing more arrives (a Content-Length larger than what was sent, an unfinished chunked body)
 * or bytes keep trickling in. */
static void test_body_deadline_is_408(void **state)
{
    fixture *f = *state; /* body_timeout_ms = 1000 */
    static const char *const heads[] = {
        "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 100\r\n\r\n{\"note\":",
        "POST /trials HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n8\r\n{\"note\":",
    };
    char buf[4096];
    for (size_t k = 0; k < 3; k++) {
        int fd = dial(f->port);
        assert_true(fd >= 0);
        double t0 = now_s();
        if (k < 2) {
            send_all(fd, heads[k], strlen(heads[k]));
        } else { /* a byte every 200 ms, for longer than the deadline */
            static const char head[] = "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 50\r\n\r\n";
            send_all(fd, head, sizeof head - 1);
            for (int i = 0; i < 12; i++) {
                send_all(fd, " ", 1);
                nanosleep(&(struct timespec){0, 200 * 1000000L}, NULL);
                struct pollfd p = {.fd = fd, .events = POLLIN};
                if (poll(&p, 1, 0) > 0) break; /* answered */
            }
        }
        int st = reply_status(fd, buf, sizeof buf);
        double t = now_s() - t0;
        close(fd);
        printf("# body case %zu: %d after %.2f s\n", k, st, t);
        if (st != 408) fail_msg("body case %zu answered %d after %.2f s, expected 408", k, st, t);
        const char *body = strstr(buf, "\r\n\r\n");
        assert_non_null(body);
        assert_json_error(buf, body + 4, 408);
        assert_non_null(strstr(body, "1000 ms"));
        assert_true(t >= 0.9 && t < 3.5);
    }
    assert_int_equal(atomic_load(&f->m.starts), 0);
    /* A body in time still starts. */
    static const char post[] = "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\nConnection: close\r\n\r\n{}";
    const char *body;
    assert_int_equal(exchange(f->port, post, sizeof post - 1, buf, sizeof buf, &body), 201);
}

/* ---------------------------------------------------------------- issue 33 item 8: Content-Length */

/* Two Content-Length headers that disagree are a malformed request: 400, nothing started. Two
 * that agree are one length (RFC 9110, 8.6). */
static void test_conflicting_content_length_is_400(void **state)
{
    fixture *f = *state;
    static const char *const rq[] = {
        "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\nContent-Length: 30\r\n\r\n{}",
        "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 30\r\ncontent-length: 2\r\n\r\n{}",
        "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\nX-A: b\r\nContent-Length: 3\r\n\r\n{}",
    };
    char buf[4096];
    const char *body;
    for (size_t k = 0; k < sizeof rq / sizeof rq[0]; k++) {
        int st = exchange(f->port, rq[k], strlen(rq[k]), buf, sizeof buf, &body);
        if (st != 400) fail_msg("request %zu answered %d, expected 400", k, st);
        assert_json_error(buf, body, 400);
        assert_non_null(strstr(body, "Content-Length"));
    }
    assert_int_equal(atomic_load(&f->m.starts), 0);
    static const char same[] =
        "POST /trials HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\nContent-Length: 2\r\nConnection: close\r\n\r\n{}";
    assert_int_equal(exchange(f->port, same, sizeof same - 1, buf, sizeof buf, &body), 201);
    assert_int_equal(atomic_load(&f->m.starts), 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_percent_nul_is_400, setup, teardown),
        cmocka_unit_test_setup_teardown(test_oversized_line_and_head_are_json, setup, teardown),
        cmocka_unit_test_setup_teardown(test_slow_headers_do_not_lock_out, setup, teardown),
        cmocka_unit_test_setup_teardown(test_slow_headers_with_token, setup_token, teardown),
        cmocka_unit_test_setup_teardown(test_bodies_that_never_come, setup, teardown),
        cmocka_unit_test_setup_teardown(test_stream_budget, setup_streams4, teardown),
        cmocka_unit_test(test_token_equal),
        cmocka_unit_test_setup_teardown(test_blank_lines_hold_no_slot, setup_short_deadlines, teardown),
        cmocka_unit_test_setup_teardown(test_body_deadline_is_408, setup_short_deadlines, teardown),
        cmocka_unit_test_setup_teardown(test_conflicting_content_length_is_400, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
