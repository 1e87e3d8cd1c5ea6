/* test_rod_fit_sandwich.c: the fit's covariance with a per-phase common-mode error (issue 32 D)
 * against closed forms: a linear model with known block-correlated noise, the sandwich against
 * the exact covariance of the weighted least-squares estimate (dense Sigma) and a Monte Carlo
 * of that estimate; the phases of a protocol; the common mode's estimate from residuals. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "rod_fit_sandwich.h"

enum { NOBS = 30, P = 3, NR = 2 * NOBS };

static const double SIG[2] = {0.002, 0.01}; /* per-frame noise of Delta Z, A */
static const double SB[2] = {0.001, 0.004}; /* common mode per phase */

static uint64_t rng = 88172645463325252ull;
static double unif(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return ((double)(rng >> 11) + 0.5) / 9007199254740992.0;
}
static double gauss(void) { return sqrt(-2.0 * log(unif())) * cos(2.0 * M_PI * unif()); }

static void inv3(const double *m, double *r)
{
    double d = m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
    r[0] = (m[4] * m[8] - m[5] * m[7]) / d; r[1] = (m[2] * m[7] - m[1] * m[8]) / d; r[2] = (m[1] * m[5] - m[2] * m[4]) / d;
    r[3] = (m[5] * m[6] - m[3] * m[8]) / d; r[4] = (m[0] * m[8] - m[2] * m[6]) / d; r[5] = (m[2] * m[3] - m[0] * m[5]) / d;
    r[6] = (m[3] * m[7] - m[4] * m[6]) / d; r[7] = (m[1] * m[6] - m[0] * m[7]) / d; r[8] = (m[0] * m[4] - m[1] * m[3]) / d;
}

/* The model: row 2k (Delta Z) and 2k+1 (A) of observation k, unweighted; phases 10/10/10. */
static void model(double *X, int *phase)
{
    for (int k = 0; k < NOBS; k++) {
        double t = (k + 1.0) / NOBS;
        phase[k] = k < 10 ? ROD_FIT_PHASE_COMPRESSION : k < 20 ? ROD_FIT_PHASE_HOLD : ROD_FIT_PHASE_SHEAR;
        double *z = X + (2 * k) * P, *a = X + (2 * k + 1) * P;
        z[0] = 1.0; z[1] = 0.5 * t; z[2] = 0.1 * t * t;
        a[0] = 0.2; a[1] = -t; a[2] = 1.0 + t;
    }
}

static void whitened(const double *X, double *Jw, double *hinv)
{
    double H[P * P] = {0};
    for (int r = 0; r < NR; r++)
        for (int j = 0; j < P; j++) Jw[r * P + j] = X[r * P + j] / SIG[r % 2];
    for (int r = 0; r < NR; r++)
        for (int i = 0; i < P; i++)
            for (int j = 0; j < P; j++) H[i * P + j] += Jw[r * P + i] * Jw[r * P + j];
    inv3(H, hinv);
}

static void sandwich(double *cov, double *hinv)
{
    double X[NR * P], Jw[NR * P];
    int phase[NOBS];
    model(X, phase);
    whitened(X, Jw, hinv);
    double rho[2] = {(SB[0] / SIG[0]) * (SB[0] / SIG[0]), (SB[1] / SIG[1]) * (SB[1] / SIG[1])};
    memcpy(cov, hinv, sizeof(double) * P * P);
    rod_fit_sandwich_add(Jw, NOBS, P, phase, rho, hinv, cov);
}

/* Exact: (X^T W X)^-1 X^T W Sigma W X (X^T W X)^-1 with the dense Sigma. */
static void test_sandwich_exact(void **state)
{
    (void)state;
    double X[NR * P], Jw[NR * P], hinv[P * P], cov[P * P];
    int phase[NOBS];
    model(X, phase);
    whitened(X, Jw, hinv);
    sandwich(cov, hinv);
    static double Sigma[NR][NR];
    for (int r = 0; r < NR; r++)
        for (int s = 0; s < NR; s++) {
            int a = r % 2, b = s % 2;
            Sigma[r][s] = (r == s ? SIG[a] * SIG[a] : 0.0) + (a == b && phase[r / 2] == phase[s / 2] ? SB[a] * SB[a] : 0.0);
        }
    /* B = hinv X^T W (P x NR), W = diag 1/sigma^2 */
    static double B[P][NR];
    for (int i = 0; i < P; i++)
        for (int r = 0; r < NR; r++) {
            double s = 0.0;
            for (int j = 0; j < P; j++) s += hinv[i * P + j] * X[r * P + j];
            B[i][r] = s / (SIG[r % 2] * SIG[r % 2]);
        }
    for (int i = 0; i < P; i++)
        for (int j = 0; j < P; j++) {
            double s = 0.0;
            for (int r = 0; r < NR; r++)
                for (int q = 0; q < NR; q++) s += B[i][r] * Sigma[r][q] * B[j][q];
            assert_true(fabs(cov[i * P + j] - s) <= 1e-10 * sqrt(cov[i * P + i] * cov[j * P + j]));
        }
    /* The common mode matters here: the independent-noise covariance is well below it. */
    assert_true(cov[0] > 1.5 * hinv[0]);
}

