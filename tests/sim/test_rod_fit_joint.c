/* test_rod_fit_joint.c: specimens fitted together sharing the hinge stiffness per unit width
 * (sim/rod_fit_joint.h, issue 32 C).
 *   - two synthetic specimens of different widths and thicknesses (5 mm x 0.25 mm and
 *     10 mm x 0.3 mm), built with one k / b = 1.0 N/rad and creases of their own, observed
 *     noise-free along a compression and a shear: the joint fit, started from k / b 0.7 N/rad
 *     and creases at -90 deg, recovers k / b to 1e-3 (relative) and each specimen's angles;
 *   - the joint Jacobian (block-sparse: the shared column everywhere, each specimen's columns on
 *     its own rows only, exact zeros elsewhere) against central differences of whole followed
 *     paths;
 *   - information adds: with the specimens independent but for k / b, 1 / se(k/b)^2 of the joint
 *     fit is the sum of 1 / se(k_s)^2 of each specimen fitted alone (its own angles and k), at
 *     the same point (the Schur complement of a block-arrowhead information matrix), so the
 *     joint standard error is below either;
 *   - an undetermined direction named per specimen: without gravity every E and k / b scale
 *     together, so "S-10mm:ribbon.youngs_modulus" and k / b get no standard error, the angles do;
 *   - one specimen fitted jointly is the single fit (rod_fit.h) of its angles and k: the same
 *     values, standard errors with the tracker's common mode (the sandwich), iterations and stop
 *     within the noise (stop_sd), on noisy data;
 *   - refusals with a reason: a width that is not known, a rigid hinge, per-crease hinges, the
 *     pair's hinge asked per specimen. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fit_scene_kit.h"
#include "rod_fit_joint.h"

#define NC 6
#define NS 6
#define NOBS (NC + NS)
#define KB_TRUE 1.0 /* N/rad */

/* Specimen 0: the PET strip 5 mm wide; specimen 1: 10 mm wide and 0.3 mm thick. Both with the
   hinge k = KB_TRUE b and creases of their own (truth) or at the scene's -90 deg and k / b 0.7
   (the start). */
static rod_scene specimen(int s, int truth)
{
    rod_scene sc = fit_kit_pet(31);
    if (s == 1) {
        sc.width = 0.010;
        sc.thickness = 0.3e-3;
        sc.fold_position = 0.2;
    }
    sc.fold_hinge_stiffness = (truth ? KB_TRUE : 0.7) * sc.width;
    if (truth) {
        sc.fold_angle_left_deg = s ? -88.0 : -86.0;
        sc.fold_angle_right_deg = s ? -92.5 : -89.5;
    }
    return sc;
}

static void observe(const rod_scene *truth, rod_fit_obs *obs)
{
    int n = fit_kit_states(obs, NC, NS, 0.12);
    assert_int_equal(n, NOBS);
    char why[256];
    rod_status st = fit_kit_observe(truth, obs, n, why, sizeof why);
    if (st != ROD_OK) printf("truth: %s\n", why);
    assert_int_equal(st, ROD_OK);
}

typedef struct kit {
    rod_scene truth[2], start[2];
    rod_fit_obs obs[2][NOBS];
    rod_fit_joint_spec spec[2];
} kit;

static void kit_init(kit *k)
{
    static const char *names[2] = {"S-5mm", "S-10mm"};
    for (int s = 0; s < 2; s++) {
        k->truth[s] = specimen(s, 1);
        k->start[s] = specimen(s, 0);
        observe(&k->truth[s], k->obs[s]);
        k->spec[s] = (rod_fit_joint_spec){names[s], &k->start[s], k->obs[s], NOBS};
    }
}

static rod_fit_joint_opts angles(void)
{
    rod_fit_joint_opts o = rod_fit_joint_opts_default();
    o.each.fit[ROD_FIT_ANGLE_LEFT] = o.each.fit[ROD_FIT_ANGLE_RIGHT] = 1;
    o.each.stop_sd = 0.0; /* noise-free: converged to round-off, not to the noise (as test_rod_fit) */
    return o;
}

