/* trial_camera_settings.c: the rig file's camera keys as vis_camera_settings (see the header). */
#include "trial_camera_settings.h"

vis_camera_settings trial_camera_settings(const rig_camera *rc)
{
    vis_camera_settings cs = vis_camera_settings_default();
    cs.index = rc->index;
    cs.path = rc->source == RIG_SOURCE_DEVICE || rc->source == RIG_SOURCE_ARAVIS ? rc->device : NULL;
    cs.aravis = rc->source == RIG_SOURCE_ARAVIS;
    cs.width_px = rc->width_px;
    cs.height_px = rc->height_px;
    cs.fps = rc->fps;
    cs.offset_x_px = rc->offset_x_px;
    cs.offset_y_px = rc->offset_y_px;
    cs.exposure_us = rc->exposure_us;
    cs.gain_db = rc->gain_db;
    cs.v4l2_gain = rc->v4l2_gain;
    return cs;
}