/* Monte Carlo of the weighted least-squares estimate with the block-correlated noise. */
static void test_sandwich_monte_carlo(void **state)
{
    (void)state;
    double X[NR * P], Jw[NR * P], hinv[P * P], cov[P * P];
    int phase[NOBS];
    model(X, phase);
    whitened(X, Jw, hinv);
    sandwich(cov, hinv);
    enum { DRAWS = 20000 };
    double s2[P * P] = {0};
    for (int d = 0; d < DRAWS; d++) {
        double cm[ROD_FIT_NPHASES][2], e[NR], g[P] = {0}, x[P];
        for (int ph = 0; ph < ROD_FIT_NPHASES; ph++)
            for (int a = 0; a < 2; a++) cm[ph][a] = SB[a] * gauss();
        for (int r = 0; r < NR; r++) e[r] = SIG[r % 2] * gauss() + cm[phase[r / 2]][r % 2];
        for (int r = 0; r < NR; r++)
            for (int j = 0; j < P; j++) g[j] += Jw[r * P + j] * e[r] / SIG[r % 2];
        for (int i = 0; i < P; i++) {
            x[i] = 0.0;
            for (int j = 0; j < P; j++) x[i] += hinv[i * P + j] * g[j];
        }
        for (int i = 0; i < P; i++)
            for (int j = 0; j < P; j++) s2[i * P + j] += x[i] * x[j] / DRAWS;
    }
    for (int i = 0; i < P; i++) { /* variances to 5% (sd of a 20000-draw variance: 1%) */
        assert_true(fabs(s2[i * P + i] / cov[i * P + i] - 1.0) < 0.05);
        assert_true(s2[i * P + i] > 1.3 * hinv[i * P + i]);
    }
}

static void test_phases(void **state)
{
    (void)state;
    rod_fit_obs o[7] = {{0.1, 0, 0, 0}, {0.2, 0, 0, 0}, {0.3, 0, 0, 0}, {0.3, 0, 0, 0}, {0.3, 0, 0, 0},
                        {0.3, 0.01, 0, 0}, {0.3, 0.02, 0, 0}};
    int ph[7], want[7] = {0, 0, 1, 1, 1, 2, 2};
    rod_fit_phases(o, 7, ph);
    for (int k = 0; k < 7; k++) assert_int_equal(ph[k], want[k]);
}

/* Raw whitened noise with a common mode rho: the estimate's mean over draws is rho (the clamp
   at 0 is rare at rho 0.5, m 10), and 0 without a common mode within its scatter. */
static void test_estimate(void **state)
{
    (void)state;
    int phase[NOBS];
    double X[NR * P];
    model(X, phase);
    for (int with = 0; with < 2; with++) {
        double rho_true[2] = {with ? 0.5 : 0.0, with ? 0.2 : 0.0}, mean[2] = {0, 0};
        enum { DRAWS = 4000 };
        for (int d = 0; d < DRAWS; d++) {
            double f[NR], cm[ROD_FIT_NPHASES][2], rho[2];
            for (int ph = 0; ph < ROD_FIT_NPHASES; ph++)
                for (int a = 0; a < 2; a++) cm[ph][a] = sqrt(rho_true[a]) * gauss();
            for (int r = 0; r < NR; r++) f[r] = gauss() + cm[phase[r / 2]][r % 2];
            rod_fit_common_mode_estimate(f, NOBS, phase, rho);
            mean[0] += rho[0] / DRAWS;
            mean[1] += rho[1] / DRAWS;
        }
        for (int a = 0; a < 2; a++)
            if (with) assert_true(fabs(mean[a] / rho_true[a] - 1.0) < 0.1);
            else assert_true(mean[a] < 0.05);
    }
}

/* The centrelines' common mode (rod_fit_sandwich_add_shapes): after the 2 NOBS rows, 3 shapes of
   8 whitened rows each; each shape's error covariance is I + r_s r_s^T with r_s its residuals.
   Against the exact H^-1 J^T Sigma J H^-1 with that dense Sigma (I elsewhere), and a Monte Carlo
   of the estimate with each shape's error a smooth deformation c_s r_s, c_s ~ N(0, 1). */
enum { NSH = 3, KSH = 8, NRS = NR + NSH * KSH };

