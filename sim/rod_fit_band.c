/* rod_fit_band.c: the linearised band of a prediction from fitted parameters (rod_fit_band.h). */
#include "rod_fit_band.h"

#include <gsl/gsl_eigen.h>
#include <gsl/gsl_matrix.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

rod_status rod_fit_band_eval(const rod_fit_result *fit, double snap0, double peak0, rod_fit_band_fn f, void *ctx,
                             rod_fit_band *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    out->scale = 1.0;
    int key[ROD_FIT_NKEYS], m = 0;
    const char *unnamed = NULL;
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        if (!fit->fitted[k] || !rod_fit_key_strip((rod_fit_key)k)) continue; /* the camera's offset: no snap */
        if (!fit->determined[k] && !(isfinite(fit->se[k]) && isfinite(fit->cov[k][k]))) {
            out->left_out++;
            if (!unnamed) unnamed = rod_fit_key_name((rod_fit_key)k);
            continue;
        }
        if (!fit->determined[k]) out->by_prior++;
        key[m++] = k;
    }
    if (out->left_out) {
        out->unbounded = 1;
        snprintf(out->note, sizeof out->note, "the band is unbounded: %s%s not determined by these "
                 "data and without a prior", unnamed ? unnamed : "?", out->left_out > 1 ? " and others" : "");
        return ROD_OK;
    }
    int dof = fit->nres - fit->nfit;
    double red = dof > 0 ? fit->chi2 / (double)dof : 1.0;
    if (!fit->cov_scaled && red > 1.0 && isfinite(red)) out->scale = red;
    out->ok = 1;
    if (m == 0) return ROD_OK;
    gsl_matrix *C = gsl_matrix_alloc((size_t)m, (size_t)m), *V = gsl_matrix_alloc((size_t)m, (size_t)m);
    gsl_vector *ev = gsl_vector_alloc((size_t)m);
    gsl_eigen_symmv_workspace *w = gsl_eigen_symmv_alloc((size_t)m);
    if (!C || !V || !ev || !w) {
        gsl_matrix_free(C); gsl_matrix_free(V); gsl_vector_free(ev); gsl_eigen_symmv_free(w);
        out->ok = 0;
        snprintf(why, why_len, "out of memory");
        return ROD_ERR_ALLOC;
    }
    for (int a = 0; a < m; a++)
        for (int b = 0; b < m; b++) gsl_matrix_set(C, (size_t)a, (size_t)b, out->scale * fit->cov[key[a]][key[b]]);
    gsl_eigen_symmv(C, ev, V, w);
    double var_s = 0.0, var_a = 0.0;
    for (int d = 0; d < m && out->ok; d++) {
        double lam = gsl_vector_get(ev, (size_t)d);
        if (!(lam > 0.0)) continue;
        double snap[2], peak[2];
        for (int sgn = 0; sgn < 2; sgn++) {
            double u[ROD_FIT_NKEYS];
            memcpy(u, fit->u, sizeof u);
            for (int a = 0; a < m; a++) {
                int k = key[a];
                u[k] += (sgn ? -1.0 : 1.0) * sqrt(lam) * gsl_matrix_get(V, (size_t)a, (size_t)d);
                u[k] = fmin(fit->hi[k], fmax(fit->lo[k], u[k]));
            }
            char w2[160] = "";
            if (f(ctx, u, &snap[sgn], &peak[sgn], w2, sizeof w2) != 0) {
                out->ok = 0;
                snprintf(out->note, sizeof out->note, "no band: one standard deviation along a principal "
                         "direction the strip %s", w2);
                break;
            }
            /* two standard deviations: the regime only (a perturbed strip that fails says nothing) */
            memcpy(u, fit->u, sizeof u);
            for (int a = 0; a < m; a++) {
                int k = key[a];
                u[k] += (sgn ? -2.0 : 2.0) * sqrt(lam) * gsl_matrix_get(V, (size_t)a, (size_t)d);
                u[k] = fmin(fit->hi[k], fmax(fit->lo[k], u[k]));
            }
            double s2, p2;
            out->peak1[out->directions][sgn] = peak[sgn];
            out->peak2[out->directions][sgn] = f(ctx, u, &s2, &p2, w2, sizeof w2) == 0 ? p2 : NAN;
        }
        if (!out->ok) break;
        var_s += 0.25 * (snap[0] - snap[1]) * (snap[0] - snap[1]);
        var_a += fmax((peak[0] - peak0) * (peak[0] - peak0), (peak[1] - peak0) * (peak[1] - peak0));
        out->directions++;
    }
    gsl_matrix_free(C); gsl_matrix_free(V); gsl_vector_free(ev); gsl_eigen_symmv_free(w);
    (void)snap0;
    if (!out->ok) {
        out->snap_sd = out->peak_sd = 0.0;
        return ROD_OK;
    }
    out->snap_sd = sqrt(var_s);
    out->peak_sd = sqrt(var_a);
    int n = 0;
    if (out->by_prior)
        n += snprintf(out->note + n, sizeof out->note - (size_t)n, "%d parameter%s in the band through %s prior "
                      "only", out->by_prior, out->by_prior == 1 ? "" : "s", out->by_prior == 1 ? "its" : "their");
    if (out->scale > 1.0 && n >= 0 && (size_t)n < sizeof out->note)
        snprintf(out->note + n, sizeof out->note - (size_t)n, "%scovariance scaled by the reduced chi-square %.2f",
                 n ? "; " : "", out->scale);
    return ROD_OK;
}

/* The tail beyond the first crossing of thr along a piecewise linear peak |A| through (0, a0),
   (1, a1), (2, a2); 0 without a crossing. */
static double crossing_tail(double a0, double a1, double a2, double thr)
{
    double s0 = a0 - thr, s1 = a1 - thr, s2 = a2 - thr, t;
    if (s0 * s1 <= 0.0 && s1 != s0) t = s0 / (s0 - s1);
    else if (isfinite(a2) && s1 * s2 <= 0.0 && s2 != s1) t = 1.0 + s1 / (s1 - s2);
    else return 0.0;
    return 0.5 * erfc(t / sqrt(2.0));
}

double rod_fit_band_p_other(const rod_fit_band *b, double peak0, double thr)
{
    if (!b->ok) return 0.0;
    double gap = fabs(peak0 - thr);
    double p = b->peak_sd > 0.0 ? 0.5 * erfc(gap / (b->peak_sd * sqrt(2.0))) : 0.0;
    for (int d = 0; d < b->directions; d++)
        for (int s = 0; s < 2; s++) p = fmax(p, crossing_tail(peak0, b->peak1[d][s], b->peak2[d][s], thr));
    return p;
}
