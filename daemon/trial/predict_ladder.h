/* predict_ladder.h: choosing the resolution of a trial's prediction.
 *
 * A ladder is the scene predicted at a few mesh sizes (nodes, e.g. 31, 61, 121; the scene's dt and
 * fast mode), each with its snap Delta W, its wall time and an estimated relative error of the snap
 * Delta W. The error is measured against a Richardson extrapolation from the finest rungs
 * (observed order from the three finest when they converge monotonically, else first order), so
 * the finest rung's own error is estimated too. The daemon computes the ladder once per scene
 * (predict_scene_hash names a scene regardless of its mesh size) and caches it in the store; each trial
 * then takes the cheapest rung whose estimated error meets the rig file's [sim] target_error. */
#ifndef RIBBON_DAEMON_PREDICT_LADDER_H
#define RIBBON_DAEMON_PREDICT_LADDER_H

#include <stdatomic.h>
#include <stddef.h>

#include "scene.h"

#define PREDICT_LADDER_MAX_RUNGS 8

typedef struct predict_ladder_rung {
    int nodes;
    double dt;          /* s */
    int adaptive;       /* fast mode */
    int snapped;
    double snap_dw;
    int asymmetric;
    double est_error;   /* relative error of snap_dw, estimated; < 0 when unknown */
    double wall_s;      /* s of wall time of the prediction */
} predict_ladder_rung;

/* 16 hex digits naming the scene without its mesh size (FNV-1a of its printed fields). */
void predict_scene_hash(const rod_scene *sc, char out[17]);

/* Predicts sc at each of nodes[0..n-1] (increasing) and estimates the errors. progress (may be
 * NULL) is told each rung as it finishes. cancel (may be NULL): once non-zero, the rung being
 * computed stops at its next time step and the ladder fails with "cancelled". Returns 0, or -1
 * with the reason when a rung fails or does not snap (the ladder of a scene that does not snap
 * has no error to estimate). */
int predict_ladder_compute(const rod_scene *sc, const int *nodes, int n, int adaptive, predict_ladder_rung *out,
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

/* Fills est_error of rungs already holding snap_dw (used by predict_ladder_compute; exposed for tests). */
void predict_ladder_estimate_errors(predict_ladder_rung *r, int n);

/* Index of the cheapest (lowest wall time) rung with est_error <= target; the most accurate rung
 * when none meets it. */
int predict_ladder_choose(const predict_ladder_rung *r, int n, double target_error);

#endif
