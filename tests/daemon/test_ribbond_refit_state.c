/* test_ribbond_refit_state: what ribbond says between a specimen's trial ending done and its
 * specimen's refit being stored (daemon/trial/trial_session.c session_refit_specimen), through
 * the HTTP API on 127.0.0.1 in mock mode (config/mock.ini at N = 31 as
 * test_campaign_specimen_calib, sim.fit off: about 7 s of CPU per trial, the refit under 1 s).
 *
 * Two queue items of one specimen S-r run back to back (POST /queue, POST /queue/start):
 *   - while trial 1's specimen is refitted, GET /status names it: trial.state "done, refitting
 *     specimen S-r" and trial.refitting_specimen "S-r"; a plain "done" is never shown while the
 *     specimen has no calibration yet (before the fix the state read "done" for the whole refit);
 *   - a start by hand then is 409 with the reason (the refit, and what to do), not "abort it first";
 *     an abort then is 409 (the trial has ended) naming the refit, not "closing its camera";
 *   - the live bus carries the state "done, refitting specimen S-r", then "done" again;
 *   - the queue's next item did not start before the refit had stored: trial 2's prediction ran
 *     with the calibration from trial 1 (its record's calibration after_trial = trial 1).
 * Then trial 2 replayed (trial_replay.h, as `ribbonctl replay 2 --db` does, a few seconds): a
 * replay does not predict (no prediction row of its own) and its record says which prediction it
 * is compared with: trial 2's as stored, made with the specimen's calibration as it was then (from
 * trial 1: its values), not the specimen's calibration now (from trials 2 and 1). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <gsl/gsl_errno.h>

#include "api.h"
#include "live.h"
#include "rig_daemon.h"
#include "store.h"
#include "trial_replay.h"

#include "test_dir.h"

static char dir[64];
static json_int_t t1, t2; /* the two trials of S-r (refit_is_said) */

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

static int http(unsigned port, const char *method, const char *path, const char *body_text, json_t **out, char *why,
                size_t why_len)
{
    char url[64];
    snprintf(url, sizeof url, "http://127.0.0.1:%u", port);
    api_client_config c = api_client_config_default();
    c.base_url = url;
    json_t *body = body_text ? json_loads(body_text, 0, NULL) : NULL;
    if (body_text && !body) fail_msg("bad test body %s", body_text);
    int status = 0;
    *out = NULL;
    int rc = api_client_request(&c, method, path, body, &status, out, NULL, NULL, why, why_len);
    json_decref(body);
    if (rc) fail_msg("%s %s: %s", method, path, why);
    return status;
}

static json_t *get(unsigned port, const char *path)
{
    char why[512] = "";
    json_t *o = NULL;
    int st = http(port, "GET", path, NULL, &o, why, sizeof why);
    if (st != 200) fail_msg("GET %s: HTTP %d %s", path, st, why);
    return o;
}

static const char *jstr(const json_t *o, const char *k)
{
    const char *s = json_string_value(json_object_get(o, k));
    return s ? s : "";
}

static json_int_t add_item(unsigned port, const char *body)
{
    char why[512] = "";
    json_t *o = NULL;
    int st = http(port, "POST", "/queue", body, &o, why, sizeof why);
    if (st != 201) fail_msg("POST /queue %s: HTTP %d: %s", body, st, why);
    json_int_t id = json_integer_value(json_object_get(o, "id"));
    json_decref(o);
    return id;
}

static json_int_t item_trial(unsigned port, json_int_t item)
{
    char path[64];
    snprintf(path, sizeof path, "/queue/%lld", (long long)item);
    json_t *o = get(port, path);
    json_int_t t = json_integer_value(json_object_get(o, "trial_id"));
    if (!t) t = json_integer_value(json_object_get(json_object_get(o, "trial"), "id"));
    json_decref(o);
    return t;
}

/* The specimen's stored calibration is there (not null). */
static int calibrated(unsigned port)
{
    json_t *sp = get(port, "/specimens/S-r");
    int c = json_is_object(json_object_get(sp, "calibration"));
    json_decref(sp);
    return c;
}

