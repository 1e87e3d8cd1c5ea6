/* test_campaign_strip.c: the lab strip (campaign_strip.h) pooled from stored fits against numbers
 * worked by hand. Three fits as trial_calibrated_json writes them, and a failed one:
 *   A  specimen designed at 90: angles -84 +- 1 and -86 +- 1 (mean 85, se 1: relaxed 5), hinge
 *      4e-3 +- 20%
 *   B  specimen designed at 60: -53 +- 2, -55 +- 2 (relaxed 6, se 2), hinge 6e-3 +- 10%
 *   C  no specimen, scene -120: left -113 +- 0.5 (relaxed 7), right at its bound (not used),
 *      hinge not determined (se null), E fitted but not determined
 *   D  ok false (a failed fit): nothing
 * Relaxation: weights 1, 1/4, 4: mean 34.5 / 5.25; chi2 = 23/7 over 2 degrees of freedom, so the
 * standard error is sqrt(23/14) / sqrt(5.25). Hinge: ln k weighted 25 and 100, mean (25 ln 4e-3 +
 * 100 ln 6e-3) / 125, Birge ratio from its chi2 over 1. E is left the scene's. The lab strip at
 * design phi 90 reads the trace at 90 - relaxation. One overconfident fit among four counts with
 * half the median standard error, not its own.
 * From a store (campaign_strip_collect): a specimen's calibration stands for its trials' fits
 * (one record per specimen), and the trials of specimens without a usable calibration count by
 * their own fits: the same three records as above, one of them a calibration, give the same
 * strip. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "campaign_strip.h"

static const char *fit_a =
    "{\"ok\":true,\"parameters\":["
    "{\"key\":\"folds.angle_left_deg\",\"scene\":-90,\"fitted\":-84,\"se\":1,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
    "{\"key\":\"folds.angle_right_deg\",\"scene\":-90,\"fitted\":-86,\"se\":1,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
    "{\"key\":\"folds.hinge_stiffness\",\"scene\":0.003,\"fitted\":0.004,\"se\":0.2,\"se_kind\":\"relative\",\"determined\":true,\"at_bound\":0}]}";
static const char *fit_b =
    "{\"ok\":true,\"parameters\":["
    "{\"key\":\"folds.angle_left_deg\",\"scene\":-60,\"fitted\":-53,\"se\":2,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
    "{\"key\":\"folds.angle_right_deg\",\"scene\":-60,\"fitted\":-55,\"se\":2,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
    "{\"key\":\"folds.hinge_stiffness\",\"scene\":0.003,\"fitted\":0.006,\"se\":0.1,\"se_kind\":\"relative\",\"determined\":true,\"at_bound\":0}]}";
static const char *fit_c =
    "{\"ok\":true,\"parameters\":["
    "{\"key\":\"folds.angle_left_deg\",\"scene\":-120,\"fitted\":-113,\"se\":0.5,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
    "{\"key\":\"folds.angle_right_deg\",\"scene\":-120,\"fitted\":-100,\"se\":0.5,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":1},"
    "{\"key\":\"folds.hinge_stiffness\",\"scene\":0.003,\"fitted\":0.03,\"se\":null,\"se_kind\":\"relative\",\"determined\":false,\"at_bound\":0},"
    "{\"key\":\"ribbon.youngs_modulus\",\"scene\":4e9,\"fitted\":5e9,\"se\":0.5,\"se_kind\":\"relative\",\"determined\":false,\"at_bound\":0}]}";
static const char *fit_d = "{\"ok\":false,\"reason_key\":\"at_bound\"}";

static int parse(const char *text, double design, campaign_strip_fit *f)
{
    json_t *j = json_loads(text, 0, NULL);
    assert_non_null(j);
    char why[256];
    int rc = campaign_strip_fit_parse(j, design, f, why, sizeof why);
    json_decref(j);
    return rc;
}

static void pooled_against_hand_worked(void **s)
{
    (void)s;
    campaign_strip_fit f[4];
    assert_int_equal(parse(fit_a, 90, &f[0]), 1);
    assert_int_equal(parse(fit_b, 60, &f[1]), 1);
    assert_int_equal(parse(fit_c, NAN, &f[2]), 1);
    assert_int_equal(parse(fit_d, 90, &f[3]), 0);
    assert_true(fabs(f[0].angle_mean_deg - 85) < 1e-12 && fabs(f[0].angle_se_deg - 1) < 1e-12);
    assert_true(fabs(f[2].angle_mean_deg - 113) < 1e-12 && fabs(f[2].angle_se_deg - 0.5) < 1e-12);
    assert_true(isnan(f[2].ln_hinge) && isnan(f[2].ln_youngs));
    campaign_lab_strip ls;
    campaign_strip_pool(f, 4, &ls);
    assert_int_equal(ls.n_fits, 3);
    assert_int_equal(ls.n_relax, 3);
    assert_int_equal(ls.n_hinge, 2);
    assert_int_equal(ls.n_youngs, 0);
    assert_true(fabs(ls.relax_deg - 34.5 / 5.25) < 1e-12);
    assert_true(fabs(ls.relax_se - sqrt(23.0 / 14.0) / sqrt(5.25)) < 1e-12);
    double m = (25 * log(4e-3) + 100 * log(6e-3)) / 125;
    double chi2 = pow((log(4e-3) - m) / 0.2, 2) + pow((log(6e-3) - m) / 0.1, 2);
    assert_true(fabs(ls.hinge - 5.53e-3) < 1e-15);           /* exp(m) = 5.5326e-3, to 3 digits */
    assert_true(fabs(exp(m) - 5.5326e-3) < 1e-7);
    assert_true(fabs(ls.hinge_se_rel - sqrt(chi2) / sqrt(125.0)) < 1e-12);
    assert_true(isnan(ls.youngs));
    char key[64];
    campaign_strip_key(&ls, key, sizeof key);
    assert_string_equal(key, "hinge=5.53e-03 youngs=scene");
    assert_int_equal(campaign_strip_needs_trace(&ls), 1);

    /* The scene with the pooled hinge: rigid creases become compliant ones of 5.53e-3. */
    rod_scene sc = rod_scene_default(), lab;
    sc.youngs_modulus = 4e9;
    campaign_strip_apply(&sc, &ls, &lab);
    assert_true(lab.fold_hinge_stiffness == 5.53e-3 && isnan(lab.fold_hinge_stiffness_left));
    assert_true(lab.youngs_modulus == 4e9 && lab.fold_angle_deg == sc.fold_angle_deg);

    /* Read at phi - relaxation on a curve through (60, 0.15), (90, 0.18), (120, 0.19). */
    double phi[] = {60, 90, 120}, gam[] = {0.15, 0.18, 0.19};
    campaign_predicted c = {.phi_deg = phi, .gamma = gam, .n = 3};
    double g;
    char why[700];
    assert_int_equal(campaign_strip_at(&c, &ls, 90, &g, why, sizeof why), 0);
    assert_true(fabs(g - (0.15 + 0.03 * (90 - 34.5 / 5.25 - 60) / 30)) < 1e-12);
    assert_int_equal(campaign_strip_at(&c, &ls, 62, &g, why, sizeof why), -1); /* 55.4 is off the curve */
    assert_non_null(strstr(why, "lab strip"));
}

