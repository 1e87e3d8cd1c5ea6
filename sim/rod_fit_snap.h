/* rod_fit_snap.h: the snap predicted with a fitted strip (issue 32 A, "Output"), with its
 * uncertainty band and the probability of the other regime.
 *
 * The prediction is the fast dynamic predictor (rod_predict with rod_predict_opts_fast, as
 * `ribbon-sim predict --fast`) on the scene with the fitted values. The band is linearised
 * (rod_fit_band.h): every fitted strip parameter with a finite covariance (determined by the data,
 * or held by its prior) is in it, the covariance is scaled by the reduced chi-square when that
 * exceeds 1, and the snap is predicted again one standard deviation either side along each
 * principal direction (2 p extra predictions, and 2 p more at two standard deviations for the
 * regime's probability). The probes start warm (rod_predict_warm, rod_protocol.h): from the
 * fitted strip's upper state and its static state at 0.7 of its own switch to the dynamics,
 * each re-solved for the probe, instead of the route and the quasi-static steps before it; the
 * answer is the cold start's (a probe that would not give it starts cold by itself), for 30% less
 * CPU (the route and two thirds of the quasi-static start were 40% of a probe at N = 61). A
 * fitted parameter the data do not determine and
 * without a prior makes the band unbounded (band_ok 0, unbounded 1: no number). The probability of
 * the other regime is that of a normal peak |A| (mean: the fitted strip's, sd from the larger
 * one-sided change along each direction) on the other side of the scene's regime threshold
 * (snap.asym_threshold, rod_regime.h).
 */
#ifndef RIBBON_SIM_ROD_FIT_SNAP_H
#define RIBBON_SIM_ROD_FIT_SNAP_H

#include <stddef.h>

#include "rod_fit.h"

typedef struct rod_fit_snap {
    int snapped;          /* the fitted strip snapped before protocol.shear_max */
    double snap_dw;       /* its snap Delta W (valid when snapped) */
    int asymmetric;       /* its regime */
    double peak_abs_a;    /* rad */
    int band_ok;          /* 1: every perturbed prediction snapped */
    double snap_sd;       /* linearised standard deviation of snap_dw (0 when no direction) */
    double peak_sd;       /* the same for peak |A| */
    double p_other;       /* probability of the other regime */
    int directions;       /* principal directions used */
    int left_out;         /* fitted parameters neither determined nor with a prior (band unbounded) */
    char note[256];       /* why the band is missing, or what it rests on; "" otherwise */
    double wall_s;
    int unbounded;        /* 1: no band because a parameter without prior is not determined */
    int by_prior;         /* parameters in the band through their prior only */
    double cov_scale;     /* reduced chi-square applied to the covariance (1: none) */
} rod_fit_snap;

/* sc: the scene the fit started from; fit: rod_fit_run's result. Returns ROD_OK when the fitted
 * strip's own prediction ran (out->band_ok says whether the band did), else its failure. */
rod_status rod_fit_snap_predict(const rod_scene *sc, const rod_fit_result *fit, rod_fit_snap *out, char *why,
                                size_t why_len);

#endif
