/* test_ribbond_safety: ribbond's safety and data items of issue 33, in mock mode in this process
 * (config/mock.ini: mock rails on a virtual clock; the API's operations called directly).
 *   1. One daemon per store: a second rig_daemon_open on the store of a running one is refused
 *      naming the holder (pid, since when) and leaves the first one's running trial as it is;
 *      the store stays readable beside it (ribbonctl --db's read-only open); once the first has
 *      closed, the second starts.
 *   3. A full store disk mid-trial (an SQLite VFS shim refusing writes: store_full_vfs.h): the
 *      trial's final status is written by the daemon's first operation after the disk has room
 *      again, and a daemon closed before that leaves it to the next start-up (interrupted).
 *   4. A replay of a trial that is still running is refused with 409 and the reason.
 *  13. An abort of a trial that has ended while its session still closes is 409, not 200.
 * And issue 34 A: a rail is homed or its zero confirmed through the API between trials only. */
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
#include "store_full_vfs.h"
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

static void sleep_s(double s)
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

/* The daemon's status: "no trial" when idle, else the running trial's state. */
static void daemon_state(rig_daemon *d, char *out, size_t n)
{
    api_ops ops = rig_daemon_ops();
    json_t *o = NULL;
    char why[256];
    assert_int_equal(ops.status(d, &o, why, sizeof why), 0);
    json_t *t = json_object_get(o, "trial");
    const char *st = json_is_object(t) ? json_string_value(json_object_get(t, "state")) : "no trial";
    snprintf(out, n, "%s", st ? st : "?");
    json_decref(o);
}

/* Polls the daemon's status until it is idle (want_idle) or a trial has begun moving. */
static int wait_state(rig_daemon *d, int want_idle, double max_s)
{
    char st[32];
    for (double t = 0; t < max_s; t += 0.05) {
        daemon_state(d, st, sizeof st);
        if (want_idle ? !strcmp(st, "no trial") : strcmp(st, "no trial") && strcmp(st, "idle")) return 1;
        sleep_s(0.05);
    }
    return 0;
}

static int64_t start_trial(rig_daemon *d)
{
    api_ops ops = rig_daemon_ops();
    json_t *body = json_object(), *out = NULL;
    int status = 0;
    char why[512];
    int rc = ops.start(d, body, &out, &status, why, sizeof why);
    json_decref(body);
    if (rc) fail_msg("start: %d %s", status, why);
    int64_t id = json_integer_value(json_object_get(out, "id"));
    json_decref(out);
    return id;
}

/* Item 3: the store's disk fills in the middle of a trial (the VFS shim refuses every write): the
 * trial fails (rails stopped), its final status cannot be written, and the row says running; the
 * first operation after the disk has room again writes it (failed, with the reason and its own
 * end time, and an event saying it came late). A daemon closed while the disk is still full
 * leaves the row to the next start-up, which marks it interrupted. */
static void full_disk_final_status_written_later(void **state)
{
    (void)state;
    all_passed = 0;
    assert_int_equal(store_full_vfs_install(), 0);
    daemon_sets s;
    sets_for(&s, "full.db");
    rig_daemon d;
    open_daemon(&d, &s);
    int64_t id = start_trial(&d);
    assert_true(wait_state(&d, 0, 60.0));
    store_full_vfs_set(1);
    assert_true(wait_state(&d, 1, 120.0)); /* the trial ended */
    long refused = store_full_vfs_refused();
    char why[512], st[32];
    store_trial tr;
    assert_int_equal(store_trial_get(d.st, id, &tr, why, sizeof why), STORE_OK);
    printf("disk full: %ld writes refused; trial %lld reads %s / %s\n", refused, (long long)id,
           store_status_name(tr.status), tr.state);
    assert_true(refused > 0);
    assert_int_equal(tr.status, STORE_STATUS_RUNNING); /* the store could not take the end */
    store_full_vfs_set(0);
    daemon_state(&d, st, sizeof st); /* the next operation */
    assert_string_equal(st, "no trial");
    assert_int_equal(store_trial_get(d.st, id, &tr, why, sizeof why), STORE_OK);
    printf("after the disk has room: trial %lld reads %s / %s: %s (ended %s)\n", (long long)id,
           store_status_name(tr.status), tr.state, tr.reason, tr.ended_at);
    assert_int_equal(tr.status, STORE_STATUS_FAILED);
    assert_string_equal(tr.state, "failed");
    assert_non_null(strstr(tr.reason, "full"));
    assert_true(tr.ended_at[0] != '\0');
    store_event *ev = NULL;
    size_t n = 0;
    assert_int_equal(store_events_get(d.st, id, &ev, &n, why, sizeof why), STORE_OK);
    assert_true(n > 0);
    assert_non_null(strstr(ev[n - 1].message, "stored late"));
    free(ev);

    /* Full again; the daemon is closed before the disk has room: the next start-up. */
    id = start_trial(&d);
    assert_true(wait_state(&d, 0, 60.0));
    store_full_vfs_set(1);
    assert_true(wait_state(&d, 1, 120.0));
    rig_daemon_close(&d, "test done");
    store_full_vfs_set(0);
    open_daemon(&d, &s);
    assert_int_equal(store_trial_get(d.st, id, &tr, why, sizeof why), STORE_OK);
    printf("closed while full, then restarted: trial %lld reads %s: %s\n", (long long)id, store_status_name(tr.status),
           tr.reason);
    assert_int_equal(tr.status, STORE_STATUS_INTERRUPTED);
    rig_daemon_close(&d, "test done");
    all_passed = 1;
}

