/* test_ctl_calibrate.c: `ribbonctl calibrate` (daemon/ribbonctl_commands/ctl_calibrate.c, issue
 * 32 C) run as a program on a store built here with the store's own API: trials whose camera
 * frames are a known strip's equilibria (the PET scene at N = 31 with creases at 86 and 89.5 deg
 * and a hinge of 2.5e-3 N m/rad, computed by the model; the scene and the trial's prediction say
 * -88 / -90 deg and 3.5e-3), surrounded by frames the command must leave out (low in the
 * compression, past the cut-off, after the snap, after the return, rail rows). Checked: the
 * truth comes back (to 1e-3 deg and 1e-4 of k: noise-free data), the creases start from the
 * prediction's record, the fitted scene reads back, two trials of one specimen share a fit, a
 * replay calibrates through its source's prediction; named refusals: an unknown id, an unfinished
 * trial, too few samples, a strip in the lower state, trials of different specimens, a key that
 * is not a parameter. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rod_fit.h"
#include "scene_file.h"
#include "store.h"

#define SCENE RIBBON_SOURCE_DIR "/config/scenes/pet-200x5.ini"

static char dir[64], db[128];

typedef struct run_out {
    int status;
    char out[32768];
    char err[4096];
} run_out;

static void slurp(const char *path, char *buf, size_t len)
{
    FILE *f = fopen(path, "r");
    size_t n = f ? fread(buf, 1, len - 1, f) : 0;
    buf[n] = '\0';
    if (f) fclose(f);
}

static void run(run_out *r, const char *args)
{
    char cmd[2048], o[160], e[160];
    snprintf(o, sizeof o, "%s/out.txt", dir);
    snprintf(e, sizeof e, "%s/err.txt", dir);
    snprintf(cmd, sizeof cmd, "%s calibrate %s --db %s >%s 2>%s", RIBBONCTL_PATH, args, db, o, e);
    int st = system(cmd);
    r->status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    slurp(o, r->out, sizeof r->out);
    slurp(e, r->err, sizeof r->err);
    printf("$ ribbonctl calibrate %s\nexit %d\n--- stdout\n%s--- stderr\n%s", args, r->status, r->out, r->err);
}

/* The truth strip's camera observables at the given states. */
static void truth(rod_fit_obs *obs, int n)
{
    cfg_error err;
    rod_scene t;
    const char *sets[] = {"mesh.nodes=31", "folds.angle_left_deg=-86", "folds.angle_right_deg=-89.5",
                          "folds.hinge_stiffness=2.5e-3"};
    assert_int_equal(cfg_scene_load(SCENE, sets, 4, &t, &err), 0);
    rod_fit_model *m = NULL;
    char why[256];
    assert_int_equal(rod_fit_model_alloc(&t, obs, n, 0, &m, why, sizeof why), ROD_OK);
    double u[ROD_FIT_NKEYS], y[256];
    rod_fit_scene_values(&t, u);
    assert_int_equal(rod_fit_model_eval(m, u, NULL, y, NULL, why, sizeof why), ROD_OK);
    rod_fit_model_free(m);
    for (int k = 0; k < n; k++) {
        obs[k].dz = y[2 * k];
        obs[k].a = y[2 * k + 1];
    }
}

static char *config_text(void)
{
    FILE *f = fopen(SCENE, "r");
    assert_non_null(f);
    static char text[16384];
    int n = snprintf(text, sizeof text, "# rig file /lab/rig.ini\n[rig]\nmode = mock\nscene = pet.ini\n# scene file %s\n",
                     SCENE);
    n += (int)fread(text + n, 1, sizeof text - (size_t)n - 64, f);
    fclose(f);
    snprintf(text + n, sizeof text - (size_t)n, "# note: calibration test\n");
    return text;
}

static void frame(store_samples *w, double t, double dl, double dw, double dz, double a)
{
    store_sample s = store_sample_default();
    char why[256];
    s.t_s = t;
    s.kind = STORE_SAMPLE_FRAME;
    s.frame = (int64_t)(t * 30.0);
    s.dl = dl;
    s.dw = dw;
    s.dz = dz;
    s.a = a;
    s.quality = 1.0;
    assert_int_equal(store_samples_add(w, &s, why, sizeof why), STORE_OK);
    store_sample r = store_sample_default(); /* a rail reading beside it: no Delta Z */
    r.t_s = t + 0.001;
    r.dl = dl;
    r.dw = dw;
    assert_int_equal(store_samples_add(w, &r, why, sizeof why), STORE_OK);
}

