/* test_trial_prediction: a prediction beside a trial that fails is stored as failed (issue 31):
 * the thread's simulation refused (a scene at N = 4, which rod_predict's scene check refuses
 * without simulating anything) reports TRIAL_PREDICTION_FAILED once, and leaves in the store a
 * warning event "prediction failed: ..." and a prediction row with status failed, the reason,
 * no snap, no curve, and the creases it was given with their sources; the same through
 * trial_prediction_store_failed, the path of a prediction that fails before its thread. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "test_dir.h"
#include "trial_prediction.h"

static char dir[64], db[128];

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/ribbon-prediction-XXXXXX");
    if (!mkdtemp(dir)) return -1;
    snprintf(db, sizeof db, "%s/trials.db", dir);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    test_dir_done(dir, 1, "prediction store");
    return 0;
}

static int64_t new_trial(void)
{
    store *st = NULL;
    char why[256];
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    store_trial_def d = store_trial_def_default();
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &d, &id, why, sizeof why), STORE_OK);
    store_close(st);
    return id;
}

typedef struct seen {
    int calls;
    trial_prediction_outcome outcome;
    char message[512];
} seen;

static void on_done(void *user, const trial_prediction_report *r)
{
    seen *s = user;
    s->calls++;
    s->outcome = r->outcome;
    snprintf(s->message, sizeof s->message, "%s", r->message);
}

static trial_prediction_def failing_def(int64_t trial, seen *s)
{
    trial_prediction_def def;
    memset(&def, 0, sizeof def);
    def.scene = rod_scene_default();
    def.scene.nodes = 4; /* rod_scene_check: "needs at least 5 nodes" */
    def.est_error = NAN;
    snprintf(def.hash, sizeof def.hash, "test-hash");
    snprintf(def.store_path, sizeof def.store_path, "%s", db);
    def.trial_id = trial;
    def.done = on_done;
    def.user = s;
    def.creases = store_creases_unknown();
    def.creases.angle_deg[0] = -88.0;
    def.creases.angle_from[0] = STORE_SOURCE_SPECIMEN;
    def.creases.angle_deg[1] = -90.0;
    def.creases.angle_from[1] = STORE_SOURCE_SCENE;
    def.creases.position[0] = 0.13;
    def.creases.position_from[0] = STORE_SOURCE_SCENE;
    def.creases.position[1] = 0.87;
    def.creases.position_from[1] = STORE_SOURCE_SCENE;
    return def;
}

/* The trial's latest prediction is failed with `needle` in its reason, a matching warning event. */
static void expect_failed(int64_t trial, const char *needle)
{
    store *st = NULL;
    char why[256];
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    store_prediction p;
    assert_int_equal(store_prediction_get_by_trial(st, trial, &p, why, sizeof why), STORE_OK);
    printf("trial %lld: prediction %s: %s\n", (long long)trial,
           p.status == STORE_PREDICTION_FAILED ? "failed" : "done", p.failure);
    assert_int_equal(p.status, STORE_PREDICTION_FAILED);
    assert_non_null(strstr(p.failure, needle));
    assert_false(p.snapped);
    assert_true(isnan(p.snap_dw) && p.regime == STORE_REGIME_UNKNOWN && p.curve.n == 0);
    assert_true(p.creases.angle_deg[0] == -88.0 && p.creases.angle_from[0] == STORE_SOURCE_SPECIMEN);
    assert_true(p.creases.position_from[1] == STORE_SOURCE_SCENE);
    store_prediction_free(&p);
    store_event *ev = NULL;
    size_t n = 0;
    assert_int_equal(store_events_get(st, trial, &ev, &n, why, sizeof why), STORE_OK);
    int warned = 0;
    for (size_t k = 0; k < n; k++)
        warned |= ev[k].kind == STORE_EVENT_WARNING && !strncmp(ev[k].message, "prediction failed: ", 19) &&
                  strstr(ev[k].message, needle) != NULL;
    free(ev);
    assert_true(warned);
    store_close(st);
}

static void thread_failure_stored(void **state)
{
    (void)state;
    int64_t trial = new_trial();
    seen s = {0};
    trial_prediction_def def = failing_def(trial, &s);
    trial_prediction *p = NULL;
    char why[256];
    assert_int_equal(trial_prediction_start(&def, &p, why, sizeof why), 0);
    trial_prediction_join(p);
    printf("reported: %s\n", s.message);
    assert_int_equal(s.calls, 1);
    assert_int_equal(s.outcome, TRIAL_PREDICTION_FAILED);
    assert_non_null(strstr(s.message, "prediction failed: "));
    expect_failed(trial, "5 nodes");
}

static void early_failure_stored(void **state)
{
    (void)state;
    int64_t trial = new_trial();
    seen s = {0};
    trial_prediction_def def = failing_def(trial, &s);
    def.scene.nodes = 61;
    store *st = NULL;
    char why[256];
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    assert_int_equal(trial_prediction_store_failed(st, &def, "no prediction resolution: ladder rung N = 31: no snap",
                                                   0.0, why, sizeof why),
                     0);
    store_close(st);
    expect_failed(trial, "ladder rung N = 31");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(thread_failure_stored),
        cmocka_unit_test(early_failure_stored),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
