/* rod_observe.h: what is measured on a rod state, in the paper's normalisation.
 *   dz     Delta Z: height of the arc-length midpoint above the line through the clamp points,
 *          over l (the clamp points are at z = 0).
 *   a      the paper's asymmetry A = int_0^1/2 k ds - int_1/2^1 k ds of the out-of-plane
 *          (toward-normal) curvature, discretely the sum of the turning angles 2 atan(kappa1/2)
 *          over nodes before the midpoint minus those after it; for a planar curve this is
 *          2 theta(1/2) - theta(0) - theta(1).
 *   a_cam  the same measure, 2 theta(1/2) - theta(0) - theta(1), on the centreline projected
 *          onto the x-z plane (a distant side camera), at the projected curve's arc-length
 *          midpoint; dz_cam is the projected midpoint's height over l. */
#ifndef RIBBON_SIM_ROD_OBSERVE_H
#define RIBBON_SIM_ROD_OBSERVE_H

#include "rod.h"

typedef struct rod_obs {
    double dz, a, a_cam, dz_cam;
} rod_obs;

/* k1 is scratch of N doubles. */
void rod_observe(const rod *r, double *k1, rod_obs *o);

#endif
