/* test_trial_specimen_calib: a specimen's calibration put into a prediction's scene
 * (trial_specimen_calib_apply, issue 35 A), on config/scenes/mock-gamma013.ini with a compliant
 * hinge (no simulation: milliseconds):
 *   - determined strip values land exactly on their scene keys (the crease angles, the hinge
 *     through rod_fit_scene_apply's meaning, E with G scaled); every other field of the scene bit
 *     for bit as it was; a value not determined and the camera's view.dz_offset kept, listed as
 *     held with why; the record lists each value with the one it replaced and its source;
 *   - a calibration fitted from another strip (a start value that differs: the specimen
 *     re-measured) applies nothing and names the value;
 *   - nothing determined, an unreadable record, and none at all apply nothing, the first two said;
 *   - a hinge fitted from sim.fit_hinge's guess on rigid creases makes a rigid scene's creases
 *     hinges of the fitted stiffness (the guess as start is not a re-measure);
 * and the refit itself (trial_specimen_calib_refit, about a second) on a store built here as
 * test_ctl_calibrate's: two done trials whose frames are a compliant strip's equilibria (the PET
 * scene at N = 31, creases -86 / -89.5 deg, hinge 2.5e-3 N m/rad, computed by the model), whose
 * prediction records rigid creases at -88 / -90 deg (mock.ini's case: a compliant twin, a rigid
 * scene): with sim.fit_hinge = 3.5e-3 it forms a calibration with the hinge among its values and
 * the truth back (noise-free frames), set up as the fit beside a trial is; without the guess
 * (sim.fit_hinge = 0, the rigid creases) no hinge is fitted and the angles stand in for it. */
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
#include "trial_specimen_calib.h"

static rod_scene scene(void)
{
    rod_scene sc;
    cfg_error err;
    const char *ov[] = {"folds.hinge_stiffness=2.5e-3"};
    if (cfg_scene_load(RIBBON_SOURCE_DIR "/config/scenes/mock-gamma013.ini", ov, 1, &sc, &err) != CFG_OK)
        fail_msg("scene: %s", err.message);
    return sc;
}

static store_creases creases(void)
{
    store_creases c = store_creases_unknown();
    c.angle_from[0] = STORE_SOURCE_SPECIMEN;
    c.angle_from[1] = STORE_SOURCE_SCENE;
    c.position_from[0] = c.position_from[1] = STORE_SOURCE_SCENE;
    return c;
}

#define CAL(params) "{\"at\":\"2026-12-06T09:00:00.000Z\",\"after_trial\":4,\"trials\":[4,2],\"parameters\":[" params "]}"

