/* truss.h: the reduced-order double-mass von Mises truss of the paper's section 4.
 *
 * Two point masses (x1, y1) and (x2, y2) hang between a left support at (0, 0) and a right
 * support at (l - dl, 0). Three linear springs of stiffness k_s join support-mass-mass-support
 * (natural lengths l1, l2, l1); four torsional springs of stiffness k_t sit at the two supports
 * (rest angle -alpha, so the natural state hangs below the axis) and at the two inner joints
 * (relaxed when the adjacent springs are aligned).
 *
 * Units: everything is dimensionless. Lengths are in l1, forces in k_s l1, energies in k_s l1^2,
 * masses in m and time in sqrt(m / k_s) (the paper's T). Then l = 2 + L2, k_t = Lambda alpha^2 / 3
 * and dl = mu alpha^2 l (the paper's normalisation: mu = dl / (alpha^2 l), psi = theta / alpha).
 *
 * Signs (DESIGN.md section 3): with y_C = y1 - y2 and dtheta = atan(y_C / w_C), the bending angles
 * at the inner joints are theta_L + dtheta and theta_R - dtheta. The paper prints the opposite
 * pair, which describes a joint that straightens as it bends; `printed_signs` reproduces that
 * model for comparison only.
 *
 * Layout of a configuration: q = [x1, y1, x2, y2]. The mirror map about the midpoint between the
 * supports sends (x1, y1, x2, y2) to (D - x2, y2, D - x1, y1), D = l - dl; on displacements it is
 * S v = (-v3, v4, -v1, v2). A mode with S v = v is symmetric (even), S v = -v antisymmetric (odd).
 *
 * Files: truss.c (energy, statics, stability, the paper's small-angle formulas), truss_continue.c
 * (continuation of the symmetric branch in mu, event location and classification, the L2 switch),
 * truss_dynamics.c (the loading run with gsl_odeiv2). No function here aborts or prints; each
 * returns a truss_error, and no result field is ever NaN. The caller owns gsl_set_error_handler_off. */
#ifndef RIBBON_SIM_TRUSS_H
#define RIBBON_SIM_TRUSS_H

#include <stddef.h>

typedef enum truss_error {
    TRUSS_OK = 0,
    TRUSS_ERR_PARAM,        /* a parameter is out of range, NaN or Inf (the message names it) */
    TRUSS_ERR_NAN,          /* a NaN or Inf appeared in a computed quantity */
    TRUSS_ERR_MAX_ITER,     /* an iteration hit its cap without converging */
    TRUSS_ERR_SINGULAR,     /* a linear system was singular */
    TRUSS_ERR_DIVERGED,     /* left the model's range: a spring collapsed (below 1e-3 of its
                               natural length), or no descent was found */
    TRUSS_ERR_NO_UPPER,     /* no stable upper (inverted) state at the starting load */
    TRUSS_ERR_NOT_FOUND,    /* the requested event or switch was not found in the searched range */
    TRUSS_ERR_GSL,          /* a GSL routine returned an error code */
    TRUSS_ERR_NOMEM         /* out of memory */
} truss_error;

/* A static human-readable description of an error code. */
const char *truss_error_message(truss_error err);

typedef struct truss_params {
    double lambda;       /* Lambda = 3 k_t / (alpha^2 k_s l1^2), torsional over stretching
                            stiffness, dimensionless, > 0 (paper: 0.1) */
    double alpha;        /* rad, rest angle of the support torsional springs, in (0, 0.5]
                            (paper: 0.1); the small-angle formulas hold as alpha -> 0 */
    double l2;           /* L2 = l2 / l1, natural length of the middle spring, > 0 (paper: 0.4, 0.8) */
    double imperfection; /* relative split of the support rest angles: alpha_L = alpha (1 + eps/2),
                            alpha_R = alpha (1 - eps/2), |eps| < 1; 0 is the perfect model */
    int printed_signs;   /* 0: consistent joint angles (default); 1: the paper's printed pair
                            theta_L - dtheta, theta_R + dtheta (comparison only) */
} truss_params;

