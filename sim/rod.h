/* rod.h: the discrete elastic rod (DER) model of a folded ribbon, after the reference paper
 * section 3 and Bergou et al. 2008/2010.
 *
 * Degrees of freedom, in this order so the Hessian is banded (half-bandwidth 10):
 *
 *     q = [ x0 (3), th0, x1 (3), th1, ..., x_{N-2} (3), th_{N-2}, x_{N-1} (3) ]   (4N - 1 values)
 *
 * Node i's position starts at q[4 i]; edge i's twist angle th_i is q[4 i + 3].
 * Clamps (reference paper, "Boundary condition"): nodes 0, 1, N-2, N-1 and the angles th0 and
 * th_{N-2} are prescribed. Node 1 and node N-2 are the clamp points; the free length l lies
 * between them, and the clamped edges (0 and N-2) lie outside it. The free DOFs are therefore
 * the contiguous range [ROD_FREE_BEGIN, 4 (N - 2)): th1, x2, th2, ..., x_{N-3}, th_{N-3}.
 *
 * Frames: each edge carries a reference frame (d1, d2, t) updated by parallel transport in time
 * (rod_frames_update transports from the tangents of the last update) and the reference twist
 * m_ref at each interior node, tracked continuously. Material frame: m1 = cos th d1 + sin th d2
 * (surface normal), m2 = t x m1 (width direction).
 *
 * Curvatures are integrated (dimensionless) quantities at interior nodes:
 *     kappa1 = (m1e . tf - m1f . te) / (1 + te . tf)    bending toward the normal (soft, E I1)
 *     kappa2 = (m2e . tf - m2f . te) / (1 + te . tf)    bending in the ribbon plane (stiff, E I2)
 *     kappa3 = th_f - th_e + m_ref                        twist (G J)
 * and each term's energy is 1/2 K (kappa - kappa_hat)^2 / dl_hat, dl_hat the rest Voronoi length.
 * (These are the paper's projections of the curvature binormal onto the averaged frame, rewritten
 * without kb.) A crease of turning angle phi toward the normal acts on the soft, out-of-plane
 * component (DESIGN.md section 3, not the paper's kappa2), in one of two ways:
 *   rigid (folds.hinge_stiffness = rigid): kappa1_hat = 2 tan(phi/2) at the crease node with E I1
 *     raised by folds.stiffness_factor, a penalty whose stiffness factor E I1 / dl_hat grows with N;
 *   compliant hinge of stiffness k (N m/rad): the crease node's kappa1 term is replaced by
 *     1/2 k_eff (psi - phi)^2, psi = 2 atan(kappa1 / 2) the node's turning angle and
 *     1 / k_eff = 1 / k + dl_hat / (E I1), the hinge in series with the strip's own bending over
 *     the node's Voronoi length (sim/rod_hinge.c derives it): a crease energy that depends on its
 *     turning angle alone as the mesh refines.
 */
#ifndef RIBBON_SIM_ROD_H
#define RIBBON_SIM_ROD_H

#include <stddef.h>
#include <stdint.h>

#include "scene.h"

#define ROD_BAND 10            /* half-bandwidth of the Hessian in the DOF ordering above */
#define ROD_FREE_BEGIN 7       /* first free DOF: th1 */

/* Errors of the simulator layer. */
typedef enum rod_status {
    ROD_OK = 0,
    ROD_ERR_ALLOC,       /* out of memory */
    ROD_ERR_SCENE,       /* the scene cannot be simulated (message says why) */
    ROD_ERR_NAN,         /* a non-finite value appeared in the state or the residual */
    ROD_ERR_SINGULAR,    /* the linear system could not be factorised */
    ROD_ERR_MAXITER,     /* Newton reached its iteration cap without converging */
    ROD_ERR_LINESEARCH,  /* the line search could not reduce the residual */
    ROD_ERR_BRANCH_LOST, /* the requested branch ceased to exist (e.g. past its fold) */
    ROD_ERR_TIME_LIMIT,  /* the protocol reached its step cap */
    ROD_ERR_ROUTE_CAP    /* a route stage reached its cap on static solves (rod_route.c) */
} rod_status;

const char *rod_status_message(rod_status s);

