/* predict_ladder.h: choosing the resolution of a trial's prediction.
 *
 * A ladder is the scene predicted at a few mesh sizes (nodes, e.g. 39, 75, 147, 291) with the time
 * step refined together with the mesh: dt in proportion to the edge length l / (N - 3), the finest
 * rung at the scene's dt, and in fast mode the step control's targets in proportion to dt
 * (rod_predict_opts.adapt_scale). Each rung has its snap Delta W, its wall time and an estimated
 * relative error of the snap Delta W (rod_ladder_estimate, sim/rod_richardson.h: Richardson at the
 * combined refinement's asymptotic order 1 when the observed order of the three finest rungs lies
 * in the expected range [0.7, 2.3]; otherwise the ladder is "not in the asymptotic range", the
 * order is not used and the errors carry a safety factor of 3). The daemon computes the ladder
 * once per scene (predict_scene_hash names a scene regardless of its mesh size) and caches it in
 * the store; each trial then takes the cheapest rung whose estimated error meets the rig file's
 * [sim] target_error, at that rung's N, dt and step control. */
#ifndef RIBBON_DAEMON_PREDICT_LADDER_H
#define RIBBON_DAEMON_PREDICT_LADDER_H

#include <stdatomic.h>
#include <stddef.h>

#include "rod_richardson.h"
#include "scene.h"

#define PREDICT_LADDER_MAX_RUNGS 8

typedef struct predict_ladder_rung {
    int nodes;
    double dt;          /* s: the scene's dt times (N_finest - 3) / (N - 3) */
    int adaptive;       /* fast mode */
    double adapt_scale; /* fast mode: the step control's targets times dt / the scene's dt (0 = fixed steps) */
    int snapped;
    double snap_dw;
    int asymmetric;
    double est_error;   /* relative error of snap_dw, estimated; < 0 when unknown */
    double wall_s;      /* s of wall time of the prediction */
} predict_ladder_rung;

/* 16 hex digits naming the scene without its mesh size (FNV-1a of its printed fields). */
void predict_scene_hash(const rod_scene *sc, char out[17]);

/* Predicts sc at each of nodes[0..n-1] (increasing; the finest at sc's dt, the others at dt times
 * the edge ratio) and estimates the errors; verdict (may be NULL) gets the observed order and
 * whether the ladder is in the asymptotic range. progress (may be NULL) is told each rung as it
 * finishes. cancel (may be NULL): once non-zero, the rung being
 * computed stops at its next time step and the ladder fails with "cancelled". Returns 0, or -1
 * with the reason when a rung fails or does not snap (the ladder of a scene that does not snap
 * has no error to estimate). */
int predict_ladder_compute(const rod_scene *sc, const int *nodes, int n, int adaptive, predict_ladder_rung *out,
                           rod_ladder_verdict *verdict,
                           void (*progress)(void *user, const predict_ladder_rung *r, int k, int n), void *user,
                           const atomic_int *cancel, char *why, size_t why_len);

/* A rough estimate (s of wall time, this machine's Release build) of computing the ladder: time
 * steps (fixed: the shear's duration shear_max l / shear_rate over dt; fast mode: a twentieth of
 * that, the measured ratio of the paper scene's fixed and fast predictions, 13.8 s / 0.6 s) times
 * nodes times the measured cost of a step per node (PREDICT_STEP_NODE_S: 13.8 s for 45,000 steps
 * at N = 201). The daemon refuses a start whose estimate exceeds its bound before computing. */
#define PREDICT_STEP_NODE_S 1.6e-6
#define PREDICT_FAST_STEP_RATIO 20.0
double predict_ladder_estimate_s(const rod_scene *sc, const int *nodes, int n, int adaptive);
/* The same estimate for one prediction at sc's resolution. */
double predict_estimate_s(const rod_scene *sc, int adaptive);

/* Time step (s) of the rung with nodes in a ladder whose finest rung has finest_nodes at dt_finest. */
double predict_ladder_dt(double dt_finest, int finest_nodes, int nodes);

/* Fills est_error of rungs already holding nodes and snap_dw (rod_ladder_estimate on the edge
 * lengths; used by predict_ladder_compute and for a ladder read back from the store; exposed for
 * tests). verdict may be NULL. */
void predict_ladder_estimate_errors(predict_ladder_rung *r, int n, rod_ladder_verdict *verdict);

/* Index of the cheapest (lowest wall time) rung with est_error <= target; the most accurate rung
 * when none meets it. */
int predict_ladder_choose(const predict_ladder_rung *r, int n, double target_error);

#endif