/* No usable fit: the scene's strip, no trace of its own, no shift. */
static void nothing_pooled_is_the_scene(void **s)
{
    (void)s;
    campaign_strip_fit f;
    assert_int_equal(parse(fit_d, 90, &f), 0);
    campaign_lab_strip ls;
    campaign_strip_pool(&f, 0, &ls);
    assert_int_equal(ls.n_fits, 0);
    assert_int_equal(campaign_strip_needs_trace(&ls), 0);
    char d[200];
    campaign_strip_describe(&ls, d, sizeof d);
    assert_non_null(strstr(d, "the scene's"));
    double phi[] = {60, 120}, gam[] = {0.15, 0.19}, g;
    campaign_predicted c = {.phi_deg = phi, .gamma = gam, .n = 2};
    assert_int_equal(campaign_strip_at(&c, &ls, 90, &g, d, sizeof d), 0);
    assert_true(fabs(g - 0.17) < 1e-12);
    /* A malformed record is refused, named. */
    json_t *j = json_loads("{\"ok\":true,\"parameters\":[{\"scene\":1}]}", 0, NULL);
    assert_int_equal(campaign_strip_fit_parse(j, NAN, &f, d, sizeof d), -1);
    assert_non_null(strstr(d, "key"));
    json_decref(j);
}

