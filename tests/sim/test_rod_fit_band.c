/* test_rod_fit_band.c: the linearised band of a fitted prediction (sim/rod_fit_band.h) against
 * closed forms: for a linear predictor s = s0 + g . (u - u*) the band must be the exactly
 * propagated sd = sqrt(g^T C g), C the posterior covariance (J^T J + P)^-1 written out by hand,
 * with and without priors; a parameter the data do not determine and without a prior makes the
 * band unbounded; the reduced chi-square widens it, never narrows it. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "rod_fit_band.h"

#include <stdio.h>

/* |a - b| <= eps, with the values printed when not */
#define assert_double_equal(a, b, eps) near((a), (b), (eps), #a, __FILE__, __LINE__)
static void near(double a, double b, double eps, const char *what, const char *file, int line)
{
    if (!(fabs(a - b) <= eps)) print_error("%s:%d: %s = %.17g, want %.17g +- %.3g\n", file, line, what, a, b, eps);
    _assert_true(fabs(a - b) <= eps, what, file, line);
}

typedef struct lin {
    double g[ROD_FIT_NKEYS], h[ROD_FIT_NKEYS], ustar[ROD_FIT_NKEYS];
    int kink; /* peak = |h . (u - u*)|: a V-shape */
    int calls;
} lin;

static int lin_fn(void *ctx, const double u[ROD_FIT_NKEYS], double *snap, double *peak, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    lin *l = ctx;
    double s = 0.25, a = 0.1;
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        s += l->g[k] * (u[k] - l->ustar[k]);
        a += (l->kink ? 0.0 : l->h[k] * (u[k] - l->ustar[k]));
    }
    if (l->kink) {
        double d = 0.0;
        for (int k = 0; k < ROD_FIT_NKEYS; k++) d += l->h[k] * (u[k] - l->ustar[k]);
        a += fabs(d);
    }
    *snap = s;
    *peak = a;
    l->calls++;
    return 0;
}

/* A fit of the two angles and the left position from a data Jacobian J (rows: residuals in noise
 * units) and priors of width sp (INFINITY: none), covariance written out by hand for the
 * block-diagonal case used here: angles coupled by J, the position's column zero (the data do
 * not see it). */
static void make_fit(rod_fit_result *f, lin *l, double sp_pos)
{
    memset(f, 0, sizeof *f);
    memset(l, 0, sizeof *l);
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        f->u[k] = l->ustar[k] = 0.3 + 0.1 * k;
        f->lo[k] = f->u[k] - 100.0;
        f->hi[k] = f->u[k] + 100.0;
    }
    /* J = [[2, 1], [1, 3], [0, 1]] on the angles: J^T J = [[5, 5], [5, 11]], det 30 */
    double a = 5.0, b = 5.0, d = 11.0, det = a * d - b * b;
    f->fitted[ROD_FIT_ANGLE_LEFT] = f->fitted[ROD_FIT_ANGLE_RIGHT] = f->fitted[ROD_FIT_POSITION_LEFT] = 1;
    f->determined[ROD_FIT_ANGLE_LEFT] = f->determined[ROD_FIT_ANGLE_RIGHT] = 1;
    f->cov[ROD_FIT_ANGLE_LEFT][ROD_FIT_ANGLE_LEFT] = d / det;
    f->cov[ROD_FIT_ANGLE_RIGHT][ROD_FIT_ANGLE_RIGHT] = a / det;
    f->cov[ROD_FIT_ANGLE_LEFT][ROD_FIT_ANGLE_RIGHT] = f->cov[ROD_FIT_ANGLE_RIGHT][ROD_FIT_ANGLE_LEFT] = -b / det;
    f->se[ROD_FIT_ANGLE_LEFT] = sqrt(d / det);
    f->se[ROD_FIT_ANGLE_RIGHT] = sqrt(a / det);
    /* the position: no data, so its posterior is its prior (as rod_fit reports it: not determined,
       se finite with a prior, INFINITY and cov 0 without) */
    f->determined[ROD_FIT_POSITION_LEFT] = 0;
    f->se[ROD_FIT_POSITION_LEFT] = isfinite(sp_pos) ? sp_pos : INFINITY;
    f->cov[ROD_FIT_POSITION_LEFT][ROD_FIT_POSITION_LEFT] = isfinite(sp_pos) ? sp_pos * sp_pos : 0.0;
    f->nobs = 3;
    f->nfit = 3;
    f->nres = 6 + isfinite(sp_pos);
    f->chi2 = 0.5 * (f->nres - f->nfit); /* reduced chi-square 0.5: no scaling */
    l->g[ROD_FIT_ANGLE_LEFT] = 0.004;
    l->g[ROD_FIT_ANGLE_RIGHT] = -0.007;
    l->g[ROD_FIT_POSITION_LEFT] = 1.5;
    l->h[ROD_FIT_ANGLE_LEFT] = 0.02;
    l->h[ROD_FIT_ANGLE_RIGHT] = 0.01;
    l->h[ROD_FIT_POSITION_LEFT] = -0.8;
}

