/* trial_camera_settings.h: the rig file's camera section as the vision layer's camera settings,
 * one mapping for the trial, ribbonctl calibrate-camera and the rig checks (three copies had
 * drifted: calibrate-camera and the checks lost camera.v4l2_gain). */
#ifndef RIBBON_TRIAL_CAMERA_SETTINGS_H
#define RIBBON_TRIAL_CAMERA_SETTINGS_H

#include "rig_config.h"
#include "vision.h"

/* Every camera key of rc (source, index or device, size, fps, offsets, exposure, gain, V4L2 gain). */
vis_camera_settings trial_camera_settings(const rig_camera *rc);

#endif
