/* test_ribbond_queue: the campaign (issue 35, parts A and B) through ribbond's API in mock mode
 * (config/mock.ini, explicit resolution so no ladder is computed).
 *   1. Specimens: added (a second add of the name 409), listed, shown; a start naming an unknown
 *      specimen is 400 and a retired one 409 (named by --specimen or by its specimen.name key),
 *      named and nothing started.
 *   2. A mixed queue runs through: a trial of S-12, an operator step asking S-12's measured
 *      crease angles, a pause, a second trial. While the first trial runs it can be neither
 *      removed nor moved (409); the operator step holds the queue until confirmed, and a
 *      confirmation with angles that cannot be clamped is refused naming the field; the pause
 *      stops the queue, saying so, until it is started again; the second trial's prediction
 *      uses the confirmed angles (source 'specimen'); a trial started by hand makes the started
 *      queue wait for its end; the queue stops when it runs out, and when a trial of it is
 *      aborted (the item aborted, the reason given, the next item still queued). Every
 *      item ends done; GET /queue/ID returns the item with its trial.
 *   3. kill -9 of ribbond while a queue item's trial runs: the restart leaves the store intact
 *      (integrity_check), the trial interrupted, the item 'unknown', the queue stopped saying
 *      why, the next item still queued, and nothing moves by itself. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <signal.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>

#include "api.h"
#include "rig_daemon.h"
#include "store.h"

static char dir[64];
static char set_store[256], set_video[256];

static void overrides(const char **ov, int *n)
{
    ov[0] = set_store;
    ov[1] = set_video;
    ov[2] = "api.port=0";
    ov[3] = "sim.nodes=61"; /* explicit resolution: no ladder */
    *n = 4;
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/ribbond-queue-XXXXXX");
    assert_non_null(mkdtemp(dir));
    snprintf(set_video, sizeof set_video, "camera.video_dir=%s/videos", dir);
    gsl_set_error_handler_off();
    char why[256];
    assert_int_equal(api_client_global_init(why, sizeof why), 0);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    api_client_global_cleanup();
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static int http(unsigned port, const char *method, const char *path, const char *body_text, json_t **out, char *why,
                size_t why_len)
{
    char url[64];
    snprintf(url, sizeof url, "http://127.0.0.1:%u", port);
    api_client_config c = api_client_config_default();
    c.base_url = url;
    json_t *body = NULL;
    if (body_text) {
        json_error_t je;
        body = json_loads(body_text, 0, &je);
        if (!body) fail_msg("bad test body %s: %s", body_text, je.text);
    }
    int status = 0;
    if (out) *out = NULL;
    int rc = api_client_request(&c, method, path, body, &status, out, NULL, NULL, why, why_len);
    json_decref(body);
    assert_int_equal(rc, 0);
    return status;
}

/* The request's status must be want; the reply is dropped (why keeps an error's message). */
static void expect(unsigned port, const char *method, const char *path, const char *body, int want, char *why,
                   size_t why_len)
{
    json_t *o = NULL;
    int st = http(port, method, path, body, &o, why, why_len);
    if (st != want) fail_msg("%s %s %s: HTTP %d, wanted %d: %s", method, path, body ? body : "", st, want, why);
    json_decref(o);
}

static void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

static json_int_t add_item(unsigned port, const char *body)
{
    char why[512];
    json_t *o = NULL;
    int st = http(port, "POST", "/queue", body, &o, why, sizeof why);
    if (st != 201) fail_msg("POST /queue %s: HTTP %d: %s", body, st, why);
    json_int_t id = json_integer_value(json_object_get(o, "id"));
    assert_string_equal(json_string_value(json_object_get(o, "status")), "queued");
    json_decref(o);
    return id;
}

static json_t *item(unsigned port, json_int_t id)
{
    char why[512], path[64];
    json_t *o = NULL;
    snprintf(path, sizeof path, "/queue/%lld", (long long)id);
    assert_int_equal(http(port, "GET", path, NULL, &o, why, sizeof why), 200);
    return o;
}

static const char *jstr(const json_t *o, const char *k) { return json_string_value(json_object_get(o, k)); }

/* Waits (at most max_s) until item id has status want; returns the item. */
static json_t *wait_item(unsigned port, json_int_t id, const char *want, double max_s)
{
    for (double t = 0; t < max_s; t += 0.1) {
        json_t *o = item(port, id);
        if (!strcmp(jstr(o, "status"), want)) return o;
        json_decref(o);
        sleep_s(0.1);
    }
    json_t *o = item(port, id);
    fail_msg("queue item %lld is %s after %g s, wanted %s (%s)", (long long)id, jstr(o, "status"), max_s, want,
             jstr(o, "reason") ? jstr(o, "reason") : "");
    return NULL;
}

