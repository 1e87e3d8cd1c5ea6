/* test_ribbond_phase_busy.c: GET /campaign/phase with a cold boundary cache does not hold ribbond's
 * API while the predicted boundary is traced (about a second of CPU on the mock scene).
 *
 * ribbond in mock mode (in this process, its HTTP server on 127.0.0.1, an ephemeral port) over a
 * store with measured trials (so the route gets as far as the predicted boundary) and no cache.
 * A: GET /campaign/phase, cold: 503 with Retry-After at once (the trace runs in the background).
 * B: GET /status sent 50 ms after A (A on a thread of its own): its latency must be below a
 * quarter of the trace's own time (the trace reports it in the curve's source). Before, A held the
 * API thread for the whole trace and B waited for it. C: GET /campaign/phase right after B is
 * still 503 (B was served while the trace ran); then polled every 100 ms (at most 1500 times: the
 * trace takes 45 s under ASan): 200 with the traced curve, and once more, at once (no second
 * trace). Plain HTTP, one socket per request, each bounded by a 30 s timeout. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <arpa/inet.h>
#include <jansson.h>
#include <math.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <pthread.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <time.h>
#include <unistd.h>

#include "rig_daemon.h"
#include "test_dir.h"

static char dir[64];
static const double T0 = 1.8e9;

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct reply {
    int status;
    char retry_after[16]; /* the header's value, "" when absent */
    char body[65536];
    double seconds;       /* from connect to the last byte */
} reply;

/* One GET to 127.0.0.1:port, Connection: close; 0, or -1 (fail_msg) on a socket error. */
static void get(unsigned port, const char *path, reply *r)
{
    memset(r, 0, sizeof *r);
    double t0 = now_s();
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct timeval tv = {30, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd, (struct sockaddr *)&a, sizeof a)) fail_msg("connect: port %u", port);
    char req[256];
    int n = snprintf(req, sizeof req, "GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", path);
    assert_int_equal(write(fd, req, (size_t)n), n);
    static char buf[1 << 17];
    size_t used = 0;
    ssize_t k;
    while (used + 1 < sizeof buf && (k = read(fd, buf + used, sizeof buf - 1 - used)) > 0) used += (size_t)k;
    buf[used] = '\0';
    close(fd);
    r->seconds = now_s() - t0;
    if (sscanf(buf, "HTTP/1.%*d %d", &r->status) != 1) fail_msg("%s: no status line in %.200s", path, buf);
    char *end = strstr(buf, "\r\n\r\n");
    if (!end) fail_msg("%s: no end of head", path);
    *end = '\0';
    for (char *line = strstr(buf, "\r\n"); line; line = strstr(line + 2, "\r\n"))
        if (!strncasecmp(line + 2, "Retry-After:", 12)) sscanf(line + 14, "%15s", r->retry_after);
    snprintf(r->body, sizeof r->body, "%s", end + 4);
}

static void *ask_phase(void *arg)
{
    struct asker { unsigned port; reply *r; } *k = arg;
    get(k->port, "/campaign/phase", k->r);
    return NULL;
}

/* The seconds a "traced from the scene (...) in X s" source names; NaN when the body has none. */
static double traced_seconds(const char *body)
{
    json_error_t je;
    json_t *o = json_loads(body, 0, &je);
    const char *src = json_string_value(json_object_get(json_object_get(o, "predicted"), "source"));
    const char *in = src && !strncmp(src, "traced", 6) ? strstr(src, " in ") : NULL;
    double s = NAN;
    if (!in || sscanf(in, " in %lf s", &s) != 1) s = NAN;
    json_decref(o);
    return s;
}

