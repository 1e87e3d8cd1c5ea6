/* rod_stability.c: inertia and the eigenpair nearest a shift of a symmetric band matrix (see
 * rod_stability.h for the method and why the count is verified by shifted refactorisations).
 *
 * The LDL^T here is a plain right-looking elimination on the upper band: for each column j the
 * pivot d = A(j, j) and, for the rows i in (j, j + B], A(i, k) -= A(j, i) A(j, k) / d. It touches
 * only the band (O(n B^2)), allocates nothing (the copy lives in the workspace) and keeps the sign
 * of every pivot, which is all the inertia needs. */
#include "rod_stability.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct rod_stab_ws {
    int n;
    double *band;         /* copy of A for LDL^T (n x (B + 1)) */
    gsl_matrix *lu;       /* general band for LU (n x (3 B + 1)) */
    gsl_vector_uint *piv;
    double *y, *av;       /* n each */
};

rod_stab_ws *rod_stab_ws_alloc(int n)
{
    if (n < 1) return NULL;
    rod_stab_ws *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    w->n = n;
    w->band = malloc(sizeof(double) * (size_t)n * (ROD_BAND + 1));
    w->y = malloc(sizeof(double) * (size_t)n);
    w->av = malloc(sizeof(double) * (size_t)n);
    w->lu = gsl_matrix_alloc((size_t)n, 3 * ROD_BAND + 1);
    w->piv = gsl_vector_uint_alloc((size_t)n);
    if (!w->band || !w->y || !w->av || !w->lu || !w->piv) {
        rod_stab_ws_free(w);
        return NULL;
    }
    return w;
}

void rod_stab_ws_free(rod_stab_ws *w)
{
    if (!w) return;
    free(w->band); free(w->y); free(w->av);
    if (w->lu) gsl_matrix_free(w->lu);
    if (w->piv) gsl_vector_uint_free(w->piv);
    free(w);
}

static double max_abs_diag(const double *A, int n)
{
    double m = 0.0;
    for (int i = 0; i < n; i++) m = fmax(m, fabs(A[i * (ROD_BAND + 1)]));
    return m;
}

int rod_band_negative_pivots(const double *A, int n, double shift, rod_stab_ws *w, double *min_pivot_rel)
{
    const int p = ROD_BAND, wd = ROD_BAND + 1;
    double *B = w->band;
    memcpy(B, A, sizeof(double) * (size_t)n * (size_t)wd);
    double scale = max_abs_diag(A, n), dmin = INFINITY;
    for (int i = 0; i < n; i++) B[i * wd] -= shift;
    int count = 0;
    for (int j = 0; j < n; j++) {
        double d = B[j * wd];
        if (d == 0.0 || !isfinite(d)) return -1;
        dmin = fmin(dmin, fabs(d));
        count += d < 0.0;
        int last = j + p < n - 1 ? j + p : n - 1;
        for (int i = j + 1; i <= last; i++) {
            double lji = B[j * wd + (i - j)] / d;
            if (lji == 0.0) continue;
            for (int k = i; k <= last; k++) B[i * wd + (k - i)] -= lji * B[j * wd + (k - j)];
        }
    }
    if (min_pivot_rel) *min_pivot_rel = scale > 0.0 ? dmin / scale : 0.0;
    return count;
}

rod_status rod_inertia_eval(const double *A, int n, double shift_rel, rod_stab_ws *w, rod_inertia *out,
                            char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    for (int i = 0; i < n * (ROD_BAND + 1); i++)
        if (!isfinite(A[i])) {
            if (why) snprintf(why, why_len, "non-finite Hessian entry at free DOF %d", i / (ROD_BAND + 1));
            return ROD_ERR_NAN;
        }
    double scale = max_abs_diag(A, n);
    out->shift = shift_rel * scale;
    int c0 = rod_band_negative_pivots(A, n, 0.0, w, &out->min_pivot_rel);
    out->below_plus = rod_band_negative_pivots(A, n, out->shift, w, NULL);
    out->below_minus = rod_band_negative_pivots(A, n, -out->shift, w, NULL);
    if (c0 < 0 && out->below_plus < 0 && out->below_minus < 0) {
        if (why) snprintf(why, why_len, "every LDL^T factorisation met an exact zero pivot");
        return ROD_ERR_SINGULAR;
    }
    if (out->below_plus >= 0 && out->below_plus == out->below_minus) {
        /* No eigenvalue within sigma of zero: the shifted counts are the count. */
        out->n_negative = out->below_plus;
        out->verified = c0 == out->below_plus;
        return ROD_OK;
    }
    out->near_singular = 1;
    out->n_negative = c0 >= 0 ? c0 : out->below_minus >= 0 ? out->below_minus : out->below_plus;
    return ROD_OK;
}