static void print_joint(const rod_fit_joint_result *r)
{
    printf("joint: rms %.3g (start %.3g), %d iterations, %d evaluations, %.3f s\n", r->rms, r->rms_start,
           r->iterations, r->evaluations, r->wall_s);
    for (int i = 0; i < r->np; i++)
        printf("  %-40s se %.4g%s\n", r->key[i], r->se[i], r->determined[i] ? "" : "  not determined by these data");
    printf("  k/b %.8g N/rad (start %.4g), relative se %.4g\n", exp(r->kb), exp(r->kb0), r->kb_se);
}

static void recovers_the_shared_hinge_per_width(void **state)
{
    (void)state;
    static kit k;
    kit_init(&k);
    rod_fit_joint_opts o = angles();
    rod_fit_joint_result r;
    char why[512];
    rod_status st = rod_fit_joint_run(k.spec, 2, &o, &r, why, sizeof why);
    if (st != ROD_OK) printf("joint fit: %s\n", why);
    assert_int_equal(st, ROD_OK);
    print_joint(&r);
    assert_int_equal(r.np, 5);
    assert_string_equal(r.key[0], ROD_FIT_JOINT_SHARED_KEY);
    assert_string_equal(r.key[3], "S-10mm:folds.angle_left_deg");
    assert_true(r.rms_start > 1.0);
    assert_true(r.rms < 1e-3);
    assert_false(r.misfit);
    assert_true(fabs(exp(r.kb) / KB_TRUE - 1.0) < 1e-3);
    assert_true(r.kb_determined && isfinite(r.kb_se));
    for (int s = 0; s < 2; s++) {
        const rod_fit_result *q = &r.spec[s];
        printf("  specimen %d: angles %.6f %.6f (truth %.1f %.1f), k %.6g (truth %.6g), rms %.3g\n", s,
               q->u[ROD_FIT_ANGLE_LEFT], q->u[ROD_FIT_ANGLE_RIGHT], k.truth[s].fold_angle_left_deg,
               k.truth[s].fold_angle_right_deg, exp(q->u[ROD_FIT_HINGE]), k.truth[s].fold_hinge_stiffness, q->rms);
        assert_true(fabs(q->u[ROD_FIT_ANGLE_LEFT] - k.truth[s].fold_angle_left_deg) < 1e-3);
        assert_true(fabs(q->u[ROD_FIT_ANGLE_RIGHT] - k.truth[s].fold_angle_right_deg) < 1e-3);
        /* Each specimen's k is k / b times its width. */
        assert_true(fabs(q->u[ROD_FIT_HINGE] - (r.kb + log(k.truth[s].width))) < 1e-12);
        assert_true(q->fitted[ROD_FIT_HINGE] && q->fitted[ROD_FIT_ANGLE_LEFT] && !q->fitted[ROD_FIT_YOUNGS]);
        assert_true(fabs(q->se[ROD_FIT_HINGE] - r.kb_se) < 1e-15);
    }
    rod_fit_joint_result_free(&r);
}

