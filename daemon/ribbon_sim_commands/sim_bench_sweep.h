/* sim_bench_sweep.h: `ribbon-sim bench --sweep`, the sweep's MPI efficiency and the time the
 * continued upper states save (sim_bench_sweep.c says what each number is). */
#ifndef RIBBON_DAEMON_SIM_BENCH_SWEEP_H
#define RIBBON_DAEMON_SIM_BENCH_SWEEP_H

/* Runs the four sweeps of the scene file with its --set overrides, prints one line (JSON with
 * json). Returns 0, or 1 when a sweep failed (reason on stderr). */
int sim_bench_sweep(const char *scene, const char *const *sets, int nsets, int json);

#endif
