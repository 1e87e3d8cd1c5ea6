/* rod_fit_snap.c: the fitted strip's snap with a linearised band (rod_fit_snap.h). */
#include "rod_fit_snap.h"

#include "rod_protocol.h"

#include <gsl/gsl_eigen.h>
#include <gsl/gsl_matrix.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static rod_status predict_at(const rod_scene *sc, const double u[ROD_FIT_NKEYS], rod_prediction *p, char *why,
                             size_t why_len)
{
    rod_scene s = *sc;
    rod_fit_scene_apply(&s, u);
    rod_predict_opts o = rod_predict_opts_fast(&s);
    return rod_predict(&s, &o, p, why, why_len);
}

rod_status rod_fit_snap_predict(const rod_scene *sc, const rod_fit_result *fit, rod_fit_snap *out, char *why,
                                size_t why_len)
{
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    memset(out, 0, sizeof *out);
    rod_prediction p;
    rod_status st = predict_at(sc, fit->u, &p, why, why_len);
    if (st != ROD_OK) return st;
    out->snapped = p.snapped;
    out->snap_dw = p.snap_dw;
    out->asymmetric = p.asymmetric;
    out->peak_abs_a = p.peak_abs_a;
    if (!p.snapped) {
        snprintf(out->note, sizeof out->note, "the fitted strip does not snap before protocol.shear_max");
        goto done;
    }
    int key[ROD_FIT_NKEYS], m = 0;
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        if (!fit->fitted[k] || !rod_fit_key_strip((rod_fit_key)k)) continue; /* the camera's offset: no snap */
        if (!fit->determined[k]) {
            out->left_out++;
            continue;
        }
        key[m++] = k;
    }
    out->band_ok = 1;
    if (m > 0) {
        gsl_matrix *C = gsl_matrix_alloc((size_t)m, (size_t)m), *V = gsl_matrix_alloc((size_t)m, (size_t)m);
        gsl_vector *ev = gsl_vector_alloc((size_t)m);
        gsl_eigen_symmv_workspace *w = gsl_eigen_symmv_alloc((size_t)m);
        if (!C || !V || !ev || !w) {
            gsl_matrix_free(C); gsl_matrix_free(V); gsl_vector_free(ev); gsl_eigen_symmv_free(w);
            snprintf(why, why_len, "out of memory");
            return ROD_ERR_ALLOC;
        }
        for (int a = 0; a < m; a++)
            for (int b = 0; b < m; b++) gsl_matrix_set(C, (size_t)a, (size_t)b, fit->cov[key[a]][key[b]]);
        gsl_eigen_symmv(C, ev, V, w);
        double var_s = 0.0, var_a = 0.0;
        for (int d = 0; d < m && out->band_ok; d++) {
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
                char w2[160];
                rod_prediction q;
                if (predict_at(sc, u, &q, w2, sizeof w2) != ROD_OK || !q.snapped) {
                    out->band_ok = 0;
                    snprintf(out->note, sizeof out->note, "no band: one standard deviation along a principal "
                             "direction the strip %s", q.snapped ? w2 : "does not snap");
                    break;
                }
                snap[sgn] = q.snap_dw;
                peak[sgn] = q.peak_abs_a;
            }
            if (!out->band_ok) break;
            var_s += 0.25 * (snap[0] - snap[1]) * (snap[0] - snap[1]);
            var_a += 0.25 * (peak[0] - peak[1]) * (peak[0] - peak[1]);
            out->directions++;
        }
        gsl_matrix_free(C); gsl_matrix_free(V); gsl_vector_free(ev); gsl_eigen_symmv_free(w);
        out->snap_sd = sqrt(var_s);
        out->peak_sd = sqrt(var_a);
    }
    if (out->band_ok) {
        double gap = fabs(out->peak_abs_a - sc->asym_threshold);
        out->p_other = out->peak_sd > 0.0 ? 0.5 * erfc(gap / (out->peak_sd * sqrt(2.0))) : 0.0;
        if (out->left_out)
            snprintf(out->note, sizeof out->note, "%d fitted parameter%s not determined by these data left out of "
                     "the band (a lower bound)", out->left_out, out->left_out == 1 ? "" : "s");
    } else {
        out->snap_sd = out->peak_sd = out->p_other = 0.0;
    }
done:
    clock_gettime(CLOCK_MONOTONIC, &t1);
    out->wall_s = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    return ROD_OK;
}
