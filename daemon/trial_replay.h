/* trial_replay.h: a recorded trial through the same measurement pipeline again.
 *
 * The recorded video (cropped, lossless) and the recorded rail positions of every frame (the
 * source trial's frame samples) go through a fresh tracker with the source's calibration record
 * (clamp points shifted by the video's region of interest) and the same snap detection, fed the
 * frames the source fed it (those from the start of shearing until the return, found from the
 * source's state events; the tracker starts fresh where the source's did, at the upper-state
 * check). The result is a new trial, mode replay, linked to its source, with its own samples and
 * events. Works without a daemon (ribbonctl replay --db) and inside one. */
#ifndef RIBBON_DAEMON_TRIAL_REPLAY_H
#define RIBBON_DAEMON_TRIAL_REPLAY_H

#include <stddef.h>
#include <stdint.h>

#include "store.h"
#include "trial_runner.h"

/* video: NULL = the source's video. progress (may be NULL) is told every 50 frames. */
int trial_replay_run(store *st, int64_t source_id, const char *video, int64_t *new_id, trial_result *res,
                     void (*progress)(void *u, long frame, long total), void *u, char *why, size_t why_len);

#endif