static void the_joint_jacobian_matches_finite_differences(void **state)
{
    (void)state;
    static kit k;
    kit_init(&k);
    rod_fit_joint_opts o = angles();
    rod_fit_joint_model *m = NULL;
    char why[512];
    assert_int_equal(rod_fit_joint_model_alloc(k.spec, 2, &o, &m, why, sizeof why), ROD_OK);
    int np = rod_fit_joint_model_np(m), nr = 2 * rod_fit_joint_model_nobs(m);
    assert_int_equal(np, 5);
    assert_int_equal(nr, 4 * NOBS);
    double th[5], tp[5], y[4 * NOBS], yp[4 * NOBS], ym[4 * NOBS], J[4 * NOBS * 5];
    rod_fit_joint_model_start(m, th);
    assert_true(fabs(exp(th[0]) - 0.7) < 1e-12);
    th[1] += 1.0; /* off the scenes' values, so nothing is symmetric by accident */
    th[4] -= 1.5;
    assert_int_equal(rod_fit_joint_model_eval(m, th, y, J, why, sizeof why), ROD_OK);
    const double h[5] = {2e-3, 0.02, 0.02, 0.02, 0.02};
    for (int j = 0; j < np; j++) {
        memcpy(tp, th, sizeof tp);
        tp[j] += h[j];
        rod_fit_joint_model_reset(m);
        assert_int_equal(rod_fit_joint_model_eval(m, tp, yp, NULL, why, sizeof why), ROD_OK);
        tp[j] -= 2.0 * h[j];
        rod_fit_joint_model_reset(m);
        assert_int_equal(rod_fit_joint_model_eval(m, tp, ym, NULL, why, sizeof why), ROD_OK);
        double err = 0.0, mag = 0.0, other = 0.0;
        int owner = j == 0 ? -1 : (j - 1) / 2;
        for (int r = 0; r < nr; r++) {
            double fd = (yp[r] - ym[r]) / (2.0 * h[j]), an = J[r * np + j];
            int row_spec = r / (2 * NOBS);
            if (owner >= 0 && owner != row_spec) {
                /* Another specimen's column: exactly zero, and its paths do not move (up to the
                   re-followed paths' own round-off: Newton stops at its tolerance). */
                assert_true(an == 0.0);
                other = fmax(other, fabs(fd));
                continue;
            }
            err = fmax(err, fabs(fd - an));
            mag = fmax(mag, fabs(fd));
        }
        printf("column %d (%s): max |dy/dtheta| %.4g, max error %.2g, other specimen's rows %.2g\n", j,
               j == 0 ? "k/b" : "angle", mag, err, other);
        assert_true(mag > 0.0);
        assert_true(other <= 1e-6 * mag);
        assert_true(err <= 1e-4 * mag);
    }
    rod_fit_joint_model_free(m);
}

static void joint_information_is_the_sum_of_the_specimens(void **state)
{
    (void)state;
    static kit k;
    kit_init(&k);
    rod_fit_joint_opts o = angles();
    rod_fit_joint_result r;
    char why[512];
    assert_int_equal(rod_fit_joint_run(k.spec, 2, &o, &r, why, sizeof why), ROD_OK);
    double info_alone = 0.0, se_min = INFINITY;
    for (int s = 0; s < 2; s++) {
        /* Alone: its own angles and its own k, from its truth (noise-free: the same point the
           joint fit ends at). */
        rod_fit_opts oa = rod_fit_opts_default();
        oa.fit[ROD_FIT_ANGLE_LEFT] = oa.fit[ROD_FIT_ANGLE_RIGHT] = oa.fit[ROD_FIT_HINGE] = 1;
        rod_fit_result a;
        assert_int_equal(rod_fit_run(&k.truth[s], k.obs[s], NOBS, &oa, &a, why, sizeof why), ROD_OK);
        assert_true(a.determined[ROD_FIT_HINGE]);
        printf("specimen %d alone: se(ln k) %.5g\n", s, a.se[ROD_FIT_HINGE]);
        info_alone += 1.0 / (a.se[ROD_FIT_HINGE] * a.se[ROD_FIT_HINGE]);
        se_min = fmin(se_min, a.se[ROD_FIT_HINGE]);
    }
    double info_joint = 1.0 / (r.kb_se * r.kb_se);
    printf("joint: se(ln k/b) %.5g; 1/se^2 joint %.6g, sum alone %.6g (rel diff %.2g)\n", r.kb_se, info_joint,
           info_alone, info_joint / info_alone - 1.0);
    assert_true(r.kb_se < se_min);
    assert_true(fabs(info_joint / info_alone - 1.0) < 1e-3);
    rod_fit_joint_result_free(&r);
}

