/* test_live_bus.c: the live page's bus on its own: messages in order with their sequence, a reader
 * that falls behind the ring told exactly how many it missed, a late reader starting at the
 * trial's first message, the frame rate limit, the curve thinned with its ends kept, the JSON
 * helpers always giving valid JSON, and publishing never waiting for a reader that holds none of
 * the bus (a reader blocked in a wait does not hold the lock). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "live_bus.h"
#include "live_jpeg.h"

#include <jansson.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static void test_order_and_seq(void **state)
{
    (void)state;
    live_bus *b = live_bus_create();
    uint64_t cur = live_bus_first(b);
    char buf[LIVE_MSG_MAX], m[64];
    for (int i = 0; i < 10; i++) {
        snprintf(m, sizeof m, "{\"i\":%d}", i);
        live_bus_publish(b, m, i == 0);
    }
    for (int i = 0; i < 10; i++) {
        uint64_t seq = 0, missed = 0;
        int n = live_bus_read(b, &cur, buf, sizeof buf, 0, &seq, &missed);
        snprintf(m, sizeof m, "{\"i\":%d}", i);
        assert_int_equal(n, (int)strlen(m));
        assert_string_equal(buf, m);
        assert_int_equal(seq, (uint64_t)i + 1);
        assert_int_equal(missed, 0);
    }
    uint64_t seq, missed;
    assert_int_equal(live_bus_read(b, &cur, buf, sizeof buf, 10, &seq, &missed), 0); /* timeout: nothing new */
    live_bus_close(b);
    assert_int_equal(live_bus_read(b, &cur, buf, sizeof buf, 1000, &seq, &missed), -1);
    live_bus_free(b);
}

static void test_reader_behind_is_told(void **state)
{
    (void)state;
    live_bus *b = live_bus_create();
    live_bus_publish(b, "{\"first\":1}", 1);
    uint64_t cur = live_bus_first(b);
    assert_int_equal(cur, 1);
    int total = LIVE_RING + 100;
    for (int i = 1; i < total; i++) live_bus_publish(b, "{}", 0);
    char buf[LIVE_MSG_MAX];
    uint64_t seq = 0, missed = 0;
    assert_true(live_bus_read(b, &cur, buf, sizeof buf, 0, &seq, &missed) > 0);
    assert_int_equal(missed, 100);          /* exactly the overwritten ones */
    assert_int_equal(seq, 101);
    /* A late reader starts at the oldest kept (the trial's first was overwritten). */
    assert_int_equal(live_bus_first(b), 101);
    live_bus_publish(b, "{\"trial\":2}", 1);
    assert_int_equal(live_bus_first(b), (uint64_t)total + 1);
    live_bus_free(b);
}

static void test_too_long_is_replaced(void **state)
{
    (void)state;
    live_bus *b = live_bus_create();
    char *big = malloc(LIVE_MSG_MAX + 10);
    memset(big, 'x', LIVE_MSG_MAX + 9);
    big[LIVE_MSG_MAX + 9] = '\0';
    live_bus_publish(b, big, 1);
    free(big);
    uint64_t cur = live_bus_first(b), seq, missed;
    char buf[LIVE_MSG_MAX];
    assert_true(live_bus_read(b, &cur, buf, sizeof buf, 0, &seq, &missed) > 0);
    json_t *j = json_loads(buf, 0, NULL);
    assert_non_null(j);
    assert_string_equal(json_string_value(json_object_get(j, "type")), "error");
    json_decref(j);
    live_bus_free(b);
}

static void test_json_helpers(void **state)
{
    (void)state;
    char s[64], n[32], m[256];
    const char *nasty = "quote \" back \\ nl \n tab \t bell \a high \xc3\xa9";
    snprintf(m, sizeof m, "{\"s\":\"%s\",\"n\":%s,\"x\":%s}", live_str(s, sizeof s, nasty), live_num(n, sizeof n, NAN),
             live_num((char[32]){0}, 32, 1.5));
    json_error_t e;
    json_t *j = json_loads(m, 0, &e);
    if (!j) fail_msg("invalid JSON %s: %s", m, e.text);
    assert_true(json_is_null(json_object_get(j, "n")));
    assert_true(json_real_value(json_object_get(j, "x")) == 1.5);
    assert_non_null(strstr(json_string_value(json_object_get(j, "s")), "quote \" back \\ nl \n tab"));
    json_decref(j);
    /* Cut to fit, never in the middle of an escape. */
    char tiny[6];
    live_str(tiny, sizeof tiny, "ab\"cd");
    assert_string_equal(tiny, "ab\\\"c");
    live_str(tiny, 4, "ab\"cd");
    assert_string_equal(tiny, "ab");
}

