/* test_rod_band: the band LDL^T of rod_band.c against GSL's own band LDL^T and a dense LU solve,
 * on random symmetric positive definite and indefinite (but factorisable) band matrices of
 * half-bandwidth ROD_BAND, including sizes below the bandwidth; a zero pivot is refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <gsl/gsl_linalg.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rod_band.h"

#define W (ROD_BAND + 1)

static double urand(unsigned *s)
{
    *s = *s * 1103515245u + 12345u;
    return ((*s >> 8) & 0xffff) / 65536.0 - 0.5;
}

/* Random band matrix; diag_shift > 0 makes it diagonally dominant (positive definite). */
static void fill(double *A, int n, double diag, unsigned seed)
{
    unsigned s = seed;
    for (int i = 0; i < n; i++)
        for (int k = 0; k < W; k++) A[i * W + k] = i + k < n ? urand(&s) : 0.0;
    for (int i = 0; i < n; i++) A[i * W] = diag * (1.0 + urand(&s));
}

static double dense_at(const double *A, int i, int j)
{
    if (i > j) { int t = i; i = j; j = t; }
    return j - i <= ROD_BAND ? A[i * W + (j - i)] : 0.0;
}

static void check_solve(int n, double diag, unsigned seed)
{
    double *A = calloc((size_t)n * W, sizeof *A), *F = calloc((size_t)n * W, sizeof *F);
    double *b = malloc(sizeof(double) * (size_t)n), *x = malloc(sizeof(double) * (size_t)n);
    fill(A, n, diag, seed);
    memcpy(F, A, sizeof(double) * (size_t)n * W);
    unsigned s = seed + 7;
    for (int i = 0; i < n; i++) b[i] = x[i] = urand(&s);
    assert_int_equal(rod_band_ldlt_decomp(F, n), 0);
    rod_band_ldlt_solve(F, n, x);
    /* Residual of the solve and agreement with a dense LU solve. */
    gsl_matrix *D = gsl_matrix_alloc((size_t)n, (size_t)n);
    gsl_permutation *p = gsl_permutation_alloc((size_t)n);
    gsl_vector *y = gsl_vector_alloc((size_t)n);
    double amax = 0.0;
    for (int i = 0; i < n; i++) {
        double r = -b[i];
        for (int j = 0; j < n; j++) {
            gsl_matrix_set(D, (size_t)i, (size_t)j, dense_at(A, i, j));
            r += dense_at(A, i, j) * x[j];
            amax = fmax(amax, fabs(dense_at(A, i, j)));
        }
        assert_true(fabs(r) < 1e-11 * amax * n);
        gsl_vector_set(y, (size_t)i, b[i]);
    }
    int sign;
    gsl_linalg_LU_decomp(D, p, &sign);
    gsl_linalg_LU_svx(D, p, y);
    for (int i = 0; i < n; i++) assert_true(fabs(gsl_vector_get(y, (size_t)i) - x[i]) < 1e-9 * (1.0 + fabs(x[i])));
    /* Same pivots as GSL's band LDL^T (lower storage: row i holds A(i + k, i)). */
    if (diag > 0.0 && n > ROD_BAND) {
        gsl_matrix *G = gsl_matrix_alloc((size_t)n, W);
        for (int i = 0; i < n; i++)
            for (int k = 0; k < W; k++) gsl_matrix_set(G, (size_t)i, (size_t)k, A[i * W + k]);
        assert_int_equal(gsl_linalg_ldlt_band_decomp(G), GSL_SUCCESS);
        for (int i = 0; i < n; i++)
            assert_true(fabs(gsl_matrix_get(G, (size_t)i, 0) - F[i * W]) < 1e-12 * fabs(F[i * W]));
        gsl_matrix_free(G);
    }
    gsl_matrix_free(D);
    gsl_permutation_free(p);
    gsl_vector_free(y);
    free(A); free(F); free(b); free(x);
}

static void test_positive_definite(void **st)
{
    (void)st;
    int sizes[] = {1, 3, 10, 11, 12, 57, 803};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) check_solve(sizes[k], 8.0, 11u + (unsigned)k);
}

static void test_indefinite(void **st)
{
    (void)st;
    /* Diagonal entries of both signs and moderate size: indefinite, yet factorisable. */
    unsigned s = 99;
    int n = 120;
    double *A = calloc((size_t)n * W, sizeof *A);
    fill(A, n, 8.0, 5u);
    for (int i = 0; i < n; i++) A[i * W] *= (urand(&s) < 0.0 ? -1.0 : 1.0);
    double *b = malloc(sizeof(double) * (size_t)n), *F = malloc(sizeof(double) * (size_t)n * W);
    memcpy(F, A, sizeof(double) * (size_t)n * W);
    for (int i = 0; i < n; i++) b[i] = urand(&s);
    double *x = malloc(sizeof(double) * (size_t)n);
    memcpy(x, b, sizeof(double) * (size_t)n);
    assert_int_equal(rod_band_ldlt_decomp(F, n), 0);
    rod_band_ldlt_solve(F, n, x);
    for (int i = 0; i < n; i++) {
        double r = -b[i];
        for (int j = 0; j < n; j++) r += dense_at(A, i, j) * x[j];
        assert_true(fabs(r) < 1e-10);
    }
    free(A); free(b); free(F); free(x);
}

static void test_zero_pivot(void **st)
{
    (void)st;
    int n = 20;
    double *A = calloc((size_t)n * W, sizeof *A);
    fill(A, n, 8.0, 3u);
    A[5 * W] = 0.0;
    for (int k = 1; k < W; k++) A[4 * W + k] = 0.0; /* row 4 cannot change pivot 5 */
    for (int i = 0; i < 5; i++)
        if (5 - i <= ROD_BAND) A[i * W + (5 - i)] = 0.0;
    assert_int_equal(rod_band_ldlt_decomp(A, n), -1);
    free(A);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_positive_definite),
        cmocka_unit_test(test_indefinite),
        cmocka_unit_test(test_zero_pivot),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
