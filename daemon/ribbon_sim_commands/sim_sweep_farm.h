/* sim_sweep_farm.h: `mpirun -np K ribbon-sim sweep ...` as a task farm on Open MPI (issue 16,
 * part C). Only this file and sim_sweep_farm.c know MPI; without it (RIBBON_HAVE_MPI undefined)
 * the functions below say "one process".
 *
 * Rank 0 hands out tasks (indices into the list every rank builds alike) and writes every row;
 * it also computes tasks on a thread of its own, so K ranks compute on K cores. Workers (ranks
 * 1..K-1) ask for a task, compute it on a thread while their main thread sends its rows as they
 * come and a heartbeat every second, then ask again. A worker that falls silent for longer than
 * the heartbeat timeout is taken for dead: its task goes back to the queue (retried on another
 * rank, at most 3 times), rows it already sent are kept (the writer skips rows it already has).
 * A worker that holds no task and has not asked for one (it left before its first READY) for as
 * long is taken for dead too ("rank K never asked for a task"): rank 0 no longer waits for it.
 * Open MPI 4.1 aborts the whole job when a rank dies unless mpirun runs with --enable-recovery
 * (docs/sweeps.md); without it a rerun resumes from the rows written. Only the main thread calls
 * MPI (MPI_THREAD_FUNNELED). Rows travel as bytes: the ranks run the same binary. */
#ifndef RIBBON_DAEMON_SIM_SWEEP_FARM_H
#define RIBBON_DAEMON_SIM_SWEEP_FARM_H

#include <signal.h>
#include <stddef.h>

#include "sim_sweep_task.h"

/* Initialises MPI when this process was started by mpirun with more than one rank (Open MPI's
 * environment says so); a plain run never touches MPI. *rank, *size: 0 and 1 for a plain run. */
void sweep_farm_start(int *argc, char ***argv, int *rank, int *size);
/* MPI_Finalize when sweep_farm_start initialised MPI, unless a rank was lost (then its closing
 * fence would wait for the dead rank: the process leaves without it). */
void sweep_farm_stop(void);
/* Waits until every rank got here (no-op for one process). */
void sweep_farm_barrier(void);

/* Computes task `task`, passing every row to emit(emit_ctx, ...). */
typedef void (*sweep_task_fn)(void *ctx, int task, sweep_emit_fn emit, void *emit_ctx);

typedef struct sweep_farm_opts {
    double heartbeat_timeout_s; /* a worker silent this long is taken for dead (default 30) */
    int die_rank, die_task;     /* test hook: rank die_rank (>= 1) exits (status 7) when handed
                                 * its die_task-th task (1-based), without a word to rank 0; 0:
                                 * before it first asks for a task (READY);
                                 * -1: never (RIBBON_SWEEP_TEST_DIE=rank:n) */
} sweep_farm_opts;

/* Runs the farm over tasks 0..ntasks-1. On rank 0 every row reaches write(write_ctx, ...), from
 * the main thread or rank 0's compute thread (write locks itself); returns the number of tasks
 * not done (given up after 3 lost workers, or cancelled) and says which in why. On workers:
 * returns 0 when rank 0 says stop. */
int sweep_farm_run(int rank, int size, int ntasks, sweep_task_fn run, void *run_ctx, sweep_emit_fn write,
                   void *write_ctx, const volatile sig_atomic_t *cancel, const sweep_farm_opts *o, char *why,
                   size_t whylen);

#endif
