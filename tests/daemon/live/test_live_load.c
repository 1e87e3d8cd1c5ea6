/* test_live_load.c: ribbond under load, end to end (heavy).
 * 1. 20 event-stream clients, one of which never reads, do not change a mock
 * trial: the same result (measured snap, regime, sample count) as the same trial with no client,
 * every reading client gets the whole trial (its result message, nothing missed), the stuck one
 * holds only its own stream, and the trial's wall time with and without the clients is printed as
 * one machine-readable line (a measurement, not a timed assertion). Each compared trial is the
 * first of a fresh ribbond on a fresh store (see the test). Heavy (three mock trials).
 * 2. Issue 17, defect 1, as the probe did it: a mock trial runs, 1,000 sockets each send the start
 *    of a request and then one header line at a time, and `ribbonctl abort` (the real CLI) still
 *    answers within 1 s of what `ribbonctl status` takes with no slow socket, and the trial is
 *    over (aborted) within 1 s of the answer. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <arpa/inet.h>
#include <jansson.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include "live_testkit.h"

#define CLIENTS 20

typedef struct client {
    unsigned port;
    int fd;
    long trial;                /* the trial whose result ends the reading */
    long messages, gaps;
    int got_result;
    atomic_int *stop;
} client;

static int dial_stream(unsigned port, int small_buffer)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    if (small_buffer) {
        int sz = 4096;
        setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &sz, sizeof sz);
    }
    struct timeval tv = {.tv_sec = 1};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    assert_int_equal(connect(fd, (struct sockaddr *)&a, sizeof a), 0);
    static const char rq[] = "GET /live/events HTTP/1.1\r\nHost: x\r\n\r\n";
    assert_int_equal(send(fd, rq, sizeof rq - 1, MSG_NOSIGNAL), (ssize_t)(sizeof rq - 1));
    return fd;
}

/* Reads the stream, counting messages, until the result of c->trial (or stop). */
static void *reader(void *arg)
{
    client *c = arg;
    char buf[65536], want[64];
    size_t keep = 0;
    snprintf(want, sizeof want, "\"type\":\"result\",\"trial\":%ld", c->trial);
    while (!atomic_load(c->stop)) {
        ssize_t r = recv(c->fd, buf + keep, sizeof buf - 1 - keep, 0);
        if (r == 0) break;
        if (r < 0) continue; /* 1 s timeout: look at stop again */
        keep += (size_t)r;
        buf[keep] = '\0';
        char *p = buf, *end;
        while ((end = strstr(p, "\n\n")) != NULL) {
            *end = '\0';
            if (strstr(p, "data: ")) c->messages++;
            if (strstr(p, "\"type\":\"gap\"")) c->gaps++;
            if (strstr(p, want)) c->got_result = 1;
            p = end + 2;
        }
        keep = strlen(p);
        memmove(buf, p, keep);
        if (c->got_result) break;
    }
    return NULL;
}

typedef struct outcome {
    long id;
    double wall_s;
    double snap_dw;
    char regime[32], status[32];
    long samples;
} outcome;

static long start_trial(const ribbond_child *c)
{
    char url[128], *body = NULL;
    snprintf(url, sizeof url, "%s/trials", c->url);
    int st = kit_http("POST", url, NULL, "{\"note\":\"load\"}", &body, 30);
    if (st != 201) fail_msg("start: %d %s", st, body);
    json_t *j = json_loads(body, 0, NULL);
    free(body);
    long id = (long)json_integer_value(json_object_get(j, "id"));
    json_decref(j);
    return id;
}

static void finish(const ribbond_child *c, long id, double t0, outcome *o)
{
    char url[128], *body = NULL;
    snprintf(url, sizeof url, "%s/status", c->url);
    for (;;) {
        int st = kit_http("GET", url, NULL, NULL, &body, 30);
        assert_int_equal(st, 200);
        json_t *j = json_loads(body, 0, NULL);
        free(body);
        const char *top = json_string_value(json_object_get(j, "state")); /* the daemon's, not the trial's */
        int idle = top && strcmp(top, "idle") == 0;
        json_decref(j);
        if (idle) break;
        if (kit_now() - t0 > 300) fail_msg("trial %ld still running after 300 s", id);
        kit_sleep_ms(50);
    }
    o->wall_s = kit_now() - t0;
    o->id = id;
    snprintf(url, sizeof url, "%s/trials/%ld", c->url, id);
    assert_int_equal(kit_http("GET", url, NULL, NULL, &body, 30), 200);
    json_t *j = json_loads(body, 0, NULL);
    free(body);
    o->snap_dw = json_real_value(json_object_get(j, "snap_dw_measured"));
    o->samples = (long)json_integer_value(json_object_get(j, "samples"));
    snprintf(o->regime, sizeof o->regime, "%s", json_string_value(json_object_get(j, "regime_measured")));
    snprintf(o->status, sizeof o->status, "%s", json_string_value(json_object_get(j, "status")));
    json_decref(j);
}