static json_t *queue_state(unsigned port)
{
    char why[256];
    json_t *o = NULL;
    assert_int_equal(http(port, "GET", "/queue", NULL, &o, why, sizeof why), 200);
    return o;
}

static int wait_queue_stopped(unsigned port, double max_s)
{
    for (double t = 0; t < max_s; t += 0.1) {
        json_t *q = queue_state(port);
        int running = json_is_true(json_object_get(q, "running"));
        json_decref(q);
        if (!running) return 1;
        sleep_s(0.1);
    }
    return 0;
}

static void specimens(unsigned port)
{
    char why[512];
    json_t *o = NULL;
    expect(port, "POST", "/specimens", "{\"name\": \"S-12\", \"phi_deg\": 90, \"gamma\": 0.13}", 201, why, sizeof why);
    expect(port, "POST", "/specimens", "{\"name\": \"S-12\", \"phi_deg\": 90, \"gamma\": 0.13}", 409, why, sizeof why);
    assert_non_null(strstr(why, "exists"));
    expect(port, "POST", "/specimens", "{\"name\": \"S 13\", \"phi_deg\": 90, \"gamma\": 0.13}", 400, why, sizeof why);
    expect(port, "POST", "/specimens", "{\"name\": \"S-13\", \"phi_deg\": 190, \"gamma\": 0.13}", 400, why, sizeof why);
    assert_non_null(strstr(why, "phi_deg"));
    expect(port, "POST", "/specimens", "{\"name\": \"S-13\", \"phi_deg\": 90, \"gamma\": 0.13, \"colour\": 1}", 400, why,
           sizeof why);
    assert_non_null(strstr(why, "colour"));
    expect(port, "POST", "/specimens", "{\"name\": \"OLD-1\", \"phi_deg\": 90, \"gamma\": 0.2}", 201, why, sizeof why);
    expect(port, "POST", "/specimens/OLD-1/retire", "{\"reason\": \"creased twice\"}", 200, why, sizeof why);
    expect(port, "POST", "/specimens/OLD-1/retire", "{\"reason\": \"again\"}", 409, why, sizeof why);
    expect(port, "GET", "/specimens/OLD-1/retire", NULL, 405, why, sizeof why);
    assert_int_equal(http(port, "GET", "/specimens", NULL, &o, why, sizeof why), 200);
    assert_int_equal(json_array_size(o), 2);
    json_decref(o);
    assert_int_equal(http(port, "GET", "/specimens/S-12", NULL, &o, why, sizeof why), 200);
    assert_string_equal(jstr(o, "state"), "new");
    assert_true(json_real_value(json_object_get(o, "phi_deg")) == 90.0);
    assert_true(json_is_array(json_object_get(o, "trials")));
    json_decref(o);
    expect(port, "GET", "/specimens/NOPE", NULL, 404, why, sizeof why);
    /* Trials naming an unknown or retired specimen: named, nothing started. */
    expect(port, "POST", "/trials", "{\"specimen\": \"NOPE\"}", 400, why, sizeof why);
    assert_non_null(strstr(why, "unknown specimen 'NOPE'"));
    expect(port, "POST", "/trials", "{\"specimen\": \"OLD-1\"}", 409, why, sizeof why);
    assert_non_null(strstr(why, "retired"));
    expect(port, "POST", "/trials", "{\"set\": [\"specimen.name=OLD-1\"]}", 409, why, sizeof why); /* named by key */
    assert_non_null(strstr(why, "specimen 'OLD-1' is retired"));
    expect(port, "POST", "/queue", "{\"kind\": \"trial\", \"specimen\": \"OLD-1\"}", 400, why, sizeof why);
    assert_non_null(strstr(why, "retired"));
    assert_int_equal(http(port, "GET", "/trials", NULL, &o, why, sizeof why), 200);
    assert_int_equal(json_array_size(o), 0);
    json_decref(o);
}