static void refit_is_said(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/ribbond-refit-XXXXXX");
    assert_non_null(mkdtemp(dir));
    gsl_set_error_handler_off();
    char why[512] = "";
    assert_int_equal(api_client_global_init(why, sizeof why), 0);
    char set_store[128], set_video[128];
    snprintf(set_store, sizeof set_store, "store.path=%s/trials.db", dir);
    snprintf(set_video, sizeof set_video, "camera.video_dir=%s/videos", dir);
    const char *ov[] = {set_store, set_video, "api.port=0", "mesh.nodes=31", "sim.nodes=31", "sim.dt=2e-3",
                        "twin.mesh.nodes=31", "twin.solver.dt=2e-3", "twin.folds.hinge_stiffness=rigid", "sim.fit=off",
                        "sim.fit_hinge=0"};
    rig_daemon d;
    if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, 11, NULL, why, sizeof why))
        fail_msg("open: %s", why);
    unsigned port = 0;
    if (rig_daemon_serve(&d, &port, why, sizeof why)) fail_msg("serve: %s", why);

    json_t *o = NULL;
    assert_int_equal(http(port, "POST", "/specimens",
                          "{\"name\": \"S-r\", \"phi_deg\": 90, \"gamma\": 0.13, \"crease_orientation\": \"down\"}", &o,
                          why, sizeof why), 201);
    json_decref(o);
    json_int_t i1 = add_item(port, "{\"kind\": \"trial\", \"specimen\": \"S-r\", \"note\": \"first\"}");
    json_int_t i2 = add_item(port, "{\"kind\": \"trial\", \"specimen\": \"S-r\", \"note\": \"second\"}");
    assert_int_equal(http(port, "POST", "/queue/start", "{}", &o, why, sizeof why), 200);
    json_decref(o);

    /* Trial 1 to its end: every GET /status of it once it is done, and a start while it says so. */
    int saw_refitting = 0, plain_done_uncalibrated = 0, tried_start = 0;
    char last[160] = "";
    const double t0 = now_s();
    while (now_s() - t0 < 240.0) {
        json_t *s = get(port, "/status");
        const json_t *tr = json_object_get(s, "trial");
        json_int_t id = json_is_object(tr) ? json_integer_value(json_object_get(tr, "id")) : 0;
        char st[160];
        snprintf(st, sizeof st, "%s", jstr(tr, "state"));
        char refitting[80];
        snprintf(refitting, sizeof refitting, "%s", jstr(tr, "refitting_specimen"));
        json_decref(s);
        if (!t1 && id) t1 = id;
        if (t1 && id != t1) break; /* idle, or the next item's trial */
        if (strcmp(st, last)) printf("# %.2f s: trial %lld %s\n", now_s() - t0, (long long)id, st);
        snprintf(last, sizeof last, "%s", st);
        if (!strcmp(st, "done") && !calibrated(port)) plain_done_uncalibrated++;
        if (!strcmp(st, "done, refitting specimen S-r")) {
            assert_string_equal(refitting, "S-r");
            saw_refitting++;
            if (!tried_start) {
                tried_start = 1;
                int code = http(port, "POST", "/trials", "{\"specimen\": \"S-r\"}", &o, why, sizeof why);
                json_decref(o);
                printf("# a start while refitting: %d %s\n", code, why);
                assert_int_equal(code, 409);
                assert_non_null(strstr(why, "specimen S-r is being refitted"));
                assert_non_null(strstr(why, "GET /status is idle"));
                code = http(port, "POST", "/trials/current/abort", NULL, &o, why, sizeof why);
                json_decref(o);
                printf("# an abort while refitting: %d %s\n", code, why);
                assert_int_equal(code, 409);
                assert_non_null(strstr(why, "specimen S-r is being refitted"));
            }
        }
        sleep_s(0.01);
    }
    printf("# trial %lld: 'done, refitting specimen S-r' in %d status replies; plain 'done' before the calibration "
           "stored in %d\n", (long long)t1, saw_refitting, plain_done_uncalibrated);
    assert_true(t1 > 0);
    assert_int_equal(item_trial(port, i1), t1);
    assert_true(saw_refitting > 0);
    assert_int_equal(plain_done_uncalibrated, 0);
    assert_true(calibrated(port));

    /* The live bus: the refit's state, then done again. */
    uint64_t cursor = live_bus_first(d.bus), seq = 0, missed = 0;
    char buf[1100];
    int len, order = 0, refit_at = 0, done_after = 0;
    while ((len = live_bus_read(d.bus, &cursor, buf, sizeof buf, 0, &seq, &missed)) > 0) {
        json_t *m = json_loads(buf, 0, NULL);
        if (m && !strcmp(jstr(m, "type"), "state") && json_integer_value(json_object_get(m, "trial")) == t1) {
            order++;
            if (!strcmp(jstr(m, "state"), "done, refitting specimen S-r")) refit_at = order;
            if (!strcmp(jstr(m, "state"), "done") && refit_at && order > refit_at) done_after = order;
        }
        json_decref(m);
    }
    printf("# live bus: trial %lld's states: refitting %d, done after it %d\n", (long long)t1, refit_at, done_after);
    assert_true(refit_at > 0 && done_after > refit_at);

    /* The queue's second trial predicted with trial 1's calibration: it started after the refit stored. */
    for (double t = 0; t < 240.0 && !t2; t += 0.1) {
        t2 = item_trial(port, i2);
        if (!t2) sleep_s(0.1);
    }
    assert_true(t2 > t1);
    for (double t = 0; t < 240.0; t += 0.1) {
        json_t *s = get(port, "/status");
        int idle = !strcmp(jstr(s, "state"), "idle");
        json_decref(s);
        if (idle) break;
        sleep_s(0.1);
    }
    char path[64];
    snprintf(path, sizeof path, "/trials/%lld", (long long)t2);
    json_t *j2 = get(port, path);
    const json_t *pc = json_object_get(json_object_get(j2, "prediction"), "calibration");
    printf("# trial %lld's prediction: calibration after trial %lld\n", (long long)t2,
           (long long)json_integer_value(json_object_get(pc, "after_trial")));
    assert_true(json_is_object(pc));
    assert_int_equal(json_integer_value(json_object_get(pc, "after_trial")), t1);
    json_decref(j2);

    rig_daemon_close(&d, "test done");
    api_client_global_cleanup();
}

