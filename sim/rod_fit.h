/* rod_fit.h: a strip's parameters fitted to observations of its static equilibria (issue 32 A).
 *
 * Observations are states (Delta L, Delta W) with the Delta Z and A seen there (the camera's
 * dz_cam and a_cam by default, the paper's dz and A on request; rod_observe.h). The model
 * follows the upper equilibrium from state to state as the protocol does (sorted by Delta W,
 * then Delta L: the compression and hold, then the shear), reached first by the documented route
 * at the first state and then by static solves in steps of at most 0.02 in Delta L and Delta W,
 * each warm-started; when the parameters change, each state is first re-solved from its own last
 * equilibrium, and followed again from its predecessor when that fails or leaves the upper
 * branch (Delta Z must keep its sign); once one state fails to re-solve, the following ones
 * are followed from their predecessor directly. Observations at the same (Delta L, Delta W) as
 * the one before (a hold's frames) share its equilibrium: solved once. The Jacobian comes from
 * rod_sensitivity.h.
 *
 * The fit is Levenberg-Marquardt (GSL gsl_multifit_nlinear, trust region with the LM step) on
 * residuals (model - observed) / noise for each observable, plus (u - prior) / prior_sigma for
 * parameters with a prior. It stops at GSL's tolerances or, sooner, once the Gauss-Newton step
 * still to go is below opts.stop_sd standard deviations (0.05: the values are then within a
 * twentieth of their standard errors of the optimum). Bounds: the model is evaluated at the parameters clamped into them,
 * and a parameter that ends at a bound is reported. A trial step where the model fails (no upper
 * state) gets a residual far above the last one, so the trust region shrinks (capped).
 *
 * Output: values, standard errors and correlations from (J^T J)^{-1} at the solution (times
 * chi2 / (n - p) when scale_covariance), and the directions the data do not determine: singular
 * vectors of the data's weighted Jacobian in units of each parameter's range (bounds) whose
 * one-sigma extent exceeds the range (singular value below 1). A parameter with a weight above
 * 0.3 in such a direction is "not determined by these data": its standard error is not reported
 * (INFINITY here, never a number). */
#ifndef RIBBON_SIM_ROD_FIT_H
#define RIBBON_SIM_ROD_FIT_H

#include <stdatomic.h>
#include <stddef.h>

#include "rod_fit_param.h"
#include "rod_shape.h"

typedef struct rod_fit_obs {
    double dl, dw, dz, a;
} rod_fit_obs;

/* A shape seen at one observation's state (rod_shape.h): k points (x, z) over l relative to the
 * left clamp point, evenly in the projected arc length. Its residuals (model - observed, each
 * coordinate over opts.sigma_shape) join the data rows; its state must be one of the
 * observations' (Delta L, Delta W) exactly. */
typedef struct rod_fit_shape {
    double dl, dw;
    int k;                           /* points, 1 .. ROD_SHAPE_MAX_POINTS */
    double xz[2 * ROD_SHAPE_MAX_POINTS];
} rod_fit_shape;

typedef struct rod_fit_opts {
    int fit[ROD_FIT_NKEYS];          /* 1: fitted, 0: held at the scene's value */
    double lo[ROD_FIT_NKEYS], hi[ROD_FIT_NKEYS]; /* bounds in fit units; NaN: the defaults
                                        (scene value -+ 20 deg, -+ 0.05 l for positions and
                                        the view's Delta Z offset, -+ ln 100 for k,
                                        -+ ln 10 for E, positions kept inside (0, 1)) */
    double prior_sigma[ROD_FIT_NKEYS]; /* fit units; INFINITY: no prior (the default) */
    double sigma_dz, sigma_a;        /* noise of each observable (Delta Z, A in rad) */
    int paper;                       /* 0: dz_cam, a_cam (the camera's); 1: dz, a */
    int scale_covariance;            /* 1: covariance times chi2 / (n - p) */
    double sigma_b_dz, sigma_b_a;    /* the tracker's error common to a phase (compression, hold,
                                        shear) on each observable, besides sigma_dz / sigma_a per
                                        frame: the covariance becomes the sandwich of
                                        rod_fit_sandwich.h (the values are unchanged). 0: none (the
                                        default); below 0: estimated from the phases' mean
                                        residuals (biased low) */
    int max_iterations;              /* LM iteration cap */
    double stop_sd;                  /* the fit stops once the Gauss-Newton step still to go is
                                        below this many standard deviations (0.05: every value
                                        within a twentieth of its standard error of the optimum;
                                        the in-trial fit's speed). 0: GSL's tolerances alone
                                        (converged to round-off: noise-free data) */
    int min_obs;                     /* fewest observations accepted (>= fitted parameters + 1) */
    double misfit;                   /* RMS residual (in units of the noise) above which no
                                        parameter set fits these data */
    const atomic_int *cancel;        /* NULL, or non-zero stops the fit at its next evaluation
                                        (ROD_ERR_TIME_LIMIT, "cancelled"): a trial's fit
                                        beside it (daemon/trial/trial_calibrate.c) */
    const rod_fit_shape *shapes;     /* NULL, or nshapes shapes seen (the projected centreline at a
                                        few states): 2 k more data rows each */
    int nshapes;
    double sigma_shape;              /* noise of each shape coordinate, over l (the tracker's
                                        centreline noise; 0.001 by default) */
    int shape_common_mode;           /* 1: each shape's error also has a common mode, its own
                                        residual's direction and size, in the covariance (the
                                        sandwich of rod_fit_sandwich.h; values unchanged); 0: the
                                        shape's rows are independent noise (the default) */
    const double *start;             /* NULL: the fit starts at the scene's values; else
                                        ROD_FIT_NKEYS values in fit units where the fitted ones start
                                        (clamped into the bounds; a non-finite one: the scene's),
                                        e.g. the fit without shapes, so the shapes' less convex cost
                                        is entered near its minimum (the priors stay centred on the
                                        scene's values; rms_start stays the scene's) */
    const double *prior_centre;      /* NULL: each prior is centred on the scene's value; else
                                        ROD_FIT_NKEYS centres in fit units (a non-finite one: the
                                        scene's), e.g. a refresh evaluated at fit 0's strip with its
                                        priors on the specimen's values (rod_fit_carry.h) */
} rod_fit_opts;