static void mixed_queue_runs_through(void **state)
{
    (void)state;
    snprintf(set_store, sizeof set_store, "store.path=%s/queue.db", dir);
    const char *ov[8];
    int nov;
    overrides(ov, &nov);
    rig_daemon d;
    char why[512];
    unsigned port = 0;
    if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why) ||
        rig_daemon_serve(&d, &port, why, sizeof why))
        fail_msg("ribbond: %s", why);
    specimens(port);

    json_int_t t1 = add_item(port, "{\"kind\": \"trial\", \"specimen\": \"S-12\", \"note\": \"first\"}");
    json_int_t op = add_item(port, "{\"kind\": \"operator\", \"specimen\": \"S-12\", \"prompt\": \"remount S-12, "
                                   "measured angles?\", \"fields\": [\"crease_angle_left_deg\", "
                                   "\"crease_angle_right_deg\"]}");
    json_int_t pa = add_item(port, "{\"kind\": \"pause\", \"note\": \"look at the strip\"}");
    json_int_t t2 = add_item(port, "{\"kind\": \"trial\", \"specimen\": \"S-12\", \"note\": \"second\"}");
    expect(port, "POST", "/queue", "{\"kind\": \"operator\", \"prompt\": \"x\", \"fields\": [\"colour\"]}", 400, why,
           sizeof why);
    expect(port, "POST", "/queue", "{\"kind\": \"trial\", \"specimen\": \"S-12\", \"set\": [\"store.path=/x\"]}", 400,
           why, sizeof why);
    assert_non_null(strstr(why, "store"));
    json_t *q = queue_state(port);
    assert_false(json_is_true(json_object_get(q, "running")));
    assert_int_equal(json_array_size(json_object_get(q, "queued")), 4);
    json_decref(q);

    expect(port, "POST", "/queue/start", "{}", 200, why, sizeof why);
    json_t *it = wait_item(port, t1, "running", 10);
    json_decref(it);
    char path[64];
    snprintf(path, sizeof path, "/queue/%lld/remove", (long long)t1);
    expect(port, "POST", path, "{}", 409, why, sizeof why);
    assert_non_null(strstr(why, "is running: it can't be removed"));
    snprintf(path, sizeof path, "/queue/%lld/move", (long long)t1);
    expect(port, "POST", path, "{\"position\": 2}", 409, why, sizeof why);
    assert_non_null(strstr(why, "is running: it can't be moved"));
    /* A trial started by hand while the queue's runs: refused. */
    expect(port, "POST", "/trials", "{}", 409, why, sizeof why);

    it = wait_item(port, t1, "done", 240);
    json_t *tr = json_object_get(it, "trial");
    assert_true(json_is_object(tr));
    assert_string_equal(jstr(tr, "status"), "done");
    assert_string_equal(jstr(tr, "specimen"), "S-12");
    json_decref(it);

    it = wait_item(port, op, "running", 10);
    assert_string_equal(jstr(it, "waiting"), "for the operator's confirmation");
    json_decref(it);
    sleep_s(0.6); /* the queue waits: the pause has not been reached */
    it = item(port, pa);
    assert_string_equal(jstr(it, "status"), "queued");
    json_decref(it);
    snprintf(path, sizeof path, "/queue/%lld/confirm", (long long)op);
    expect(port, "POST", path, "{\"values\": {\"crease_angle_left_deg\": 200, \"crease_angle_right_deg\": 91}}", 400,
           why, sizeof why);
    assert_non_null(strstr(why, "crease_angle_left_deg"));
    expect(port, "POST", path, "{\"values\": {\"crease_angle_left_deg\": 89}}", 400, why, sizeof why);
    assert_non_null(strstr(why, "crease_angle_right_deg"));
    snprintf(path, sizeof path, "/queue/%lld/confirm", (long long)t2);
    expect(port, "POST", path, "{\"values\": {}}", 409, why, sizeof why);
    snprintf(path, sizeof path, "/queue/%lld/confirm", (long long)op);
    expect(port, "POST", path, "{\"values\": {\"crease_angle_left_deg\": 89, \"crease_angle_right_deg\": 91}}", 200,
           why, sizeof why);

    /* The pause stops the queue, saying so; the second trial waits. */
    assert_true(wait_queue_stopped(port, 10));
    q = queue_state(port);
    assert_non_null(strstr(jstr(q, "reason"), "paused by item"));
    assert_non_null(strstr(jstr(q, "reason"), "look at the strip"));
    json_decref(q);
    it = item(port, pa);
    assert_string_equal(jstr(it, "status"), "done");
    json_decref(it);
    it = item(port, t2);
    assert_string_equal(jstr(it, "status"), "queued");
    json_decref(it);

    /* A trial started by hand: the started queue waits for its end instead of failing its item. */
    json_t *manual = NULL;
    assert_int_equal(http(port, "POST", "/trials", "{\"note\": \"by hand\"}", &manual, why, sizeof why), 201);
    json_decref(manual);
    expect(port, "POST", "/queue/start", NULL, 200, why, sizeof why);
    sleep_s(1.0);
    it = item(port, t2);
    assert_string_equal(jstr(it, "status"), "queued");
    json_decref(it);
    q = queue_state(port);
    assert_true(json_is_true(json_object_get(q, "running")));
    json_decref(q);
    expect(port, "POST", "/trials/current/abort", NULL, 200, why, sizeof why);
    it = wait_item(port, t2, "done", 240);
    json_int_t tid2 = json_integer_value(json_object_get(it, "trial_id"));
    json_t *sr = json_object_get(it, "specimen_record");
    assert_true(json_real_value(json_object_get(sr, "crease_angle_left_deg")) == 89.0);
    json_decref(it);
    assert_true(wait_queue_stopped(port, 10));
    q = queue_state(port);
    assert_non_null(strstr(jstr(q, "reason"), "ran to its end"));
    assert_int_equal(json_array_size(json_object_get(q, "queued")), 0);
    assert_int_equal(json_array_size(json_object_get(q, "history")), 4);
    json_decref(q);

    /* The second trial's prediction used the confirmed angles (signed as the scene's, -90). */
    sqlite3 *h = store_handle(d.st);
    sqlite3_stmt *s = NULL;
    assert_int_equal(sqlite3_prepare_v2(h,
                                        "SELECT crease_angle_left_deg, crease_angle_left_from, crease_angle_right_deg"
                                        " FROM predictions WHERE trial_id = ?",
                                        -1, &s, NULL),
                     SQLITE_OK);
    sqlite3_bind_int64(s, 1, tid2);
    assert_int_equal(sqlite3_step(s), SQLITE_ROW);
    printf("second trial %lld: prediction creases %g (%s), %g\n", (long long)tid2, sqlite3_column_double(s, 0),
           sqlite3_column_text(s, 1), sqlite3_column_double(s, 2));
    assert_true(sqlite3_column_double(s, 0) == -89.0);
    assert_string_equal((const char *)sqlite3_column_text(s, 1), "specimen");
    assert_true(sqlite3_column_double(s, 2) == -91.0);
    sqlite3_finalize(s);
    json_t *sp = NULL;
    assert_int_equal(http(port, "GET", "/specimens/S-12", NULL, &sp, why, sizeof why), 200);
    assert_string_equal(jstr(sp, "state"), "in use");
    assert_int_equal(json_array_size(json_object_get(sp, "trials")), 2); /* not the one by hand */
    json_decref(sp);

    /* A queue trial aborted: the item ends aborted and the queue stops, saying why. */
    json_int_t t3 = add_item(port, "{\"kind\": \"trial\", \"specimen\": \"S-12\", \"note\": \"third\"}");
    add_item(port, "{\"kind\": \"pause\"}");
    expect(port, "POST", "/queue/start", "{}", 200, why, sizeof why);
    it = wait_item(port, t3, "running", 10);
    json_decref(it);
    for (int k = 0; k < 100; k++) { /* its trial may still be starting */
        json_t *o = NULL;
        if (http(port, "POST", "/trials/current/abort", NULL, &o, why, sizeof why) == 200) {
            json_decref(o);
            break;
        }
        json_decref(o);
        sleep_s(0.1);
    }
    it = wait_item(port, t3, "aborted", 60);
    json_decref(it);
    assert_true(wait_queue_stopped(port, 10));
    q = queue_state(port);
    assert_non_null(strstr(jstr(q, "reason"), "ended aborted"));
    assert_non_null(strstr(jstr(q, "reason"), "check the rig"));
    assert_int_equal(json_array_size(json_object_get(q, "queued")), 1); /* the pause after it waits */
    json_decref(q);
    rig_daemon_close(&d, "test done");
}

