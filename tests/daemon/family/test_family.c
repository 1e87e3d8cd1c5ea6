/* test_family.c: the calibration fit against strips it does not know (daemon/family/, issue 32 D),
 * the short version of `ribbon-fit-family`.
 *
 * (a) the family's draws stay inside the ranges, cover them, and depend on (seed, index)
 *     only;
 * (b) the summary's medians, band coverage and regime score on hand-made cases (closed form);
 * (c) (argument "twins", test_family_twins) three twins of the benchmark's family (seed 1, indices 0..2, PET strip at N = 61) filmed by
 *     the synthetic camera at the rig's resolution and noise, measured by the tracker, fitted
 *     before the shear and at 80% of the way to the snap. What is asserted is what the fit meets
 *     on the whole family (docs/calibration.md, "Tested against strips the fit does not know"):
 *     at 80% the median error at most 0.3% and every twin's snap inside the 2-sigma band, the
 *     regime right; before the shear the calibrated prediction closer than the scene's for every
 *     twin (the 1% target is not met before the shear, and why is in that section); the tracker
 *     within 0.2 px of the twin's projected Delta Z;
 * (d) the tracked centreline kept for the fit (issue 32 A): one twin's compression filmed at three
 *     states, the tracker's centreline mapped to the plane within 0.003 l RMS of the twin's own
 *     projection at each (the family measured 0.00023 median, 0.0016 with the smooth curve; a
 *     wrong sign, scale or origin in the mapping is 0.01 l or more), with no mean offset above
 *     5e-4 l, and the twin's projection ending where the clamps put it (the last point 1/(2K) of
 *     the arc before the right clamp);
 * (e) the same on the mock trial's sharp creases, every point within 0.002 l (the traced points,
 *     not the smooth curve, which rounds the creases off). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <gsl/gsl_errno.h>

#include "family.h"
#include "scene_file.h"

#define SCENES RIBBON_SOURCE_DIR "/config/scenes/"

static rod_scene pet61(void)
{
    const char *set[] = {"mesh.nodes=61"};
    rod_scene sc;
    cfg_error e;
    assert_int_equal(cfg_scene_load(SCENES "pet-200x5.ini", set, 1, &sc, &e), CFG_OK);
    return sc;
}

static void test_draws_in_ranges(void **state)
{
    (void)state;
    rod_scene sc = pet61(), tw, tw2;
    family_ranges rg = family_ranges_default();
    char why[256];
    double ei1 = sc.width * pow(sc.thickness, 3) / 12.0;
    double amin = 1e9, amax = 0, lmin = 1e9, lmax = 0, dmax = 0, emin = 1e9, emax = 0;
    for (int i = 0; i < 2000; i++) {
        assert_int_equal(family_draw(&sc, &rg, 1, i, &tw, why, sizeof why), 0);
        double l = -tw.fold_angle_left_deg, r = -tw.fold_angle_right_deg;
        assert_true(l >= 75 - 1e-9 && l <= 95 + 1e-9 && r >= 75 - 1e-9 && r <= 95 + 1e-9);
        double d = fabs(l - r) / (0.5 * (l + r));
        assert_true(d <= 0.05 + 1e-12);
        double hl = tw.youngs_modulus * ei1 / tw.fold_hinge_stiffness / sc.length;
        assert_true(hl >= 0.01 - 1e-12 && hl <= 0.20 + 1e-12);
        double e = tw.youngs_modulus / sc.youngs_modulus;
        assert_true(e >= 0.8 && e <= 1.2);
        assert_true(fabs(tw.shear_modulus / tw.youngs_modulus - sc.shear_modulus / sc.youngs_modulus) < 1e-12);
        assert_true(fabs(tw.fold_position_left - 0.21) <= 0.01 + 1e-12);
        assert_true(fabs(tw.fold_position_right - 0.79) <= 0.01 + 1e-12);
        assert_int_equal(tw.nodes, sc.nodes);
        amin = fmin(amin, fmin(l, r));
        amax = fmax(amax, fmax(l, r));
        lmin = fmin(lmin, hl);
        lmax = fmax(lmax, hl);
        dmax = fmax(dmax, d);
        emin = fmin(emin, e);
        emax = fmax(emax, e);
    }
    /* The draws reach the ends of every range. */
    assert_true(amin < 75.5 && amax > 94.5);
    assert_true(lmin < 0.011 && lmax > 0.19);
    assert_true(dmax > 0.048);
    assert_true(emin < 0.81 && emax > 1.19);
    /* (seed, index) alone decides a twin. */
    assert_int_equal(family_draw(&sc, &rg, 1, 7, &tw, why, sizeof why), 0);
    assert_int_equal(family_draw(&sc, &rg, 1, 7, &tw2, why, sizeof why), 0);
    assert_memory_equal(&tw, &tw2, sizeof tw);
    assert_int_equal(family_draw(&sc, &rg, 2, 7, &tw2, why, sizeof why), 0);
    assert_true(tw.fold_angle_left_deg != tw2.fold_angle_left_deg);
    /* A scene with rigid creases has no hinge to draw. */
    rod_scene rigid = sc;
    rigid.fold_hinge_stiffness = ROD_HINGE_RIGID;
    assert_int_equal(family_draw(&rigid, &rg, 1, 0, &tw, why, sizeof why), -1);
    assert_non_null(strstr(why, "compliant"));
}

