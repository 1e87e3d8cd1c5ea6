/* rod_shape.h: the strip's shape as a side camera sees it, for the fit (issue 32 A): the
 * centreline's x-z projection between the clamp points, resampled at K points evenly in the
 * projected arc length, (i + 1/2) / K of it for i = 0 .. K-1 (the clamp points themselves are
 * where the rails put them and carry nothing), each point's (x, z) relative to the left clamp
 * point over l. A tracked centreline mapped to the plane is resampled the same way
 * (rod_shape_resample), so model and camera are compared point by point.
 *
 * The projection depends on the free DOFs alone (the clamp points are fixed by Delta L and
 * Delta W), so its derivative in a strip parameter is its directional derivative along the
 * equilibrium's dq/du (rod_sensitivity.h): rod_shape_directional. */
#ifndef RIBBON_SIM_ROD_SHAPE_H
#define RIBBON_SIM_ROD_SHAPE_H

#include "rod.h"

#define ROD_SHAPE_MAX_POINTS 64 /* most points K of one shape */

/* n points (x, z) of a polyline (xz: 2 n values, any unit) resampled at k points (i + 1/2) / k of
 * its arc length into out (2 k values, the same unit). Returns 0, or -1 when n < 2, k is not in
 * 1 .. ROD_SHAPE_MAX_POINTS, a value is not finite or the polyline has no length. */
int rod_shape_resample(const double *xz, int n, int k, double *out);

/* The rod's projected centreline, nodes 1 .. N-2 (the free length), relative to the left clamp
 * point over l, resampled at k points into out (2 k). 0 or -1 as rod_shape_resample. */
int rod_shape_sample(const rod *r, int k, double *out);

/* d(rod_shape_sample)/dt along q_free + t dir (dir: rod_nfree(r) values, e.g. dq/du_j), by a
 * central difference whose largest node displacement is 1e-7 l (the projection is piecewise
 * linear in the nodes between resampling breakpoints). save: scratch of rod_nfree(r) values. The
 * rod is left exactly as it came. 0 or -1. */
int rod_shape_directional(rod *r, int k, const double *dir, double *save, double *out);

#endif