static ribbond_child child; /* the test's ribbond, stopped by the teardown however the test ends */

static int teardown(void **state)
{
    (void)state;
    if (child.pid > 0) kit_ribbond_stop(&child);
    return 0;
}

static void test_twenty_clients(void **state)
{
    (void)state;
    char dir[300];
    /* Each compared trial is the first of a fresh ribbond on a fresh store: consecutive mock
     * trials of one daemon are not identical (the second one of a run had 960 samples where the
     * first and the third had 962, its snap 5e-13 away), so only equal starts compare. */
    kit_fresh_dir("live_load_none", dir, sizeof dir);
    assert_int_equal(kit_ribbond_start(&child, dir, 0, NULL), 0);
    outcome none, busy;
    double t0 = kit_now();
    finish(&child, start_trial(&child), t0, &none);
    assert_int_equal(kit_ribbond_stop(&child), 0);

    kit_fresh_dir("live_load_clients", dir, sizeof dir);
    ribbond_child *cp = &child;
    assert_int_equal(kit_ribbond_start(cp, dir, 0, NULL), 0);
    ribbond_child c = *cp;

    /* 19 reading clients and one that never reads, all connected before the trial starts. */
    atomic_int stop = 0;
    client cl[CLIENTS];
    pthread_t th[CLIENTS];
    memset(cl, 0, sizeof cl);
    long next_id = 1;
    for (int i = 0; i < CLIENTS; i++) {
        cl[i].port = c.port;
        cl[i].trial = next_id;
        cl[i].stop = &stop;
        cl[i].fd = dial_stream(c.port, i == CLIENTS - 1);
        if (i < CLIENTS - 1) pthread_create(&th[i], NULL, reader, &cl[i]);
    }
    kit_sleep_ms(300);
    t0 = kit_now();
    long id = start_trial(&c);
    assert_int_equal(id, next_id);
    finish(&c, id, t0, &busy);
    double t_wait = kit_now();
    for (int i = 0; i < CLIENTS - 1; i++) {
        while (!cl[i].got_result && kit_now() - t_wait < 10) kit_sleep_ms(20);
    }
    atomic_store(&stop, 1);
    for (int i = 0; i < CLIENTS - 1; i++) pthread_join(th[i], NULL);

    printf("{\"bench\":\"live_sse_clients\",\"clients\":%d,\"never_reading\":1,\"trial_wall_s_no_client\":%.3f,"
           "\"trial_wall_s_with_clients\":%.3f,\"ratio\":%.3f,\"messages_per_client\":%ld}\n",
           CLIENTS, none.wall_s, busy.wall_s, busy.wall_s / none.wall_s, cl[0].messages);
    assert_string_equal(none.status, "done");
    assert_string_equal(busy.status, "done");
    /* The same trial, bit for bit. */
    printf("# measured snap: %.17g without clients, %.17g with %d; samples %ld and %ld\n", none.snap_dw, busy.snap_dw,
           CLIENTS, none.samples, busy.samples);
    assert_true(busy.snap_dw == none.snap_dw);
    assert_string_equal(busy.regime, none.regime);
    assert_int_equal(busy.samples, none.samples);
    for (int i = 0; i < CLIENTS - 1; i++) {
        if (!cl[i].got_result) fail_msg("client %d never got the trial's result (%ld messages)", i, cl[i].messages);
        assert_int_equal(cl[i].gaps, 0);
        assert_true(cl[i].messages > busy.samples); /* every sample, plus states and events */
    }
    /* The stuck client holds one stream slot, nothing else: a new stream still opens. */
    int fd = dial_stream(c.port, 0);
    char buf[512];
    ssize_t r = recv(fd, buf, sizeof buf - 1, 0);
    assert_true(r > 12);
    assert_int_equal(strncmp(buf, "HTTP/1.1 200", 12), 0);
    close(fd);
    for (int i = 0; i < CLIENTS; i++) close(cl[i].fd);
    assert_int_equal(kit_ribbond_stop(cp), 0);
}