static family_case made(double truth, int asym, double scene, double before, double sd_b, double at, double sd_a,
                        double p_other)
{
    family_case c;
    memset(&c, 0, sizeof c);
    c.ok = 1;
    c.truth_dw = truth;
    c.truth_asym = asym;
    c.scene_dw = scene;
    family_fit *f[2] = {&c.before, &c.at};
    double dw[2] = {before, at}, sd[2] = {sd_b, sd_a};
    for (int k = 0; k < 2; k++) {
        f[k]->ok = 1;
        f[k]->snap.snapped = 1;
        f[k]->snap.band_ok = 1;
        f[k]->snap.snap_dw = dw[k];
        f[k]->snap.snap_sd = sd[k];
        f[k]->snap.asymmetric = asym;
        f[k]->snap.p_other = p_other;
    }
    return c;
}

static void test_summary_closed_form(void **state)
{
    (void)state;
    family_case c[4] = {
        made(0.20, 0, 0.22, 0.202, 0.0011, 0.2002, 0.00011, 0.0), /* 10%, 1% (1.8 sd), 0.1% (1.8 sd) */
        made(0.25, 1, 0.20, 0.255, 0.001, 0.2505, 0.001, 0.0),   /* 20%, 2% (5 sd), 0.2% (0.5 sd) */
        made(0.10, 0, 0.105, 0.1005, 0.01, 0.1, 0.001, 0.5),     /* 5%, 0.5%, 0%; regime not scored */
        made(0.20, 0, 0.20, 0.2, 0.001, 0.2, 0.001, 0.0),
    };
    c[3].ok = 0; /* did not run: counted in twins, nowhere else */
    c[1].at.snap.asymmetric = 0; /* the regime wrong at 80% */
    family_summary s;
    family_summarise(c, 4, &s);
    assert_int_equal(s.twins, 4);
    assert_int_equal(s.ran, 3);
    assert_int_equal(s.fits_before, 3);
    assert_float_equal(s.scene_median, 0.10, 1e-12);
    assert_float_equal(s.scene_max, 0.20, 1e-12);
    assert_float_equal(s.before_median, 0.01, 1e-12);
    assert_float_equal(s.before_max, 0.02, 1e-12);
    assert_float_equal(s.before_in2sd, 2.0 / 3.0, 1e-12);
    assert_float_equal(s.at_median, 0.001, 1e-12);
    assert_float_equal(s.at_in2sd, 1.0, 1e-12);
    assert_int_equal(s.regime_scored_before, 2);
    assert_int_equal(s.regime_right_before, 2);
    assert_int_equal(s.regime_scored_at, 2);
    assert_int_equal(s.regime_right_at, 1);
}

static void test_three_twins(void **state)
{
    (void)state;
    rod_scene sc = pet61();
    family_ranges rg = family_ranges_default();
    family_case_opts o = family_case_opts_default(&sc);
    family_case c[3];
    for (int i = 0; i < 3; i++) {
        assert_int_equal(family_case_run(&sc, &rg, 1, i, &o, &c[i]), 0);
        if (!c[i].ok) fail_msg("%s", c[i].why);
        const family_fit *f[2] = {&c[i].before, &c[i].at};
        for (int k = 0; k < 2; k++)
            if (!f[k]->ok) fail_msg("twin %d %s: %s", i, k ? "at 80%" : "before the shear", f[k]->why);
        double e_scene = fabs(c[i].scene_dw - c[i].truth_dw) / c[i].truth_dw;
        double e_before = fabs(c[i].before.snap.snap_dw - c[i].truth_dw) / c[i].truth_dw;
        double e_at = fabs(c[i].at.snap.snap_dw - c[i].truth_dw) / c[i].truth_dw;
        print_message("twin %d: truth %.5f scene %+.2f%% before %+.2f%% (sd %.2f%%) at80 %+.3f%% (sd %.3f%%) "
                      "tracker dz %.2g a %.2g\n",
                      i, c[i].truth_dw, 100 * (c[i].scene_dw - c[i].truth_dw) / c[i].truth_dw,
                      100 * (c[i].before.snap.snap_dw - c[i].truth_dw) / c[i].truth_dw,
                      100 * c[i].before.snap.snap_sd / c[i].truth_dw,
                      100 * (c[i].at.snap.snap_dw - c[i].truth_dw) / c[i].truth_dw,
                      100 * c[i].at.snap.snap_sd / c[i].truth_dw, c[i].film_stats.dz_rms, c[i].film_stats.a_rms);
        assert_true(e_before < e_scene);
        assert_true(fabs(c[i].at.snap.snap_dw - c[i].truth_dw) <= 2.0 * c[i].at.snap.snap_sd);
        assert_true(e_at < 0.01);
        assert_int_equal(c[i].at.snap.asymmetric, c[i].truth_asym);
        /* The tracker within 0.2 px of the twin's projected Delta Z (l = 200 mm at 2.9 px/mm:
           0.2 px is 3.4e-4 l), every frame measured. */
        assert_true(c[i].film_stats.dz_rms < 3.4e-4);
        assert_int_equal(c[i].film_stats.lost, 0);
    }
    family_summary s;
    family_summarise(c, 3, &s);
    assert_int_equal(s.fits_at, 3);
    assert_true(s.at_median <= 0.003);
}

