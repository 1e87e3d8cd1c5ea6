/* rod_fit_joint.h: several specimens fitted at once, each with its own strip parameters, all
 * sharing one hinge stiffness per unit width (issue 32 C: "separate specimens can share the
 * hinge stiffness per unit width").
 *
 * A crease's hinge is a line of material along the crease: its stiffness k (N m/rad) grows with
 * the strip's width b (ribbon.width), so specimens of one sheet share k / b (N/rad), not k. Each
 * specimen is a scene of its own (geometry, width, thickness, its own crease angles and
 * positions, a compliant hinge as the start) with the observations of it (all its trials
 * pooled, rod_fit.h). The joint parameters are
 *     theta[0]                 = ln(k / b)       shared: folds.hinge_stiffness_per_width
 *     theta[1 + s nown + i]    = u_s[own[i]]     specimen s's own key own[i] (rod_fit_param.h),
 * the same own keys for every specimen (crease angles, positions, E, the camera's offset), and
 * specimen s's pair hinge is k_s = (k / b) b_s, that is u_s[ROD_FIT_HINGE] = theta[0] + ln b_s
 * (a scene with one k per crease keeps its ratio: both scale together, rod_fit_param.h).
 *
 * The Jacobian is block-sparse: specimen s's rows (Delta Z, A of each of its observations) have
 * non-zeros only in the shared column and in s's own columns. The shared column is each scene's
 * own hinge sensitivity (rod_sensitivity.h) times d ln k_s / d ln(k / b) = 1; on the natural
 * scale it is b_s dy/dk_s, each scene's sensitivity scaled by its width. It is stored dense for
 * GSL's solver (the zeros explicit); the test checks the zeros and every column against central
 * differences of whole followed paths.
 *
 * The fit is rod_fit.h's, run by the same code (rod_fit_lm.h): Levenberg-Marquardt on
 * (model - observed) / noise plus priors, bounds by clamping, the stop within each.stop_sd
 * standard deviations of the optimum, covariance (J^T J)^{-1} over the whole joint parameter set
 * (the sandwich of rod_fit_sandwich.h with each.sigma_b_dz / _a, per phase of each specimen's
 * observations), and "not determined by these data" by the same two rules (a singular direction of the range-scaled data Jacobian
 * with a weight above 0.3, or a standard error wider than the range), with the specimen's name
 * in the key ("S-12:folds.angle_left_deg"). Because the joint information matrix is
 * block-arrowhead, the shared parameter's information is the sum of each specimen's (its
 * Schur complement): for specimens fitted alone with their own k, 1 / se(k/b)^2 is the sum of
 * their 1 / se(k_s)^2 at the same point.
 *
 * Refused with a reason: a specimen without a known width (not finite or not positive), with
 * rigid creases or none (no hinge to share), the per-crease hinge keys (which crease of one
 * specimen matches which of another is not known: the pair's k / b is shared), the pair's key as
 * a specimen's own (it is the shared one), two specimens of one name. */
#ifndef RIBBON_SIM_ROD_FIT_JOINT_H
#define RIBBON_SIM_ROD_FIT_JOINT_H

#include <stddef.h>

#include "rod_fit.h"

#define ROD_FIT_JOINT_KEY_LEN 128

/* The shared parameter's key. */
#define ROD_FIT_JOINT_SHARED_KEY "folds.hinge_stiffness_per_width"

typedef struct rod_fit_joint_spec {
    const char *name;          /* the specimen's name, prefix of its keys ("S-12") */
    const rod_scene *scene;    /* its strip (width > 0, compliant creases) */
    const rod_fit_obs *obs;    /* its observations; kept by pointer until the fit ends */
    int nobs;
} rod_fit_joint_spec;

