/* campaign_edge.h: the regime boundary the experiments support, per crease angle phi
 * (campaign_edge.c; issue 35 part C). Pure statistics on counts: no store, no simulator.
 *
 * The measured regimes of a campaign at one phi are points (Gamma, asymmetric count, symmetric
 * count): specimens at the same design pooled, repeated trials as counts. Asymmetric is below the
 * boundary, symmetric above (the paper's and rod_boundary.h's orientation). Where the measured
 * regimes switch:
 *   - bracket: every asymmetric trial lies below every symmetric one. The boundary lies between
 *     the highest asymmetric Gamma and the lowest symmetric one; its estimate is the middle,
 *     its interval the bracket itself (no noise width can be told from separated data).
 *   - probit: the two overlap (a specimen near the boundary went either way). P(asymmetric) =
 *     Phi((Gamma* - Gamma) / w): maximum likelihood over Gamma* and the noise width w on a grid,
 *     Gamma*'s 95% interval from the profile likelihood (log-likelihood within 1.92 of its
 *     maximum), a documented and deterministic answer for the few points a lab has.
 *   - below / above: only symmetric (only asymmetric) trials: the boundary lies below the lowest
 *     (above the highest) Gamma tried; one side of the interval is open (NaN in lo / hi).
 *   - none: no asymmetric or symmetric trial at that phi (no snap and unknown do not count). */
#ifndef RIBBON_CAMPAIGN_EDGE_H
#define RIBBON_CAMPAIGN_EDGE_H

#include <stddef.h>

/* One design point of the campaign: a (phi, Gamma) and its measured regimes as counts. */
typedef struct campaign_obs {
    double phi_deg; /* crease angle magnitude, deg */
    double gamma;   /* crease position, fraction of the free length */
    int n_asym;     /* trials measured asymmetric */
    int n_sym;      /* trials measured symmetric */
    int n_other;    /* trials with no snap or an unknown regime (drawn, not fitted) */
    int n_specimens; /* specimens pooled into the point */
    int n_unknown;  /* of n_other: trials that snapped but whose regime the camera could not tell
                       (the planner's third outcome, campaign_plan.h) */
} campaign_obs;

typedef enum campaign_edge_method {
    CAMPAIGN_EDGE_NONE = 0, /* nothing to fit at this phi */
    CAMPAIGN_EDGE_BELOW,    /* only symmetric: the boundary lies below the lowest Gamma (hi set) */
    CAMPAIGN_EDGE_ABOVE,    /* only asymmetric: the boundary lies above the highest Gamma (lo set) */
    CAMPAIGN_EDGE_BRACKET,  /* separated: between the highest asymmetric and lowest symmetric */
    CAMPAIGN_EDGE_PROBIT    /* overlapping: probit fit with a noise width */
} campaign_edge_method;

const char *campaign_edge_method_name(campaign_edge_method m); /* "none", "below", ... */

typedef struct campaign_edge {
    double phi_deg;
    campaign_edge_method method;
    double gamma;   /* the estimate; NaN for none, below and above */
    double lo, hi;  /* the interval (bracket or probit 95%); NaN where open */
    double width;   /* probit noise width w (Gamma units); 0 for a bracket; NaN otherwise */
    int n_asym, n_sym, n_points;
} campaign_edge;

/* The edge at phi_deg from the observations whose phi is within 1e-6 deg of it (others are
 * ignored). Never fails: *out always set. */
void campaign_edge_fit(const campaign_obs *obs, size_t n, double phi_deg, campaign_edge *out);

/* The distinct phi values of obs, ascending, into phis (at most max); returns how many. */
size_t campaign_edge_phis(const campaign_obs *obs, size_t n, double *phis, size_t max);

#endif
