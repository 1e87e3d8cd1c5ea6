/* rod_critical.h: critical points of the symmetric branch as solutions of an augmented system,
 * for continuing them in two parameters (rod_boundary.h): the saddle-node (fold in Delta W, even
 * critical mode), the symmetry-breaking pitchfork (odd critical mode), and the codimension-2
 * point where both are critical at once.
 *
 * Parameters. p = (Delta W, Gamma, phi, Delta L) (rod_par), applied to a built rod by
 * rod_params_apply: Gamma moves the mesh with its number of outer edges held (rod_mesh_set), so
 * every rest quantity is smooth in it; phi (rad, signed as the scene's crease angle) sets both
 * creases (perfect scene); Delta L and Delta W place the clamps.
 *
 * Test functions (minimally augmented, after Govaerts; the bordering of MatCont and
 * BifurcationKit). On a C2-symmetric state the free Hessian K commutes with the mirror S
 * (rod_symmetry.h), so it splits into an even and an odd block. For each block, with v a unit
 * vector of that parity (the previous critical mode), the bordered system
 *     [ K    v ] [ w ]   [ 0 ]
 *     [ v^T  0 ] [ g ] = [ 1 ]      restricted to the block,
 * gives g = -1 / (v^T K^-1 v) and w = K^-1 v / (v^T K^-1 v): g is smooth through zero, vanishes
 * exactly when the block is singular, and equals minus the block's critical eigenvalue when v is
 * its eigenvector. g_even = 0 is the fold, g_odd = 0 the pitchfork, both the codim-2 point.
 * Restricting to the blocks (projecting K^-1 v onto the parity of v) is what keeps the system
 * regular at the codim-2 point, where K has a two-dimensional kernel: a single border would be
 * singular there. The solves use K's band LU (GSL, partial pivoting), as the tracer's do.
 *
 * Gamma. The state is carried along the rod as Gamma changes (rod_crit_move_gamma): the Gamma
 * column of the Jacobian is differenced along that map and Newton's Gamma steps follow it.
 *
 * Derivatives. dg = -w^T dK w (differentiate the bordered system; w^T K dw = -g v^T dw = 0).
 * Along q: grad_q g = -D3E[w, w, .], one directional difference of the analytic Hessian,
 * (K(q + e w) - K(q - e w)) w / (2 e); along a parameter, central differences of w^T K w and of
 * the residual R. Tests check both against differences of g itself.
 *
 * Newton on the augmented system. Unknowns: the even part of q and m free parameters; equations:
 * R = 0 and m test functions (fold: g_even; pitchfork: g_odd; codim-2: both, m = 2). Each
 * iteration solves the bordered Jacobian [[K, R_p], [grad_q g^T, g_p]] by block elimination with
 * K's factors, every solution projected onto the even subspace (the odd part of a solve of an
 * even right-hand side is round-off amplified by the odd block's near singularity). The
 * bordering vectors are updated to the normalised w after each iteration. Converged when the
 * residual is within the tolerance and the parameter step below step_tol (or stalled at the
 * round-off floor of g, about 1e-16 max |K_ii|); capped. */
#ifndef RIBBON_SIM_ROD_CRITICAL_H
#define RIBBON_SIM_ROD_CRITICAL_H

#include <stddef.h>

#include "rod.h"

typedef enum rod_par {
    ROD_PAR_DW = 0,    /* Delta W */
    ROD_PAR_GAMMA = 1, /* Gamma (mesh with fixed outer edge count) */
    ROD_PAR_PHI = 2,   /* crease angle, rad, signed */
    ROD_PAR_DL = 3,    /* Delta L */
    ROD_NPAR = 4
} rod_par;

/* Applies p (ROD_NPAR values) to r: mesh, crease angle (no imperfection), clamps; frames updated. */
void rod_params_apply(rod *r, const double *p);

typedef struct rod_crit rod_crit;

/* Moves the rod to Gamma p[ROD_PAR_GAMMA] on a mesh of n_out outer edges, carrying the state
 * along: node positions and twist angles interpolated linearly in arc length from the current
 * mesh; then applies p. A change of Gamma at fixed q would strain every edge by dGamma / Gamma
 * (huge against the bending forces); along this map the state stays near equilibrium. */
void rod_crit_move_gamma(rod_crit *c, const double *p, int n_out);

typedef enum rod_crit_kind {
    ROD_CRIT_FOLD = 1,      /* g_even = 0 */
    ROD_CRIT_PITCHFORK = 2, /* g_odd = 0 */
    ROD_CRIT_CODIM2 = 3     /* both */
} rod_crit_kind;

