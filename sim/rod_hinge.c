/* rod_hinge.c: a compliant crease, its energy as a function of the crease node's turning angle.
 *
 * Owned here because it is the one place where a crease's physics lives (a hinge of rest angle
 * phi and rotational stiffness k, N m/rad); the bending kernels (rod_bend.c) call it for the
 * kappa1 term at the two crease nodes when the scene's creases are compliant (terms.hinge).
 * Each crease may have its own k (hand-made creases differ; folds.hinge_stiffness_left/right).
 *
 * Model. At the crease node the centreline turns by psi toward the surface normal,
 * psi = 2 atan(kappa1 / 2) (kappa1 the integrated curvature, rod.h; exact for a planar turn).
 * Over the node's Voronoi length v that turn is shared by the hinge (a) and the strip's own
 * bending around it (b): psi - phi = a + b with energy k a^2 / 2 + E I1 b^2 / (2 v). The split
 * that minimises it has k a = E I1 b / v, the moment balance across the hinge that the continuum
 * strip with a concentrated hinge satisfies, and leaves
 *     E_hinge(psi) = 1/2 k_eff (psi - phi)^2,   1 / k_eff = 1 / k + v / (E I1).
 * As the mesh refines (v -> 0) k_eff -> k: the crease's energy depends on its turning angle alone
 * and the strip around it bends with its own stiffness at the other nodes; k -> infinity gives a
 * rigid crease with the strip's bending (in psi) at the node. The in-plane (kappa2) and twist
 * terms at the node are the strip's, unchanged.
 *
 * Derivatives in kappa1 (the kernels chain them with kappa1's own, rod_bend.c):
 *     psi' = 1 / (1 + kappa1^2 / 4),  psi'' = -(kappa1 / 2) psi'^2,
 *     dE/dkappa1 = k_eff (psi - phi) psi',  d2E/dkappa1^2 = k_eff (psi'^2 + (psi - phi) psi''). */
#include "rod_kernels.h"

#include <math.h>

/* The stiffness of the hinge at crease k: its own (hinge_k_side, the scene's per-crease key or a
   fit's per-crease parameter) when set, else the pair's. */
static double hinge_k_of(const rod *r, int k)
{
    return k >= 0 && r->hinge_k_side[k] > 0.0 ? r->hinge_k_side[k] : r->hinge_k;
}

static int crease_of(const rod *r, int i)
{
    return i == r->fold_node[0] ? 0 : i == r->fold_node[1] ? 1 : -1;
}

int rod_hinge_kappa1(const rod *r, int i, double kappa1, double *e, double *de, double *d2e)
{
    if (!r->terms.hinge) return 0;
    int k = crease_of(r, i);
    if (k < 0) return 0;
    double keff = 1.0 / (1.0 / hinge_k_of(r, k) + r->vor0[i] / r->EI1[i]);
    double p1 = 1.0 / (1.0 + 0.25 * kappa1 * kappa1);
    double p2 = -0.5 * kappa1 * p1 * p1;
    double d = 2.0 * atan(0.5 * kappa1) - r->hinge_phi[k];
    *e = 0.5 * keff * d * d;
    *de = keff * d * p1;
    *d2e = keff * (p1 * p1 + d * p2);
    return 1;
}

double rod_hinge_stiffness_eff(const rod *r, int i)
{
    return 1.0 / (1.0 / hinge_k_of(r, crease_of(r, i)) + r->vor0[i] / r->EI1[i]);
}

double rod_hinge_share(const rod *r, int i)
{
    return rod_hinge_stiffness_eff(r, i) / hinge_k_of(r, crease_of(r, i));
}
