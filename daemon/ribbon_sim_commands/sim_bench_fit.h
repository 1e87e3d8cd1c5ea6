/* sim_bench_fit.h: the fit part of `ribbon-sim bench --fit` (issue 32 E): a strip fitted from a
 * compression and hold, and the sensitivities' Jacobian against finite differences of whole
 * paths. */
#ifndef RIBBON_DAEMON_SIM_BENCH_FIT_H
#define RIBBON_DAEMON_SIM_BENCH_FIT_H

#include <stddef.h>

#include "scene.h"

typedef struct sim_bench_fit_result {
    int nodes, samples, parameters, iterations, evaluations;
    double fit_wall_s, fit_cpu_s;   /* the whole rod_fit_run */
    double rms;                     /* its residual in noise units */
    double sens_jacobian_s;         /* one model evaluation with the Jacobian by sensitivities,
                                       the path followed from the route */
    double fd_jacobian_s;           /* the same Jacobian by central differences of whole paths:
                                       1 + 2 p paths from the route */
    double sens_speedup;            /* fd_jacobian_s / sens_jacobian_s */
} sim_bench_fit_result;

/* On scene sc: the observed strip is sc with creases of 0.96 and 0.99 times its angles and a
 * hinge 0.7 times as stiff, filmed at 20 states of the compression from Delta L - 0.05 to Delta L
 * and 20 frames of the hold, with the tracker's noise (fixed seed); fitted: both angles and the
 * hinge (the angles alone with rigid creases). 0, or -1 with why. */
int sim_bench_fit(const rod_scene *sc, sim_bench_fit_result *out, char *why, size_t why_len);

#endif