typedef struct rod_crit_opts {
    double tolerance;    /* residual within tolerance EI1 / l^2 */
    double step_tol;     /* and the last parameter step below this (Gamma and Delta W units) */
    int max_iterations;  /* Newton cap */
    double eps_q;        /* directional difference step along a mode, times l */
    double eps_p;        /* central difference step of the parameters */
    double max_dp[ROD_NPAR]; /* largest parameter change per Newton iteration (else scaled down) */
} rod_crit_opts;

/* tolerance 1e-6 (or below 1e2 of it with a step under 1e-6 l: the stiff floor), step_tol 1e-9 (or a step below 1e4 step_tol that stopped halving: round-off), 40 iterations, eps_q 1e-7, eps_p 1e-8 (at fixed q the test functions are steep in the parameters: a clamp
 * move strains the stiff edges; 1e-6 is 1.5% off, measured), max_dp (0.05, 0.02,
 * 0.05, 0.05). */
rod_crit_opts rod_crit_opts_default(void);

/* Workspace for rod r (not owned). NULL when out of memory. */
rod_crit *rod_crit_alloc(rod *r, const rod_crit_opts *o);
void rod_crit_free(rod_crit *c);

typedef struct rod_crit_report {
    int iterations;
    double residual_rel;  /* max |R| / (EI1 / l^2) */
    double g_even, g_odd; /* test functions at the solution (minus the blocks' critical eigenvalues) */
    double eig_even, eig_odd;       /* Rayleigh quotients of the normalised w's */
    double eig_res_even, eig_res_odd; /* |K w - eig w| of the unit w's */
    double parity_even, parity_odd; /* rod_mode_parity of the two modes */
    double scale;         /* max |K_ii|: the round-off floor of the eigenvalues is ~1e-16 of it */
    int n_negative;       /* eigenvalues below -1e-13 scale (the critical ones, ~0, not counted);
                             -1 when the inertia could not be evaluated */
} rod_crit_report;

/* Critical modes at the rod's state under p: the eigenvector of the even and of the odd block
 * nearest zero, by inverse iteration projected onto each block (the bordering vectors' start);
 * fills the eig and parity fields of rep (may be NULL). */
rod_status rod_crit_modes(rod_crit *c, const double *p, rod_crit_report *rep, char *why, size_t why_len);

/* Sets a bordering vector (sign > 0 even, < 0 odd) from v (projected and normalised), e.g. an
 * event's critical mode from the tracer. */
void rod_crit_set_mode(rod_crit *c, int sign, const double *v);

/* Sets the bordering vector of the block of sign to the mode of that block nearest sigma (NAN:
 * the Rayleigh quotient of v0) by shift-invert inverse iteration in the block from v0 (60
 * steps), its Rayleigh quotient into *eig (may be NULL): picks a given mode when another of the
 * block lies nearer zero. */
rod_status rod_crit_refine_mode(rod_crit *c, const double *p, int sign, const double *v0, double sigma, double *eig);

/* Sets both bordering vectors to the normalised w's at the rod's state under p (one step of
 * inverse iteration in each block): at a codim-2 point, where both blocks' critical modes are the
 * ones nearest zero, this keeps the borders aligned with them as the point moves. */
rod_status rod_crit_update_borders(rod_crit *c, const double *p);

/* Sets the Newton cap of the solves (rod_crit_opts.max_iterations); returns the previous one. */
int rod_crit_set_cap(rod_crit *c, int cap);

/* Sets the number of iterations after which a solve whose residual is still above the phase-1
 * threshold (far from equilibrium) fails at once (default: the Newton cap): a continuation
 * that halves its step on failure gives up on a bad predictor early. Returns the previous one. */
int rod_crit_set_phase1_cap(rod_crit *c, int cap);

/* Evaluates R and both test functions at the rod's state under p, without moving anything. */
rod_status rod_crit_eval(rod_crit *c, const double *p, rod_crit_report *rep, char *why, size_t why_len);

/* Newton on the augmented system of kind from the rod's state and p (in/out): free lists the
 * free parameters (1 for fold and pitchfork, 2 for codim-2). The rod holds the solution on
 * success, and on failure the last iterate (callers keep a snapshot). */
rod_status rod_crit_solve(rod_crit *c, rod_crit_kind kind, const rod_par *free, double *p, rod_crit_report *rep,
                          char *why, size_t why_len);

/* For tests: grad_q g (even sign > 0 or odd) at the rod's state under p by the directional
 * difference, into out (rod_nfree values), and dg/dp_k by central differences into *gp (may be
 * NULL), both at the current bordering vectors. */
rod_status rod_crit_gradient(rod_crit *c, const double *p, int sign, rod_par k, double *out, double *gp);

/* For tests: the test function of the block of sign at the state under p, bordering vectors
 * held (not updated). */
rod_status rod_crit_testfn(rod_crit *c, const double *p, int sign, double *g);

#endif