/* Measured trials at phi 90 (so /campaign/phase draws), written before ribbond opens the store. */
static void fill(const char *db)
{
    store *st = NULL;
    char why[300];
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    const double gamma[] = {0.15, 0.16, 0.17, 0.18};
    for (int k = 0; k < 4; k++) {
        store_specimen sp = store_specimen_default();
        snprintf(sp.name, sizeof sp.name, "S%d", k);
        sp.length_m = 0.2, sp.width_m = 0.005, sp.thickness_m = 2.5e-4, sp.phi_deg = 90, sp.fold_position = gamma[k];
        int64_t sid = 0, id = 0;
        assert_int_equal(store_specimen_upsert(st, &sp, &sid, why, sizeof why), STORE_OK);
        store_trial_def d = store_trial_def_default();
        d.specimen_id = sid;
        d.created_wall_s = T0;
        assert_int_equal(store_trial_create(st, &d, &id, why, sizeof why), STORE_OK);
        assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, T0 + 1, why, sizeof why), STORE_OK);
        store_regime rg = k < 2 ? STORE_REGIME_ASYMMETRIC : STORE_REGIME_SYMMETRIC;
        assert_int_equal(store_trial_set_result(st, id, 1, 0.4, rg, why, sizeof why), STORE_OK);
        assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_DONE, NULL, T0 + 2, why, sizeof why), STORE_OK);
    }
    store_close(st);
}

static void test_phase_does_not_hold_the_api(void **state)
{
    (void)state;
    static rig_daemon d;
    char db[128], s_store[160], s_video[160], why[1024] = "";
    snprintf(db, sizeof db, "%s/phase.db", dir);
    fill(db);
    snprintf(s_store, sizeof s_store, "store.path=%s", db);
    snprintf(s_video, sizeof s_video, "camera.video_dir=%s/videos", dir);
    const char *ov[] = {s_store, s_video, "api.port=0"};
    if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, 3, NULL, why, sizeof why))
        fail_msg("mock daemon: %s", why);
    unsigned port = 0;
    if (rig_daemon_serve(&d, &port, why, sizeof why)) fail_msg("serve: %s", why);

    static reply a, b, c;
    static struct asker { unsigned port; reply *r; } ask;
    ask.port = port, ask.r = &a;
    pthread_t t;
    assert_int_equal(pthread_create(&t, NULL, ask_phase, &ask), 0);
    usleep(50000); /* A is in: the trace has begun (or, before, holds the API thread) */
    get(port, "/status", &b);
    get(port, "/campaign/phase", &c);
    pthread_join(t, NULL);
    printf("# cold /campaign/phase: %d in %.3f s (Retry-After %s): %.200s\n", a.status, a.seconds,
           a.retry_after[0] ? a.retry_after : "none", a.body);
    printf("# /status meanwhile: %d in %.3f s; /campaign/phase after it: %d\n", b.status, b.seconds, c.status);
    int c_status = c.status;
    reply *p = &c;
    for (int i = 0; i < 1500 && p->status == 503; i++) {
        usleep(100000);
        get(port, "/campaign/phase", p);
    }
    printf("# then: %d: %.300s\n", p->status, p->body);
    assert_int_equal(p->status, 200);
    /* the trace's own time, from whichever answer carried the traced curve (before: A itself) */
    double trace_s = traced_seconds(a.body);
    if (isnan(trace_s)) trace_s = traced_seconds(p->body);
    if (isnan(trace_s)) fail_msg("no answer carried a traced curve");
    printf("# the trace took %.3f s\n", trace_s);
    if (!(b.seconds < 0.25 * trace_s))
        fail_msg("GET /status took %.3f s while the boundary was traced (%.3f s): not below a quarter of it",
                 b.seconds, trace_s);
    assert_int_equal(a.status, 503);
    assert_true(a.retry_after[0] != '\0');
    assert_int_equal(b.status, 200);
    assert_int_equal(c_status, 503); /* B was served while the trace ran */
    get(port, "/campaign/phase", &a); /* the curve stays: no second trace */
    assert_int_equal(a.status, 200);
    assert_true(a.seconds < 0.25 * trace_s);
    rig_daemon_close(&d, "test done");
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/ribbond-phase-XXXXXX");
    if (!mkdtemp(dir)) return 1;
    char locks[128];
    snprintf(locks, sizeof locks, "%s/locks", dir);
    mkdir(locks, 0700);
    setenv("RIBBON_LOCK_DIR", locks, 1);
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_phase_does_not_hold_the_api)};
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    test_dir_done(dir, rc == 0, "ribbond phase busy");
    return rc;
}
