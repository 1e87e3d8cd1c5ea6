/* rod_quasi.h: the quasi-static start of the fast prediction: follow the stable static branch in
 * Delta W with large steps while the shear is slow compared with the ribbon's own dynamics, stop
 * on the first sign of an approaching instability, and hand the dynamics a state a safety margin
 * before it, with the quasi-static velocity.
 *
 * Why: at the paper's rate (0.01 m/s) the ribbon sits on its static branch, to the Newton
 * tolerance, until close to the first instability; integrating that part in time costs hundreds
 * of steps that a few dozen static solves replace. What the static branch cannot give is the
 * snap itself, which lags the instability (the critical mode grows from the imperfection at a
 * finite shear rate: 6% in Delta W for the paper's pitchfork scene, README "Continuation"), so
 * the dynamics must start early enough to build that delay: the margin is QS_BACK_TIME seconds
 * of shear (about one period of the soft modes) before the first warning below.
 *
 * Steps of QS_STEP in Delta W (or shear_max / 20 when smaller), each a minimising static Newton
 * solve started from the secant through the last two states. After each, the lowest eigenvalue
 * of M^-1/2 H M^-1/2 (the squared frequency of the softest mode, by shift-invert iteration from
 * rod_stability.h) is extrapolated linearly to zero, which estimates the critical Delta W_c
 * (exactly at a pitchfork, where it is linear in Delta W; twice too far at a saddle-node, where
 * it goes like a square root). The dynamics starts once Delta W_c - Delta W < 2 m + QS_STEP,
 * m = QS_BACK_TIME times the rate. Hard warnings stop the stepping too, and then the dynamics
 * starts m before the last good state: a solve fails, Delta Z jumps (Newton left the branch), or
 * the static Hessian has a non-positive LDL^T pivot (no longer a strict minimum).
 * The last few states are kept in a ring, so going back costs no solve. */
#ifndef RIBBON_SIM_ROD_QUASI_H
#define RIBBON_SIM_ROD_QUASI_H

#include "rod_dynamics.h"

#define QS_STEP 5e-3        /* Delta W per static step */
#define QS_BACK_TIME 2.0    /* s of shear between the dynamics' start and the first warning */

typedef struct rod_quasi_report {
    double dw_switch;   /* Delta W where the dynamics starts */
    double dw_warning;  /* Delta W of the first warning */
    int solves;         /* static solves run */
    int steps;          /* static states accepted (before going back) */
    int back;           /* states a hard warning goes back by (the margin in steps) */
} rod_quasi_report;

/* Starts from the static equilibrium in d (after the route, at Delta W = 0, Delta L = dl) and a
 * shear rate of rate_dw (Delta W per second, > 0). Stops before dw_max. On return the rod sits
 * in the static equilibrium at rep->dw_switch with d's velocities set to the quasi-static ones,
 * ready for rod_dyn_try (rod_dyn_start has been called). Returns ROD_OK, or ROD_ERR_ALLOC. */
rod_status rod_quasi_follow(rod_dyn *d, const rod_scene *sc, double dl, double rate_dw, double dw_max,
                            rod_quasi_report *rep);

/* The Delta W step of the static states: QS_STEP, or shear_max / 20 when smaller. */
double rod_quasi_step(const rod_scene *sc);

/* The same from the static equilibrium in d at Delta W = dw0 (a warm start: the grid of steps
 * runs from dw0, so from a grid point k QS_STEP it is the cold start's grid). The switch can only
 * be as far back as dw0, and the eigenvalue's extrapolation needs two states after it: a caller
 * that wants the cold start's answer starts more than back + 2 steps before the switch
 * (rod_protocol.c checks rep->steps). */
rod_status rod_quasi_follow_from(rod_dyn *d, const rod_scene *sc, double dl, double dw0, double rate_dw,
                                 double dw_max, rod_quasi_report *rep);

#endif