static double quad(const rod_fit_result *f, const double *g)
{
    double s = 0.0;
    for (int i = 0; i < ROD_FIT_NKEYS; i++)
        for (int j = 0; j < ROD_FIT_NKEYS; j++) s += g[i] * f->cov[i][j] * g[j];
    return s;
}

static void test_linear_without_prior_the_band_is_exact(void **state)
{
    (void)state;
    rod_fit_result f;
    lin l;
    make_fit(&f, &l, INFINITY);
    f.fitted[ROD_FIT_POSITION_LEFT] = 0; /* held: the two angles alone */
    rod_fit_band b;
    char why[128];
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.1, lin_fn, &l, &b, why, sizeof why), ROD_OK);
    assert_true(b.ok);
    assert_int_equal(b.directions, 2);
    assert_int_equal(l.calls, 8); /* one and two standard deviations either side, 2 directions */
    /* closed form: g^T C g = (11 g1^2 - 10 g1 g2 + 5 g2^2) / 30 */
    double g1 = 0.004, g2 = -0.007, exact = sqrt((11 * g1 * g1 - 10 * g1 * g2 + 5 * g2 * g2) / 30.0);
    assert_double_equal(b.snap_sd, exact, 1e-12 * exact);
    assert_double_equal(b.snap_sd, sqrt(quad(&f, l.g)), 1e-12 * exact);
    assert_double_equal(b.peak_sd, sqrt(quad(&f, l.h)), 1e-12);
    assert_double_equal(b.scale, 1.0, 0.0);
}

static void test_linear_with_prior_the_undetermined_parameter_is_in_the_band(void **state)
{
    (void)state;
    rod_fit_result f;
    lin l;
    make_fit(&f, &l, 0.006);
    rod_fit_band b;
    char why[128];
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.1, lin_fn, &l, &b, why, sizeof why), ROD_OK);
    assert_true(b.ok);
    assert_false(b.unbounded);
    assert_int_equal(b.by_prior, 1);
    assert_int_equal(b.directions, 3);
    double g1 = 0.004, g2 = -0.007, gp = 1.5;
    double exact = sqrt((11 * g1 * g1 - 10 * g1 * g2 + 5 * g2 * g2) / 30.0 + gp * gp * 0.006 * 0.006);
    assert_double_equal(b.snap_sd, exact, 1e-12 * exact);
    assert_double_equal(b.peak_sd, sqrt(quad(&f, l.h)), 1e-12);
    assert_non_null(strstr(b.note, "prior"));
}

static void test_undetermined_without_prior_is_unbounded(void **state)
{
    (void)state;
    rod_fit_result f;
    lin l;
    make_fit(&f, &l, INFINITY);
    rod_fit_band b;
    char why[128];
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.1, lin_fn, &l, &b, why, sizeof why), ROD_OK);
    assert_false(b.ok);
    assert_true(b.unbounded);
    assert_int_equal(b.left_out, 1);
    assert_int_equal(l.calls, 0);
    assert_non_null(strstr(b.note, "folds.position_left"));
    assert_non_null(strstr(b.note, "unbounded"));
}

static void test_the_camera_offset_is_not_in_the_band(void **state)
{
    (void)state;
    rod_fit_result f;
    lin l;
    make_fit(&f, &l, 0.006);
    f.fitted[ROD_FIT_DZ_OFFSET] = 1; /* not determined and no prior, but not the strip's */
    f.se[ROD_FIT_DZ_OFFSET] = INFINITY;
    rod_fit_band b;
    char why[128];
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.1, lin_fn, &l, &b, why, sizeof why), ROD_OK);
    assert_true(b.ok);
    assert_int_equal(b.directions, 3);
}

static void test_reduced_chi_square_widens_never_narrows(void **state)
{
    (void)state;
    rod_fit_result f;
    lin l;
    make_fit(&f, &l, 0.006);
    double exact = sqrt(quad(&f, l.g));
    rod_fit_band b;
    char why[128];
    f.chi2 = 4.0 * (f.nres - f.nfit); /* residuals twice the stated noise */
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.1, lin_fn, &l, &b, why, sizeof why), ROD_OK);
    assert_double_equal(b.scale, 4.0, 1e-12);
    assert_double_equal(b.snap_sd, 2.0 * exact, 1e-12 * exact);
    assert_non_null(strstr(b.note, "chi-square"));
    f.cov_scaled = 1; /* the fit already scaled its covariance: not twice */
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.1, lin_fn, &l, &b, why, sizeof why), ROD_OK);
    assert_double_equal(b.snap_sd, exact, 1e-12 * exact);
    f.cov_scaled = 0;
    f.chi2 = 0.25 * (f.nres - f.nfit);
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.1, lin_fn, &l, &b, why, sizeof why), ROD_OK);
    assert_double_equal(b.snap_sd, exact, 1e-12 * exact);
}