static const char *daemon_state(const ribbond_child *c, char *trial_state, size_t n)
{
    static char top[32];
    char url[128], *body = NULL;
    snprintf(url, sizeof url, "%s/status", c->url);
    top[0] = trial_state[0] = '\0';
    if (kit_http("GET", url, NULL, NULL, &body, 10) != 200) {
        free(body);
        return "unreachable";
    }
    json_t *j = json_loads(body, 0, NULL);
    free(body);
    snprintf(top, sizeof top, "%s", json_string_value(json_object_get(j, "state")) ? json_string_value(json_object_get(j, "state")) : "");
    const char *ts = json_string_value(json_object_get(json_object_get(j, "trial"), "state"));
    snprintf(trial_state, n, "%s", ts ? ts : "");
    json_decref(j);
    return top;
}

#define SLOW 1000

static void test_abort_through_slow_sockets(void **state)
{
    (void)state;
    struct rlimit rl;
    getrlimit(RLIMIT_NOFILE, &rl);
    if (rl.rlim_cur < SLOW + 200) {
        if (rl.rlim_max != RLIM_INFINITY && rl.rlim_max < SLOW + 200) skip();
        rl.rlim_cur = SLOW + 200;
        assert_int_equal(setrlimit(RLIMIT_NOFILE, &rl), 0);
    }
    char dir[300];
    kit_fresh_dir("live_slow", dir, sizeof dir);
    assert_int_equal(kit_ribbond_start(&child, dir, 0, NULL), 0);
    const ribbond_child *c = &child;
    long id = start_trial(c);
    char ts[32];
    double t0 = kit_now();
    while (strcmp(daemon_state(c, ts, sizeof ts), "running") != 0 || strcmp(ts, "compressing") != 0) {
        if (kit_now() - t0 > 120) fail_msg("trial %ld never reached compressing (%s)", id, ts);
        kit_sleep_ms(20);
    }
    /* The CLI's own cost on this machine (start-up, libraries: 0.7 s under a load average of 20),
     * measured the same way before any slow socket exists. */
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "'%s/ribbonctl' status --url %s > /dev/null 2>&1", RIBBON_BIN_DIR, c->url);
    double tb = kit_now();
    assert_int_equal(system(cmd), 0);
    double t_baseline = kit_now() - tb;
    int *fds = malloc(SLOW * sizeof *fds);
    for (int i = 0; i < SLOW; i++) {
        fds[i] = socket(AF_INET, SOCK_STREAM, 0);
        struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)c->port)};
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        assert_int_equal(connect(fds[i], (struct sockaddr *)&a, sizeof a), 0);
        static const char part[] = "GET /status HTTP/1.1\r\nHost: x\r\n";
        send(fds[i], part, sizeof part - 1, MSG_NOSIGNAL);
    }
    for (int i = 0; i < SLOW; i++) send(fds[i], "X-Slow: 1\r\n", 11, MSG_NOSIGNAL);
    snprintf(cmd, sizeof cmd, "'%s/ribbonctl' abort --url %s > '%s/abort.out' 2>&1", RIBBON_BIN_DIR, c->url, dir);
    double ta = kit_now();
    int rc = system(cmd);
    double t_answer = kit_now() - ta;
    const char *top;
    while (strcmp(top = daemon_state(c, ts, sizeof ts), "idle") != 0) {
        if (kit_now() - ta > 30) fail_msg("trial %ld still %s/%s 30 s after the abort", id, top, ts);
        kit_sleep_ms(10);
    }
    double t_stopped = kit_now() - ta;
    char url[1024], *body = NULL;
    snprintf(url, sizeof url, "%s/trials/%ld", c->url, id);
    assert_int_equal(kit_http("GET", url, NULL, NULL, &body, 10), 200);
    json_t *j = json_loads(body, 0, NULL);
    free(body);
    printf("{\"bench\":\"abort_through_slow_sockets\",\"slow_sockets\":%d,\"ribbonctl_status_alone_s\":%.3f,"
           "\"ribbonctl_abort_s\":%.3f,\"trial_idle_s\":%.3f,\"status\":\"%s\"}\n",
           SLOW, t_baseline, t_answer, t_stopped, json_string_value(json_object_get(j, "status")));
    assert_int_equal(rc, 0);
    assert_string_equal(json_string_value(json_object_get(j, "status")), "aborted");
    /* Within 1 s of what the CLI costs anyway; the trial idle within 1 s of the answer. */
    assert_true(t_answer - t_baseline < 1.0);
    assert_true(t_stopped - t_answer < 1.0);
    json_decref(j);
    for (int i = 0; i < SLOW; i++) close(fds[i]);
    free(fds);
    assert_int_equal(kit_ribbond_stop(&child), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test_teardown(test_twenty_clients, teardown),
                                       cmocka_unit_test_teardown(test_abort_through_slow_sockets, teardown)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
