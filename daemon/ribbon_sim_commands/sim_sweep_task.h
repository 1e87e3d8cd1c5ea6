/* sim_sweep_task.h: one task of `ribbon-sim sweep`: a row of the phase diagram, every Gamma of
 * the grid at one (phi, Delta L), computed alone from the scene, so the same task gives the same
 * rows bit for bit whichever thread, MPI rank or shard runs it (issue 16, part C).
 *
 * A row task:
 *   1. the upper state at every grid Gamma: the documented route (rod_route.h) at one anchor
 *      (the middle Gamma, else the nearest one the route reaches), then continuation in Gamma
 *      from the neighbour (rod_seed.h) outward both ways; where continuation loses the state,
 *      the route at that point, and the chain goes on from whichever was solved last.
 *      `seed_route` = 1 runs the route at every point instead (the former behaviour, kept to
 *      measure the saving);
 *   2. each grid point classified by continuation in Delta W from its upper state (point rows);
 *      a point whose upper state neither path reaches is `no-upper` when both lost it as a stable
 *      state (the note: where continuation lost it and its lowest Hessian eigenvalue there),
 *      else `failed`;
 *   3. each grid cell with different regimes either side bisected in Gamma to gamma_tol (probe
 *      rows, each probe's upper state continued from the cell's lower grid point), one boundary
 *      row per boundary.
 * Rows already known (a resumed sweep: the table read at the start) are reused, not recomputed:
 * emitted with is_new = 0. */
#ifndef RIBBON_DAEMON_SIM_SWEEP_TASK_H
#define RIBBON_DAEMON_SIM_SWEEP_TASK_H

#include <signal.h>

#include "scene.h"
#include "sim_sweep_row.h"

typedef struct sweep_spec {
    rod_scene base;          /* the scene (its crease sign, position and Delta L replaced per task) */
    double sign;             /* sign of the scene's crease angle */
    const double *gamma;     /* the grid's Gammas */
    int ngamma;
    double gamma_tol;
    int seed_route;          /* 1: the route at every point (no continuation) */
} sweep_spec;

/* Receives every row of the task in order; is_new = 0 for a row taken from `known`. */
typedef void (*sweep_emit_fn)(void *ctx, const sweep_row *row, int is_new);

/* Runs the row task (phi, dl). known: rows read at the start (not modified; may be empty).
 * cancel: when it becomes non-zero the task stops between classifications (rows emitted so far
 * are whole). */
void sweep_run_row(const sweep_spec *sp, double phi, double dl, const sweep_table *known, sweep_emit_fn emit,
                   void *ctx, const volatile sig_atomic_t *cancel);

/* The scene a task solves at (phi, gamma, dl): the base scene with the crease magnitude phi (deg,
 * the base's sign), position gamma, Delta L dl and no imperfection. */
rod_scene sweep_scene_at(const sweep_spec *sp, double phi, double gamma, double dl);

/* rod_scene_check on every grid point (each phi, each of sp->gamma, each dl): 0 when all hold,
 * else -1 with the first point that does not and its reason ("phi 90 deg, Gamma 0.05, Delta L
 * 0.5: folds.position: the crease ... lies inside the clamp ...") in why. A sweep refuses such a
 * grid before it computes anything (issue 33, item 10). */
int sweep_grid_check(const sweep_spec *sp, const double *phi, int nphi, const double *dl, int ndl, char *why,
                     size_t why_len);

/* Regimes a boundary may separate: asymmetric, symmetric and none (no snap). */
int sweep_is_regime(const sweep_row *r);

/* Whether the table already holds the whole row task (every grid point classified and a boundary
 * in every cell between two different regimes): a resumed sweep skips it. */
int sweep_row_complete(const sweep_spec *sp, double phi, double dl, const sweep_table *t);

#endif
