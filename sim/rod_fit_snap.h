/* rod_fit_snap.h: the snap predicted with a fitted strip (issue 32 A, "Output"), with its
 * uncertainty band and the probability of the other regime.
 *
 * The prediction is the fast dynamic predictor (rod_predict with rod_predict_opts_fast, as
 * `ribbon-sim predict --fast`) on the scene with the fitted values. The band is linearised: the
 * covariance of the determined fitted parameters is diagonalised, C = sum lambda_k v_k v_k^T,
 * and the snap is predicted again at u +- sqrt(lambda_k) v_k (clamped into the bounds) for each
 * principal direction: sd^2 = sum_k ((snap+ - snap-) / 2)^2 (central differences, 2 p extra
 * predictions). The peak |A| of the snap gets the same treatment, and the probability of the
 * other regime is that of a normal peak |A| (mean: the fitted strip's, sd as above) on the other
 * side of the scene's regime threshold (snap.asym_threshold, rod_regime.h). Parameters the data do not determine are not in
 * the band (the note says which): the band is then a lower bound. */
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
    int left_out;         /* fitted parameters left out of the band (not determined) */
    char note[256];       /* why the band is partial or missing, "" otherwise */
    double wall_s;
} rod_fit_snap;

/* sc: the scene the fit started from; fit: rod_fit_run's result. Returns ROD_OK when the fitted
 * strip's own prediction ran (out->band_ok says whether the band did), else its failure. */
rod_status rod_fit_snap_predict(const rod_scene *sc, const rod_fit_result *fit, rod_fit_snap *out, char *why,
                                size_t why_len);

#endif