static void applies_determined_values_only(void **state)
{
    (void)state;
    rod_scene m = scene(), sc = m;
    sc.nodes = 121; /* the prediction's resolution */
    rod_scene before = sc;
    store_creases c = creases();
    trial_specimen_calib_use use;
    const char *cal = CAL("{\"key\":\"folds.angle_left_deg\",\"start\":-90,\"value\":-86.25,\"se\":0.4,\"determined\":true},"
                          "{\"key\":\"folds.angle_right_deg\",\"start\":-90,\"value\":-84.5,\"se\":null,\"determined\":false},"
                          "{\"key\":\"folds.hinge_stiffness\",\"start\":0.0025,\"value\":0.004,\"se\":0.1,\"determined\":true},"
                          "{\"key\":\"ribbon.youngs_modulus\",\"start\":4e9,\"value\":4.4e9,\"se\":0.05,\"determined\":true},"
                          "{\"key\":\"view.dz_offset\",\"start\":0,\"value\":0.01,\"se\":0.001,\"determined\":true}");
    assert_int_equal(trial_specimen_calib_apply(cal, &m, &c, &sc, &use), 3);
    printf("%s\n%s\n", use.message, use.record);
    assert_true(sc.fold_angle_left_deg == -86.25);
    assert_memory_equal(&sc.fold_angle_right_deg, &before.fold_angle_right_deg, sizeof(double)); /* kept */
    assert_true(fabs(sc.fold_hinge_stiffness / 0.004 - 1.0) < 1e-15);
    assert_true(isnan(sc.fold_hinge_stiffness_left) && isnan(sc.fold_hinge_stiffness_right));
    assert_true(fabs(sc.youngs_modulus / 4.4e9 - 1.0) < 1e-15);
    assert_true(fabs(sc.shear_modulus / (before.shear_modulus * 1.1) - 1.0) < 1e-12); /* G / E held */
    /* Everything else bit for bit. */
    rod_scene back = sc;
    back.fold_angle_left_deg = before.fold_angle_left_deg;
    back.fold_hinge_stiffness = before.fold_hinge_stiffness;
    back.youngs_modulus = before.youngs_modulus;
    back.shear_modulus = before.shear_modulus;
    assert_memory_equal(&back, &before, sizeof back);
    /* The record: each applied value with what it replaced and where that came from; the held ones. */
    json_t *r = json_loads(use.record, 0, NULL);
    assert_non_null(r);
    json_t *ap = json_object_get(r, "applied"), *held = json_object_get(r, "held");
    assert_int_equal(json_array_size(ap), 3);
    json_t *a0 = json_array_get(ap, 0);
    assert_string_equal(json_string_value(json_object_get(a0, "key")), "folds.angle_left_deg");
    assert_true(json_number_value(json_object_get(a0, "value")) == -86.25);
    assert_true(json_number_value(json_object_get(a0, "replaced")) == -90.0);
    assert_string_equal(json_string_value(json_object_get(a0, "replaced_from")), "specimen");
    assert_string_equal(json_string_value(json_object_get(json_array_get(ap, 1), "replaced_from")), "scene");
    assert_true(json_number_value(json_object_get(json_array_get(ap, 1), "replaced")) == 2.5e-3); /* exact */
    assert_true(json_number_value(json_object_get(json_array_get(ap, 2), "replaced")) == 4e9);
    assert_int_equal(json_array_size(held), 2);
    assert_string_equal(json_string_value(json_object_get(json_array_get(held, 0), "why")), "not determined by these data");
    assert_string_equal(json_string_value(json_object_get(json_array_get(held, 1), "key")), "view.dz_offset");
    assert_int_equal(json_integer_value(json_array_get(json_object_get(r, "trials"), 1)), 2);
    json_decref(r);
    assert_non_null(strstr(use.message, "folds.angle_left_deg -86.25 (specimen -90)"));
    assert_non_null(strstr(use.message, "kept as measured: folds.angle_right_deg (not determined by these data)"));
}

static void stale_unreadable_or_empty_apply_nothing(void **state)
{
    (void)state;
    rod_scene m = scene(), sc = m, before = sc;
    store_creases c = creases();
    trial_specimen_calib_use use;
    /* Fitted from a strip measured at -88: the trial's says -90. */
    const char *stale = CAL("{\"key\":\"folds.angle_left_deg\",\"start\":-88,\"value\":-86.25,\"se\":0.4,\"determined\":true}");
    assert_int_equal(trial_specimen_calib_apply(stale, &m, &c, &sc, &use), 0);
    printf("%s\n", use.message);
    assert_memory_equal(&sc, &before, sizeof sc);
    assert_string_equal(use.record, "");
    assert_non_null(strstr(use.message, "not applied"));
    assert_non_null(strstr(use.message, "folds.angle_left_deg = -88"));
    assert_non_null(strstr(use.message, "re-measured"));
    assert_int_equal(use.warning, 1);
    const char *none = CAL("{\"key\":\"folds.angle_left_deg\",\"start\":-90,\"value\":-86.25,\"se\":null,\"determined\":false}");
    assert_int_equal(trial_specimen_calib_apply(none, &m, &c, &sc, &use), 0);
    printf("%s\n", use.message);
    assert_memory_equal(&sc, &before, sizeof sc);
    assert_non_null(strstr(use.message, "determines none"));
    assert_int_equal(use.warning, 0);
    assert_int_equal(trial_specimen_calib_apply("{not json", &m, &c, &sc, &use), 0);
    printf("%s\n", use.message);
    assert_non_null(strstr(use.message, "cannot be read"));
    assert_int_equal(use.warning, 1);
    assert_memory_equal(&sc, &before, sizeof sc);
    assert_int_equal(trial_specimen_calib_apply("", &m, &c, &sc, &use), 0);
    assert_string_equal(use.message, "");
    assert_memory_equal(&sc, &before, sizeof sc);
}

