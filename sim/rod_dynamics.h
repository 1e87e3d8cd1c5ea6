/* rod_dynamics.h: one implicit Euler step of a rod whose clamps move, with the energy books kept.
 *
 * Shared by the simulated protocol (rod_protocol.c: the clamp follows the scene's shear rate) and
 * the digital twin (rod_twin.c: the clamps follow the rails). A step places the clamps at the new
 * (Delta L, Delta W), predicts the free DOFs by extrapolating the last two velocities
 * (q_n + h v_n + h^2 (v_n - v_{n-1}) / h_{n-1}: implicit Euler's own update with the last
 * acceleration; with one velocity known, q_n + h v_n) and solves
 *     M (q - q_n - h v_n) / h^2 + mu M (q - q_n) / h + grad E(q) = 0
 * with Newton (rod_solver.h). A solved step is pending until the caller accepts it (velocities,
 * clamp work by the trapezoidal rule on the reaction, damping losses mu v^T M v h) or rejects it
 * (the state before the step comes back), so adaptive callers can look at the result first.
 * Everything is allocated once in rod_dyn_open; a step allocates nothing. */
#ifndef RIBBON_SIM_ROD_DYNAMICS_H
#define RIBBON_SIM_ROD_DYNAMICS_H

#include "rod.h"
#include "rod_solver.h"

typedef struct rod_dyn {
    rod *r;              /* the rod (owned) */
    rod_solver *s;       /* its Newton workspace (owned) */
    double *q_n;         /* DOFs at the start of the pending step */
    double *v;           /* DOF velocities after the last accepted step */
    double *v_prev;      /* DOF velocities after the step before it */
    double h_prev;       /* length of the last accepted step, s (0 when none since the start) */
    double *g_old;       /* full gradient (clamp reactions) of the last accepted state */
    double dl, dw;       /* clamp placement of the last accepted state */
    double h;            /* length of the pending step, s (0 when none) */
    double dl_new, dw_new;
    double kinetic;      /* J, kinetic energy of the free DOFs after the last accepted step */
    double work;         /* J, work done by the moving clamps so far */
    double damped;       /* J, energy removed by the damping so far */
    double mu;           /* 1/s, mass-proportional damping */
    rod_newton_opts no;  /* Newton settings of the steps */
} rod_dyn;

/* Allocates the rod of scene sc (clamps at Delta L = sc->compression, Delta W = 0, flat). */
rod_status rod_dyn_open(rod_dyn *d, const rod_scene *sc, char *why, size_t why_len);
void rod_dyn_close(rod_dyn *d);

/* Call once the rod sits in a static equilibrium (after a route) so the first step's clamp work
 * uses the right reactions: copies the solver's last gradient, zeroes the velocities and sets the
 * clamp placement the equilibrium was solved at. */
void rod_dyn_start(rod_dyn *d, double dl, double dw);

/* Solves one step of length h > 0 to the clamp placement (dl, dw). On failure the state before
 * the step is restored and the status says why (nr gets the last Newton report). On success the
 * step is pending: call rod_dyn_accept or rod_dyn_reject before the next step. */
rod_status rod_dyn_try(rod_dyn *d, double h, double dl, double dw, rod_newton_report *nr);
void rod_dyn_accept(rod_dyn *d);
void rod_dyn_reject(rod_dyn *d);

#endif
