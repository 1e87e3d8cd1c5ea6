/* rod_fit_lm.h: the least-squares machinery both strip fits run (rod_fit.h, one strip;
 * rod_fit_joint.h, several sharing k / b): the Levenberg-Marquardt loop and the covariance with
 * its "not determined by these data" rules, on a parameter vector of any length.
 *
 * Owned apart from the two fits so that they cannot drift: the joint fit used to carry a copy of
 * GSL's driver without the stop within the noise (stop_sd) and a covariance without the tracker's
 * common mode (the sandwich, rod_fit_sandwich.h).
 *
 * The problem is the caller's: x (p values, the caller's scaled units), residual rows f (nres:
 * the data's 2 per observation first, Delta Z then A, then one per prior) and the weighted
 * Jacobian J (nres x p, row major). The loop is GSL's trust region with the LM step (GSL 2.7's
 * gsl_multifit_nlinear_driver: its tolerances, its return codes) with one more stop: the
 * Gauss-Newton step still to go below stop_sd standard deviations (rod_fit_opts.stop_sd). A model
 * evaluation that fails (no upper state there) is given a residual far above the last good one,
 * so the trust region shrinks. The Jacobian computed with each f is kept for the df call GSL
 * makes at the same x. */
#ifndef RIBBON_SIM_ROD_FIT_LM_H
#define RIBBON_SIM_ROD_FIT_LM_H

#include <stddef.h>

#include "rod.h"

/* Failed model evaluations (trial parameter sets without an upper state) a fit accepts. */
#define ROD_FIT_LM_FAIL_CAP 30

typedef struct rod_fit_lm_problem {
    int p, nres;
    /* Evaluates at x (p values) into last_f (nres) and last_J (nres x p, row major). Returns 0;
       1 when the model failed there (last_f and last_J left at the last good point: the loop
       answers a residual far above it, with no Jacobian, not cached); -1 to stop the fit
       (cancelled, a cap). */
    int (*eval)(void *user, const double *x);
    const double *last_f, *last_J; /* the caller's */
    void *user;
} rod_fit_lm_problem;

/* Runs from x (p values; the position reached on return, whatever the outcome). Returns ROD_OK
 * when the position is the fit's answer: converged (GSL's tolerances or stop_sd), no step
 * reducing the cost any more (the best found), or *capped = 1 at maxiter iterations (or when no
 * step reduced the cost at the first, as GSL's driver says it); ROD_ERR_ALLOC; ROD_ERR_TIME_LIMIT
 * when eval stopped it (the caller knows why: cancelled, its cap); ROD_ERR_SINGULAR with GSL's
 * reason for anything else. *iterations: GSL's count; *gn_sd: the Gauss-Newton step still to go
 * at the end in standard deviations (-1 unknown). */
rod_status rod_fit_lm_drive(const rod_fit_lm_problem *pr, double *x, int maxiter, double stop_sd, int *iterations,
                            double *gn_sd, int *capped, char *why, size_t why_len);

/* What the covariance is made from, at the solution. Parameter j has bounds lo[j] < hi[j] and
 * prior width prior[j] (INFINITY: none) in natural fit units, and x_j = (u_j - u0_j) / scale[j]. */
typedef struct rod_fit_lm_cov_in {
    int p, nres, nobs;           /* parameters, residual rows, observations (2 nobs data rows first) */
    int nshape;                  /* the shapes' data rows after those (rod_fit_opts.shapes; 0: none):
                                    they count in what the data determine */
    const double *Jw;            /* nres x p, row major, weighted, in x units */
    const double *f;             /* nres residuals at the solution (the data's: the common mode's
                                    estimate) */
    const double *lo, *hi, *scale, *prior;
    double factor;               /* the covariance times this (chi2 / dof when scaled; 1 otherwise) */
    const int *phase;            /* nobs: each observation's phase (rod_fit_phases) */
    double sigma[2], sigma_b[2]; /* per-frame noise and common mode (0: none; < 0: estimated from
                                    the residuals) of Delta Z and A: rod_fit_opts */
    int nshapes;                 /* shapes with a common mode each (rod_fit_opts.shape_common_mode;
                                    0: none): shape s has shape_rows[s] of the nshape rows, in order */
    const int *shape_rows;
} rod_fit_lm_cov_in;

typedef struct rod_fit_lm_cov_out {
    double *cov, *corr;          /* p x p, natural fit units; 0 on rows of a parameter not determined
                                    and without a prior */
    double *se;                  /* p; INFINITY: not determined by these data (and no prior) */
    int *determined;             /* p */
    double sv_min, sv_max;       /* singular values of the range-scaled data Jacobian */
    double sigma_b[2];           /* the common mode used */
} rod_fit_lm_cov_out;

/* (J^T J)^-1 (pseudo-inverse below 1e-12 of the largest singular value), plus the sandwich's
 * common-mode terms, times factor; a parameter is not determined when it weighs above 0.3 in a
 * singular direction of the data rows in units of each range with a singular value below 1, or
 * when its standard error exceeds its range. 0, or -1 when out of memory. */
int rod_fit_lm_covariance(const rod_fit_lm_cov_in *in, rod_fit_lm_cov_out *out);

#endif