/* One specimen fitted "jointly" is the single fit of its angles and its own k (ln k = ln(k / b) +
   ln b, the same start and bounds): the same LM loop, the same stop within the noise (stop_sd,
   default 0.05) and the same covariance with the tracker's common mode (sigma_b_a, the sandwich),
   on data with noise in them (a fixed pattern), so the stop matters. */
static void one_specimen_is_the_single_fit(void **state)
{
    (void)state;
    static kit k;
    kit_init(&k);
    rod_fit_obs obs[NOBS];
    for (int i = 0; i < NOBS; i++) {
        obs[i] = k.obs[0][i];
        obs[i].dz += 0.002 * sin(7.0 * i);
        obs[i].a += 0.015 * cos(5.0 * i);
    }
    rod_fit_joint_spec one = {"S-5mm", &k.start[0], obs, NOBS};
    rod_fit_joint_opts o = rod_fit_joint_opts_default();
    o.each.fit[ROD_FIT_ANGLE_LEFT] = o.each.fit[ROD_FIT_ANGLE_RIGHT] = 1;
    o.each.sigma_b_a = 0.003;
    rod_fit_opts so = o.each;
    so.fit[ROD_FIT_HINGE] = 1;
    rod_fit_joint_result r;
    rod_fit_result a, plain;
    char why[512];
    assert_int_equal(rod_fit_joint_run(&one, 1, &o, &r, why, sizeof why), ROD_OK);
    assert_int_equal(rod_fit_run(&k.start[0], obs, NOBS, &so, &a, why, sizeof why), ROD_OK);
    so.sigma_b_a = 0.0;
    assert_int_equal(rod_fit_run(&k.start[0], obs, NOBS, &so, &plain, why, sizeof why), ROD_OK);
    const rod_fit_result *q = &r.spec[0];
    printf("joint of one: %d iterations, Gauss-Newton step left %.3g sd, sigma_b %g %g; single: %d, %.3g sd\n",
           r.iterations, r.gn_sd, r.sigma_b[0], r.sigma_b[1], a.iterations, a.gn_sd);
    const int keys[3] = {ROD_FIT_ANGLE_LEFT, ROD_FIT_ANGLE_RIGHT, ROD_FIT_HINGE};
    for (int i = 0; i < 3; i++) {
        int key = keys[i];
        printf("  %-24s joint %.10g +- %.6g, single %.10g +- %.6g (without the common mode +- %.6g)\n",
               rod_fit_key_name(key), q->u[key], q->se[key], a.u[key], a.se[key], plain.se[key]);
        assert_true(fabs(q->u[key] - a.u[key]) < 1e-9);
        assert_true(fabs(q->se[key] / a.se[key] - 1.0) < 1e-6);
        /* The common mode widens the angles' errors (by about 1%; the hinge's by 1e-5): without
           the sandwich the joint's would be the plain ones. */
        if (key != ROD_FIT_HINGE) assert_true(a.se[key] > plain.se[key] * (1.0 + 1e-3));
    }
    assert_true(fabs(r.kb_se / a.se[ROD_FIT_HINGE] - 1.0) < 1e-6);
    assert_true(r.sigma_b[1] == 0.003 && r.sigma_b[0] == 0.0);
    assert_int_equal(r.iterations, a.iterations);
    assert_true(r.gn_sd >= 0.0 && r.gn_sd < o.each.stop_sd);
    assert_true(fabs(r.gn_sd - a.gn_sd) < 1e-6);
    rod_fit_joint_result_free(&r);
}

