/* trial_cam_watch.h: the runner's side of the camera's time offset (issue 34 C): which frames and
 * readings go to the fit (trial_cam_offset.h), when it runs, and what it says.
 *
 * The last TRIAL_CAM_WATCH_STAND_S of the hold and the check give the clamps standing; the shear's
 * first window_s (or up to the snap's detection, if sooner) give them moving, with the shear rail's
 * fresh readings over the same span. Each jaw's position in a frame is its centroid in a window
 * beyond the calibration's clamp point (jaw_centroid: a window of 0.3 x the clamp spacing; about
 * 0.01 px of noise on ribbon-rigsim's images); the clamp search of vis_find_clamps (0.04 px there)
 * was too coarse for milliseconds and found no jaws on a tilted camera. At the window's end the fit runs once and its result is one event: the
 * offset with its standard deviation, and either "used for this trial's Delta W" (the rig file's
 * camera.time_offset = measure: the frames after it are placed on the rails' clock with it) or,
 * when it disagrees with calibration.camera_time_offset_s by more than a frame period (plus two
 * standard deviations), a warning naming both. A fit that cannot be made is a warning with its
 * reason, and the configured offset stays. */
#ifndef RIBBON_TRIAL_CAM_WATCH_H
#define RIBBON_TRIAL_CAM_WATCH_H

#include <stddef.h>

#include "trial_cam_offset.h"
#include "vision.h"

#define TRIAL_CAM_WATCH_STAND_S 1.5 /* s of the hold's end kept as the clamp standing */

typedef struct trial_cam_watch trial_cam_watch;

/* window_s: s of the shear after its command in the fit (> 0); fps the camera's; measure: 1 to use
 * the measured offset (camera.time_offset = measure); configured_s: calibration's offset; the
 * calibration's clamp points (px, at least 20 px apart): each jaw is looked for beyond its own. */
trial_cam_watch *trial_cam_watch_alloc(double window_s, double fps, int measure, double configured_s,
                                       const double left_px[2], const double right_px[2]);
void trial_cam_watch_free(trial_cam_watch *w);
/* The hold's frames from now on count (call at most TRIAL_CAM_WATCH_STAND_S before the shear). */
void trial_cam_watch_standing(trial_cam_watch *w);
/* The shear was commanded at t_cmd (rail clock, as the frames' and readings' times). */
void trial_cam_watch_shear(trial_cam_watch *w, double t_cmd);
/* A frame at its mapped time (no offset applied). Searched for the clamps while collecting. */
void trial_cam_watch_frame(trial_cam_watch *w, double t_frame, const vis_frame *f);
/* A fresh reading of the shear rail. */
void trial_cam_watch_reading(trial_cam_watch *w, double t_s, double shear_mm);

typedef enum trial_cam_watch_verdict {
    TRIAL_CAM_WATCH_PENDING = 0, /* nothing to say yet (or said already) */
    TRIAL_CAM_WATCH_AGREES,      /* measured, within a frame period of the configured offset */
    TRIAL_CAM_WATCH_USED,        /* measured and used from now on (measure) */
    TRIAL_CAM_WATCH_DISAGREES,   /* measured, more than a frame period from the configured offset */
    TRIAL_CAM_WATCH_UNCERTAIN,   /* measured (measure), but its standard deviation is above half a
                                    frame period: not used, the configured offset stays */
    TRIAL_CAM_WATCH_FAILED       /* not measured: the message says why */
} trial_cam_watch_verdict;

/* Once, when the window is over at rail-clock time t (or force: the shear ended early, e.g. the
 * snap): runs the fit and writes the event's message. The fit is in *fit (offset NaN when not
 * measured). */
trial_cam_watch_verdict trial_cam_watch_poll(trial_cam_watch *w, double t, int force, trial_cam_offset_fit *fit,
                                             char *msg, size_t msg_len);

#endif
