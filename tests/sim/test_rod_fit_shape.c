/* test_rod_fit_shape.c: the projected centreline as a fit observable (sim/rod_shape.h,
 * rod_fit.h's shapes; issue 32 A):
 *   - resampling by arc length against closed forms: a straight segment (points at (i + 1/2) / k
 *     exactly) and a fine polyline of a half circle (the points at their angles, to the chord's
 *     error);
 *   - the shapes' Jacobian rows (dq/du from the factorised Hessian, then the projection's
 *     directional derivative) against central differences of the model re-solved at u +- h for
 *     every strip parameter (PET strip, N = 31, a compression state and the hold);
 *   - what they add: on one noise-free twin whose creases sit 0.6% and 0.8% of l off the scene's,
 *     the compression and hold's Delta Z and A leave the crease positions "not determined"; with
 *     the centreline at three states both are determined and recovered;
 *   - bad input: a shape at a state no observation has, a non-positive noise. */
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

#define NMAX 32
#define K 24

static void resample_matches_closed_forms(void **state)
{
    (void)state;
    double line[4] = {0.0, 0.0, 3.0, 4.0}, out[2 * K];
    assert_int_equal(rod_shape_resample(line, 2, K, out), 0);
    for (int i = 0; i < K; i++) {
        double f = (i + 0.5) / K;
        assert_true(fabs(out[2 * i] - 3.0 * f) < 1e-12 && fabs(out[2 * i + 1] - 4.0 * f) < 1e-12);
    }
    /* Half circle of radius 1 from (1, 0) to (-1, 0) through (0, 1), 2001 points. */
    enum { NP = 2001 };
    static double arc[2 * NP];
    for (int i = 0; i < NP; i++) {
        double t = M_PI * i / (NP - 1);
        arc[2 * i] = cos(t);
        arc[2 * i + 1] = sin(t);
    }
    assert_int_equal(rod_shape_resample(arc, NP, K, out), 0);
    double h = M_PI / (NP - 1), chord = h * h / 8.0 + 1e-12; /* the polyline's sagitta */
    for (int i = 0; i < K; i++) {
        double t = M_PI * (i + 0.5) / K;
        assert_true(hypot(out[2 * i] - cos(t), out[2 * i + 1] - sin(t)) < 2.0 * chord + 1e-6 * h);
    }
    assert_int_equal(rod_shape_resample(arc, 1, K, out), -1);
    assert_int_equal(rod_shape_resample(arc, NP, ROD_SHAPE_MAX_POINTS + 1, out), -1);
    double flat[4] = {1.0, 1.0, 1.0, 1.0};
    assert_int_equal(rod_shape_resample(flat, 2, K, out), -1);
}

/* Observations at the compression states of the kit (n_c), and the truth's shapes at `which`. */
static int states(rod_fit_obs *obs, int n_c)
{
    return fit_kit_states(obs, n_c, 0, 0.0);
}

static void shapes_of(const rod_scene *truth, rod_fit_obs *obs, int n, rod_fit_shape *sh, const int *which, int ns)
{
    rod_fit_model *m = NULL;
    char why[256];
    assert_int_equal(rod_fit_model_alloc(truth, obs, n, 0, &m, why, sizeof why), ROD_OK);
    for (int i = 0; i < ns; i++) {
        sh[i] = (rod_fit_shape){.dl = obs[which[i]].dl, .dw = obs[which[i]].dw, .k = K};
    }
    assert_int_equal(rod_fit_model_set_shapes(m, sh, ns, why, sizeof why), ROD_OK);
    double u[ROD_FIT_NKEYS], y[2 * NMAX];
    rod_fit_scene_values(truth, u);
    rod_status st = rod_fit_model_eval(m, u, NULL, y, NULL, why, sizeof why);
    if (st != ROD_OK) printf("truth: %s\n", why);
    assert_int_equal(st, ROD_OK);
    for (int k = 0; k < n; k++) {
        obs[k].dz = y[2 * k];
        obs[k].a = y[2 * k + 1];
    }
    const double *sy, *sj;
    int rows = rod_fit_model_shape_rows(m, &sy, &sj);
    assert_int_equal(rows, 2 * K * ns);
    assert_null(sj);
    for (int i = 0; i < ns; i++) memcpy(sh[i].xz, &sy[2 * K * i], sizeof(double) * 2 * K);
    rod_fit_model_free(m);
}

