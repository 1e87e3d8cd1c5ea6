/* test_trial_fit_out: the fit's events and landed results written off the trial's loop
 * (daemon/trial/trial_fit_out.h). Another connection holds the store's write lock for 300 ms (a
 * long commit, a checkpoint, a bulk writer): a direct event append, as the loop made one for every
 * fit landing before, waits for the lock (checked: over 200 ms, so the case is real), while posting
 * an event and a landed result returns at once (under 20 ms with the machine loaded; a copy into a
 * queue). After the lock goes and the writer drains, both are stored in the order posted with the
 * state they were posted in, and the trial's calibrated columns hold the landed result. A writer
 * whose store cannot be opened is refused with the reason. No simulation: under a second. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <jansson.h>
#include <math.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "trial.h"
#include "trial_fit_out.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct holder {
    const char *db;
    volatile int locked;
} holder;

/* Holds the write lock for 300 ms on a connection of its own. */
static void *hold_lock(void *arg)
{
    holder *h = arg;
    sqlite3 *c = NULL;
    assert_int_equal(sqlite3_open(h->db, &c), SQLITE_OK);
    assert_int_equal(sqlite3_exec(c, "BEGIN IMMEDIATE", NULL, NULL, NULL), SQLITE_OK);
    __atomic_store_n(&h->locked, 1, __ATOMIC_SEQ_CST);
    usleep(300000);
    assert_int_equal(sqlite3_exec(c, "COMMIT", NULL, NULL, NULL), SQLITE_OK);
    sqlite3_close(c);
    return NULL;
}

static store_event event(const char *state, const char *msg, double t)
{
    store_event ev;
    memset(&ev, 0, sizeof ev);
    ev.t_s = t;
    ev.wall_s = store_wall_now();
    ev.kind = STORE_EVENT_INFO;
    snprintf(ev.state, sizeof ev.state, "%s", state);
    snprintf(ev.message, sizeof ev.message, "%s", msg);
    return ev;
}

static int logged;
static void count_log(void *user, const char *line)
{
    (void)user;
    (void)line;
    __atomic_add_fetch(&logged, 1, __ATOMIC_SEQ_CST);
}

static void posts_do_not_wait_for_the_store(void **state)
{
    (void)state;
    char dir[] = "/tmp/test_trial_fit_out.XXXXXX", db[128], why[512] = "";
    assert_non_null(mkdtemp(dir));
    snprintf(db, sizeof db, "%s/trials.db", dir);
    store *st = NULL;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_MOCK;
    d.config_text = "# test";
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &d, &id, why, sizeof why), STORE_OK);
    trial_fit_out *o = trial_fit_out_open(db, id, NULL, count_log, NULL, why, sizeof why);
    assert_non_null(o);

    holder h = {db, 0};
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, hold_lock, &h), 0);
    while (!__atomic_load_n(&h.locked, __ATOMIC_SEQ_CST)) usleep(1000);

    trial_calibrated r;
    memset(&r, 0, sizeof r);
    r.ok = 1;
    r.snapped = 1;
    r.snap_dw = 0.39227;
    r.snap_sd = 0.02818;
    r.p_other = 2.75e-9;
    r.asymmetric = 1;
    r.t_landed = 12.5;
    r.dw_limit = r.limit_snap = NAN;
    double t0 = now_s();
    store_event e1 = event("holding", "calibration: fitting both crease angles", 3.0);
    assert_int_equal(trial_fit_out_event(o, &e1), 0);
    assert_int_equal(trial_fit_out_calibrated(o, &r), 0);
    store_event e2 = event("shearing", "calibrated prediction fit 0 landed", 12.5);
    assert_int_equal(trial_fit_out_event(o, &e2), 0);
    double posted = now_s() - t0;
    /* What the loop did before: the append itself, which waits for the lock. */
    store_event e0 = event("shearing", "the loop's own event", 12.6);
    e0.trial_id = id;
    t0 = now_s();
    assert_int_equal(store_event_append(st, &e0, why, sizeof why), STORE_OK);
    double direct = now_s() - t0;
    pthread_join(th, NULL);
    trial_fit_out_drain(o);
    printf("# with the write lock held 300 ms: 3 posts took %.3f ms, a direct append %.1f ms\n", 1e3 * posted,
           1e3 * direct);
    assert_true(direct > 0.2);
    assert_true(posted < 0.02);

    json_t *t = NULL;
    assert_int_equal(store_trial_json(st, id, &t, why, sizeof why), STORE_OK);
    assert_true(fabs(json_number_value(json_object_get(t, "snap_dw_calibrated")) - 0.39227) < 1e-12);
    assert_string_equal(json_string_value(json_object_get(t, "regime_calibrated")), "asymmetric");
    assert_true(json_is_object(json_object_get(t, "fit")));
    const json_t *evs = json_object_get(t, "events");
    int i1 = -1, i2 = -1;
    for (size_t k = 0; k < json_array_size(evs); k++) {
        const json_t *e = json_array_get(evs, k);
        const char *m = json_string_value(json_object_get(e, "message"));
        if (!strcmp(m, e1.message)) {
            i1 = (int)k;
            assert_string_equal(json_string_value(json_object_get(e, "state")), "holding");
        }
        if (!strcmp(m, e2.message)) {
            i2 = (int)k;
            assert_string_equal(json_string_value(json_object_get(e, "state")), "shearing");
        }
    }
    assert_true(i1 >= 0 && i2 > i1);
    json_decref(t);
    trial_fit_out_close(o);
    assert_int_equal(__atomic_load_n(&logged, __ATOMIC_SEQ_CST), 2); /* each event's message */
    store_close(st);
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

static void a_store_that_cannot_open_is_refused(void **state)
{
    (void)state;
    char why[512] = "";
    trial_fit_out *o = trial_fit_out_open("/nonexistent-dir/x/trials.db", 1, NULL, NULL, NULL, why, sizeof why);
    assert_null(o);
    printf("# refused: %s\n", why);
    assert_true(why[0] != '\0');
    trial_fit_out_close(NULL);
    trial_fit_out_drain(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(posts_do_not_wait_for_the_store),
        cmocka_unit_test(a_store_that_cannot_open_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