static void shape_model(double *Jw, double *f, double *hinv)
{
    double X[NR * P];
    int phase[NOBS];
    model(X, phase);
    for (int r = 0; r < NR; r++)
        for (int j = 0; j < P; j++) Jw[r * P + j] = X[r * P + j] / SIG[r % 2];
    for (int s = 0; s < NSH; s++)
        for (int q = 0; q < KSH; q++) {
            int r = NR + s * KSH + q;
            double t = (q + 0.5) / KSH;
            Jw[r * P + 0] = 900.0 * sin(M_PI * t) * (s + 1);
            Jw[r * P + 1] = 1500.0 * t * (1.0 - 0.3 * s);
            Jw[r * P + 2] = 600.0 * (cos(2.0 * M_PI * t) + 0.5 * s);
            f[r] = (2.0 + 0.5 * s) * sin(M_PI * t + 0.3 * s); /* a smooth residual */
        }
    for (int r = 0; r < NR; r++) f[r] = 0.0;
    double H[P * P] = {0};
    for (int r = 0; r < NRS; r++)
        for (int i = 0; i < P; i++)
            for (int j = 0; j < P; j++) H[i * P + j] += Jw[r * P + i] * Jw[r * P + j];
    inv3(H, hinv);
}

static void test_shape_common_mode_exact(void **state)
{
    (void)state;
    static double Jw[NRS * P], f[NRS];
    double hinv[P * P], cov[P * P];
    int rows[NSH] = {KSH, KSH, KSH};
    shape_model(Jw, f, hinv);
    memcpy(cov, hinv, sizeof cov);
    assert_int_equal(rod_fit_sandwich_add_shapes(Jw, f, P, NR, rows, NSH, hinv, cov), 0);
    static double Sigma[NRS][NRS], B[P][NRS];
    for (int r = 0; r < NRS; r++)
        for (int q = 0; q < NRS; q++) {
            int sr = r < NR ? -1 : (r - NR) / KSH, sq = q < NR ? -1 : (q - NR) / KSH;
            Sigma[r][q] = (r == q ? 1.0 : 0.0) + (sr >= 0 && sr == sq ? f[r] * f[q] : 0.0);
        }
    for (int i = 0; i < P; i++)
        for (int r = 0; r < NRS; r++) {
            double s = 0.0;
            for (int j = 0; j < P; j++) s += hinv[i * P + j] * Jw[r * P + j];
            B[i][r] = s;
        }
    for (int i = 0; i < P; i++)
        for (int j = 0; j < P; j++) {
            double s = 0.0;
            for (int r = 0; r < NRS; r++)
                for (int q = 0; q < NRS; q++) s += B[i][r] * Sigma[r][q] * B[j][q];
            assert_true(fabs(cov[i * P + j] - s) <= 1e-10 * sqrt(cov[i * P + i] * cov[j * P + j]));
        }
    assert_true(cov[0] > 1.5 * hinv[0]); /* the shapes' common mode matters in this model */
    /* Monte Carlo: e = N(0, I) + c_s f_s on shape s's rows */
    enum { DRAWS = 20000 };
    double s2[P * P] = {0};
    for (int d = 0; d < DRAWS; d++) {
        double g[P] = {0}, x[P], c[NSH];
        for (int s = 0; s < NSH; s++) c[s] = gauss();
        for (int r = 0; r < NRS; r++) {
            double e = gauss() + (r >= NR ? c[(r - NR) / KSH] * f[r] : 0.0);
            for (int j = 0; j < P; j++) g[j] += Jw[r * P + j] * e;
        }
        for (int i = 0; i < P; i++) {
            x[i] = 0.0;
            for (int j = 0; j < P; j++) x[i] += hinv[i * P + j] * g[j];
        }
        for (int i = 0; i < P; i++)
            for (int j = 0; j < P; j++) s2[i * P + j] += x[i] * x[j] / DRAWS;
    }
    for (int i = 0; i < P; i++) assert_true(fabs(s2[i * P + i] / cov[i * P + i] - 1.0) < 0.05);
    /* Zero residuals add nothing. */
    for (int r = NR; r < NRS; r++) f[r] = 0.0;
    memcpy(cov, hinv, sizeof cov);
    assert_int_equal(rod_fit_sandwich_add_shapes(Jw, f, P, NR, rows, NSH, hinv, cov), 0);
    for (int i = 0; i < P * P; i++) assert_true(cov[i] == hinv[i]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sandwich_exact),
        cmocka_unit_test(test_sandwich_monte_carlo),
        cmocka_unit_test(test_phases),
        cmocka_unit_test(test_estimate),
        cmocka_unit_test(test_shape_common_mode_exact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
