/* test_trial_specimen_calib: a specimen's calibration put into a prediction's scene
 * (trial_specimen_calib_apply, issue 35 A), on config/scenes/mock-gamma013.ini with a compliant
 * hinge (no simulation: milliseconds):
 *   - determined strip values land exactly on their scene keys (the crease angles, the hinge
 *     through rod_fit_scene_apply's meaning, E with G scaled); every other field of the scene bit
 *     for bit as it was; a value not determined and the camera's view.dz_offset kept, listed as
 *     held with why; the record lists each value with the one it replaced and its source;
 *   - a calibration fitted from another strip (a start value that differs: the specimen
 *     re-measured) applies nothing and names the value;
 *   - nothing determined, an unreadable record, and none at all apply nothing, the first two said. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(applies_determined_values_only),
        cmocka_unit_test(stale_unreadable_or_empty_apply_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
