/* rod_fit_band.h: the linearised uncertainty band of a quantity predicted from fitted parameters
 * (issue 32 A, "Output"): which parameters enter it, how their covariance is scaled, and the
 * propagation itself, apart from the predictor so that it can be checked on closed forms.
 *
 * Parameters in the band: every fitted strip parameter (rod_fit_key_strip) whose covariance is
 * finite, that is determined by the data or held by its prior (a parameter the data do not
 * determine but that has a prior has the prior-bounded posterior covariance: it is in the band).
 * A fitted strip parameter the data do not determine and that has no prior (se INFINITY) makes
 * the band unbounded: no number is given (ok = 0, unbounded = 1, the note names it).
 *
 * Covariance scale: when the fit's covariance was not already scaled (fit->cov_scaled == 0), it is
 * multiplied by the reduced chi-square chi2 / (nres - nfit) when that exceeds 1: residuals larger
 * than the stated noise (the tracker's bias, which the hold's scatter does not show) widen the
 * band; a reduced chi-square below 1 never narrows it.
 *
 * Propagation: C = sum lambda_k v_k v_k^T over the band's parameters, the quantity evaluated at
 * u +- sqrt(lambda_k) v_k (clamped into the bounds). The snap's variance is the sum of the
 * squared central differences ((s+ - s-) / 2)^2; the peak |A|'s uses the larger one-sided change
 * max((a+ - a0)^2, (a- - a0)^2), so that a kink (a change of pathway between the two sides, where
 * a central difference cancels) widens it instead of vanishing. Both are exact for a linear model
 * (sd^2 = g^T C g).
 *
 * The probability of the other regime: peak |A| normal (mean peak0, sd peak_sd) beyond the
 * threshold, but not less than the tail beyond the first crossing of the threshold along any
 * principal direction, found by following peak |A| piecewise linearly through its values at 0, 1
 * and 2 standard deviations (2 p more predictions): a strip next to a change of pathway, whose
 * peak |A| jumps rather than moves, gets the probability of the jump, not a normal tail. */
#ifndef RIBBON_SIM_ROD_FIT_BAND_H
#define RIBBON_SIM_ROD_FIT_BAND_H

#include <stddef.h>

#include "rod_fit.h"

/* The predictor at parameters u: 0 with *snap and *peak set, else non-zero with the reason. */
typedef int (*rod_fit_band_fn)(void *ctx, const double u[ROD_FIT_NKEYS], double *snap, double *peak, char *why,
                               size_t why_len);

typedef struct rod_fit_band {
    int ok;               /* 1: a band (sd below are numbers) */
    int unbounded;        /* 1: a parameter without prior is not determined: no band */
    double snap_sd, peak_sd;
    double scale;         /* the factor applied to the covariance (>= 1) */
    int directions;       /* principal directions used */
    int by_prior;         /* parameters in the band through their prior only (not determined by data) */
    int left_out;         /* fitted strip parameters neither determined nor with a prior */
    char note[256];       /* why there is no band, or what it rests on; "" otherwise */
    double peak1[ROD_FIT_NKEYS][2], peak2[ROD_FIT_NKEYS][2]; /* peak |A| one and two standard
                                        deviations along each direction, + and - */
} rod_fit_band;

/* fit: rod_fit_run's result; snap0, peak0: the predictor at fit->u. Returns ROD_OK (out->ok says
 * whether there is a band) or ROD_ERR_ALLOC. */
rod_status rod_fit_band_eval(const rod_fit_result *fit, double snap0, double peak0, rod_fit_band_fn f, void *ctx,
                             rod_fit_band *out, char *why, size_t why_len);

/* The probability of the other regime (above): peak0 the fitted strip's peak |A|, thr the
 * regime threshold. 0 when there is no band. */
double rod_fit_band_p_other(const rod_fit_band *b, double peak0, double thr);

#endif