static void test_tracked_centreline(void **state)
{
    (void)state;
    rod_scene sc = pet61(), twin;
    family_ranges rg = family_ranges_default();
    char why[256];
    assert_int_equal(family_draw(&sc, &rg, 1, 0, &twin, why, sizeof why), 0);
    family_film_opts fo = family_film_opts_default(&twin);
    fo.n_compress = 3;
    fo.n_hold = 0;
    fo.n_shapes = 3;
    family_film f;
    if (family_film_run(&twin, &fo, &f, why, sizeof why) != 0) fail_msg("%s", why);
    print_message("centreline: %d shapes, tracker off by %.3g l RMS (mean x %+.2g, z %+.2g)\n", f.nshapes, f.shape_rms,
                  f.shape_mean_x, f.shape_mean_z);
    assert_int_equal(f.nshapes, 3);
    assert_true(f.shape_rms < 0.003);
    assert_true(fabs(f.shape_mean_x) < 5e-4 && fabs(f.shape_mean_z) < 5e-4);
    for (int i = 0; i < f.nshapes; i++) {
        const rod_fit_shape *t = &f.true_shapes[i];
        assert_int_equal(t->k, fo.shape_points);
        assert_true(t->dl == f.obs[i].dl && t->dw == 0.0);
        /* Nearly inextensible: the arc between the clamp points is about l, and its last sample
           1 / (2K) of it short of the right clamp point at (1 - Delta L, 0). */
        double ex = t->xz[2 * t->k - 2] - (1.0 - t->dl), ez = t->xz[2 * t->k - 1];
        assert_true(hypot(ex, ez) < 0.6 / t->k);
        assert_true(hypot(ex, ez) > 0.4 / t->k);
    }
    family_film_free(&f);
}

/* (e) Sharp creases: the mock trial's twin (config/mock.ini's [twin] with rigid creases, as
 * test_trial_calibrate's session takes it: -86 deg, 2.5% apart, N = 61) filmed at three
 * compression states. The smooth fit rounds a rigid crease off and, with the crease inside its
 * end window, moves the curve's ends 0.004 l outside the clamp points: its 24 points were 0.0022 l
 * RMS and up to 0.0045 l off the twin's own projection (the fit's centreline pulled the crease
 * angles 4 deg toward the scene, docs/calibration.md). The traced points (vis_tracker_samples)
 * follow the crease: 0.00045 l RMS, 0.0013 l at most (asserted: 0.001, 0.002). */
static void test_tracked_centreline_sharp_creases(void **state)
{
    (void)state;
    const char *set[] = {"mesh.nodes=61", "folds.angle_deg=-86", "imperfection.fold_angle_rel=0.025"};
    rod_scene twin;
    cfg_error e;
    assert_int_equal(cfg_scene_load(SCENES "mock-gamma013.ini", set, 3, &twin, &e), CFG_OK);
    family_film_opts fo = family_film_opts_default(&twin);
    fo.n_compress = 3;
    fo.n_hold = 0;
    fo.n_shapes = 3;
    family_film f;
    char why[256];
    if (family_film_run(&twin, &fo, &f, why, sizeof why) != 0) fail_msg("%s", why);
    assert_int_equal(f.nshapes, 3);
    double worst = 0.0;
    int at = -1;
    for (int i = 0; i < f.nshapes; i++)
        for (int p = 0; p < f.true_shapes[i].k; p++) {
            double d = hypot(f.tracked_shapes[i].xz[2 * p] - f.true_shapes[i].xz[2 * p],
                             f.tracked_shapes[i].xz[2 * p + 1] - f.true_shapes[i].xz[2 * p + 1]);
            if (d > worst) {
                worst = d;
                at = p;
            }
        }
    print_message("sharp creases: tracker off by %.3g l RMS, %.3g l at most (point %d of %d)\n", f.shape_rms, worst, at,
                  fo.shape_points);
    assert_true(f.shape_rms < 0.001);
    assert_true(worst < 0.002);
    family_film_free(&f);
}

/* No argument: (a), (b), (d) and (e), seconds, in both builds. "twins": (c), about 10 s of CPU, registered
   as test_family_twins (heavy: under the sanitizers it is ten times that). */
int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    if (argc > 1 && !strcmp(argv[1], "twins")) {
        const struct CMUnitTest twins[] = {cmocka_unit_test(test_three_twins)};
        return cmocka_run_group_tests(twins, NULL, NULL);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_draws_in_ranges),
        cmocka_unit_test(test_summary_closed_form),
        cmocka_unit_test(test_tracked_centreline),
        cmocka_unit_test(test_tracked_centreline_sharp_creases),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
