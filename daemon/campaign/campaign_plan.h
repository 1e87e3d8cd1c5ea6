/* campaign_plan.h: the next specimens to make (campaign_plan.c; issue 35 part D). Pure numbers:
 * the predicted boundary at each phi and the measured counts in, beliefs and proposals out.
 *
 * The model. At each planned phi the true boundary is Gamma*_j = P_j + delta + e_j: P_j the
 * predicted boundary (ribbon-sim boundary on the rig's scene), delta one systematic offset shared
 * by every phi (the strips differ from the scene in a way the model does not know: relaxed
 * creases, a compliant hinge), e_j ~ N(0, tau^2) what the offset does not explain. delta has a
 * prior N(0, offset_sd^2) and is fitted from the trials so far: every phi's measurements tell
 * about it, so one phi's results move the others' beliefs. A trial at Gamma reads asymmetric with
 * probability Phi((Gamma*_j - Gamma) / noise): a specimen near the boundary may go either way
 * (its creases differ from the design by a percent or so).
 *
 * A trial may also read undecided (the camera's departure between its two thresholds, near the
 * boundary: docs/trials.md "The measured regime"): with undecided = h > 0 the outcome is an
 * ordered probit, asymmetric when Gamma*_j - Gamma + eps > h, symmetric when it is < -h,
 * undecided between (eps ~ N(0, noise^2)), so an undecided trial says the boundary is near its
 * Gamma instead of nothing (before, the belief stayed as it was, so the next specimen went to the
 * same phi and the same Gamma again). h = 0: two outcomes, undecided trials ignored.
 *
 * Calibration off (calibrate = 0) fixes delta at 0: each phi then has the prior N(P_j, tau^2 +
 * offset_sd^2), the same width, and learns from its own trials only.
 *
 * Beliefs are computed on grids (Gamma*_j and delta in steps of grid_step), exactly. Proposals:
 * each next specimen goes to the phi whose belief is widest, at the quantiles of that belief
 * that split it evenly (one specimen: the median, so either outcome halves it; m specimens at one
 * phi: quantiles i / (m + 1)); a phi given m specimens counts as sd / (m + 1) for the next choice. */
#ifndef RIBBON_CAMPAIGN_PLAN_H
#define RIBBON_CAMPAIGN_PLAN_H

#define PLAN_MAX_SPREAD 8 /* the spread s on 8 log-spaced values */

#include <stddef.h>

#include "campaign_edge.h"

typedef struct campaign_plan_opts {
    double tau;        /* Gamma, the model's error at one phi after the offset (default 0.003) */
    double offset_sd;  /* Gamma, prior sd of the systematic offset (default 0.03) */
    double spread_max; /* Gamma, the per-phi offsets' spread s: prior log-uniform on [tau, spread_max]
                          (default 0.02; = tau: one offset for every phi, the planner before) */
    double noise;      /* Gamma, probit width of one trial's outcome (default 0.002) */
    double undecided;  /* Gamma, half-width h of the band where a trial reads undecided (default
                          0.002; 0: two outcomes, undecided trials ignored) */
    double gamma_min, gamma_max; /* the span of Gamma* considered (0.02, 0.45: rod_boundary's) */
    double grid_step;  /* Gamma, the belief grids' step (default 2.5e-4) */
    int calibrate;     /* 1 (default): fit delta; 0: delta fixed at 0 (see above) */
} campaign_plan_opts;

campaign_plan_opts campaign_plan_opts_default(void);

/* What the planner believes at one phi. */
typedef struct campaign_belief {
    double phi_deg;
    double predicted;  /* P_j */
    double mean, sd;   /* of Gamma*_j */
    double lo, hi;     /* 95% interval (2.5% and 97.5% quantiles) */
    double median;
    double offset_mean; /* this phi's offset Gamma*_j - P_j: mean - predicted (its sd is sd) */
} campaign_belief;

typedef struct campaign_proposal {
    double phi_deg, gamma;
    double sd_before;  /* the belief's sd at that phi now */
} campaign_proposal;

typedef struct campaign_plan_result {
    double offset_mean, offset_sd; /* delta's posterior (0, 0 without calibration) */
    double spread_mean;            /* s's posterior mean (0 without calibration) */
    campaign_belief *beliefs;      /* one per planned phi (caller's array of nphi) */
    campaign_proposal *proposals;  /* k (caller's array) */
    size_t k;
} campaign_plan_result;

/* Beliefs at the nphi planned phi (phi_deg[j], predicted[j]) given obs (observations at other
 * phi values inform delta only when that phi is also planned), and k proposals. Returns 0, or -1
 * with why: bad options, a predicted boundary outside [gamma_min, gamma_max], out of memory. */
int campaign_plan_run(const double *phi_deg, const double *predicted, size_t nphi, const campaign_obs *obs,
                      size_t nobs, const campaign_plan_opts *o, size_t k, campaign_plan_result *res, char *why,
                      size_t why_len);

#endif