static rod_scene twin(void)
{
    rod_scene t = fit_kit_pet(31);
    t.fold_angle_left_deg = -86.0;
    t.fold_angle_right_deg = -92.0;
    t.fold_position_left = 0.21 + 0.006;
    t.fold_position_right = 0.79 - 0.008;
    t.fold_hinge_stiffness = 2.5e-3;
    t.youngs_modulus = 4.4e9;
    t.shear_modulus = 4.4e9 / 2.76;
    return t;
}

static void shape_jacobian_matches_re_solved_paths(void **state)
{
    (void)state;
    rod_scene sc = twin();
    rod_fit_obs obs[NMAX];
    int n = states(obs, 4);
    int which[2] = {1, n - 1};
    rod_fit_shape sh[2];
    for (int i = 0; i < 2; i++) sh[i] = (rod_fit_shape){.dl = obs[which[i]].dl, .dw = 0.0, .k = K};
    rod_fit_model *m = NULL;
    char why[256];
    assert_int_equal(rod_fit_model_alloc(&sc, obs, n, 0, &m, why, sizeof why), ROD_OK);
    assert_int_equal(rod_fit_model_set_shapes(m, sh, 2, why, sizeof why), ROD_OK);
    double u[ROD_FIT_NKEYS], y[2 * NMAX], jac[2 * NMAX * ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, u);
    int use[ROD_FIT_NKEYS] = {0};
    for (int j = 0; j <= ROD_FIT_YOUNGS; j++) use[j] = 1;
    assert_int_equal(rod_fit_model_eval(m, u, use, y, jac, why, sizeof why), ROD_OK);
    const double *sy, *sj;
    int rows = rod_fit_model_shape_rows(m, &sy, &sj);
    assert_int_equal(rows, 4 * K);
    assert_non_null(sj);
    static double J[4 * K * ROD_FIT_NKEYS], yp[4 * K], ym[4 * K];
    memcpy(J, sj, sizeof(double) * (size_t)rows * ROD_FIT_NKEYS);
    const double hfd[ROD_FIT_NKEYS] = {0.02, 0.02, 2e-5, 2e-5, 2e-3, 2e-3};
    for (int j = 0; j <= ROD_FIT_YOUNGS; j++) {
        double up[ROD_FIT_NKEYS];
        memcpy(up, u, sizeof up);
        up[j] = u[j] + hfd[j];
        assert_int_equal(rod_fit_model_eval(m, up, NULL, y, NULL, why, sizeof why), ROD_OK);
        rod_fit_model_shape_rows(m, &sy, &sj);
        memcpy(yp, sy, sizeof(double) * (size_t)rows);
        up[j] = u[j] - hfd[j];
        assert_int_equal(rod_fit_model_eval(m, up, NULL, y, NULL, why, sizeof why), ROD_OK);
        rod_fit_model_shape_rows(m, &sy, &sj);
        memcpy(ym, sy, sizeof(double) * (size_t)rows);
        double err = 0.0, mag = 0.0;
        for (int p = 0; p < rows; p++) {
            double fd = (yp[p] - ym[p]) / (2.0 * hfd[j]);
            err = fmax(err, fabs(fd - J[p * ROD_FIT_NKEYS + j]));
            mag = fmax(mag, fabs(fd));
        }
        printf("  %-24s |d shape| %.3g, largest difference %.3g\n", rod_fit_key_name(j), mag, err);
        assert_true(mag > 0.0);
        assert_true(err <= 2e-3 * mag);
    }
    rod_fit_model_free(m);
}