static void an_undetermined_direction_is_named_per_specimen(void **state)
{
    (void)state;
    /* Without gravity, under displacement control, a strip's shape depends on its hinge only
       through k / (E I1): scaling every specimen's E and the shared k / b together changes
       nothing, so E of each specimen and k / b are "not determined by these data" (no number),
       while the crease angles are. */
    static kit k;
    for (int s = 0; s < 2; s++) {
        k.truth[s] = specimen(s, 1);
        k.truth[s].gravity[2] = 0.0;
        observe(&k.truth[s], k.obs[s]);
        k.start[s] = k.truth[s];
    }
    rod_fit_joint_spec sp[2] = {{"S-5mm", &k.start[0], k.obs[0], NOBS}, {"S-10mm", &k.start[1], k.obs[1], NOBS}};
    rod_fit_joint_opts o = angles();
    o.each.fit[ROD_FIT_YOUNGS] = 1;
    rod_fit_joint_result r;
    char why[512];
    rod_status st = rod_fit_joint_run(sp, 2, &o, &r, why, sizeof why);
    if (st != ROD_OK) printf("joint fit: %s\n", why);
    assert_int_equal(st, ROD_OK);
    print_joint(&r);
    assert_int_equal(r.np, 7);
    assert_string_equal(r.key[6], "S-10mm:ribbon.youngs_modulus");
    assert_false(r.kb_determined);
    assert_true(isinf(r.kb_se));
    for (int i = 1; i < r.np; i++) {
        int young = strstr(r.key[i], "youngs_modulus") != NULL;
        assert_int_equal(r.determined[i], !young);
        assert_int_equal(isfinite(r.se[i]), !young);
    }
    printf("smallest singular value of the range-scaled Jacobian %.3g (largest %.3g)\n", r.sv_min, r.sv_max);
    assert_true(r.sv_min < 1e-3 * r.sv_max);
    assert_false(r.spec[1].determined[ROD_FIT_YOUNGS]);
    assert_true(r.spec[1].determined[ROD_FIT_ANGLE_LEFT]);
    rod_fit_joint_result_free(&r);
}

/* Runs the joint fit expecting a refusal whose reason holds each of the words given. */
static void refused(const rod_fit_joint_spec *sp, const rod_fit_joint_opts *o, const char *w1, const char *w2)
{
    rod_fit_joint_result r;
    char why[512] = "";
    rod_status st = rod_fit_joint_run(sp, 2, o, &r, why, sizeof why);
    printf("refused: %s\n", why);
    rod_fit_joint_result_free(&r);
    assert_int_equal(st, ROD_ERR_SCENE);
    assert_non_null(strstr(why, w1));
    if (w2) assert_non_null(strstr(why, w2));
}

static void refusals_are_named(void **state)
{
    (void)state;
    rod_fit_obs obs[NOBS];
    fit_kit_states(obs, NC, NS, 0.12);
    rod_scene a = specimen(0, 0), b = specimen(1, 0);
    rod_fit_joint_spec sp[2] = {{"A", &a, obs, NOBS}, {"B", &b, obs, NOBS}};
    rod_fit_joint_opts o = angles();
    b.width = NAN;
    refused(sp, &o, "specimen B: its width is unknown", NULL);
    b.width = 0.0;
    refused(sp, &o, "specimen B: its width is unknown", NULL);
    b = specimen(1, 0);
    a.fold_hinge_stiffness = ROD_HINGE_RIGID;
    refused(sp, &o, "specimen A: no hinge to share", "rigid");
    a = specimen(0, 0);
    o.each.fit[ROD_FIT_HINGE_LEFT] = 1;
    refused(sp, &o, "not shared per unit width", NULL);
    o = angles();
    o.each.fit[ROD_FIT_HINGE] = 1;
    refused(sp, &o, "shared parameter", NULL);
    o = angles();
    sp[1].name = "A";
    refused(sp, &o, "two specimens are named A", NULL);
    sp[1].name = "B";
    sp[1].nobs = 3;
    refused(sp, &o, "specimen B: too few observations", NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(recovers_the_shared_hinge_per_width),
        cmocka_unit_test(the_joint_jacobian_matches_finite_differences),
        cmocka_unit_test(joint_information_is_the_sum_of_the_specimens),
        cmocka_unit_test(one_specimen_is_the_single_fit),
        cmocka_unit_test(an_undetermined_direction_is_named_per_specimen),
        cmocka_unit_test(refusals_are_named),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