/* The value (%.6g) of key in a calibration's list (applied: "value"; the specimen's parameters: "value"). */
static void value_of(const json_t *list, const char *key, char *out, size_t n)
{
    out[0] = 0;
    for (size_t k = 0; k < json_array_size(list); k++)
        if (!strcmp(jstr(json_array_get(list, k), "key"), key))
            snprintf(out, n, "%s %.6g", key, json_number_value(json_object_get(json_array_get(list, k), "value")));
}

static void replay_says_its_prediction(void **state)
{
    (void)state;
    if (!t2) fail_msg("needs refit_is_said's trials");
    char path[128], why[512] = "";
    snprintf(path, sizeof path, "%s/trials.db", dir);
    store *st = NULL;
    assert_int_equal(store_open(path, &st, why, sizeof why), STORE_OK);
    trial_replay *r = NULL;
    if (trial_replay_from_trial(st, t2, NULL, &r, why, sizeof why)) fail_msg("replay: %s", why);
    int64_t nid = 0;
    trial_result res;
    if (trial_replay_run(r, st, NULL, NULL, NULL, &nid, &res, why, sizeof why)) fail_msg("replay: %s", why);
    trial_replay_free(r);
    json_t *rj = NULL, *j2 = NULL;
    assert_int_equal(store_trial_json(st, nid, &rj, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_json(st, t2, &j2, why, sizeof why), STORE_OK);
    store_specimen sp;
    assert_int_equal(store_specimen_get_by_name(st, "S-r", &sp, why, sizeof why), STORE_OK);
    json_t *now = json_loads(sp.calibration_json, 0, NULL);
    assert_non_null(now);
    const char *said = NULL;
    const json_t *evs = json_object_get(rj, "events");
    for (size_t k = 0; k < json_array_size(evs); k++)
        if (!strncmp(jstr(json_array_get(evs, k), "message"), "prediction: ", 12))
            said = jstr(json_array_get(evs, k), "message");
    printf("# replay %lld of trial %lld: %s\n", (long long)nid, (long long)t2, said ? said : "(no prediction event)");
    /* No prediction of its own. */
    store_prediction p = store_prediction_default();
    assert_int_equal(store_prediction_get_by_trial(st, nid, &p, why, sizeof why), STORE_E_NOTFOUND);
    store_prediction_free(&p);
    assert_non_null(said);
    char want[160];
    snprintf(want, sizeof want, "prediction: trial %lld's as stored (", (long long)t2);
    assert_non_null(strstr(said, want));
    assert_non_null(strstr(said, "the specimen's calibration as it was then (trials "));
    snprintf(want, sizeof want, "(trials %lld, ", (long long)t1);
    assert_non_null(strstr(said, want));
    /* Its values are the ones trial 2's prediction took (from trial 1), not the specimen's now. */
    const json_t *applied = json_object_get(json_object_get(json_object_get(j2, "prediction"), "calibration"), "applied");
    assert_true(json_array_size(applied) > 0);
    for (size_t k = 0; k < json_array_size(applied); k++) {
        const char *key = jstr(json_array_get(applied, k), "key");
        char then[96], later[96];
        value_of(applied, key, then, sizeof then);
        value_of(json_object_get(now, "parameters"), key, later, sizeof later);
        printf("#   %s (trial %lld's prediction); the specimen's now: %s\n", then, (long long)t2, later);
        assert_non_null(strstr(said, then));
        if (strcmp(then, later)) assert_null(strstr(said, later));
    }
    json_decref(now);
    json_decref(rj);
    json_decref(j2);
    store_close(st);
    test_dir_done(dir, 1, "refit state");
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(refit_is_said), cmocka_unit_test(replay_says_its_prediction)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
