/* rod_fit_sandwich.h: the fit's covariance when part of the tracker's error is common to a phase
 * (issue 32 D). The tracker's error on A and Delta Z is partly a bias that changes with the
 * strip's state (per phase: compression, hold, shear); weighting it as independent frame noise
 * makes the fit's (J^T J)^-1 too narrow. Here each phase's error covariance is
 * sigma^2 I + sigma_b^2 1 1^T per observable, and the covariance of the fit's (unchanged, weighted
 * least-squares) estimate is the sandwich H^-1 J^T Sigma_w J H^-1 = H^-1 + sum (H^-1 g)(H^-1 g)^T,
 * g = (sigma_b / sigma) times the sum of the phase's whitened Jacobian rows for that observable. */
#ifndef RIBBON_SIM_ROD_FIT_SANDWICH_H
#define RIBBON_SIM_ROD_FIT_SANDWICH_H

#include "rod_fit.h"

enum { ROD_FIT_PHASE_COMPRESSION, ROD_FIT_PHASE_HOLD, ROD_FIT_PHASE_SHEAR, ROD_FIT_NPHASES };

/* The protocol's phase of each observation: the shear where Delta W is not 0, the hold where
   (Delta L, Delta W) repeats another observation's, the compression otherwise. */
void rod_fit_phases(const rod_fit_obs *obs, int nobs, int *phase);

/* The common-mode variance ratios rho[a] = (sigma_b / sigma)^2 of observable a (0: Delta Z,
   1: A) estimated from the whitened data residuals f (2 nobs, Delta Z and A per observation):
   the mean over phases with at least 2 observations of (phase mean)^2 - 1 / m, at least 0.
   Biased low: the part of the bias the parameters absorb is not in the residuals. */
void rod_fit_common_mode_estimate(const double *f, int nobs, const int *phase, double rho[2]);

/* cov (p x p, row major, the whitened problem's units) += sum over phases and
   observables of rho[a] (hinv g)(hinv g)^T, hinv = H^-1 = (J^T J)^-1 and g the sum of the phase's rows of the whitened data
   Jacobian Jw (2 nobs x p, row major, Delta Z and A per observation). 0, or -1 (out of memory:
   cov untouched). */
int rod_fit_sandwich_add(const double *Jw, int nobs, int p, const int *phase, const double rho[2], const double *hinv,
                          double *cov);

/* The centrelines' common mode (rod_fit_opts.shape_common_mode): the tracker's error on one
   centreline is a smooth deformation of the whole curve, not 2 k independent rows, so each
   shape's whitened error covariance is taken as I + r_s r_s^T, r_s its own whitened residuals at
   the solution (the deformation the fit could not follow, as its direction and size). The
   sandwich's extra term per shape is then (H^-1 g_s)(H^-1 g_s)^T with g_s = J_s^T r_s, J_s the
   shape's whitened rows. Jw and f hold the data rows in order: the shapes' rows start at row0,
   shape s has rows[s] of them. cov += sum over shapes; 0, or -1 (out of memory: cov untouched). */
int rod_fit_sandwich_add_shapes(const double *Jw, const double *f, int p, int row0, const int *rows, int nshapes,
                                const double *hinv, double *cov);

#endif
