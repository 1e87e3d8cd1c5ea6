/* rod_fit_snap.c: the fitted strip's snap with a linearised band (rod_fit_snap.h). */
#include "rod_fit_snap.h"

#include "rod_fit_band.h"
#include "rod_protocol.h"
#include "rod_quasi.h"
#include "rod_route.h"
#include "rod_snapshot.h"
#include "rod_solver.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#define WARM_FRACTION 0.7 /* the probes start at this fraction of the fitted strip's switch */

/* What the band's probes start from: the fitted strip's upper state and its static state at
   Delta W = dw (rod_predict_warm), or nothing (cold). */
typedef struct band_ctx {
    const rod_scene *sc;
    const rod_predict_warm *warm;
} band_ctx;

static rod_status predict_at(const rod_scene *sc, const rod_predict_warm *warm, const double u[ROD_FIT_NKEYS],
                             rod_prediction *p, char *why, size_t why_len)
{
    rod_scene s = *sc;
    rod_fit_scene_apply(&s, u);
    rod_predict_opts o = rod_predict_opts_fast(&s);
    o.warm = warm;
    return rod_predict(&s, &o, p, why, why_len);
}

/* rod_fit_band_fn over the fast predictor: a perturbed strip must snap. */
static int band_fn(void *ctx, const double u[ROD_FIT_NKEYS], double *snap, double *peak, char *why, size_t why_len)
{
    const band_ctx *b = ctx;
    rod_prediction q;
    if (predict_at(b->sc, b->warm, u, &q, why, why_len) != ROD_OK) return 1;
    if (!q.snapped) {
        snprintf(why, why_len, "does not snap");
        return 1;
    }
    *snap = q.snap_dw;
    *peak = q.peak_abs_a;
    return 0;
}

/* The probes' warm start from the fitted strip (scene sc with u): its upper state by the route,
   and its static branch followed to the quasi-static grid point at WARM_FRACTION of its own
   switch to the dynamics (dw_switch), far enough before any probe's switch that each probe's
   answer is its cold start's (rod_protocol.h); a probe whose switch comes too close falls back
   to the cold start by itself. 0, or -1 (no warm start: the probes run cold). */
static int warm_states(const rod_scene *sc, const double u[ROD_FIT_NKEYS], double dw_switch, rod_snapshot *upper,
                       rod_snapshot *at, double *dw)
{
    rod_scene s = *sc;
    rod_fit_scene_apply(&s, u);
    char why[160];
    rod *r = NULL;
    if (rod_alloc(&s, &r, why, sizeof why) != ROD_OK) return -1;
    rod_solver *sv = rod_solver_alloc(r);
    int rc = -1;
    double step = rod_quasi_step(&s);
    int k = (int)floor(WARM_FRACTION * dw_switch / step);
    if (!sv || !rod_snapshot_alloc(r, upper) || !rod_snapshot_alloc(r, at)) goto done;
    rod_route_report rep = {0};
    if (rod_route_to_state(r, sv, &s, +1, &rep) != ROD_OK) goto done;
    rod_snapshot_save(r, upper);
    *dw = k * step;
    double reached = 0.0;
    if (k > 0 && rod_follow_shear(r, sv, &s, s.compression, 0.0, *dw, step, &reached, NULL) != ROD_OK) goto done;
    rod_snapshot_save(r, at);
    rc = 0;
done:
    rod_solver_free(sv);
    rod_free(r);
    return rc;
}

rod_status rod_fit_snap_predict(const rod_scene *sc, const rod_fit_result *fit, rod_fit_snap *out, char *why,
                                size_t why_len)
{
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    memset(out, 0, sizeof *out);
    rod_prediction p;
    rod_snapshot upper = {0}, at = {0};
    rod_predict_warm warm = {&upper, &at, 0.0};
    band_ctx bc = {sc, NULL};
    rod_status st = predict_at(sc, NULL, fit->u, &p, why, why_len);
    if (st != ROD_OK) return st;
    out->snapped = p.snapped;
    out->snap_dw = p.snap_dw;
    out->asymmetric = p.asymmetric;
    out->peak_abs_a = p.peak_abs_a;
    if (!p.snapped) {
        snprintf(out->note, sizeof out->note, "the fitted strip does not snap before protocol.shear_max");
        goto done;
    }
    if (warm_states(sc, fit->u, p.dw_switch, &upper, &at, &warm.dw) == 0) bc.warm = &warm;
    rod_fit_band b;
    st = rod_fit_band_eval(fit, p.snap_dw, p.peak_abs_a, band_fn, &bc, &b, why, why_len);
    rod_snapshot_free(&upper);
    rod_snapshot_free(&at);
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
