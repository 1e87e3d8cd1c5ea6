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

/* The C2 map on perturbations (free-DOF vectors): out = S v. Node i's displacement comes from
 * node N-1-i with signs (-1, -1, +1) on (x, y, z); the twist angle of edge j from edge N-2-j,
 * negated (the mirrored edge runs the other way, so its angle about its tangent changes sign:
 * with frames d1' = R d1, d2' = -R d2, t' = -R t, the material normal R m1 has angle -theta).
 * On a symmetric state of the perfect scene the free Hessian commutes with S (tested). out must
 * not alias v. */
void rod_mode_mirror(const rod *r, const double *v, double *out);

/* Projects v in place onto the even (sign > 0: S v = v) or odd (sign < 0: S v = -v) subspace,
 * (v + sign S v) / 2; scratch holds rod_nfree(r) values. */
void rod_mode_project(const rod *r, int sign, double *v, double *scratch);

/* Replaces the state by its C2-symmetric part: each free node's position by the mean of itself and
 * the rotated image of its mirror node, each free twist angle by the mean of itself and minus its
 * mirror edge's (frames that arrived symmetric, as the route's do, keep that relation). Near a
 * pitchfork an odd displacement costs almost no residual, so solvers accumulate one along the odd
 * critical mode; it must be removed before the parameters move. Frames are not updated. */
void rod_state_symmetrize(rod *r);

/* How far the current state is from C2-symmetric: max over nodes of |x_i - S x_{N-1-i}| / l. */
double rod_state_asymmetry(const rod *r);

#endif