/* Which energy terms a rod evaluates (a scene pays only for what it uses). fold: rigid creases
 * (the bending term's natural curvature and raised stiffness at the crease nodes); hinge:
 * compliant creases (their own term at the crease nodes, rod_hinge.c). */
typedef struct rod_terms {
    int stretch, bend, twist, fold, gravity, hinge;
} rod_terms;

/* Counters of what was actually evaluated, for "the run reports which terms and stages ran". */
typedef struct rod_counters {
    uint64_t stretch_evals, bend_evals, twist_evals, fold_evals, gravity_evals;
    uint64_t hessian_assemblies, factorisations, newton_iterations, damping_evals;
    uint64_t hinge_evals;
} rod_counters;

typedef struct rod {
    int n;               /* nodes N */
    int ndof;            /* 4 N - 1 */
    int free_end;        /* one past the last free DOF: 4 (N - 2) */
    double length;       /* m, free length l */
    double h_clamp;      /* m, length of each clamped edge */
    double *q;           /* DOFs (ndof) */
    double *len0;        /* m, rest edge lengths (N - 1) */
    double *vor0;        /* m, rest Voronoi length at interior nodes (N), 0 at the ends */
    double *mass;        /* kg or kg m^2, lumped mass per DOF (ndof) */
    double *s_node;      /* arc length of each node from the left clamp point over l (N) */
    double EA;           /* N, axial stiffness */
    double *EI1;         /* N m^2, soft bending stiffness per node (raised at fold nodes) */
    double EI2;          /* N m^2, stiff (in-plane) bending stiffness */
    double GJ;           /* N m^2, twist stiffness */
    double *kap1_hat;    /* natural integrated curvature toward the normal, per node */
    double gravity[3];   /* m/s^2 */
    int fold_node[2];    /* node indices of the left and right creases (-1 if none) */
    double fold_kappa[2];/* rigid: their full natural curvatures 2 tan(phi_k / 2) */
    double fold_phi[2];  /* rad, their full angles (imperfection included) */
    double fold_factor;  /* rigid: stiffness factor at the creases */
    double hinge_k;      /* N m/rad, compliant hinges' stiffness (terms.hinge) */
    double hinge_k_side[2]; /* N m/rad, the left and right crease's own k when > 0; 0: hinge_k */
    double hinge_phi[2]; /* rad, the hinges' current rest angles (the route ramps them) */
    double fold_position;/* left crease position (Gamma) the mesh was built for (rod_mesh_set) */
    double fold_position_right; /* right crease position, from the left clamp point, over l */
    int fold_outer_edges;/* edges between the left clamp point and its crease, 0 without creases */
    int fold_outer_right;/* edges between the right crease and its clamp point */
    double rho_area;     /* kg/m, rho A: lumped node masses per unit rest length */
    double rho_polar;    /* kg m, rho (I1 + I2): twist inertia per unit rest length */
    int mid_node;        /* node at arc length 1/2, or -1 when the midpoint is mid-edge */
    int mid_edge;        /* edge containing arc length 1/2 when mid_node < 0 */
    double mid_w;        /* weight of node mid_edge + 1 at arc length 1/2 (0.5 on a symmetric mesh) */
    /* frames */
    double (*d1)[3];     /* reference director 1 per edge (N - 1) */
    double (*d2)[3];     /* reference director 2 per edge */
    double (*tref)[3];   /* tangent at which d1, d2 were last transported */
    double *mref;        /* reference twist per node (N), continuous in time */
    rod_terms terms;
    rod_counters count;
    double force_scale;  /* N, EI1 / l^2: scale for residual tolerances */
} rod;

/* Builds the rod for a scene: mesh with a node on each crease (rod_mesh_set_creases), straight along x with the
 * surface normal along +z, clamps at Delta L = 0, Delta W = 0, creases present at full angle
 * in the natural curvature (the route ramps them with rod_set_folds). */
rod_status rod_alloc(const rod_scene *s, rod **out, char *why, size_t why_len);
void rod_free(rod *r);

/* Edges between a clamp point and its crease in the mesh rod_alloc builds for N nodes and crease
 * position gamma: round(gamma (N - 3)), at least 1, leaving at least one middle edge. */
int rod_mesh_outer_edges(int nodes, double gamma);

