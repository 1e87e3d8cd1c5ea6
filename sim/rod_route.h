/* rod_route.h: quasi-static paths of a rod: reaching the upper (or lower) state at Delta L by the
 * documented route, and following a static branch in Delta W.
 *
 * Route (DESIGN.md section 3: a creased ribbon cannot be clamped flat at Delta L = 0):
 *   1. Start from the crease-free ribbon as a cosine arch of the right arc length at a small
 *      compression min(Delta L, 0.05), bulging up (upper state) or down (lower state): this is
 *      the bias that selects the branch.
 *   2. compress-then-fold (default): compress to Delta L with the creases off, then ramp the
 *      crease angle and the crease stiffness factor together from 0 to their scene values at
 *      fixed Delta L. together: ramp compression and creases at the same time.
 * Every stage is a sequence of static Newton solves started from the secant through the last
 * two states, whose increments halve on failure (down to 2^-10 of the nominal step) and grow
 * while Newton converges quickly; intermediate states are solved to a looser residual than the
 * last one (rod_route.c). A trial that ends in a non-finite value is a failed step (retried from
 * the affine predictor), never the end of the route. A stage that cannot go on stops with a named
 * reason: the branch lost (the last converged state is unstable), else the last failed solve's
 * status, or the cap on solves; the last converged state is left in the rod. Tests check that
 * both routes end in the same equilibrium. */
#ifndef RIBBON_SIM_ROD_ROUTE_H
#define RIBBON_SIM_ROD_ROUTE_H

#include "rod.h"
#include "rod_solver.h"

typedef struct rod_route_report {
    int solves;            /* static Newton solves run */
    int newton_iterations; /* total Newton iterations */
    double residual_rel;   /* final residual over the force scale */
    double reached;        /* fraction of the last stage reached before a failure (1 on success) */
    rod_status last_failure; /* status of the last failed solve (ROD_OK if none failed) */
    int inject_nan_solve;  /* input, fault injection for tests: when > 0, the trial state of that
                            * solve (1-based, as counted in solves) gets a NaN in a free DOF, as a
                            * predictor gone wrong would give; 0 (the {0} initialiser) in production */
} rod_route_report;

/* branch: +1 upper (Delta Z > 0), -1 lower. Leaves the rod in equilibrium at Delta L, Delta W = 0
 * with the creases at full angle. On a failure (other than ROD_ERR_ALLOC) residual_rel is finite:
 * the last failed solve's residual, or the residual of the state left in the rod. */
rod_status rod_route_to_state(rod *r, rod_solver *s, const rod_scene *sc, int branch,
                              rod_route_report *rep);

/* Follows the static branch from the current equilibrium (at dw_from) to dw_to at fixed Delta L,
 * with step dw_step halved on failure. On ROD_ERR_BRANCH_LOST, *dw_reached is the last Delta W
 * where the branch was followed. */
rod_status rod_follow_shear(rod *r, rod_solver *s, const rod_scene *sc, double dl, double dw_from,
                            double dw_to, double dw_step, double *dw_reached, rod_route_report *rep);

/* Places the free nodes on a cosine arch of arc length l spanning the gap l (1 - dl), bulging
 * toward sign(branch) z. Twist angles are zeroed. */
void rod_place_arch(rod *r, double dl, int branch);

#endif
