/* trial_prediction.h: the prediction that runs beside a trial, on a thread of its own with its own
 * store connection, so it never blocks the rails (trial_prediction.c). It predicts the scene at
 * the resolution the session chose, keeps a thinned curve (t, Delta W, Delta Z, A), stores the
 * prediction with the curve beside the trial, and reports the outcome once through a callback
 * (the session's status and log; the prediction never reaches into the session). Cancellable: a
 * set cancel flag stops the simulation at its next step. */
#ifndef RIBBON_TRIAL_PREDICTION_H
#define RIBBON_TRIAL_PREDICTION_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "rig_config.h"
#include "scene.h"
#include "store.h"

typedef enum trial_prediction_outcome {
    TRIAL_PREDICTION_STORED = 0, /* predicted and stored: snap_dw, regime */
    TRIAL_PREDICTION_FAILED,     /* the simulation failed or was cancelled (a warning event and a
                                    failed prediction row with the reason are stored) */
    TRIAL_PREDICTION_NOT_STORED  /* the store refused it (the message says why) */
} trial_prediction_outcome;

typedef struct trial_prediction_report {
    trial_prediction_outcome outcome;
    double snap_dw;        /* NaN when no snap or not stored */
    store_regime regime;
    char message[512];     /* one line for the log and the status */
    size_t n;              /* STORED: the thinned curve, valid during the callback only */
    const double *dw, *dz, *a;
} trial_prediction_report;

/* Called once, on the prediction's thread, when it ends. */
typedef void (*trial_prediction_done_fn)(void *user, const trial_prediction_report *r);

typedef struct trial_prediction_def {
    rod_scene scene;         /* at the chosen resolution */
    int adaptive;            /* fast mode */
    double adapt_scale;      /* fast mode: rod_predict_opts.adapt_scale of the ladder's rung (0 = 1) */
    double est_error;        /* the ladder's estimate of the snap's relative error; NaN if unknown */
    char hash[72];           /* the scene's hash (predictions.scene_hash) */
    store_creases creases;   /* the creases as measured or designed and where each came from
                                (trial_specimen.h) */
    char calibration_json[2048]; /* the specimen's calibration the scene carries instead of some of
                                    them (trial_specimen_calib.h); "" = none */
    char store_path[RIG_PATH_MAX];
    int64_t trial_id;
    const atomic_int *cancel; /* non-zero: stop (may be NULL) */
    int idle;                 /* 1: the thread runs in SCHED_IDLE (thread_class.h): rig mode, where the
                                 compression it overlaps moves the rails; 0 in mock mode */
    trial_prediction_done_fn done;
    void *user;
} trial_prediction_def;

typedef struct trial_prediction trial_prediction;

/* Starts the thread. Returns 0, or -1 with why (no thread started, done is not called). */
int trial_prediction_start(const trial_prediction_def *def, trial_prediction **out, char *why, size_t why_len);
/* A prediction that failed before or without its thread (the resolution ladder found no snap,
 * the simulator refused the scene, the thread could not start): the failed prediction row of
 * def's trial, with def's resolution and creases and the reason, and the warning event saying
 * "prediction failed: REASON", on st (the caller's connection). wall_s: what it cost. Returns 0,
 * or -1 with why when the store refused. */
int trial_prediction_store_failed(store *st, const trial_prediction_def *def, const char *reason, double wall_s,
                                  char *why, size_t why_len);
/* Waits for the thread and frees. NULL is a no-op. */
void trial_prediction_join(trial_prediction *p);

#endif
