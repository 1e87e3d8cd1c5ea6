/* trial_replay.h: a recording through the same measurement pipeline again.
 *
 * Two kinds of recording:
 *  - a stored trial: its video (cropped, lossless) and the rail positions recorded with every frame
 *    (its frame samples), with its calibration record (clamp points shifted by the video's region
 *    of interest) and snap settings. The frames fed to snap detection are the ones the source fed
 *    it (from the start of shearing until the return, found from its state events); the tracker
 *    starts fresh where the source's did, at the upper-state check;
 *  - outside files named by a replay-mode rig file: replay.video, replay.rails (a CSV of rail
 *    readings t_s,compress_mm,shear_mm on the rails' clock) and camera.calibration, with the rig
 *    file's [calibration], [detect] and scene. Frame f is at t = f / fps + camera_time_offset_s on
 *    the rails' clock, or, when VIDEO.frames.csv is beside the video (rig mode's recorder writes
 *    it), at its t_s minus frame 0's t_s + camera_time_offset_s: the real, possibly uneven, times; its rail positions are interpolated linearly between the readings (frames
 *    outside the readings are skipped and counted). Shearing is taken to run from the first reading
 *    where the shear rail has left its first position by more than 0.05 mm to the reading of
 *    largest Delta W; the tracker starts fresh at its start and snap detection sees only it.
 * Frames with the compress rail away from the trial's compression are stored untracked ("clamp not
 * found"), except the compression's last part (trial_comp_track.h: before the rail first reaches
 * the compression, from trial_comp_track_from_dl on), tracked with the clamp point moved to where
 * the recorded rail puts it, as the trial did.
 * The result is a new trial, mode replay, linked to its source trial if there is one, with its own
 * samples and events. Works without a daemon (ribbonctl replay) and inside one (on a thread of its
 * own: create on one store connection, execute on another). */
#ifndef RIBBON_DAEMON_TRIAL_REPLAY_H
#define RIBBON_DAEMON_TRIAL_REPLAY_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "live.h"
#include "rig_config.h"
#include "store.h"
#include "trial_runner.h"

typedef struct trial_replay trial_replay;

/* trial_replay_from_trial's (and _prepare's) return for a source trial that has not ended (status
 * created or running: its video and samples are still being written): the API answers 409. */
#define TRIAL_REPLAY_UNFINISHED (-2)

/* A stored trial; video NULL = the trial's own. 0, or -1 with why, or TRIAL_REPLAY_UNFINISHED.
 * A replay that ended before its video's end (aborted, failed) is refused naming its source. */
int trial_replay_from_trial(store *st, int64_t source_id, const char *video, trial_replay **out, char *why,
                            size_t why_len);
/* Outside files named by a replay-mode rig file (checks that the video opens and the CSV parses). */
int trial_replay_from_files(const rig_config *cfg, trial_replay **out, char *why, size_t why_len);

/* Records the new trial (mode replay, status running); note may be NULL. */
int trial_replay_create(trial_replay *r, store *st, const char *note, int64_t *new_id, char *why, size_t why_len);
/* Tracks every frame and detects the snap, writing samples and events to the trial created above.
 * cancel (may be NULL) is polled every frame: when set the trial ends aborted. progress (may be
 * NULL) is told every 50 frames; total is -1 when the video does not say. Returns 0 when the trial
 * ended done, -1 with why otherwise (the trial is then failed or aborted, with the reason). */
int trial_replay_execute(trial_replay *r, store *st, const atomic_int *cancel,
                         void (*progress)(void *u, long frame, long total), void *u, trial_result *res, char *why,
                         size_t why_len);
void trial_replay_free(trial_replay *r);
/* The live page's bus (may be NULL: nothing published, as in `ribbonctl replay`): execute then
 * publishes what a trial does (docs/live-page.md): the trial, its states ("replaying", then the
 * source's checking, shearing, snapped, returning as the replay passes them, then done / aborted
 * / failed), every sample, camera frames with the tracked centreline, its events, the source
 * trial's stored prediction (if it has one) and the result. The bus must outlive the execution. */
void trial_replay_set_bus(trial_replay *r, live_bus *bus);

/* The source trial (0 for files) and the video's frame count (-1 = unknown). */
int64_t trial_replay_source(const trial_replay *r);
const char *trial_replay_video(const trial_replay *r); /* the video it reads */
long trial_replay_frame_count(const trial_replay *r);

/* What a request names: trial `source` (> 0; video NULL = its own); else the rig file's [replay]
 * source_trial (with replay.video if set); else the outside files it names. cfg may be NULL. */
int trial_replay_prepare(store *st, const rig_config *cfg, int64_t source, const char *video, trial_replay **out,
                         char *why, size_t why_len);
/* create + execute on one connection (no cancel). */
int trial_replay_run(trial_replay *r, store *st, const char *note, void (*progress)(void *u, long frame, long total),
                     void *u, int64_t *new_id, trial_result *res, char *why, size_t why_len);

#endif
