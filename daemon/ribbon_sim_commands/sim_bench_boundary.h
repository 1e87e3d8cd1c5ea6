/* sim_bench_boundary.h: the boundary part of `ribbon-sim bench` (issue 16 F): the traced boundary
 * Gamma*(phi) at 20 phi against what the sweep's bisection needs for the same answer. */
#ifndef RIBBON_DAEMON_SIM_BENCH_BOUNDARY_H
#define RIBBON_DAEMON_SIM_BENCH_BOUNDARY_H

#include <stddef.h>

#include "scene.h"

typedef struct sim_bench_boundary_result {
    double boundary_wall_s;   /* s, start plus Gamma*(phi) at the 20 phi (60..130 deg) */
    double sweep_wall_s;      /* s, the sweep's work for the same 20 phi (see the .c) */
    double boundary_cpu_s;    /* s, CPU time of the same */
    double sweep_cpu_s;       /* s, CPU time of the sweep's work */
    double boundary_vs_sweep; /* sweep_cpu_s / boundary_cpu_s (one thread each) */
    double sweep_phi90_gamma; /* the bisected Gamma* at 90 deg, and the traced one there */
    double traced_phi90_gamma;
    int sweep_classifications;/* classifications of the measured phi */
} sim_bench_boundary_result;

/* Runs both on scene sc (its N, Delta L; phi magnitudes 60..130 deg). 0, or -1 with err. */
int sim_bench_boundary(const rod_scene *sc, sim_bench_boundary_result *out, char *why, size_t why_len);

#endif