/* Lambda = 0.1, alpha = 0.1, L2 = 0.8, perfect, consistent signs. */
truss_params truss_params_default(void);

/* Range checks of every field. Writes a message naming the field to msg (may be NULL). */
truss_error truss_params_check(const truss_params *p, char *msg, size_t msglen);

/* ---- model (truss.c) ---- */

/* Energy U, gradient g = dU/dq (4), Hessian H = d2U/dq2 (4 x 4, row-major) and load vector
 * g_mu = d(dU/dq)/dmu (4) at load mu and configuration q. Any output pointer may be NULL.
 * Fails with TRUSS_ERR_DIVERGED when a spring is shorter than 1e-3 of its natural length (the
 * joint angles are undefined at zero length). */
truss_error truss_energy_eval(const truss_params *p, double mu, const double q[4], double *energy,
                              double grad[4], double hess[16], double grad_mu[4]);

/* Right support abscissa D = (2 + L2)(1 - mu alpha^2), in l1. */
double truss_support_right(const truss_params *p, double mu);

/* Symmetric and antisymmetric coordinates psi_S = (theta_L + theta_R) / (2 alpha),
 * psi_A = (theta_L - theta_R) / (2 alpha) of configuration q at load mu. */
void truss_coords_psi(const truss_params *p, double mu, const double q[4], double *psi_s, double *psi_a);

/* Symmetric upper-state guess at load mu: both side springs at angle alpha * psi_s with their
 * natural length. */
void truss_config_guess(const truss_params *p, double mu, double psi_s, double q[4]);

typedef struct truss_newton_opts {
    int max_iter;        /* Newton iteration cap per solve, > 0 */
    double step_tol;     /* convergence: every |dq_i| <= step_tol alpha^2 l1 + 8 eps |q_i| */
    double res_tol;      /* and max |dU/dq| <= res_tol k_s l1 alpha^3 + 100 eps k_s l1 (eps: the
                            double epsilon; the second terms are round-off floors, which matter
                            for alpha below about 0.01); a residual at that floor alone passes */
} truss_newton_opts;

truss_newton_opts truss_newton_opts_default(void);

/* A stable static equilibrium (a local minimum of U) at load mu from the guess q (in: guess,
 * out: solution; unchanged on failure): Newton's method, with the Hessian shifted where it is
 * not positive definite and a backtracking line search on U, so it converges to a minimum
 * (quadratically near one). It stops at a saddle only from a guess on the saddle's stable
 * manifold (a symmetric guess at a symmetric saddle, say): check with truss_stability_eval.
 * iterations may be NULL. */
truss_error truss_statics_solve(const truss_params *p, double mu, double q[4],
                                const truss_newton_opts *opts, int *iterations);

typedef struct truss_stability {
    double eig[4];         /* Hessian eigenvalues, ascending, in k_s */
    double mode[4];        /* unit eigenvector of the eigenvalue nearest zero (the critical mode
                              at an event; the lowest one may already be negative there) */
    double mode_eig;       /* that eigenvalue */
    double mode_parity;    /* v . S v of that mode: +1 symmetric, -1 antisymmetric */
    double load_projection;/* |mode . g_mu| / |g_mu|: non-zero at a saddle-node, 0 at a pitchfork */
    double eig_min_sym;    /* lowest eigenvalue restricted to symmetric modes */
    double eig_min_anti;   /* lowest eigenvalue restricted to antisymmetric modes */
    int n_negative;        /* count of negative eigenvalues */
    int stable;            /* 1 when every eigenvalue is positive */
} truss_stability;

/* Eigen-analysis of the Hessian at (mu, q). The symmetric/antisymmetric split is exact only on
 * the symmetric branch of the perfect model. */
truss_error truss_stability_eval(const truss_params *p, double mu, const double q[4],
                                 truss_stability *out);

/* ---- the paper's small-angle formulas (truss.c) ---- */

