/* rod_symmetry.h: the C2 symmetry of the clamped ribbon, used to classify critical modes.
 *
 * The two clamps swap under the rotation by pi about the vertical (z) axis through the midpoint
 * between the clamp points (DESIGN.md section 3). On node positions it maps node i to node
 * N-1-i, rotated: (x, y, z) -> (2 c_x - x, -y, z) with c_x the middle of the clamp gap, so a
 * displacement (dx, dy, dz) of node N-1-i becomes (-dx, -dy, dz) at node i. Edge directions
 * reverse under the map, so twist angles and reference frames do not map one to one: the
 * parity of a mode is measured on its node-position components only.
 *
 * Parity of a free-DOF vector v: p = <v_x, S v_x> / <v_x, v_x> over the free node positions
 * (nodes 2 .. N-3), +1 for a symmetric (even) mode, -1 for an antisymmetric (odd) one. On the
 * symmetric branch of the symmetric scene the Hessian commutes with S and a simple critical mode
 * has parity +-1 up to round-off. */
#ifndef RIBBON_SIM_ROD_SYMMETRY_H
#define RIBBON_SIM_ROD_SYMMETRY_H

#include "rod.h"

/* Parity of the free-DOF vector v (rod_nfree(r) values), in [-1, 1]; 0 when v has no position
 * components. */
double rod_mode_parity(const rod *r, const double *v);

/* How far the current state is from C2-symmetric: max over nodes of |x_i - S x_{N-1-i}| / l. */
double rod_state_asymmetry(const rod *r);

#endif
