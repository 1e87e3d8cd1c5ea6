/* truss_private.h: helpers shared by the truss files (truss.c, truss_continue.c,
 * truss_dynamics.c), not part of the public interface. */
#ifndef RIBBON_SIM_TRUSS_PRIVATE_H
#define RIBBON_SIM_TRUSS_PRIVATE_H

#include "truss.h"

/* Newton convergence test of truss_newton_opts for n unknowns: every step component
 * |dx_i| <= step_tol alpha^2 scale_i + 8 eps |x_i| and res_max <= res_tol alpha^3 + 100 eps,
 * or res_max <= 100 eps alone. */
int truss_newton_converged(const truss_newton_opts *o, double alpha, const double *dx,
                           const double *x, const double *scale, int n, double res_max);

#endif