static void event(store *st, int64_t id, double t, const char *msg)
{
    store_event e;
    memset(&e, 0, sizeof e);
    e.trial_id = id;
    e.t_s = t;
    e.wall_s = store_wall_now();
    e.kind = STORE_EVENT_STATE;
    snprintf(e.message, sizeof e.message, "%s", msg);
    char why[256];
    assert_int_equal(store_event_append(st, &e, why, sizeof why), STORE_OK);
}

enum { WITH_COMPRESSION = 1, WITH_SHEAR = 2, LOWER = 4, FEW = 8 };

/* A trial of specimen `specimen` (a replay of `source` when non-zero) with the truth's frames
   (dz negated: the lower state) and the frames to be left out; ended as `status`. */
static int64_t add_trial(store *st, const char *specimen, int parts, store_status status, int64_t source)
{
    char why[256];
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "%s", specimen);
    sp.length_m = 0.2;
    sp.width_m = 0.005;
    sp.thickness_m = 0.25e-3;
    int64_t spid = 0;
    assert_int_equal(store_specimen_upsert(st, &sp, &spid, why, sizeof why), STORE_OK);
    store_trial_def d = store_trial_def_default();
    d.mode = source ? STORE_MODE_REPLAY : STORE_MODE_MOCK;
    d.config_text = config_text();
    d.specimen_id = spid;
    d.source_trial_id = source;
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &d, &id, why, sizeof why), STORE_OK);
    if (!source) {
        store_prediction p = store_prediction_default();
        p.trial_id = id;
        snprintf(p.scene_hash, sizeof p.scene_hash, "test");
        p.snapped = true;
        p.snap_dw = 0.21;
        p.regime = STORE_REGIME_SYMMETRIC;
        p.nodes = 101;
        p.dt = 1e-3;
        p.imperfection = 1e-6;
        p.wall_s = 1.0;
        p.creases.angle_deg[0] = -88.0; /* "measured" on the specimen: the fit starts here */
        p.creases.angle_from[0] = STORE_SOURCE_SPECIMEN;
        p.creases.angle_deg[1] = -90.0;
        p.creases.angle_from[1] = STORE_SOURCE_SCENE;
        p.creases.position[0] = 0.21;
        p.creases.position[1] = 0.79;
        p.creases.position_from[0] = p.creases.position_from[1] = STORE_SOURCE_SCENE;
        p.creases.hinge_stiffness = 3.5e-3;
        double t[2] = {0, 1}, dw[2] = {0, 0.21}, z[2] = {0.3, 0.3};
        p.curve = (store_curve){2, t, dw, z, z};
        assert_int_equal(store_prediction_insert(st, &p, NULL, why, sizeof why), STORE_OK);
    }
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, store_wall_now(), why, sizeof why),
                     STORE_OK);
    rod_fit_obs obs[32];
    int nc = 0, n = 0;
    if (parts & WITH_COMPRESSION)
        for (int k = 0; k < 6; k++) obs[n++] = (rod_fit_obs){0.25 + 0.01 * k, 0.0, 0, 0};
    nc = n;
    if (parts & WITH_SHEAR)
        for (int k = 1; k <= 12; k++) obs[n++] = (rod_fit_obs){0.3, 0.15 * k / 12, 0, 0};
    if (parts & FEW) n = nc = 3;
    truth(obs, n);
    double sg = parts & LOWER ? -1.0 : 1.0;
    store_samples *w = NULL;
    assert_int_equal(store_samples_begin(st, id, NULL, &w, why, sizeof why), STORE_OK);
    double t = 0.0;
    for (int k = 1; k <= 5; k++) frame(w, t += 0.1, 0.04 * k, 0.0, 0.01, 0.7); /* low: no upper state in the model */
    for (int k = 0; k < nc; k++) frame(w, t += 0.1, obs[k].dl, obs[k].dw, sg * obs[k].dz, obs[k].a);
    event(st, id, t += 0.05, "state shearing");
    for (int k = nc; k < n; k++) frame(w, t += 0.1, obs[k].dl, obs[k].dw, sg * obs[k].dz, obs[k].a);
    frame(w, t += 0.1, 0.3, 0.17, 0.9, 1.5);  /* past the cut-off (0.8 of the snap, 0.16) */
    frame(w, t += 0.1, 0.3, 0.20, -0.2, 0.0); /* the snap itself, the lower state */
    event(st, id, t += 0.05, "state returning");
    frame(w, t += 0.1, 0.3, 0.1, 0.9, 2.0);   /* the return */
    assert_int_equal(store_samples_end(w, why, sizeof why), STORE_OK);
    if (status != STORE_STATUS_RUNNING) {
        assert_int_equal(store_trial_set_result(st, id, true, 0.20, STORE_REGIME_SYMMETRIC, why, sizeof why), STORE_OK);
        assert_int_equal(store_trial_set_status(st, id, status, NULL, store_wall_now(), why, sizeof why), STORE_OK);
    }
    return id;
}

