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

#endif
