/* rod_kernels.h (private to sim/): per-element energy kernels with analytic gradient and
 * Hessian, in local coordinates.
 *
 * Stretch element j (edge j): local DOFs [x_j (3), x_{j+1} (3)].
 * Bend and twist element i (interior node i): local DOFs
 *     [x_{i-1} (3), th_{i-1}, x_i (3), th_i, x_{i+1} (3)]   = q[4 (i-1) .. 4 (i-1) + 10]
 * so a node element's local block is a contiguous slice of q, which is what makes the global
 * Hessian banded with half-bandwidth 10.
 * Each kernel returns the element energy and, when g (and H) are non-NULL, overwrites them with
 * the local gradient (and the symmetric local Hessian). Frames must be up to date. */
#ifndef RIBBON_SIM_ROD_KERNELS_H
#define RIBBON_SIM_ROD_KERNELS_H

#include "rod.h"

#define ROD_NODE_LOCAL 11

double rod_stretch_element(const rod *r, int j, double g[6], double H[6][6]);
double rod_bend_element(const rod *r, int i, double g[11], double H[11][11]);
double rod_twist_element(const rod *r, int i, double g[11], double H[11][11]);

/* Maps a gradient and Hessian in (e, f, th_e, th_f) space (8 values: e, f, th_e, th_f) to the
 * node element's 11 local DOFs, using e = x_i - x_{i-1}, f = x_{i+1} - x_i. Adds s times. */
/* Bending and twist at interior node i plus the stretching of edge i-1, as the rod's terms ask,
 * in (e, f, th_e, th_f) space (rod_bend.c explains the shared evaluation): returns the energy,
 * overwrites g8 and, when non-NULL, the symmetric H8. Map to local DOFs as rod_local_from_ef.
 * mf_e and mf_f (m1 then m2 of edges i-1 and i) may carry the material frames when the caller
 * has them (each edge serves two nodes); NULL computes them. */
double rod_node_ef(const rod *r, int i, const double mf_e[6], const double mf_f[6], double g8[8],
                   double H8[8][8]);

/* The kappa1 term of a compliant crease at node i (rod_hinge.c): returns 0 when node i is not a
 * hinge of this rod (or its creases are rigid); otherwise 1, with the energy *e and its first
 * and second derivatives in kappa1. */
int rod_hinge_kappa1(const rod *r, int i, double kappa1, double *e, double *de, double *d2e);

/* k_eff = 1 / (1 / k + dl_hat_i / (E I1)) of the hinge at node i (N m/rad). */
double rod_hinge_stiffness_eff(const rod *r, int i);

void rod_local_from_ef(double s, const double g8[8], double H8[8][8], double g[11], double H[11][11]);

#endif