/* psi_S^SN = (Lambda / 2)^(1/3). */
double truss_analytic_psi_sn(double lambda);
/* psi_S^PF = L2 (L2 + 2) / 4. */
double truss_analytic_psi_pf(double l2);
/* Load on the small-angle symmetric branch at psi (> 0): from the paper's cubic
 * a4 psi^3 + (a2 - a3 mu) psi + a1 = 0, mu = (psi^3 + 2 Lambda psi + Lambda) / ((2 + L2) psi). */
double truss_analytic_mu_at_psi(double lambda, double l2, double psi);
/* L2* solving psi_SN = psi_PF: L2^2 + 2 L2 - 4 psi_SN = 0, L2* = 2 sqrt(psi_SN + 1/4) - 1. */
double truss_analytic_l2_star(double lambda);
/* Real roots of the paper's cubic at load mu, ascending; returns how many (1 or 3). */
int truss_analytic_psi_roots(double lambda, double l2, double mu, double roots[3]);

/* ---- continuation and classification (truss_continue.c) ---- */

typedef enum truss_event_type {
    TRUSS_EVENT_NONE = 0,
    TRUSS_EVENT_SADDLE_NODE,   /* symmetric critical mode, turning point in mu */
    TRUSS_EVENT_PITCHFORK      /* antisymmetric critical mode, symmetric branch goes on */
} truss_event_type;

const char *truss_event_name(truss_event_type t); /* "saddle-node", "pitchfork", "none" */

typedef struct truss_point {
    double mu;             /* load */
    double q[4];           /* configuration */
    double psi_s, psi_a;   /* symmetric / antisymmetric angle coordinates */
    double s;              /* arclength from the start, in scaled coordinates */
    truss_stability stab;
} truss_point;

typedef struct truss_event {
    int found;             /* 0: not met before the branch ended (other fields zero) */
    truss_event_type type;
    truss_point at;        /* the located point */
    int step;              /* index of the branch point just before the event */
} truss_event;

/* Largest compression dl / l = mu alpha^2 the continuation and the dynamics accept. */
#define TRUSS_COMPRESSION_MAX 0.9

typedef struct truss_cont_opts {
    double mu_start;       /* load where the upper branch is picked up (paper: 1) */
    double mu_max;         /* the branch ends when mu exceeds this or TRUSS_COMPRESSION_MAX /
                              alpha^2 (the middle branch runs to mu -> infinity as psi_S -> 0);
                              mu_start must lie below both */
    double psi_min;        /* the branch ends when psi_S falls below this (> 0) */
    double ds;             /* initial arclength step in scaled coordinates (x/alpha^2, y/alpha, mu) */
    double ds_min, ds_max; /* step bounds */
    int max_steps;         /* cap on continuation steps */
    int max_locate_iter;   /* cap on event-location iterations */
    double locate_tol;     /* events located to this arclength (scaled), also ~ this in mu */
    truss_newton_opts newton;
} truss_cont_opts;

truss_cont_opts truss_cont_opts_default(void);

typedef struct truss_branch {
    truss_point *points;   /* the symmetric branch, from the upper state at mu_start (NULL
                              with keep_points = 0) */
    size_t n;              /* number of points */
    truss_event saddle_node;
    truss_event pitchfork;
    truss_event_type first;/* first instability met while releasing from the upper state */
    truss_error end_reason;/* why the branch ended: TRUSS_OK once both events were found,
                              TRUSS_ERR_NOT_FOUND at mu_max / psi_min / the compression limit
                              (no pitchfork met: the saddle-node came first), else a failure */
} truss_branch;

/* Follow the symmetric branch of the perfect model (imperfection must be 0) from the stable
 * upper state at mu_start by pseudo-arclength continuation in (x1, y1, mu) restricted to
 * symmetric configurations, past the saddle-node; locate the saddle-node (turning point, zero
 * symmetric eigenvalue) and the pitchfork (zero antisymmetric eigenvalue) by the Illinois
 * false-position method on the arclength; stop once both are found. Fails (returning why the
 * branch ended, and freeing it) when the saddle-node was not reached; TRUSS_ERR_NO_UPPER when
 * the symmetric upper state at mu_start is not stable. On success the branch may own memory
 * (keep_points = 1): release with truss_branch_free. */
