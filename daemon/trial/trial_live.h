/* trial_live.h: what a rig-mode trial opens for its live pipeline, in one place.
 *
 * The camera from the rig file (V4L2 index or path, or a GenICam camera through Aravis with its
 * Mono8, region, frame rate, exposure and gain), the capture pipeline on it (trial_capture.h: the
 * capture and recorder threads, the video as raw Y800 AVI with its frame-times file), and the rails'
 * polling thread (trial_rail_poller.h). trial_live_close stops them in reverse order and writes the
 * pipeline's counts as one line for the trial's events. The session calls these three and nothing
 * else of the live pipeline. */
#ifndef RIBBON_DAEMON_TRIAL_LIVE_H
#define RIBBON_DAEMON_TRIAL_LIVE_H

#include <stddef.h>

#include "rig_config.h"
#include "trial_capture.h"
#include "trial_runner.h"

typedef struct trial_live trial_live;

/* Opens the camera and starts capture (recording into video_path, region roi) and the rail poller.
 * expect_w/expect_h (> 0): the frame size the trial was set up for (camera.width_px/height_px);
 * the first frame must have it. cal (or NULL): the trial's calibration, whose points (the clamps,
 * the principal point) must lie inside that frame: a calibration made for another camera size is a
 * named error (the file stores no size of its own). Nothing moves before this returns. */
int trial_live_open(const rig_config *cfg, rail *compress, rail *shear, const char *video_path, trial_roi roi,
                    int expect_w, int expect_h, const vis_calib *cal, trial_live **out, char *why,
                    size_t why_len);
/* Hands the pipeline to the runner (trial_runner_set_live). */
void trial_live_attach(trial_live *l, trial_runner *tr);
/* Stops everything; `summary` gets the counts line ("pipeline: N frames captured, ..."). Returns 0,
 * or -1 (why) when the video could not be completed. NULL is a no-op. */
int trial_live_close(trial_live *l, trial_capture_counts *counts, char *summary, size_t summary_len, char *why,
                     size_t why_len);

#endif
