/* rigsim_twin.h: the rig simulator's ribbon: the digital twin (sim/rod_twin.h) stepped on its own
 * thread with the axes' actual positions, and the trajectory it logs, from which the camera
 * (rigsim_camera.h) renders each frame.
 *
 * Why its own thread: the camera must show the strip at every frame's own exposure instant, but
 * near the snap the solver slows (stiff dynamics, more Newton iterations) and a solver step plus a
 * render no longer fit in a frame period; done in one thread, every second frame repeated the
 * previous image (the regime flake: a whole snap between two renders). Here the solver steps
 * ahead of the renders, at most `lead` seconds ahead of real time (the axes extrapolated that far,
 * rigsim_rails_positions_at), in chunks of at most one solver step (the scene's dt) that land
 * exactly on every frame's exposure instant of the camera's grid, and publishes the state after
 * every chunk (its shape, Delta L, Delta W, Delta Z, the twin time) into a ring. The camera's
 * render thread takes the state of its frame's exposure instant (rigsim_twin_state_at); when the
 * solver is behind real time it takes the latest state there is, and the frame is stamped with
 * the instant that state stands for (the truth), never a repeat of the previous frame's state.
 * The twin's clock pauses while nobody streams (rigsim_twin_hold). */
#ifndef RIBBON_RIGSIM_TWIN_H
#define RIBBON_RIGSIM_TWIN_H

#include <stddef.h>

#include "rig_config.h"
#include "rigsim_rails.h"
#include "rod_snap_watch.h"
#include "twin.h"

typedef struct rigsim_twin rigsim_twin;

/* One logged state as the camera takes it. */
typedef struct rigsim_twin_state {
    double t;          /* the twin's time, s */
    double mono;       /* the host monotonic instant it stands for (the twin's time 0 + t) */
    double dl, dw, dz; /* the clamps' Delta L, Delta W, the twin's Delta Z (camera projection) */
    int exact;         /* 1: t is the instant asked for; 0: the solver was behind, the latest state */
} rigsim_twin_state;

/* The twin of scene sc, mounted at dl_start (the static solve: seconds), its time 0 at t0_mono;
 * the axes' positions become (Delta L, Delta W) through calib on sc->length. Does not start the
 * thread (rigsim_twin_run). */
int rigsim_twin_open(const rod_scene *sc, double dl_start, const rig_calibration *calib, rigsim_rails *rails,
                     rigsim_twin **out, char *why, size_t why_len);
/* Starts the solver's thread, the twin's time 0 at t0_mono, on core `cpu` (-1: any); tries
 * SCHED_FIFO at `priority` (0: none); 1 in *realtime when granted. */
int rigsim_twin_run(rigsim_twin *tw, double t0_mono, int priority, int cpu, int *realtime, char *why,
                    size_t why_len);
void rigsim_twin_close(rigsim_twin *tw);

/* The camera's exposure instants (host monotonic): grid + k period; the solver lands on each and
 * runs at most lead s ahead of real time. Sets the twin going (after rigsim_twin_hold). */
void rigsim_twin_set_grid(rigsim_twin *tw, double grid_mono, double period_s, double lead_s);
/* Nobody streams: the solver stops and the twin's clock pauses: its latest state stands for now
 * (its time 0 moves on) until rigsim_twin_set_grid sets it going again. */
void rigsim_twin_hold(rigsim_twin *tw, double now_mono);
/* The twin's time 0 now (host monotonic). */
double rigsim_twin_t0(rigsim_twin *tw);

/* The state for the exposure instant at_mono: waits until the solver has reached it or until
 * deadline_mono, then copies the logged state at at_mono (exact) or, the solver behind, the latest
 * logged (into shape, sized for the scene with twin_shape_init, and st). Only a state newer than
 * twin time after_t counts. 1 when copied, 0 when there is none newer by the deadline. */
int rigsim_twin_state_at(rigsim_twin *tw, double at_mono, double deadline_mono, double after_t, twin_shape *shape,
                         rigsim_twin_state *st);

/* The twin's own snap so far and its Delta W at the latest logged state. */
void rigsim_twin_truth(rigsim_twin *tw, rod_snap_report *snap, double *dw_now);

/* What the solver did: its thread's CPU (s), chunks stepped, the slowest chunk's wall time (s),
 * failed advances, and the latest logged twin time against real time (s behind; < 0 ahead). */
typedef struct rigsim_twin_stats {
    double cpu_s, worst_chunk_s, behind_s, behind_max_s;
    double latest_mono; /* the host instant the latest logged state stands for */
    long chunks, failures;
} rigsim_twin_stats;
void rigsim_twin_stats_get(rigsim_twin *tw, rigsim_twin_stats *out);
/* The last solver failure's reason ("" if none). */
void rigsim_twin_last_error(rigsim_twin *tw, char *out, size_t n);

#endif