truss_error truss_continue(const truss_params *p, const truss_cont_opts *opts, int keep_points,
                           truss_branch *out);
void truss_branch_free(truss_branch *b);

/* The L2 where the ordering switches (psi_S at the pitchfork equals psi_S at the saddle-node),
 * from the full model, by bracketing in [l2_lo, l2_hi] and Illinois false position to l2_tol.
 * Where the branch shows no pitchfork (it ended first) the saddle-node counts as first.
 * p->l2 is ignored. TRUSS_ERR_NOT_FOUND when the order is the same at both ends. */
truss_error truss_switch_find(const truss_params *p, const truss_cont_opts *opts, double l2_lo,
                              double l2_hi, double l2_tol, double *l2_switch);

/* ---- the switch as a codimension-2 point (truss_codim2.c) ---- */

typedef struct truss_codim2 {
    double l2;             /* L2 where the saddle-node and the pitchfork coincide */
    double mu;             /* the load there */
    double q[4];           /* the symmetric configuration there */
    double psi_s;          /* its symmetric angle coordinate */
    double eig_sym, eig_anti; /* lowest symmetric and antisymmetric Hessian eigenvalues (both ~0) */
    int iterations;        /* Newton iterations */
} truss_codim2;

/* The same codimension-2 location as the rod's (rod_boundary.h) on the perfect truss: unknowns the
 * symmetric configuration (x1, y1; x2 = D - x1, y2 = y1), mu and L2; equations the gradient's two
 * symmetric components and the lowest eigenvalue of the symmetric and of the antisymmetric block
 * of the Hessian (truss_stability_eval). Newton with a central-difference Jacobian, from the
 * saddle-node of the symmetric branch at p->l2 (truss_continue), capped at 50 iterations. */
truss_error truss_codim2_find(const truss_params *p, const truss_cont_opts *opts, truss_codim2 *out);

/* ---- dynamics (truss_dynamics.c) ---- */

typedef struct truss_dyn_opts {
    double mu_start;       /* load at T = 0, the run starts at rest in the upper state (paper: 1);
                              mu_start alpha^2 < TRUSS_COMPRESSION_MAX */
    double mu_rate;        /* d(1 - mu)/dT, > 0 (paper: 0.001) */
    double mu_end;         /* the run stops when mu reaches this */
    double damping;        /* viscous damping c in sqrt(k_s m) (force -c v on each mass), >= 0 */
    double sample_dt;      /* output interval in T, > 0 */
    double rtol, atol;     /* gsl_odeiv2 error control (atol on q in l1 and v in l1/T) */
    size_t max_steps;      /* cap on the total number of integrator steps */
} truss_dyn_opts;

truss_dyn_opts truss_dyn_opts_default(void);

typedef struct truss_dyn_sample {
    double t;              /* T */
    double mu;             /* load at t */
    double psi_s, psi_a;   /* angle coordinates */
} truss_dyn_sample;

typedef struct truss_dyn_result {
    truss_dyn_sample *samples; /* every sample_dt, may be NULL (keep_samples = 0) */
    size_t n;
    int snapped;           /* 1 when psi_S changed sign (upper -> natural state) */
    double mu_snap;        /* load at the first psi_S < 0 (0 when not snapped) */
    double t_snap;         /* T at that moment */
    double psi_a_max_before;/* max |psi_A| from the start to the snap (to the end if none): the
                              asymmetry grown on the way into the snap */
    double psi_a_max;      /* max |psi_A| over the whole run */
} truss_dyn_result;

/* Release the load from mu_start at rate mu_rate (1 - mu = mu_rate T shifted to mu_start),
 * starting at rest in the static upper state of p (imperfection included), integrating
 * m q'' = -dU/dq - c q' with gsl_odeiv2 (RK8PD, adaptive). */
truss_error truss_dynamics_run(const truss_params *p, const truss_dyn_opts *opts, int keep_samples,
                               truss_dyn_result *out);
void truss_dyn_result_free(truss_dyn_result *r);

#endif