/* The bench's path: a rod_fit_result with two angles (one undetermined) and a hinge. */
static void from_result(void **s)
{
    (void)s;
    rod_fit_result r;
    memset(&r, 0, sizeof r);
    r.u0[ROD_FIT_ANGLE_LEFT] = r.u0[ROD_FIT_ANGLE_RIGHT] = -90;
    r.u[ROD_FIT_ANGLE_LEFT] = -87, r.u[ROD_FIT_ANGLE_RIGHT] = -80;
    r.se[ROD_FIT_ANGLE_LEFT] = 0.8, r.se[ROD_FIT_ANGLE_RIGHT] = INFINITY;
    r.fitted[ROD_FIT_ANGLE_LEFT] = r.fitted[ROD_FIT_ANGLE_RIGHT] = r.fitted[ROD_FIT_HINGE] = 1;
    r.determined[ROD_FIT_ANGLE_LEFT] = r.determined[ROD_FIT_HINGE] = 1;
    r.u0[ROD_FIT_HINGE] = log(3e-3), r.u[ROD_FIT_HINGE] = log(5e-3), r.se[ROD_FIT_HINGE] = 0.3;
    campaign_strip_fit f;
    assert_int_equal(campaign_strip_fit_from_result(&r, 90, &f), 1);
    assert_true(fabs(f.angle_mean_deg - 87) < 1e-12 && fabs(f.angle_se_deg - 0.8) < 1e-12);
    assert_true(fabs(f.ln_hinge - log(5e-3)) < 1e-12 && fabs(f.ln_hinge_se - 0.3) < 1e-12);
    campaign_lab_strip ls;
    campaign_strip_pool(&f, 1, &ls);
    assert_true(fabs(ls.relax_deg - 3) < 1e-12 && fabs(ls.relax_se - 0.8) < 1e-12);
    assert_true(ls.hinge == 5e-3);
}

/* One fit far more confident than the others: its standard error counts as half the median of
 * the four (0.5), not its own 0.01. Relaxations 5, 5, 5 (se 1) and 9 (se 0.01): weights 1, 1, 1,
 * 4; mean (15 + 36) / 7; chi2 = 3 (51/7 - 5)^2 + (9 - 51/7)^2 / 0.25 over 3. */
static void one_overconfident_fit_is_floored(void **s)
{
    (void)s;
    campaign_strip_fit f[4];
    for (int i = 0; i < 4; i++) {
        memset(&f[i], 0, sizeof f[i]);
        f[i].design_phi_deg = 90;
        f[i].angle_mean_deg = i < 3 ? 85 : 81;
        f[i].angle_se_deg = i < 3 ? 1 : 0.01;
        f[i].ln_hinge = f[i].ln_hinge_se = f[i].ln_youngs = f[i].ln_youngs_se = NAN;
    }
    campaign_lab_strip ls;
    campaign_strip_pool(f, 4, &ls);
    double m = 51.0 / 7.0, chi2 = 3 * (m - 5) * (m - 5) + (9 - m) * (9 - m) / 0.25;
    assert_true(fabs(ls.relax_deg - m) < 1e-12);
    assert_true(fabs(ls.relax_se - sqrt(chi2 / 3) / sqrt(7.0)) < 1e-12);
}