static void hinge_on_rigid_creases(void **state)
{
    (void)state;
    rod_scene m = scene();
    m.fold_hinge_stiffness = INFINITY; /* the scene's rigid creases */
    m.fold_hinge_stiffness_left = m.fold_hinge_stiffness_right = NAN;
    rod_scene sc = m, before = m;
    store_creases c = creases();
    trial_specimen_calib_use use;
    const char *cal = CAL("{\"key\":\"folds.angle_left_deg\",\"start\":-90,\"value\":-86.25,\"se\":0.4,\"determined\":true},"
                          "{\"key\":\"folds.hinge_stiffness\",\"start\":0.0035,\"value\":0.0027,\"se\":0.1,\"determined\":true}");
    assert_int_equal(trial_specimen_calib_apply(cal, &m, &c, &sc, &use), 2);
    printf("%s\n%s\n", use.message, use.record);
    assert_int_equal(use.warning, 0);
    assert_true(sc.fold_angle_left_deg == -86.25);
    assert_false(rod_scene_hinge_rigid(&sc));
    assert_true(fabs(sc.fold_hinge_stiffness / 0.0027 - 1.0) < 1e-15);
    assert_true(isnan(sc.fold_hinge_stiffness_left) && isnan(sc.fold_hinge_stiffness_right));
    assert_true(fabs(rod_scene_hinge_k(&sc, 0) / 0.0027 - 1.0) < 1e-15);
    assert_true(fabs(rod_scene_hinge_k(&sc, 1) / 0.0027 - 1.0) < 1e-15);
    rod_scene back = sc;
    back.fold_angle_left_deg = before.fold_angle_left_deg;
    back.fold_hinge_stiffness = before.fold_hinge_stiffness;
    assert_memory_equal(&back, &before, sizeof back);
    json_t *r = json_loads(use.record, 0, NULL);
    assert_non_null(r);
    json_t *h = json_array_get(json_object_get(r, "applied"), 1);
    assert_string_equal(json_string_value(json_object_get(h, "key")), "folds.hinge_stiffness");
    assert_true(json_is_null(json_object_get(h, "replaced")));
    assert_string_equal(json_string_value(json_object_get(h, "replaced_from")), "rigid creases");
    json_decref(r);
    assert_non_null(strstr(use.message, "folds.hinge_stiffness 0.0027 (rigid creases)"));
}

/* A calibration of one crease's hinge (folds.hinge_stiffness_left, fitted from the strip's own
   2e-3 N m/rad while the pair's key says 3.5e-3) applied to that strip: the crease gets the value
   itself (absolute, as rod_fit_param.h's keys are), the other crease and the pair's key unchanged;
   read relative to the pair's k it would become 2.4e-3 * 3.5e-3 / 2e-3 or 2.4e-3 * 2e-3 / 3.5e-3. */
static void per_crease_hinge_applied_as_its_value(void **state)
{
    (void)state;
    rod_scene m = scene();
    m.fold_hinge_stiffness = 3.5e-3;
    m.fold_hinge_stiffness_left = 2e-3;
    m.fold_hinge_stiffness_right = 5e-3;
    rod_scene sc = m;
    store_creases c = creases();
    trial_specimen_calib_use use;
    const char *cal = CAL("{\"key\":\"folds.hinge_stiffness_left\",\"start\":0.002,\"value\":0.0024,\"se\":0.1,"
                          "\"determined\":true}");
    assert_int_equal(trial_specimen_calib_apply(cal, &m, &c, &sc, &use), 1);
    printf("%s\n", use.message);
    assert_int_equal(use.warning, 0);
    assert_true(fabs(sc.fold_hinge_stiffness_left / 2.4e-3 - 1.0) < 1e-14);
    assert_true(fabs(rod_scene_hinge_k(&sc, 0) / 2.4e-3 - 1.0) < 1e-14);
    assert_true(sc.fold_hinge_stiffness_right == 5e-3);
    assert_true(sc.fold_hinge_stiffness == 3.5e-3);
}

/* ---- the refit on pooled frames (test_ctl_calibrate's fixture) ---------------------------------- */

#define PET RIBBON_SOURCE_DIR "/config/scenes/pet-200x5.ini"

