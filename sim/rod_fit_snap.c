/* rod_fit_snap.c: the fitted strip's snap with a linearised band (rod_fit_snap.h). */
#include "rod_fit_snap.h"

#include "rod_fit_band.h"
#include "rod_protocol.h"

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

/* rod_fit_band_fn over the fast predictor: a perturbed strip must snap. */
static int band_fn(void *ctx, const double u[ROD_FIT_NKEYS], double *snap, double *peak, char *why, size_t why_len)
{
    rod_prediction q;
    if (predict_at((const rod_scene *)ctx, u, &q, why, why_len) != ROD_OK) return 1;
    if (!q.snapped) {
        snprintf(why, why_len, "does not snap");
        return 1;
    }
    *snap = q.snap_dw;
    *peak = q.peak_abs_a;
    return 0;
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
    rod_fit_band b;
    st = rod_fit_band_eval(fit, p.snap_dw, p.peak_abs_a, band_fn, (void *)sc, &b, why, why_len);
    if (st != ROD_OK) return st;
    out->band_ok = b.ok;
    out->unbounded = b.unbounded;
    out->left_out = b.left_out;
    out->by_prior = b.by_prior;
    out->cov_scale = b.scale;
    out->directions = b.directions;
    snprintf(out->note, sizeof out->note, "%s", b.note);
    if (b.ok) {
        out->snap_sd = b.snap_sd;
        out->peak_sd = b.peak_sd;
        out->p_other = rod_fit_band_p_other(&b, out->peak_abs_a, sc->asym_threshold);
    }
done:
    clock_gettime(CLOCK_MONOTONIC, &t1);
    out->wall_s = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    return ROD_OK;
}