void rod_band_symv(const double *A, int n, const double *x, double *y)
{
    const int wd = ROD_BAND + 1;
    for (int i = 0; i < n; i++) y[i] = 0.0;
    for (int i = 0; i < n; i++) {
        y[i] += A[i * wd] * x[i];
        for (int k = 1; k <= ROD_BAND && i + k < n; k++) {
            double a = A[i * wd + k];
            y[i] += a * x[i + k];
            y[i + k] += a * x[i];
        }
    }
}

/* Factorises A - sigma I by band LU into the workspace. */
static int lu_factor(const double *A, int n, double sigma, rod_stab_ws *w)
{
    const int wd = ROD_BAND + 1;
    gsl_matrix_set_zero(w->lu);
    for (int a = 0; a < n; a++)
        for (int k = 0; k <= ROD_BAND && a + k < n; k++) {
            double v = A[a * wd + k] - (k == 0 ? sigma : 0.0);
            gsl_matrix_set(w->lu, (size_t)a, (size_t)(2 * ROD_BAND + k), v);
            gsl_matrix_set(w->lu, (size_t)(a + k), (size_t)(2 * ROD_BAND - k), v);
        }
    if (gsl_linalg_LU_band_decomp((size_t)n, ROD_BAND, ROD_BAND, w->lu, w->piv) != GSL_SUCCESS) return 0;
    return 1;
}

static double normalise(double *v, int n)
{
    double s = 0.0;
    for (int i = 0; i < n; i++) s += v[i] * v[i];
    s = sqrt(s);
    if (s > 0.0 && isfinite(s))
        for (int i = 0; i < n; i++) v[i] /= s;
    return s;
}

rod_status rod_eig_nearest(const double *A, int n, double sigma, int max_iter, double rel_tol, rod_stab_ws *w,
                           double *v, rod_eigpair *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    double scale = max_abs_diag(A, n);
    double floor_r = 1e-14 * scale;
    /* Factor; an exactly singular A - sigma I (sigma on an eigenvalue) is nudged twice. */
    int ok = 0;
    for (int attempt = 0; attempt < 3 && !ok; attempt++) {
        ok = lu_factor(A, n, sigma, w);
        if (!ok) sigma += (attempt + 1) * 1e-12 * (scale > 0.0 ? scale : 1.0);
    }
    if (!ok) {
        if (why) snprintf(why, why_len, "A - sigma I could not be factorised (band LU failed)");
        return ROD_ERR_SINGULAR;
    }
    if (normalise(v, n) == 0.0) {
        /* Built-in start: not symmetric under any index reversal, non-zero everywhere. */
        for (int i = 0; i < n; i++) v[i] = 1.0 + 0.5 * sin(1.37 * i + 0.3) + 0.25 * cos(0.11 * i * i);
        normalise(v, n);
    }
    gsl_vector_view yv = gsl_vector_view_array(w->y, (size_t)n);
    double mu = NAN, mu_prev = NAN;
    int steady = 0;
    for (int it = 1; it <= max_iter; it++) {
        memcpy(w->y, v, sizeof(double) * (size_t)n);
        if (gsl_linalg_LU_band_svx(ROD_BAND, ROD_BAND, w->lu, w->piv, &yv.vector) != GSL_SUCCESS) {
            if (why) snprintf(why, why_len, "band LU solve failed in inverse iteration");
            return ROD_ERR_SINGULAR;
        }
        double s = normalise(w->y, n);
        if (!(s > 0.0) || !isfinite(s)) {
            if (why) snprintf(why, why_len, "inverse iteration produced a non-finite vector (iteration %d)", it);
            return ROD_ERR_NAN;
        }
        /* Keep the sign of the vector steady from one iteration to the next. */
        double dot = 0.0;
        for (int i = 0; i < n; i++) dot += w->y[i] * v[i];
        for (int i = 0; i < n; i++) v[i] = dot < 0.0 ? -w->y[i] : w->y[i];
        rod_band_symv(A, n, v, w->av);
        mu = 0.0;
        for (int i = 0; i < n; i++) mu += v[i] * w->av[i];
        double res = 0.0;
        for (int i = 0; i < n; i++) res += (w->av[i] - mu * v[i]) * (w->av[i] - mu * v[i]);
        res = sqrt(res);
        out->value = mu;
        out->residual = res;
        out->iterations = it;
        if (!isfinite(mu) || !isfinite(res)) {
            if (why) snprintf(why, why_len, "non-finite Rayleigh quotient (iteration %d)", it);
            return ROD_ERR_NAN;
        }
        if (res <= rel_tol * fabs(mu - sigma) + floor_r) return ROD_OK;
        steady = (isfinite(mu_prev) && fabs(mu - mu_prev) <= 1e-13 * (fabs(mu) + floor_r)) ? steady + 1 : 0;
        if (steady >= 2) return ROD_OK;
        mu_prev = mu;
    }
    if (why)
        snprintf(why, why_len, "inverse iteration did not converge in %d iterations (residual %.3g, eigenvalue %.6g)",
                 max_iter, out->residual, mu);
    return ROD_ERR_MAXITER;
}