static void test_frames_rate_limited(void **state)
{
    (void)state;
    live_bus *b = live_bus_create();
    live_frame f;
    assert_int_equal(live_bus_latest_frame(b, &f), -1);
    uint8_t px[4 * 3 * 3];
    for (size_t i = 0; i < sizeof px; i++) px[i] = (uint8_t)i;
    double uv[6] = {0, 0, 1, 1, 2, 2};
    int kept = 0;
    for (int k = 0; k < 100; k++) { /* 100 frames at 100 fps = 1 s: about 10 kept */
        double t = k * 0.01;
        if (live_bus_frame_due(b, t)) {
            live_bus_publish_frame(b, t, k, 4, 3, 3, 12, px, uv, 3);
            kept++;
        }
    }
    assert_in_range(kept, 9, 11);
    assert_int_equal(live_bus_latest_frame(b, &f), 0);
    assert_int_equal(f.width, 4);
    assert_int_equal(f.n_uv, 3);
    assert_memory_equal(f.pixels, px, sizeof px);
    unsigned char *jpg = NULL;
    size_t len = 0;
    char why[128];
    assert_int_equal(live_jpeg_encode(&f, 80, &jpg, &len, why, sizeof why), 0);
    assert_true(len > 100 && jpg[0] == 0xff && jpg[1] == 0xd8); /* a JPEG's start-of-image marker */
    free(jpg);
    free(f.pixels);
    live_bus_free(b);
}

static void test_curve_thinned_ends_kept(void **state)
{
    (void)state;
    live_bus *b = live_bus_create();
    size_t n = 3 * LIVE_CURVE_MAX + 7;
    double *dw = malloc(n * sizeof *dw), *dz = malloc(n * sizeof *dz), *a = malloc(n * sizeof *a);
    for (size_t i = 0; i < n; i++) dw[i] = dz[i] = a[i] = (double)i;
    live_bus_publish_curve(b, 5, n, dw, dz, a);
    double *x, *y, *z;
    int64_t id = 0;
    size_t m = live_bus_curve(b, &id, &x, &y, &z);
    assert_int_equal(m, LIVE_CURVE_MAX);
    assert_int_equal(id, 5);
    assert_true(x[0] == 0.0 && x[m - 1] == (double)(n - 1));
    for (size_t k = 1; k < m; k++) assert_true(x[k] > x[k - 1]);
    free(x), free(y), free(z), free(dw), free(dz), free(a);
    live_bus_free(b);
}

typedef struct waiter {
    live_bus *b;
    int got;
} waiter;

static void *wait_one(void *arg)
{
    waiter *w = arg;
    uint64_t cur = live_bus_first(w->b), seq, missed;
    char buf[LIVE_MSG_MAX];
    w->got = live_bus_read(w->b, &cur, buf, sizeof buf, 5000, &seq, &missed);
    return NULL;
}

/* Readers waiting for news do not hold the lock: a publisher gets through at once and wakes them. */
static void test_waiting_readers_do_not_block_publishers(void **state)
{
    (void)state;
    live_bus *b = live_bus_create();
    live_bus_publish(b, "{}", 1);
    uint64_t c0 = live_bus_first(b), s, mm;
    char buf[LIVE_MSG_MAX];
    live_bus_read(b, &c0, buf, sizeof buf, 0, &s, &mm);
    enum { N = 20 };
    waiter w[N];
    pthread_t t[N];
    for (int i = 0; i < N; i++) {
        w[i].b = b;
        w[i].got = -2;
        pthread_create(&t[i], NULL, wait_one, &w[i]);
    }
    struct timespec ts = {0, 100 * 1000000L};
    nanosleep(&ts, NULL);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (int k = 0; k < 1000; k++) live_bus_publish(b, "{\"k\":1}", 0);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    for (int i = 0; i < N; i++) pthread_join(t[i], NULL);
    for (int i = 0; i < N; i++) assert_true(w[i].got > 0);
    double us = ((double)(t1.tv_sec - t0.tv_sec) * 1e9 + (double)(t1.tv_nsec - t0.tv_nsec)) / 1e3 / 1000;
    printf("# 1000 publishes with %d waiting readers: %.2f us each\n", N, us);
    live_bus_free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_order_and_seq),
        cmocka_unit_test(test_reader_behind_is_told),
        cmocka_unit_test(test_too_long_is_replaced),
        cmocka_unit_test(test_json_helpers),
        cmocka_unit_test(test_frames_rate_limited),
        cmocka_unit_test(test_curve_thinned_ends_kept),
        cmocka_unit_test(test_waiting_readers_do_not_block_publishers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
