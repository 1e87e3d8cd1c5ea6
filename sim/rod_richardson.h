/* rod_richardson.h: observed order of convergence and Richardson extrapolation of a quantity
 * computed on a ladder of resolutions refined by a constant ratio (mesh edges, time steps).
 *
 * Shared by `ribbon-sim convergence`, the daemon's prediction ladder (daemon/predict_ladder.c) and
 * the convergence tests, so the three agree on when an order counts as observed. With
 * s(h) = s* + C h^p, three values s0, s1, s2 at h, h / ratio, h / ratio^2 give
 *     p = log((s1 - s0) / (s2 - s1)) / log(ratio),   s* = s2 + (s2 - s1) / (ratio^p - 1). */
#ifndef RIBBON_SIM_ROD_RICHARDSON_H
#define RIBBON_SIM_ROD_RICHARDSON_H

/* The observed order from three successive values (s0 the coarsest), or NAN when none is
 * observed: the two differences must have the same sign and shrink (monotone convergence), and
 * ratio must exceed 1. */
double rod_observed_order(double s0, double s1, double s2, double ratio);

/* The Richardson-extrapolated value from the two finest values s1, s2 and order p > 0; NAN when
 * ratio^p - 1 is not positive or an input is not finite. */
double rod_richardson(double s1, double s2, double ratio, double p);

/* The observed order when the two refinements differ: h0 / h1 = r0, h1 / h2 = r1 (both > 1).
 * With s = s* + C h^p, (s0 - s1) / (s1 - s2) = (r0^p - 1) / (1 - r1^-p), increasing in p, solved
 * by bisection on [1e-3, 30] (60 halvings). NAN as rod_observed_order, and when the ratio of the
 * differences lies outside what that bracket gives. Equal ratios give rod_observed_order's p. */
double rod_observed_order_ratios(double s0, double s1, double s2, double r0, double r1);

/* ---- error estimates of a ladder that refines the mesh and the time step together ----------
 *
 * The snap Delta W's error has a spatial part (DER: centred curvatures, lumped masses, O(h^2)) and
 * a temporal part (implicit Euler, and the onset found to one step: O(dt)). A ladder that refines
 * both together, dt in proportion to the edge length h (and, in fast mode, the step control's
 * targets in proportion to dt), has the error
 *     e(h) = a h + b h^2,
 * whose order is 1 as h -> 0. Three rungs at ratio r observe (s0 - s1) / (s1 - s2) =
 * r (a + b h0 (1 + 1/r)) / (a + b h0 (1 + 1/r) / r), which lies between r and r^2: the observed
 * order lies in [1, 2] whenever a and b have one sign. The onset's step quantum (shear rate
 * times one step) scatters the temporal orders by a few tenths (tests/sim/test_convergence_orders.c
 * measures 1.00-1.74 in dt alone and 1.71-1.90 in N alone), so the expected range is [1, 2]
 * widened by 0.3 each way. In that range the estimate is Richardson's at the asymptotic order 1:
 *     s* = s_fin + (s_fin - s_prev) / (r - 1),   err_k = |s_k - s*|,
 * which bounds the error of the finest rung from above and by at most (r^2 - 1) / (r - 1) = r + 1
 * (3 at r = 2) when the error is a h + b h^2, and of the coarser rungs by less. An observed order
 * outside the range (or none: differences that change sign or grow) means the rungs are not in
 * the asymptotic range; then the order is not used, the distance to the finest rung is taken
 * with a safety factor of 3 (Roache's grid convergence index for an unverified order):
 *     err_k = |s_k - s_fin| + 3 |s_fin - s_prev| / (r - 1),
 * and the ladder says so. Errors are relative to |s*|. */
#define ROD_LADDER_ORDER_FORMAL 1.0 /* asymptotic order of the combined refinement */
#define ROD_LADDER_ORDER_LO 0.7     /* expected range of the observed order */
#define ROD_LADDER_ORDER_HI 2.3
#define ROD_LADDER_SAFETY 3.0       /* safety factor outside the asymptotic range */

typedef struct rod_ladder_verdict {
    double order;        /* observed from the three finest rungs; NAN when none is observed */
    int asymptotic;      /* 1: order within [ROD_LADDER_ORDER_LO, ROD_LADDER_ORDER_HI] */
    double extrapolated; /* s*: Richardson at ROD_LADDER_ORDER_FORMAL from the two finest; NAN when unknown */
    double safety;       /* 1 in the asymptotic range, ROD_LADDER_SAFETY otherwise */
    char note[200];      /* "" in the asymptotic range, else why not ("not in the asymptotic range: ...") */
} rod_ladder_verdict;

/* h[0..n-1]: each rung's resolution (edge length, decreasing), s[]: its value. Fills err[k] with
 * the estimated relative error of s[k] (-1 when none can be estimated: fewer than two rungs, the
 * two finest equal, a non-finite value) and the verdict (may be NULL). */
void rod_ladder_estimate(const double *h, const double *s, int n, double *err, rod_ladder_verdict *v);

#endif