static void shapes_determine_the_crease_positions(void **state)
{
    (void)state;
    rod_scene truth = twin(), sc = fit_kit_pet(31);
    rod_fit_obs obs[NMAX];
    int n = states(obs, 8);
    int which[3] = {0, 4, n - 1};
    rod_fit_shape sh[3];
    shapes_of(&truth, obs, n, sh, which, 3);
    rod_fit_opts o = rod_fit_opts_default();
    for (int k = ROD_FIT_ANGLE_LEFT; k <= ROD_FIT_YOUNGS; k++) o.fit[k] = 1;
    o.stop_sd = 0.0;
    rod_fit_result r0, r1;
    char why[256];
    rod_status st = rod_fit_run(&sc, obs, n, &o, &r0, why, sizeof why);
    if (st != ROD_OK) printf("without shapes: %s\n", why);
    assert_int_equal(st, ROD_OK);
    o.shapes = sh;
    o.nshapes = 3;
    o.sigma_shape = 1e-3;
    st = rod_fit_run(&sc, obs, n, &o, &r1, why, sizeof why);
    if (st != ROD_OK) printf("with shapes: %s\n", why);
    assert_int_equal(st, ROD_OK);
    double ut[ROD_FIT_NKEYS];
    rod_fit_scene_values(&truth, ut);
    for (int k = ROD_FIT_ANGLE_LEFT; k <= ROD_FIT_YOUNGS; k++)
        printf("  %-24s truth %.6g | without %.6g %s | with %.6g +- %.3g%s\n", rod_fit_key_name(k), ut[k], r0.u[k],
               r0.determined[k] ? "" : "(not determined)", r1.u[k], r1.se[k], r1.determined[k] ? "" : " (not determined)");
    printf("  sv_min without %.3g, with %.3g; rms %.3g, shape rms %.3g, %d iterations\n", r0.sv_min, r1.sv_min, r1.rms,
           r1.shape_rms, r1.iterations);
    assert_false(r0.determined[ROD_FIT_POSITION_LEFT] && r0.determined[ROD_FIT_POSITION_RIGHT]);
    assert_int_equal(r1.nshape_rows, 3 * 2 * K);
    for (int k = ROD_FIT_ANGLE_LEFT; k <= ROD_FIT_YOUNGS; k++) {
        assert_true(r1.determined[k]);
        assert_true(fabs(r1.u[k] - ut[k]) <= 1e-5 * (r1.hi[k] - r1.lo[k]));
    }
    assert_true(r1.rms < 1e-3);
    /* Started at the optimum (opts.start: the truth, noise-free data) the fit stays there: at most
     * one step, where from the scene's values it took r1.iterations. */
    rod_fit_result r2;
    o.start = ut;
    st = rod_fit_run(&sc, obs, n, &o, &r2, why, sizeof why);
    assert_int_equal(st, ROD_OK);
    printf("  started at the truth: %d iterations (from the scene's values %d), rms_start %.3g (the scene's %.3g)\n",
           r2.iterations, r1.iterations, r2.rms_start, r1.rms_start);
    assert_true(r1.iterations > 1);
    assert_true(r2.iterations <= 1);
    assert_true(r2.rms_start == r1.rms_start);
    for (int k = ROD_FIT_ANGLE_LEFT; k <= ROD_FIT_YOUNGS; k++)
        assert_true(fabs(r2.u[k] - ut[k]) <= 1e-5 * (r2.hi[k] - r2.lo[k]));
}

static void bad_shapes_are_named(void **state)
{
    (void)state;
    rod_scene sc = fit_kit_pet(31);
    rod_fit_obs obs[NMAX];
    int n = states(obs, 4);
    rod_fit_shape sh = {.dl = 0.2, .dw = 0.0, .k = K};
    rod_fit_opts o = rod_fit_opts_default();
    o.fit[ROD_FIT_ANGLE_LEFT] = 1;
    o.shapes = &sh;
    o.nshapes = 1;
    rod_fit_result r;
    char why[256] = "";
    assert_int_equal(rod_fit_run(&sc, obs, n, &o, &r, why, sizeof why), ROD_ERR_SCENE);
    assert_non_null(strstr(why, "no observation at its state"));
    sh.dl = obs[0].dl;
    o.sigma_shape = 0.0;
    assert_int_equal(rod_fit_run(&sc, obs, n, &o, &r, why, sizeof why), ROD_ERR_SCENE);
    assert_non_null(strstr(why, "noise"));
    o.sigma_shape = 1e-3;
    sh.k = 0;
    assert_int_equal(rod_fit_run(&sc, obs, n, &o, &r, why, sizeof why), ROD_ERR_SCENE);
    assert_non_null(strstr(why, "points"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(resample_matches_closed_forms),
        cmocka_unit_test(shape_jacobian_matches_re_solved_paths),
        cmocka_unit_test(shapes_determine_the_crease_positions),
        cmocka_unit_test(bad_shapes_are_named),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