/* Calibration records as trial_specimen_calib writes them. */
static const char *cal_a = /* specimen A (designed at 90), after its trials 1 and 2: fit_a's values */
    "{\"at\":\"2026-12-06T09:22:37.145Z\",\"after_trial\":2,\"trials\":[2,1],\"parameters\":["
    "{\"key\":\"folds.angle_left_deg\",\"start\":-90,\"value\":-84,\"se\":1,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
    "{\"key\":\"folds.angle_right_deg\",\"start\":-90,\"value\":-86,\"se\":1,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
    "{\"key\":\"folds.hinge_stiffness\",\"start\":null,\"value\":0.004,\"se\":0.2,\"se_kind\":\"relative\",\"determined\":true,\"at_bound\":0}]}";
static const char *cal_c = /* specimen C: a calibration that determined nothing (its trial's fit counts) */
    "{\"at\":\"2026-12-06T09:30:00.000Z\",\"after_trial\":4,\"trials\":[4],\"parameters\":["
    "{\"key\":\"folds.angle_left_deg\",\"start\":-120,\"value\":null,\"se\":null,\"se_kind\":\"absolute\",\"determined\":false,\"at_bound\":0},"
    "{\"key\":\"folds.angle_right_deg\",\"start\":-120,\"value\":-110,\"se\":null,\"se_kind\":\"absolute\",\"determined\":false,\"at_bound\":0}]}";
/* trials of specimen A: its creases relaxed 10 deg by each trial's own fit (not to be pooled) */
static const char *fit_a_trial =
    "{\"ok\":true,\"parameters\":["
    "{\"key\":\"folds.angle_left_deg\",\"scene\":-90,\"fitted\":-80,\"se\":1,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0},"
    "{\"key\":\"folds.angle_right_deg\",\"scene\":-90,\"fitted\":-80,\"se\":1,\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0}]}";

static char swhy[512];
#define OK(x) assert_int_equal((x), STORE_OK)

static int64_t add_specimen(store *st, const char *name, double phi)
{
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "%s", name);
    sp.length_m = 0.2;
    sp.width_m = 0.005;
    sp.thickness_m = 2.5e-4;
    sp.phi_deg = phi;
    sp.fold_position = 0.15;
    int64_t id = 0;
    if (store_specimen_upsert(st, &sp, &id, swhy, sizeof swhy) != STORE_OK) fail_msg("%s", swhy);
    return id;
}

/* A finished trial of specimen sid (0: none) with its stored fit (or its failure). */
static int64_t add_trial(store *st, int64_t sid, const char *fit, const char *failure)
{
    store_trial_def d = store_trial_def_default();
    d.specimen_id = sid;
    d.created_wall_s = 1.8e9;
    int64_t id;
    OK(store_trial_create(st, &d, &id, swhy, sizeof swhy));
    OK(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, 1.8e9 + 1, swhy, sizeof swhy));
    OK(store_trial_set_result(st, id, true, 0.4, STORE_REGIME_ASYMMETRIC, swhy, sizeof swhy));
    store_calibrated c = {.snap_dw = 0.4, .snap_sd = 0.01, .p_other = 0.01, .regime = "asymmetric", .fit_json = fit,
                          .failure = failure};
    if (failure) c = (store_calibrated){.failure = failure};
    OK(store_trial_set_calibrated(st, id, &c, swhy, sizeof swhy));
    OK(store_trial_set_status(st, id, STORE_STATUS_DONE, NULL, 1.8e9 + 2, swhy, sizeof swhy));
    return id;
}

/* A (90): calibrated from trials 1 and 2 (relaxed 5, hinge 4e-3), the trials' own fits relaxed
 * 10; B (60): no calibration (its last refit failed), trial 3 by fit_b; C (120, fit_c's design by
 * its scene): a calibration that determined nothing, trial 4 by fit_c; trial 5 without a
 * specimen, its fit failed. Pooled: A's calibration, B's and C's trials: hand_worked's strip. */
