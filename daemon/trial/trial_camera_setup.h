/* trial_camera_setup.h: the camera calibration, frame size and video region of a trial of this rig
 * (trial_camera_setup.c). */
#ifndef RIBBON_TRIAL_CAMERA_SETUP_H
#define RIBBON_TRIAL_CAMERA_SETUP_H

#include <stddef.h>

#include "rig_config.h"
#include "trial_video.h"
#include "vision.h"

/* Mock mode computes the synthetic camera's calibration; rig mode loads camera.calibration.
 * Returns 0, or -1 with why. */
int trial_camera_setup(const rig_config *cfg, vis_calib *cal, int *width, int *height, trial_roi *roi,
                       char *why, size_t why_len);

#endif
