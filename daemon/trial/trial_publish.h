/* trial_publish.h: the trial session's (and a replay's) publish hook into the live page's bus (live_bus.h): one call
 * per state, event, sample, frame, prediction and result, each formatted into one JSON message
 * (the messages are documented in docs/live-page.md). Every call is a bounded copy into the bus,
 * never a wait on a browser; a NULL bus makes every call a no-op. */
#ifndef RIBBON_DAEMON_TRIAL_PUBLISH_H
#define RIBBON_DAEMON_TRIAL_PUBLISH_H

#include <stddef.h>
#include <stdint.h>

#include "live.h"
#include "trial_runner.h"
#include "vision.h"

void trial_publish_begin(live_bus *b, int64_t trial_id, const char *mode, const char *note);
void trial_publish_state(live_bus *b, int64_t trial_id, trial_state s, double t_s, const char *why);
/* A state by name: the replay's ("replaying", then the source's steps as it passes them). */
void trial_publish_state_name(live_bus *b, int64_t trial_id, const char *state, double t_s, const char *why);
void trial_publish_event(live_bus *b, int64_t trial_id, double t_s, const char *kind, const char *message);
void trial_publish_sample(live_bus *b, int64_t trial_id, const trial_sample *smp);
/* The frame with the tracker's last centreline, when the bus wants one (at most 10 a second). */
void trial_publish_frame(live_bus *b, const vis_frame *f, const vis_tracker *trk, long index, double t_s);
/* The same with the centreline given (n (u, v) pairs, the first LIVE_UV_MAX kept). */
void trial_publish_frame_curve(live_bus *b, const vis_frame *f, const double *uv, size_t n, long index, double t_s);
void trial_publish_prediction(live_bus *b, int64_t trial_id, int ok, int snapped, double snap_dw, const char *regime,
                           size_t n, const double *dw, const double *dz, const double *a, const char *why);
/* A calibrated prediction that landed (trial_calibrate.h): the fit beside the trial, or why it failed. */
void trial_publish_calibrated(live_bus *b, int64_t trial_id, const trial_calibrated *r);
void trial_publish_result(live_bus *b, int64_t trial_id, const trial_result *r);
/* The trial's final status is in the store (the page reloads the trials table and the phase
 * diagram on it: the result message comes before the store has it). */
void trial_publish_stored(live_bus *b, int64_t trial_id, trial_state final);

#endif