rod_fit_opts rod_fit_opts_default(void);

typedef struct rod_fit_result {
    double u[ROD_FIT_NKEYS];         /* fitted values (held ones: the scene's), fit units */
    double u0[ROD_FIT_NKEYS];        /* the scene's */
    double lo[ROD_FIT_NKEYS], hi[ROD_FIT_NKEYS]; /* the bounds used */
    int fitted[ROD_FIT_NKEYS];       /* 1: fitted, 0: held */
    double se[ROD_FIT_NKEYS];        /* standard errors, fit units; INFINITY: not determined */
    int determined[ROD_FIT_NKEYS];   /* fitted and determined by the data */
    int at_bound[ROD_FIT_NKEYS];     /* ended at (within 1e-9 of the range of) a bound */
    double cov[ROD_FIT_NKEYS][ROD_FIT_NKEYS]; /* fit units, 0 where not determined */
    double corr[ROD_FIT_NKEYS][ROD_FIT_NKEYS];
    int nobs, nres, nfit;            /* nres: data rows, 2 nobs plus 2 k per shape */
    int nshape_rows;                 /* of which the shapes' */
    double chi2;                     /* sum of squared data residuals */
    double shape_rms;                /* the shapes' residual alone in units of their noise (0: none) */
    double rms;                      /* sqrt(chi2 / nres): residual in units of the noise */
    double rms_start;                /* the same at the scene's values */
    int iterations, evaluations, model_failures;
    int capped;                      /* LM stopped at max_iterations before converging */
    int misfit;                      /* rms above opts.misfit */
    double sv_min, sv_max;           /* singular values of the range-scaled data Jacobian */
    double wall_s;
    double sigma_b[2];               /* the common mode used (Delta Z, A; 0: none) */
    int cov_scaled;                  /* 1: cov already times chi2 / (n - p) (scale_covariance) */
    double gn_sd;                    /* the Gauss-Newton step still to go when the fit stopped, in
                                        standard deviations (below 0.05: converged to well within
                                        the noise); -1 when not known */
} rod_fit_result;

/* Fits. Returns ROD_OK with res filled (misfit and at_bound are verdicts the caller reports),
 * or an error with the reason in why: ROD_ERR_SCENE for input that cannot be fitted (too few
 * observations, a parameter the scene does not have, non-finite data, bounds that exclude the
 * start), or the model's failure at the scene's values (no upper state there). */
rod_status rod_fit_run(const rod_scene *sc, const rod_fit_obs *obs, int nobs, const rod_fit_opts *o,
                       rod_fit_result *res, char *why, size_t why_len);

/* The model alone (for the benchmark and tests): observables at parameters u for every
 * observation, and optionally their Jacobian by sensitivities. */
typedef struct rod_fit_model rod_fit_model;

rod_status rod_fit_model_alloc(const rod_scene *sc, const rod_fit_obs *obs, int nobs, int paper,
                               rod_fit_model **out, char *why, size_t why_len);
void rod_fit_model_free(rod_fit_model *m);
/* Forgets the stored equilibria (the next evaluation follows the whole path from the route). */
void rod_fit_model_reset(rod_fit_model *m);
/* y: 2 nobs values (Delta Z, A per observation, in the caller's order); jac (NULL to skip): row
 * major 2 nobs x ROD_FIT_NKEYS, derivatives for the parameters with use[j] set (others 0). */
rod_status rod_fit_model_eval(rod_fit_model *m, const double u[ROD_FIT_NKEYS], const int *use, double *y,
                              double *jac, char *why, size_t why_len);
/* Shapes to model at the next evaluations (copied in; n 0 removes them): each at the observation
 * with its (Delta L, Delta W). ROD_ERR_SCENE with the reason when a shape's state is no
 * observation's or its k is out of range. */
rod_status rod_fit_model_set_shapes(rod_fit_model *m, const rod_fit_shape *shapes, int n, char *why,
                                    size_t why_len);
/* After an evaluation: the shapes' model values (*y: 2 k per shape, in their order) and, when the
 * evaluation computed a Jacobian, its rows (*jac: row major, ROD_FIT_NKEYS per row, NULL
 * otherwise); returns the number of rows. */
int rod_fit_model_shape_rows(const rod_fit_model *m, const double **y, const double **jac);

#endif