typedef struct rod_fit_joint_opts {
    rod_fit_opts each;         /* fit[], lo[], hi[], prior_sigma[]: every specimen's own keys
                                  (bounds NaN: the defaults around each specimen's scene value);
                                  noise, paper, caps, misfit, scale_covariance, cancel: the fit's */
    double kb_lo, kb_hi;       /* bounds of ln(k / b), ln(N/rad); NaN: the start -+ ln 100 */
    double kb_start;           /* ln(k / b) to start from; NaN: the mean of ln(k_s / b_s) over the
                                  specimens' scenes */
    double kb_prior_sigma;     /* prior width on ln(k / b) about the start; INFINITY: none */
} rod_fit_joint_opts;

rod_fit_joint_opts rod_fit_joint_opts_default(void);

typedef struct rod_fit_joint_result {
    int nspec, nown, np;       /* specimens, own keys per specimen, joint parameters (1 + nspec nown) */
    int own[ROD_FIT_NKEYS];    /* the own keys, in key order */
    double kb, kb0;            /* ln(k / b) fitted and started from (k / b in N/rad) */
    double kb_lo, kb_hi;
    double kb_se;              /* standard error of ln(k / b) (a relative error of k / b);
                                  INFINITY: not determined by these data */
    int kb_determined, kb_at_bound;
    rod_fit_result *spec;      /* nspec: each specimen as rod_fit_run would report it, with
                                  folds.hinge_stiffness fitted (k_s = (k / b) b_s), its own rows'
                                  chi2, rms, rms_start, nobs, nres, and its block of the joint
                                  covariance (own keys and the hinge: marginal), so
                                  rod_fit_snap_predict takes it as it is */
    char (*key)[ROD_FIT_JOINT_KEY_LEN]; /* np joint key names: the shared one, then "NAME:key" */
    double *cov, *corr;        /* np x np, row major, fit units; 0 where not determined */
    double *se;                /* np; INFINITY: not determined */
    int *determined;           /* np */
    int nobs, nres;            /* all observations, data residuals (2 nobs) */
    double chi2, rms, rms_start;
    int iterations, evaluations, model_failures, capped, misfit, cov_scaled;
    double sv_min, sv_max;     /* of the range-scaled data Jacobian */
    double wall_s;
    double sigma_b[2];         /* the tracker's common mode in the covariance (Delta Z, A; 0: none):
                                  each.sigma_b_dz, _a, per phase of each specimen's observations */
    double gn_sd;              /* the Gauss-Newton step still to go when the fit stopped, in standard
                                  deviations (each.stop_sd); -1 when not known */
} rod_fit_joint_result;

/* Fits. ROD_OK with res filled (free it with rod_fit_joint_result_free, also after a failure),
 * or an error with the reason in why (ROD_ERR_SCENE for input refused as above, the model's
 * failure at the start, ROD_ERR_TIME_LIMIT "cancelled"). */
rod_status rod_fit_joint_run(const rod_fit_joint_spec *specs, int nspec, const rod_fit_joint_opts *o,
                             rod_fit_joint_result *res, char *why, size_t why_len);
void rod_fit_joint_result_free(rod_fit_joint_result *res);

/* The joint model alone (tests): y (2 nobs, specimens in order, each in its observations' order)
 * and J (row major 2 nobs x np, NULL to skip) at joint parameters theta (fit units, as above). */
typedef struct rod_fit_joint_model rod_fit_joint_model;

rod_status rod_fit_joint_model_alloc(const rod_fit_joint_spec *specs, int nspec, const rod_fit_joint_opts *o,
                                     rod_fit_joint_model **out, char *why, size_t why_len);
void rod_fit_joint_model_free(rod_fit_joint_model *m);
int rod_fit_joint_model_np(const rod_fit_joint_model *m);
int rod_fit_joint_model_nobs(const rod_fit_joint_model *m);
/* The start: theta[0] the ln(k / b) start, the own keys at each specimen's scene values. */
void rod_fit_joint_model_start(const rod_fit_joint_model *m, double *theta);
/* Forgets the stored equilibria (the next evaluation follows every path from its route). */
void rod_fit_joint_model_reset(rod_fit_joint_model *m);
rod_status rod_fit_joint_model_eval(rod_fit_joint_model *m, const double *theta, double *y, double *J, char *why,
                                    size_t why_len);

#endif
