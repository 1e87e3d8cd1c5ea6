/* rod_solver.h: Newton's method on the free DOFs of a rod, shared by statics and the implicit
 * Euler step of the dynamics.
 *
 * Solves  R(q) = c1 M (q - q_n) - c2 M v_n + grad E(q) = 0  over the free DOFs, the clamps
 * being already placed by the caller. Statics is c1 = c2 = 0. Implicit Euler with
 * mass-proportional damping C = mu M is c1 = 1/dt^2 + mu/dt, c2 = 1/dt. The Jacobian
 * c1 M + Hess E is banded (half-bandwidth ROD_BAND) and factorised banded: LDL^T (GSL, no
 * pivoting) when it is known positive definite, LU with partial pivoting otherwise. Frames are
 * transported from the state at the start of the solve to every trial state, so within one solve
 * the energy is a genuine function of q and the line search on |R| is consistent.
 * The workspace is allocated once per rod; nothing allocates inside the iteration. */
#ifndef RIBBON_SIM_ROD_SOLVER_H
#define RIBBON_SIM_ROD_SOLVER_H

#include "rod.h"

typedef struct rod_solver rod_solver;

typedef struct rod_newton_opts {
    double c1, c2;         /* inertia coefficients, 0 for statics (see above) */
    const double *q_n;     /* previous DOFs (ndof), used when c1 != 0 */
    const double *v_n;     /* previous velocities (ndof), used when c2 != 0 */
    double tolerance;      /* converged when max |R| <= tolerance * force scale */
    int max_iterations;    /* iteration cap */
    int damped;            /* 1: c1 includes a damping term mu / dt (counted as damping_evals;
                              the damping itself costs nothing beyond the inertia term) */
    int positive_definite; /* 1: minimise the incremental potential (stable states): LDL^T,
                              shifted when indefinite, line search on the potential;
                              0: root finding on R with LU and pivoting (any equilibrium) */
} rod_newton_opts;

typedef struct rod_newton_report {
    int iterations;
    double residual;       /* N, final max |R| over the free DOFs */
    double residual_rel;   /* residual / force scale */
} rod_newton_report;

rod_solver *rod_solver_alloc(const rod *r);
void rod_solver_free(rod_solver *s);

rod_newton_opts rod_newton_opts_static(const rod_scene *scene);

/* Runs Newton from the current state. On failure the rod is left where Newton stopped; callers
 * that retry save the state first (rod_state_save). */
rod_status rod_newton_solve(rod *r, rod_solver *s, const rod_newton_opts *o, rod_newton_report *rep);

/* Full-DOF gradient of the last converged state (valid after a successful solve): the clamp
 * reactions are its entries at the prescribed DOFs. */
const double *rod_solver_gradient(const rod_solver *s);

/* Snapshot and restore of a rod's state (q and frames) using the solver's storage slot k
 * (0 <= k < ROD_SOLVER_SLOTS), for quasi-static stepping with retries. */
#define ROD_SOLVER_SLOTS 2
void rod_state_save(const rod *r, rod_solver *s, int k);
void rod_state_restore(rod *r, const rod_solver *s, int k);

#endif