static int64_t t_full, t_comp, t_other, t_running, t_few, t_lower, t_replay;

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/test_ctl_calibrate.XXXXXX");
    if (!mkdtemp(dir)) return 1;
    snprintf(db, sizeof db, "%s/trials.db", dir);
    store *st;
    char why[256];
    if (store_open(db, &st, why, sizeof why) != STORE_OK) return 1;
    t_full = add_trial(st, "S-1", WITH_COMPRESSION | WITH_SHEAR, STORE_STATUS_DONE, 0);
    t_comp = add_trial(st, "S-1", WITH_COMPRESSION, STORE_STATUS_DONE, 0);
    t_other = add_trial(st, "S-2", WITH_COMPRESSION | WITH_SHEAR, STORE_STATUS_DONE, 0);
    t_running = add_trial(st, "S-1", WITH_COMPRESSION, STORE_STATUS_RUNNING, 0);
    t_few = add_trial(st, "S-1", WITH_COMPRESSION | FEW, STORE_STATUS_ABORTED, 0);
    t_lower = add_trial(st, "S-1", WITH_COMPRESSION | LOWER, STORE_STATUS_DONE, 0);
    t_replay = add_trial(st, "S-1", WITH_COMPRESSION | WITH_SHEAR, STORE_STATUS_DONE, t_full);
    store_close(st);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : 1;
}

static json_t *param(json_t *j, const char *key)
{
    json_t *ps = json_object_get(j, "parameters");
    for (size_t i = 0; i < json_array_size(ps); i++)
        if (!strcmp(json_string_value(json_object_get(json_array_get(ps, i), "key")), key)) return json_array_get(ps, i);
    fail_msg("no parameter %s", key);
    return NULL;
}

#define TIGHT "--set mesh.nodes=31 --sigma-dz 1e-4 --sigma-a 1e-3"

static void fits_a_trial_and_writes_the_scene(void **state)
{
    (void)state;
    char args[512], scene[160];
    snprintf(scene, sizeof scene, "%s/fitted.ini", dir);
    snprintf(args, sizeof args, "%lld " TIGHT " --json --no-snap --write-scene %s", (long long)t_full, scene);
    run_out r;
    run(&r, args);
    assert_int_equal(r.status, 0);
    json_error_t je;
    json_t *j = json_loads(r.out, 0, &je);
    assert_non_null(j);
    /* 6 compression and 12 shear frames; the low, past-cut-off, snap and return frames left out */
    assert_int_equal(json_integer_value(json_object_get(j, "samples")), 18);
    json_t *t0 = json_array_get(json_object_get(j, "trials"), 0);
    assert_int_equal(json_integer_value(json_object_get(t0, "frames")), 25);
    assert_true(fabs(json_real_value(json_object_get(t0, "dw_max")) - 0.16) < 1e-12);
    /* the strip starts from the prediction's record of the creases (-88 "measured"), not the scene's -90 */
    assert_true(fabs(json_real_value(json_object_get(param(j, "folds.angle_left_deg"), "scene")) + 88.0) < 1e-12);
    assert_true(fabs(json_real_value(json_object_get(param(j, "folds.angle_left_deg"), "fitted")) + 86.0) < 1e-3);
    assert_true(fabs(json_real_value(json_object_get(param(j, "folds.angle_right_deg"), "fitted")) + 89.5) < 1e-3);
    assert_true(fabs(json_real_value(json_object_get(param(j, "folds.hinge_stiffness"), "fitted")) / 2.5e-3 - 1.0) < 1e-4);
    assert_true(json_real_value(json_object_get(j, "rms")) < 0.1);
    json_decref(j);
    cfg_error err;
    rod_scene f;
    assert_int_equal(cfg_scene_load(scene, NULL, 0, &f, &err), 0);
    assert_true(fabs(f.fold_angle_left_deg + 86.0) < 1e-3);
    assert_true(fabs(f.fold_angle_right_deg + 89.5) < 1e-3);
    assert_true(fabs(f.fold_hinge_stiffness / 2.5e-3 - 1.0) < 1e-4);
    assert_int_equal(f.nodes, 31);
}

