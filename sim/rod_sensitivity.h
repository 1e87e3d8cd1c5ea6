/* rod_sensitivity.h: how a static equilibrium and what is observed on it move when a strip
 * parameter changes (issue 32 A), from the Hessian at the equilibrium rather than from
 * re-solved paths.
 *
 * At an equilibrium R(q, u) = 0 of the free DOFs, with the clamps at (Delta L, Delta W):
 *     dq/du_j = -H^{-1} dR/du_j,
 * H the free Hessian, factorised once (banded LDL^T, rod_band.h: the equilibria a fit follows
 * are stable, so H is positive definite and the factorisation is also the stability check), one
 * banded solve per parameter. dR/du_j is the derivative of the residual at fixed free DOFs: a
 * central difference of the gradient (O(N), no solve) with the parameter applied by
 * rod_fit_apply and the clamps placed again (a moved crease moves the mesh and the clamped edges).
 * Then for an observable y(q, u) (rod_observe.h) dy/du_j = dy/dq dq/du_j + dy/du_j|_q by the
 * chain rule, evaluated as one central difference along the direction (dq/du_j, e_j).
 * tests/sim/test_rod_sensitivity.c checks both against finite differences of re-solved
 * equilibria. */
#ifndef RIBBON_SIM_ROD_SENSITIVITY_H
#define RIBBON_SIM_ROD_SENSITIVITY_H

#include "rod_fit_param.h"
#include "rod_observe.h"
#include "rod_snapshot.h"

typedef struct rod_sens_ws rod_sens_ws;

rod_sens_ws *rod_sens_alloc(const rod *r);
void rod_sens_free(rod_sens_ws *w);

/* Central-difference step of parameter k in fit units. */
double rod_sens_step(rod_fit_key k);

/* At the equilibrium in r (frames current, parameters u applied, clamps at dl, dw): for each
 * parameter j with use[j] set, dq[j] (rod_nfree(r) values, NULL to skip) and dobs[j] the
 * observables' derivatives. The rod is left as it came. Returns ROD_OK; ROD_ERR_BRANCH_LOST
 * when H is not positive definite (the state is not stable: *n_negative, if not NULL, says how
 * many pivots were not positive); ROD_ERR_NAN on a non-finite derivative. */
rod_status rod_sens_eval(rod_sens_ws *w, rod *r, const rod_fit_base *b, const double u[ROD_FIT_NKEYS],
                         const int use[ROD_FIT_NKEYS], double dl, double dw, double *dq[ROD_FIT_NKEYS],
                         rod_obs dobs[ROD_FIT_NKEYS], int *n_negative);

#endif