static void collect_prefers_specimen_calibrations(void **s)
{
    (void)s;
    char dir[] = "/tmp/test_campaign_strip.XXXXXX", db[64], cmd[96];
    assert_non_null(mkdtemp(dir));
    snprintf(db, sizeof db, "%s/s.db", dir);
    store *st = NULL;
    OK(store_open(db, &st, swhy, sizeof swhy));
    int64_t a = add_specimen(st, "A", 90), b = add_specimen(st, "B", 60), c = add_specimen(st, "C", 120);
    assert_int_equal(add_trial(st, a, fit_a_trial, NULL), 1);
    assert_int_equal(add_trial(st, a, fit_a_trial, NULL), 2);
    assert_int_equal(add_trial(st, b, fit_b, NULL), 3);
    assert_int_equal(add_trial(st, c, fit_c, NULL), 4);
    assert_int_equal(add_trial(st, 0, NULL, "at_bound: folds.angle_left_deg"), 5);
    OK(store_specimen_set_calibration(st, a, cal_a, NULL, swhy, sizeof swhy));
    OK(store_specimen_set_calibration(st, b, NULL, "{\"reason_key\":\"misfit\",\"after_trial\":3}", swhy, sizeof swhy));
    OK(store_specimen_set_calibration(st, c, cal_c, NULL, swhy, sizeof swhy));

    campaign_strip_fit *f = NULL;
    size_t n = 0;
    int failed = -1;
    assert_int_equal(campaign_strip_collect(st, &f, &n, &failed, swhy, sizeof swhy), 0);
    assert_int_equal(n, 3);
    assert_int_equal(failed, 1);
    int seen_a = 0;
    for (size_t i = 0; i < n; i++) {
        if (f[i].from_calibration) {
            seen_a++;
            assert_int_equal(f[i].trial_id, 2);
            assert_true(f[i].design_phi_deg == 90 && fabs(f[i].angle_mean_deg - 85) < 1e-12);
            assert_true(fabs(f[i].ln_hinge - log(4e-3)) < 1e-12 && isnan(f[i].hinge_scene));
        } else {
            assert_true(f[i].trial_id == 3 || f[i].trial_id == 4);
        }
    }
    assert_int_equal(seen_a, 1);
    campaign_lab_strip ls;
    campaign_strip_pool(f, n, &ls);
    free(f);
    assert_int_equal(ls.n_fits, 3);
    assert_int_equal(ls.n_calibrations, 1);
    assert_true(fabs(ls.relax_deg - 34.5 / 5.25) < 1e-12);
    assert_true(fabs(ls.relax_se - sqrt(23.0 / 14.0) / sqrt(5.25)) < 1e-12);
    assert_true(fabs(ls.hinge - 5.53e-3) < 1e-15);

    /* A malformed calibration is refused, named. */
    int64_t d = add_specimen(st, "D", 90);
    OK(store_specimen_set_calibration(st, d, "{\"after_trial\":9,\"parameters\":5}", NULL, swhy, sizeof swhy));
    assert_int_equal(campaign_strip_collect(st, &f, &n, &failed, swhy, sizeof swhy), -1);
    assert_non_null(strstr(swhy, "specimen D's stored calibration"));
    assert_non_null(strstr(swhy, "\"parameters\" is not an array"));
    store_close(st);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

int main(void)
{
    const struct CMUnitTest t[] = {cmocka_unit_test(pooled_against_hand_worked),
                                   cmocka_unit_test(nothing_pooled_is_the_scene), cmocka_unit_test(from_result),
                                   cmocka_unit_test(one_overconfident_fit_is_floored),
                                   cmocka_unit_test(collect_prefers_specimen_calibrations)};
    return cmocka_run_group_tests(t, NULL, NULL);
}