static void truth(rod_fit_obs *obs, int n)
{
    cfg_error err;
    rod_scene t;
    const char *sets[] = {"mesh.nodes=31", "folds.angle_left_deg=-86", "folds.angle_right_deg=-89.5",
                          "folds.hinge_stiffness=2.5e-3"};
    assert_int_equal(cfg_scene_load(PET, sets, 4, &t, &err), 0);
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

/* The trial's stored config: a mock rig file and the PET scene at N = 31. */
static char *config_text(void)
{
    FILE *f = fopen(PET, "r");
    assert_non_null(f);
    static char text[16384];
    int n = snprintf(text, sizeof text, "# rig file /lab/rig.ini\n[rig]\nmode = mock\nscene = pet.ini\n# scene file %s\n", PET);
    n += (int)fread(text + n, 1, sizeof text - (size_t)n - 64, f);
    fclose(f);
    text[n] = '\0';
    char *nodes = strstr(text, "nodes = 101");
    assert_non_null(nodes);
    memcpy(nodes, "nodes = 31 ", 11);
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
}

static void state_event(store *st, int64_t id, double t, const char *msg)
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

/* A done mock trial of specimen spid: the truth's frames of the compression's end and the shear,
 * a snap at Delta W = 0.20 (the pool cuts at 0.16); its prediction ran rigid creases. */
static int64_t add_trial(store *st, int64_t spid)
{
    char why[256];
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_MOCK;
    d.config_text = config_text();
    d.specimen_id = spid;
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &d, &id, why, sizeof why), STORE_OK);
    store_prediction p = store_prediction_default();
    p.trial_id = id;
    snprintf(p.scene_hash, sizeof p.scene_hash, "test");
    p.snapped = true;
    p.snap_dw = 0.21;
    p.regime = STORE_REGIME_SYMMETRIC;
    p.nodes = 31;
    p.dt = 1e-3;
    p.imperfection = 1e-6;
    p.wall_s = 1.0;
    p.creases.angle_deg[0] = -88.0;
    p.creases.angle_from[0] = STORE_SOURCE_SPECIMEN;
    p.creases.angle_deg[1] = -90.0;
    p.creases.angle_from[1] = STORE_SOURCE_SCENE;
    p.creases.position[0] = 0.21;
    p.creases.position[1] = 0.79;
    p.creases.position_from[0] = p.creases.position_from[1] = STORE_SOURCE_SCENE;
    p.creases.hinge_stiffness = INFINITY; /* the scene's rigid creases */
    double t[2] = {0, 1}, dw[2] = {0, 0.21}, z[2] = {0.3, 0.3};
    p.curve = (store_curve){2, t, dw, z, z};
    assert_int_equal(store_prediction_insert(st, &p, NULL, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, store_wall_now(), why, sizeof why),
                     STORE_OK);
    rod_fit_obs obs[18];
    int n = 0;
    for (int k = 0; k < 6; k++) obs[n++] = (rod_fit_obs){0.25 + 0.01 * k, 0.0, 0, 0};
    for (int k = 1; k <= 12; k++) obs[n++] = (rod_fit_obs){0.3, 0.15 * k / 12, 0, 0};
    truth(obs, n);
    store_samples *w = NULL;
    assert_int_equal(store_samples_begin(st, id, NULL, &w, why, sizeof why), STORE_OK);
    double ts = 0.0;
    for (int k = 0; k < 6; k++) frame(w, ts += 0.1, obs[k].dl, obs[k].dw, obs[k].dz, obs[k].a);
    state_event(st, id, ts += 0.05, "state shearing");
    for (int k = 6; k < n; k++) frame(w, ts += 0.1, obs[k].dl, obs[k].dw, obs[k].dz, obs[k].a);
    frame(w, ts += 0.1, 0.3, 0.20, -0.2, 0.0); /* the snap, the lower state */
    state_event(st, id, ts += 0.05, "state returning");
    assert_int_equal(store_samples_end(w, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_result(st, id, true, 0.20, STORE_REGIME_SYMMETRIC, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_DONE, NULL, store_wall_now(), why, sizeof why), STORE_OK);
    return id;
}

static json_t *param(json_t *j, const char *key)
{
    json_t *ps = json_object_get(j, "parameters");
    for (size_t i = 0; i < json_array_size(ps); i++)
        if (!strcmp(json_string_value(json_object_get(json_array_get(ps, i), "key")), key)) return json_array_get(ps, i);
    return NULL;
}