static int64_t q_int(sqlite3 *h, const char *sql)
{
    sqlite3_stmt *s = NULL;
    int64_t v = -1;
    if (sqlite3_prepare_v2(h, sql, -1, &s, NULL) == SQLITE_OK && sqlite3_step(s) == SQLITE_ROW)
        v = sqlite3_column_int64(s, 0);
    sqlite3_finalize(s);
    return v;
}

static void kill9_mid_item(void **state)
{
    (void)state;
    char db[128];
    snprintf(db, sizeof db, "%s/killed.db", dir);
    snprintf(set_store, sizeof set_store, "store.path=%s", db);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        const char *ov[8];
        int nov;
        overrides(ov, &nov);
        rig_daemon d;
        char why[512];
        unsigned port = 0;
        if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why)) _exit(3);
        if (rig_daemon_serve(&d, &port, why, sizeof why)) _exit(4);
        store_specimen sp = store_specimen_default();
        snprintf(sp.name, sizeof sp.name, "K-1");
        sp.length_m = 0.2;
        sp.width_m = 0.005;
        sp.thickness_m = 2.5e-4;
        sp.phi_deg = 90;
        sp.fold_position = 0.13;
        int64_t sid = 0;
        if (store_specimen_upsert(d.st, &sp, &sid, why, sizeof why)) _exit(5);
        for (int k = 0; k < 2; k++) {
            store_queue_item it = store_queue_item_default();
            it.kind = STORE_QUEUE_TRIAL;
            it.specimen_id = sid;
            if (store_queue_add(d.st, &it, store_wall_now(), NULL, why, sizeof why)) _exit(6);
        }
        if (store_queue_state_set(d.st, true, "started by the test", store_wall_now(), why, sizeof why)) _exit(7);
        for (;;) pause();
    }
    /* Wait until the first item's trial is well under way, then kill without warning. */
    int64_t trial = 0, seen = 0;
    for (int k = 0; k < 1200 && seen < 200; k++) {
        sleep_s(0.1);
        sqlite3 *h = NULL;
        if (sqlite3_open_v2(db, &h, SQLITE_OPEN_READONLY, NULL) != SQLITE_OK) {
            sqlite3_close(h);
            continue;
        }
        sqlite3_busy_timeout(h, 1000);
        trial = q_int(h, "SELECT trial_id FROM queue_items WHERE status = 'running' AND trial_id IS NOT NULL");
        if (trial > 0) {
            char sql[128];
            snprintf(sql, sizeof sql, "SELECT count(*) FROM samples WHERE trial_id = %lld", (long long)trial);
            seen = q_int(h, sql);
        }
        sqlite3_close(h);
    }
    kill(pid, SIGKILL);
    int ws;
    waitpid(pid, &ws, 0);
    assert_true(WIFSIGNALED(ws));
    assert_true(trial > 0 && seen >= 200);

    const char *ov[8];
    int nov;
    overrides(ov, &nov);
    rig_daemon d;
    char why[512];
    unsigned port = 0;
    if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why) ||
        rig_daemon_serve(&d, &port, why, sizeof why))
        fail_msg("restart: %s", why);
    sqlite3 *h = store_handle(d.st);
    sqlite3_stmt *s = NULL;
    assert_int_equal(sqlite3_prepare_v2(h, "PRAGMA integrity_check", -1, &s, NULL), SQLITE_OK);
    assert_int_equal(sqlite3_step(s), SQLITE_ROW);
    assert_string_equal((const char *)sqlite3_column_text(s, 0), "ok");
    sqlite3_finalize(s);
    store_trial tr;
    assert_int_equal(store_trial_get(d.st, trial, &tr, why, sizeof why), STORE_OK);
    assert_int_equal(tr.status, STORE_STATUS_INTERRUPTED);
    json_t *q = queue_state(port);
    assert_false(json_is_true(json_object_get(q, "running")));
    printf("after kill -9 of trial %lld (%lld samples seen): queue stopped: %s\n", (long long)trial, (long long)seen,
           jstr(q, "reason"));
    assert_non_null(strstr(jstr(q, "reason"), "found running"));
    assert_true(json_is_null(json_object_get(q, "current")));
    assert_int_equal(json_array_size(json_object_get(q, "queued")), 1);
    json_t *hist = json_array_get(json_object_get(q, "history"), 0);
    assert_string_equal(jstr(hist, "status"), "unknown");
    assert_int_equal(json_integer_value(json_object_get(hist, "trial_id")), trial);
    json_decref(q);
    /* Nothing moves by itself: no new trial, the next item still queued. */
    sleep_s(1.0);
    assert_int_equal(q_int(h, "SELECT count(*) FROM trials"), 1);
    assert_int_equal(q_int(h, "SELECT count(*) FROM queue_items WHERE status = 'queued'"), 1);
    assert_int_equal(q_int(h, "SELECT count(*) FROM queue_items WHERE status = 'running'"), 0);
    json_t *st = NULL;
    assert_int_equal(http(port, "GET", "/status", NULL, &st, why, sizeof why), 200);
    assert_string_equal(jstr(st, "state"), "idle");
    assert_false(json_is_true(json_object_get(json_object_get(st, "queue"), "running")));
    json_decref(st);
    rig_daemon_close(&d, "test done");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(mixed_queue_runs_through),
        cmocka_unit_test(kill9_mid_item),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