/* Item 13 (its last part): a trial that has ended but whose session is still closing (here: its
 * prediction still computing; in rig mode a dead camera's close) is not aborted with 200
 * "requested": 409, it has already ended. The shear rail left off its zero fails the trial at
 * once; the prediction beside it runs on at fixed steps of 0.2 ms. */
static void abort_of_an_ended_trial_refused(void **state)
{
    (void)state;
    all_passed = 0;
    daemon_sets s;
    sets_for(&s, "ended.db");
    s.ov[s.n++] = "rail.shear.start_mm=60";
    s.ov[s.n++] = "sim.fast=off";
    s.ov[s.n++] = "solver.dt=2e-4";
    rig_daemon d;
    open_daemon(&d, &s);
    int64_t id = start_trial(&d);
    api_ops ops = rig_daemon_ops();
    char st[32] = "", why[512] = "";
    double waited = 0;
    for (; waited < 60.0; waited += 0.02) {
        daemon_state(&d, st, sizeof st);
        if (!strcmp(st, "failed") || !strcmp(st, "no trial")) break;
        sleep_s(0.02);
    }
    printf("trial %lld: %s after %.2f s\n", (long long)id, st, waited);
    assert_string_equal(st, "failed"); /* ended, the session still closing */
    json_t *out = NULL;
    int status = 0;
    int rc = ops.abort_current(&d, &out, &status, why, sizeof why);
    printf("abort: %d %s\n", rc ? status : 200, rc ? why : "requested");
    json_decref(out);
    assert_int_not_equal(rc, 0);
    assert_int_equal(status, 409);
    assert_non_null(strstr(why, "has already ended failed"));
    /* The store follows the runner's state within moments (its final status comes before the
     * session closes anything). */
    store_trial tr;
    for (int k = 0; k < 100; k++) {
        assert_int_equal(store_trial_get(d.st, id, &tr, why, sizeof why), STORE_OK);
        if (tr.status != STORE_STATUS_RUNNING) break;
        sleep_s(0.05);
    }
    assert_int_equal(tr.status, STORE_STATUS_FAILED);
    rig_daemon_close(&d, "test done");
    all_passed = 1;
}

/* POST /rails/NAME/{home,confirm-zero} through the op (issue 34 A: a restarted ribbond refuses to
 * move a rail whose position is not trusted, and holds its lock: it must home or confirm it):
 * an explicit confirm is required, an unknown rail is 404, a running trial makes it 409, and
 * between trials a mock rail homes (202) while confirm-zero is refused as for a non-G-code rail. */
static int rail_op(rig_daemon *d, const char *path, int confirm, int *status, char *why, size_t n)
{
    api_ops ops = rig_daemon_ops();
    assert_non_null(ops.rail);
    json_t *body = confirm ? json_pack("{s:b}", "confirm", 1) : json_object(), *out = NULL;
    *status = 200;
    int rc = ops.rail(d, path, body, &out, status, why, n);
    printf("%s: %d %s\n", path, *status, rc ? why : "ok");
    if (rc == 0) {
        char *txt = json_dumps(out, JSON_COMPACT);
        snprintf(why, n, "%s", txt ? txt : "");
        free(txt);
    }
    json_decref(body);
    json_decref(out);
    return rc;
}

static void rails_homed_or_confirmed_between_trials_only(void **state)
{
    (void)state;
    all_passed = 0;
    daemon_sets s;
    sets_for(&s, "rails.db");
    rig_daemon d;
    open_daemon(&d, &s);
    char why[512];
    int status = 0;
    assert_int_not_equal(rail_op(&d, "/rails/shear/home", 0, &status, why, sizeof why), 0);
    assert_int_equal(status, 400);
    assert_non_null(strstr(why, "confirm"));
    assert_int_not_equal(rail_op(&d, "/rails/nope/home", 1, &status, why, sizeof why), 0);
    assert_int_equal(status, 404);
    assert_non_null(strstr(why, "no rail named 'nope'"));
    assert_int_not_equal(rail_op(&d, "/rails/shear/jog", 1, &status, why, sizeof why), 0);
    assert_int_equal(status, 404);

    start_trial(&d);
    assert_true(wait_state(&d, 0, 20.0));
    assert_int_not_equal(rail_op(&d, "/rails/shear/home", 1, &status, why, sizeof why), 0);
    assert_int_equal(status, 409);
    assert_non_null(strstr(why, "is running"));
    assert_int_not_equal(rail_op(&d, "/rails/compress/confirm-zero", 1, &status, why, sizeof why), 0);
    assert_int_equal(status, 409);
    api_ops ops = rig_daemon_ops();
    json_t *out = NULL;
    assert_int_equal(ops.abort_current(&d, &out, &status, why, sizeof why), 0);
    json_decref(out);
    assert_true(wait_state(&d, 1, 30.0));

    assert_int_not_equal(rail_op(&d, "/rails/shear/confirm-zero", 1, &status, why, sizeof why), 0);
    assert_int_equal(status, 409);
    assert_non_null(strstr(why, "not a G-code rail"));
    assert_int_equal(rail_op(&d, "/rails/shear/home", 1, &status, why, sizeof why), 0);
    assert_int_equal(status, 202);
    assert_non_null(strstr(why, "\"action\":\"home\""));
    rig_daemon_close(&d, "test done");
    all_passed = 1;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(second_daemon_refused),
        cmocka_unit_test(replay_of_running_trial_refused),
        cmocka_unit_test(full_disk_final_status_written_later),
        cmocka_unit_test(abort_of_an_ended_trial_refused),
        cmocka_unit_test(rails_homed_or_confirmed_between_trials_only),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