static void refit_rigid_scene_fits_the_hinge_guess(void **state)
{
    (void)state;
    char dir[64] = "/tmp/test_trial_specimen_calib.XXXXXX", db[128], why[256];
    assert_non_null(mkdtemp(dir));
    snprintf(db, sizeof db, "%s/trials.db", dir);
    store *st;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "S-hinge");
    sp.length_m = 0.2;
    sp.width_m = 0.005;
    sp.thickness_m = 0.25e-3;
    int64_t spid = 0;
    assert_int_equal(store_specimen_upsert(st, &sp, &spid, why, sizeof why), STORE_OK);
    add_trial(st, spid);
    int64_t t2 = add_trial(st, spid);

    /* The scene's rigid creases (sim.fit_hinge = 0, and every refit before it used sim.fit_hinge):
     * no hinge among the values; here the angles stand in for it (printed: about 11 deg off). */
    trial_specimen_refit r;
    trial_specimen_calib_refit(st, spid, "S-hinge", t2, "", 0.0, NULL, &r);
    printf("fit_hinge = 0: %s (%.2f s)\n", r.message, r.wall_s);
    assert_true(isnan(r.hinge_guess));
    assert_null(strstr(r.message, "folds.hinge_stiffness"));

    /* sim.fit_hinge = 3.5e-3 (mock.ini's): the creases fitted as hinges from the guess. */
    trial_specimen_calib_refit(st, spid, "S-hinge", t2, "", 3.5e-3, NULL, &r);
    printf("fit_hinge = 3.5e-3: %s (%.2f s)\n", r.message, r.wall_s);
    assert_int_equal(r.ok, 1);
    assert_int_equal(r.ntrials, 2);
    assert_true(r.hinge_guess == 3.5e-3);
    assert_non_null(strstr(r.message, "fitted as hinges from sim.fit_hinge = 0.0035"));
    store_specimen now;
    assert_int_equal(store_specimen_get(st, spid, &now, why, sizeof why), STORE_OK);
    printf("%s\n", now.calibration_json);
    json_t *j = json_loads(now.calibration_json, 0, NULL);
    assert_non_null(j);
    assert_true(json_real_value(json_object_get(j, "hinge_guess")) == 3.5e-3);
    json_t *h = param(j, "folds.hinge_stiffness");
    assert_non_null(h);
    assert_true(json_is_true(json_object_get(h, "determined")));
    assert_int_equal(json_integer_value(json_object_get(h, "at_bound")), 0);
    assert_true(json_real_value(json_object_get(h, "start")) == 3.5e-3);
    double k = json_real_value(json_object_get(h, "value"));
    double al = json_real_value(json_object_get(param(j, "folds.angle_left_deg"), "value"));
    double ar = json_real_value(json_object_get(param(j, "folds.angle_right_deg"), "value"));
    printf("fitted: hinge %.6g (truth 2.5e-3, guess 3.5e-3), angles %.4f %.4f (truth -86, -89.5)\n", k, al, ar);
    /* Noise-free frames: the truth back, to what the priors (0.88 in ln k, 10 deg) leave. */
    assert_true(fabs(k / 2.5e-3 - 1.0) < 0.02);
    assert_true(fabs(al + 86.0) < 0.2 && fabs(ar + 89.5) < 0.2);

    /* Its use: the next prediction's rigid scene gets the fitted hinge and angles. */
    rod_scene m;
    cfg_error err;
    const char *sets[] = {"mesh.nodes=31", "folds.angle_left_deg=-88", "folds.angle_right_deg=-90"};
    assert_int_equal(cfg_scene_load(PET, sets, 3, &m, &err), 0);
    m.fold_hinge_stiffness = INFINITY; /* as the pool reads the prediction's rigid creases */
    rod_scene sc = m;
    store_creases c = creases();
    trial_specimen_calib_use use;
    assert_int_equal(trial_specimen_calib_apply(now.calibration_json, &m, &c, &sc, &use), 3);
    printf("%s\n", use.message);
    assert_true(fabs(sc.fold_hinge_stiffness / k - 1.0) < 1e-12);
    assert_true(sc.fold_angle_left_deg == al && sc.fold_angle_right_deg == ar);
    json_decref(j);
    store_close(st);
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(applies_determined_values_only),
        cmocka_unit_test(stale_unreadable_or_empty_apply_nothing),
        cmocka_unit_test(hinge_on_rigid_creases),
        cmocka_unit_test(per_crease_hinge_applied_as_its_value),
        cmocka_unit_test(refit_rigid_scene_fits_the_hinge_guess),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
