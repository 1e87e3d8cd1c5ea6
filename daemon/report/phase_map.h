/* phase_map.h: ribbond's predicted phase diagram, computed once on a thread of its own.
 *
 * The phase report (every trial's measured regime on the predicted (phi, Gamma) map) needs a grid
 * of predictions: 30 at the default resolution, some 15 s of one core. The API must answer at
 * once and a trial must not wait for it, so the grid is computed on its own thread, started by
 * the first request that wants it, in SCHED_IDLE (thread_class.h: a trial's loop, capture and
 * poller always come first; its rails may be moving), once per daemon (the map depends on the scene only; the trials drawn over
 * it are read from the store on every request). Until it is ready the report is drawn with the
 * trials only, and the state says how far the grid is. phase_map_free cancels a computation in
 * progress at its next time step. */
#ifndef RIBBON_REPORT_PHASE_MAP_H
#define RIBBON_REPORT_PHASE_MAP_H

#include <stddef.h>

#include "phase_grid.h"
#include "scene.h"

typedef struct phase_map phase_map;

/* The grid ribbond draws: phi from 30 to 150 deg in 5 values, Gamma from 0.08 to 0.28 in 6
 * (ribbonctl phase-report's default), each point predicted at N = 41 and dt = 0.01 s (adaptive)
 * from the daemon's scene. Nothing is computed yet. NULL when out of memory. */
phase_map *phase_map_create(const rod_scene *scene);
/* Starts the computation unless it has started already (any number of callers, any thread).
 * Returns 0, or -1 with why when the thread could not be started (the state then says so). */
int phase_map_start(phase_map *m, char *why, size_t why_len);
/* The grid once it is ready (then never changes until phase_map_free), else NULL. */
const phase_grid *phase_map_grid(phase_map *m);
/* One line: "not started", "computing K/N", "ready (N points, N = 41)", "failed: why". */
void phase_map_state(phase_map *m, char *line, size_t line_len);
/* Cancels and joins the computation, frees. NULL is a no-op. */
void phase_map_free(phase_map *m);

#endif
