/* test_ribbond_safety: ribbond's safety and data items of issue 33, in mock mode in this process
 * (config/mock.ini: mock rails on a virtual clock; the API's operations called directly).
 *   1. One daemon per store: a second rig_daemon_open on the store of a running one is refused
 *      naming the holder (pid, since when) and leaves the first one's running trial as it is;
 *      the store stays readable beside it (ribbonctl --db's read-only open); once the first has
 *      closed, the second starts.
 *   4. A replay of a trial that is still running is refused with 409 and the reason. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>

#include "rig_daemon.h"
#include "store.h"
#include "test_dir.h"
#include "trial.h"

static char dir[64];
static int all_passed = 1;

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/ribbond-safety-XXXXXX");
    if (!mkdtemp(dir)) return -1;
    setenv("RIBBON_LOCK_DIR", dir, 1);
    gsl_set_error_handler_off();
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    test_dir_done(dir, all_passed, "test_ribbond_safety");
    return 0;
}

__attribute__((unused)) static void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

/* Overrides for a mock daemon on dir/NAME (its videos in dir/videos). */
typedef struct daemon_sets {
    char store[200], video[200];
    const char *ov[8];
    int n;
} daemon_sets;

static void sets_for(daemon_sets *s, const char *name)
{
    snprintf(s->store, sizeof s->store, "store.path=%s/%s", dir, name);
    snprintf(s->video, sizeof s->video, "camera.video_dir=%s/videos", dir);
    s->ov[0] = s->store;
    s->ov[1] = s->video;
    s->ov[2] = "api.port=0";
    s->ov[3] = "sim.nodes=61"; /* explicit resolution: no ladder */
    s->n = 4;
}

static void open_daemon(rig_daemon *d, daemon_sets *s)
{
    char why[1024];
    int rc = rig_daemon_open(d, RIBBON_SOURCE_DIR "/config/mock.ini", s->ov, s->n, NULL, why, sizeof why);
    if (rc) fail_msg("rig_daemon_open: %s", why);
}

/* Item 1. */
static void second_daemon_refused(void **state)
{
    (void)state;
    all_passed = 0;
    daemon_sets s;
    sets_for(&s, "one.db");
    rig_daemon first;
    open_daemon(&first, &s);
    /* The first daemon's trial, running. */
    char why[1024], db[128];
    snprintf(db, sizeof db, "%s/one.db", dir);
    store *st = NULL;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    store_trial_def def = store_trial_def_default();
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &def, &id, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, store_wall_now(), why, sizeof why),
                     STORE_OK);

    rig_daemon second;
    int rc = rig_daemon_open(&second, RIBBON_SOURCE_DIR "/config/mock.ini", s.ov, s.n, NULL, why, sizeof why);
    printf("second daemon: %s\n", rc ? why : "started");
    assert_int_not_equal(rc, 0);
    char pid[40];
    snprintf(pid, sizeof pid, "pid %ld since ", (long)getpid());
    assert_non_null(strstr(why, "in use by another daemon"));
    assert_non_null(strstr(why, pid));
    store_trial tr;
    assert_int_equal(store_trial_get(st, id, &tr, why, sizeof why), STORE_OK);
    assert_int_equal(tr.status, STORE_STATUS_RUNNING); /* not marked interrupted by the second */

    /* Read-only beside the daemon, as ribbonctl --db reads it. */
    store_open_params ro = store_open_params_default();
    ro.read_only = true;
    store *reader = NULL;
    assert_int_equal(store_open_ex(db, &ro, &reader, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_get(reader, id, &tr, why, sizeof why), STORE_OK);
    store_close(reader);
    store_close(st);

    rig_daemon_close(&first, "test done");
    open_daemon(&second, &s); /* free now; it marks the trial interrupted, as at any start-up */
    assert_int_equal(store_trial_get(second.st, id, &tr, why, sizeof why), STORE_OK);
    assert_int_equal(tr.status, STORE_STATUS_INTERRUPTED);
    rig_daemon_close(&second, "test done");
    all_passed = 1;
}

/* Item 4: in replay mode, POST /trials {"source_trial": ID} of a trial still running is 409 with
 * the reason (it was 201, and the replay read the half-written video). */
static void replay_of_running_trial_refused(void **state)
{
    (void)state;
    all_passed = 0;
    char set_store[200], why[1024], db[128];
    snprintf(db, sizeof db, "%s/replay.db", dir);
    snprintf(set_store, sizeof set_store, "store.path=%s", db);
    const char *ov[] = {set_store, "api.port=0"};
    rig_daemon d;
    int rc = rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/replay.ini", ov, 2, NULL, why, sizeof why);
    if (rc) fail_msg("rig_daemon_open: %s", why);
    store *st = NULL;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    store_trial_def def = store_trial_def_default();
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &def, &id, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, store_wall_now(), why, sizeof why),
                     STORE_OK);
    assert_int_equal(store_trial_set_state(st, id, "shearing", why, sizeof why), STORE_OK);
    api_ops ops = rig_daemon_ops();
    json_t *body = json_pack("{s:I}", "source_trial", (json_int_t)id), *out = NULL;
    int status = 0;
    rc = ops.start(&d, body, &out, &status, why, sizeof why);
    printf("replay of running trial %lld: %d %s\n", (long long)id, status, why);
    json_decref(body);
    json_decref(out);
    assert_int_not_equal(rc, 0);
    assert_int_equal(status, 409);
    assert_non_null(strstr(why, "is not finished (status running, state shearing)"));
    store_close(st);
    rig_daemon_close(&d, "test done");
    all_passed = 1;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(second_daemon_refused),
        cmocka_unit_test(replay_of_running_trial_refused),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
