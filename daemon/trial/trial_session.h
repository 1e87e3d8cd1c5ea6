/* trial_session.h: one trial from request to stored result, on its own thread.
 *
 * trial_session_start (called from the API thread while no trial runs) refuses a start whose
 * prediction would take longer than TRIAL_PREDICTION_MAX_S (estimated, with the estimate in the
 * reason), or whose specimen measurements cannot be simulated (trial_specimen.h), puts the
 * specimen's creases into the prediction's scene, records the trial in the store (status created, the rig and scene texts, the
 * calibration record, the specimen) and starts the trial's thread, whose steps are functions of
 * trial_session.c:
 *   session_check_disk             the free disk space for the video;
 *   session_start_prediction       the prediction's resolution: explicit in [sim], or the cheapest
 *                                  rung of the scene's error-against-run-time ladder meeting [sim]
 *                                  target_error (computed once per scene and cached in the store);
 *                                  then the prediction on a thread of its own beside the trial
 *                                  (trial_prediction.h), which never blocks the rails. A
 *                                  prediction that cannot be made (no snap on a ladder rung,
 *                                  the simulator refusing the scene) is stored as failed with
 *                                  its reason, and the trial runs without it;
 *   session_open_camera            mock mode: the digital twin ([twin]'s strip at its own mesh and
 *                                  step, or without [twin] the scene at the prediction's resolution),
 *                                  mounted at the compression rail's current position, its
 *                                  parameters an event ("twin: ..."); rig: the camera;
 *   session_open_tracker_and_video the tracker and the cropped video;
 *   session_run                    the trial runner, storing every sample (batched), event and state;
 *   session_twin_truth             mock mode: the twin's own snap as an event ("twin truth: ...");
 *   session_store_result           the measured result and the final status;
 *   session_release                closes what was opened and waits for the prediction;
 *   session_refit_specimen         a done trial of a named specimen (sim.specimen_fit): the
 *                                  specimen refitted from all its finished trials
 *                                  (trial_specimen_calib.h), before the session says it ended, so
 *                                  its next trial predicts with the new calibration; meanwhile
 *                                  the status's refitting names the specimen (the API's state
 *                                  "done, refitting specimen NAME") and the live page is told so.
 * Every failure ends in the store as a failed trial with the reason, and in the log. An abort
 * (or SIGTERM through it) also cancels the ladder and the prediction at their next time step, so
 * it takes effect within a step whatever the trial is computing. */
#ifndef RIBBON_TRIAL_SESSION_H
#define RIBBON_TRIAL_SESSION_H

#include <stddef.h>
#include <stdint.h>

#include "rail.h"
#include "rig_config.h"
#include "live.h"
#include "trial_err.h"
#include "trial_runner.h"
#include "trial_transcoder.h"

/* s: the longest estimated prediction (or ladder) a start may ask for (predict_ladder.h). */
#define TRIAL_PREDICTION_MAX_S 300.0

typedef struct trial_session trial_session;

/* What the API and the log see of a session. */
typedef struct session_status {
    int64_t trial_id;
    trial_state state;
    int finished;            /* the thread has ended */
    long frames, measured;
    double t_s, dl, dw, dz, a;
    int prediction_done;
    int prediction_failed;
    double snap_dw_predicted;
    char regime_predicted[16];
    int nodes;               /* prediction resolution */
    double dt;
    char message[256];       /* last event */
    char refitting[RIG_NAME_MAX]; /* from the runner's done until its specimen's refit has stored
                               (session_refit_specimen): that specimen's name (the session has not
                               finished; the rails stand); "" otherwise */
    /* The store refused the trial's final status (a full disk): what to write once it takes
     * writes again (the daemon does, rig_daemon.c; at the latest the next start-up marks the
     * trial interrupted). */
    int final_unstored;
    trial_state final_state;  /* done, aborted or failed */
    char final_reason[256];
    double final_wall_s;      /* s since the Unix epoch: when it ended */
    char final_why[256];      /* why the store refused it */
} session_status;

/* cfg is copied. The rails stay the caller's and must not be used by anyone else until the
 * session has finished. log (may be NULL) receives one line per event. bus (may be NULL) is the
 * live page's: the session publishes every state, event, sample, frame (at most 10/s), the
 * prediction and the result into it, and never waits on it; it must outlive the session.
 * TRIAL_E_REFUSED: the prediction's estimate exceeds the bound, or the specimen's measurements
 * are bad input (named: specimen.KEY ...; nothing recorded);
 * TRIAL_E_FAILED: the store or the thread failed. */
trial_err trial_session_start(const rig_config *cfg, rail *compress, rail *shear, const char *note,
                              void (*log)(const char *line), live_bus *bus, trial_session **out, int64_t *trial_id,
                              char *why, size_t why_len);
/* The same, with the daemon's transcoder (may be NULL): in rig mode, with camera.transcode = ffv1,
 * the trial's raw video is handed to it once the live pipeline has closed it complete (queued
 * only; the session does not wait for it). The transcoder must outlive the session. sets: the
 * n_sets overrides cfg was loaded with, in order, stored in the trial's config text (the record of
 * the scene it ran: trial_config_text.h; NULL: not known, none stored); trial_session_start
 * passes NULL. */
trial_err trial_session_start_tx(const rig_config *cfg, const char *const *sets, int n_sets, rail *compress, rail *shear, const char *note,
                                 void (*log)(const char *line), live_bus *bus, trial_transcoder *tx,
                                 trial_session **out, int64_t *trial_id, char *why, size_t why_len);
void trial_session_abort(trial_session *s, const char *reason);
void trial_session_status(trial_session *s, session_status *out);
/* Waits for the thread and frees. The result is in the store (unless status->final_unstored). */
void trial_session_join(trial_session *s, trial_result *result);
/* The same, with the session's last status (may be NULL). */
void trial_session_join_status(trial_session *s, trial_result *result, session_status *status);

#endif