/* Re-meshes for crease position gamma with n_out edges outside each crease (0: no creases,
 * uniform): arc-length positions, rest and Voronoi lengths, masses, clamped-edge length and the
 * crease nodes. q and the frames are not touched; call rod_set_clamps after it (the clamped
 * edges take the length of their neighbour). With n_out held, every rest quantity is a smooth
 * function of gamma: what continuation in Gamma differentiates (rod_critical.h). The mesh is
 * exactly symmetric under s -> 1 - s. */
void rod_mesh_set(rod *r, double gamma, int n_out);

/* Edge counts of the general mesh for creases at p_left < p_right (from the left clamp point,
 * over l): *n_left = round(p_left (N - 3)), *n_right = round((1 - p_right) (N - 3)), each at
 * least 1, the larger one cut until at least one edge is left between the creases. */
void rod_mesh_crease_edges(int nodes, double p_left, double p_right, int *n_left, int *n_right);

/* Re-meshes with a node on each crease wherever they are: [0, p_left], [p_left, p_right] and
 * [p_right, 1] meshed with equal edges inside each piece (n_left, the rest, n_right edges). A
 * mirrored pair (p_left + p_right = 1 within 1e-12, n_left = n_right) is rod_mesh_set's symmetric mesh
 * exactly; otherwise the mesh has no symmetry and Delta Z is interpolated at arc length 1/2. */
void rod_mesh_set_creases(rod *r, double p_left, double p_right, int n_left, int n_right);

/* Sets both crease angles to phi (rad) split by the relative imperfection rel as rod_alloc does,
 * at full angle and stiffness. No effect on a rod without creases. */
void rod_set_fold_angle(rod *r, double phi, double rel);

/* Sets the full angles of the left and right creases (rad, imperfection included), at full
 * angle and stiffness. No effect on a rod without creases. */
void rod_set_crease_angles(rod *r, double phi_left, double phi_right);

/* Sets the natural curvature of the two creases to frac_angle times their scene angle and their
 * stiffness factor to 1 + frac_stiff (factor - 1). Compliant hinges: their rest angles to
 * frac_angle times the scene's; their stiffness is a property of the strip and stays k. */
void rod_set_folds(rod *r, double frac_angle, double frac_stiff);

/* Places the clamps: left clamp point at (0, -dw l / 2, 0), right clamp point at
 * (l (1 - dl), +dw l / 2, 0) (symmetric shear, see rod.c); clamped edges along +x, angles 0. */
void rod_set_clamps(rod *r, double dl, double dw);

/* Transports the reference frames from their stored tangents to the current ones and updates
 * the reference twist. Call after every change of q and before evaluating energy terms. */
void rod_frames_update(rod *r);

/* Material directors of edge i. */
void rod_material_frame(const rod *r, int i, double m1[3], double m2[3]);

/* Total elastic + gravitational potential energy (J). */
double rod_energy(rod *r);
/* Gradient of the potential energy over all DOFs (ndof values, overwritten). */
void rod_gradient(rod *r, double *g);
/* Adds s * Hessian into the symmetric band matrix H over the free DOFs, stored lower-packed:
 * H[(i) * (ROD_BAND + 1) + (j - i)] for free indices i <= j < i + ROD_BAND + 1 (that is GSL's
 * symmetric band layout, row i holding A(i, i + k)). Only the free block is assembled. */
void rod_hessian_add(rod *r, double s, double *H);

/* Both in one pass over the elements (they share the geometry): overwrites g (ndof values)
 * unless NULL and adds s * Hessian into H as rod_hessian_add unless H is NULL. */
void rod_gradient_hessian(rod *r, double *g, double s, double *H);

/* Share of a compliant crease node's turn beyond its rest angle, psi - phi, that the hinge itself
 * takes (the rest is the strip's own bending over the node's Voronoi length): k_eff / k
 * (rod_hinge.c). The hinge's own turn is phi + (psi - phi) rod_hinge_share(r, i). */
double rod_hinge_share(const rod *r, int i);

/* Integrated curvature kappa1 at each interior node (N values, 0 at the ends). */
void rod_kappa1(const rod *r, double *k1);

static inline double *rod_x(const rod *r, int i) { return r->q + 4 * i; }
static inline double rod_theta(const rod *r, int i) { return r->q[4 * i + 3]; }
static inline int rod_nfree(const rod *r) { return r->free_end - ROD_FREE_BEGIN; }

#endif