static void test_a_kink_in_peak_widens_its_sd(void **state)
{
    (void)state;
    rod_fit_result f;
    lin l;
    make_fit(&f, &l, 0.006);
    l.kink = 1; /* peak = 0.1 + |h . du|: central differences would give 0 */
    rod_fit_band b;
    char why[128];
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.1, lin_fn, &l, &b, why, sizeof why), ROD_OK);
    assert_true(b.ok);
    double exact = sqrt(quad(&f, l.h)); /* |h . du| along each direction: one-sided, exact */
    assert_double_equal(b.peak_sd, exact, 1e-12);
}

static void test_p_other_is_the_normal_tail_for_a_linear_peak(void **state)
{
    (void)state;
    rod_fit_result f;
    lin l;
    make_fit(&f, &l, 0.006);
    rod_fit_band b;
    char why[128];
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.1, lin_fn, &l, &b, why, sizeof why), ROD_OK);
    double sd = sqrt(quad(&f, l.h)), thr = 0.1 + 2.5 * sd; /* 2.5 sd away: no probe reaches it */
    assert_double_equal(rod_fit_band_p_other(&b, 0.1, thr), 0.5 * erfc(2.5 / sqrt(2.0)), 1e-12);
}

/* peak |A| 0.55 - 0.01 z for z > -1.5 standard deviations of the one fitted parameter, then 0.25:
   a change of pathway between 1 and 2 sd, as twin 18 of the family (docs/calibration.md) */
static int jump_fn(void *ctx, const double u[ROD_FIT_NKEYS], double *snap, double *peak, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    const rod_fit_result *f = ctx;
    double z = (u[ROD_FIT_ANGLE_LEFT] - f->u[ROD_FIT_ANGLE_LEFT]) / f->se[ROD_FIT_ANGLE_LEFT];
    *snap = 0.25 + 0.001 * z;
    *peak = z > -1.5 ? 0.55 - 0.01 * z : 0.25;
    return 0;
}

static void test_p_other_sees_a_jump_across_the_threshold(void **state)
{
    (void)state;
    rod_fit_result f;
    memset(&f, 0, sizeof f);
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        f.lo[k] = -100.0;
        f.hi[k] = 100.0;
    }
    f.u[ROD_FIT_ANGLE_LEFT] = -85.0;
    f.fitted[ROD_FIT_ANGLE_LEFT] = f.determined[ROD_FIT_ANGLE_LEFT] = 1;
    f.se[ROD_FIT_ANGLE_LEFT] = 0.5;
    f.cov[ROD_FIT_ANGLE_LEFT][ROD_FIT_ANGLE_LEFT] = 0.25;
    f.nres = 40;
    f.nfit = 1;
    rod_fit_band b;
    char why[128];
    assert_int_equal(rod_fit_band_eval(&f, 0.25, 0.55, jump_fn, &f, &b, why, sizeof why), ROD_OK);
    assert_true(b.ok);
    assert_double_equal(b.peak_sd, 0.01, 1e-12);
    /* the normal tail alone: 0.05 / 0.01 = 5 sd, 2.9e-7; the jump: peak 0.56 at z = -1 and 0.25 at
       z = -2 cross 0.5 at z = -(1 + 0.06 / 0.31) */
    double t = 1.0 + 0.06 / 0.31;
    assert_double_equal(rod_fit_band_p_other(&b, 0.55, 0.5), 0.5 * erfc(t / sqrt(2.0)), 1e-12);
    assert_true(rod_fit_band_p_other(&b, 0.55, 0.5) > 0.1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_linear_without_prior_the_band_is_exact),
        cmocka_unit_test(test_linear_with_prior_the_undetermined_parameter_is_in_the_band),
        cmocka_unit_test(test_undetermined_without_prior_is_unbounded),
        cmocka_unit_test(test_the_camera_offset_is_not_in_the_band),
        cmocka_unit_test(test_reduced_chi_square_widens_never_narrows),
        cmocka_unit_test(test_a_kink_in_peak_widens_its_sd),
        cmocka_unit_test(test_p_other_is_the_normal_tail_for_a_linear_peak),
        cmocka_unit_test(test_p_other_sees_a_jump_across_the_threshold),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