static void prints_the_calibrated_snap(void **state)
{
    (void)state;
    char args[256];
    snprintf(args, sizeof args, "%lld --set mesh.nodes=31", (long long)t_full);
    run_out r;
    run(&r, args);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "folds.hinge_stiffness"));
    assert_non_null(strstr(r.out, "calibrated   snap Delta W"));
    assert_non_null(strstr(r.out, "scene's prediction 0.21000"));
}

static void shares_one_strip_over_trials_and_replays(void **state)
{
    (void)state;
    char args[256];
    run_out r;
    snprintf(args, sizeof args, "%lld %lld " TIGHT " --json --no-snap", (long long)t_full, (long long)t_comp);
    run(&r, args);
    assert_int_equal(r.status, 0);
    json_t *j = json_loads(r.out, 0, NULL);
    assert_non_null(j);
    assert_int_equal(json_array_size(json_object_get(j, "trials")), 2);
    assert_int_equal(json_integer_value(json_object_get(j, "samples")), 24);
    assert_true(fabs(json_real_value(json_object_get(param(j, "folds.angle_left_deg"), "fitted")) + 86.0) < 1e-3);
    json_decref(j);
    snprintf(args, sizeof args, "%lld " TIGHT " --json --no-snap --fit folds.angle_left_deg,folds.angle_right_deg",
             (long long)t_replay);
    run(&r, args);
    assert_int_equal(r.status, 0);
    j = json_loads(r.out, 0, NULL);
    assert_non_null(j);
    json_t *t0 = json_array_get(json_object_get(j, "trials"), 0);
    assert_string_equal(json_string_value(json_object_get(t0, "mode")), "replay");
    assert_int_equal(json_integer_value(json_object_get(t0, "prediction_of")), t_full);
    assert_int_equal(json_array_size(json_object_get(j, "parameters")), 2);
    json_decref(j);
}

static void refusals_are_named(void **state)
{
    (void)state;
    char args[256];
    run_out r;
    run(&r, "99 " TIGHT);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "trial 99: no such trial"));
    snprintf(args, sizeof args, "%lld " TIGHT, (long long)t_running);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "is unfinished (status running)"));
    snprintf(args, sizeof args, "%lld " TIGHT, (long long)t_few);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "too few samples: 3 usable frames"));
    snprintf(args, sizeof args, "%lld " TIGHT, (long long)t_lower);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "in the lower state"));
    snprintf(args, sizeof args, "%lld %lld " TIGHT, (long long)t_full, (long long)t_other);
    run(&r, args);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "different specimens (S-1, S-2)"));
    snprintf(args, sizeof args, "%lld --fit folds.angle_left_deg,ribbon.width", (long long)t_full);
    run(&r, args);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "--fit ribbon.width: not a fit parameter"));
    run(&r, "");
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "which trials?"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(fits_a_trial_and_writes_the_scene),
        cmocka_unit_test(prints_the_calibrated_snap),
        cmocka_unit_test(shares_one_strip_over_trials_and_replays),
        cmocka_unit_test(refusals_are_named),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
