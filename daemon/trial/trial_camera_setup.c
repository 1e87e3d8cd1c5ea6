/* trial_camera_setup.c: the camera a trial measures with, as numbers: its calibration (mock mode:
 * computed from the synthetic camera that frames the scene; rig mode: the rig file's
 * camera.calibration), the frame size and the saved video's region of interest. */
#include "trial_camera_setup.h"

#include <stdio.h>

#include "twin.h"

int trial_camera_setup(const rig_config *cfg, vis_calib *cal, int *width, int *height, trial_roi *roi,
                       char *why, size_t why_len)
{
    *width = cfg->camera.width_px > 0 ? cfg->camera.width_px : 640;
    *height = cfg->camera.height_px > 0 ? cfg->camera.height_px : 480;
    vis_error ve = {0};
    if (cfg->mode == RIG_MODE_MOCK) {
        twin_camera_params cp = twin_camera_params_default();
        cp.width_px = *width;
        cp.height_px = *height;
        vis_render_params rp;
        char err[256] = "";
        if (twin_render_params_for_scene(&cfg->scene, &cp, &rp, err, sizeof err) != TWIN_OK ||
            twin_calib_for_scene(&cfg->scene, &rp.camera, cal, err, sizeof err) != TWIN_OK) {
            snprintf(why, why_len, "synthetic camera: %s", err);
            return -1;
        }
    } else if (cfg->mode == RIG_MODE_RIG) {
        if (vis_calib_load(cal, cfg->camera.calibration, &ve) != VIS_OK) {
            snprintf(why, why_len, "camera calibration %s: %s", cfg->camera.calibration, ve.message);
            return -1;
        }
    } else {
        snprintf(why, why_len, "replay mode records no camera of its own");
        return -1;
    }
    /* A calibration without a principal point (negative: the image's centre; the clamps' calibration
     * leaves it so) gets the full frame's, which the live tracker takes for it: the trial's record
     * then stores the real point, and a replay moves it into the saved video's pixels
     * (trial_record_video_calib). Left negative, a replay's tracker took the cropped video's centre. */
    if (cal->principal_px[0] < 0 || cal->principal_px[1] < 0) {
        cal->principal_px[0] = 0.5 * (*width - 1);
        cal->principal_px[1] = 0.5 * (*height - 1);
    }
    trial_roi full = {0, 0, *width & ~1, *height & ~1};
    *roi = full;
    if (cfg->camera.roi == RIG_ROI_AUTO)
        *roi = trial_roi_auto(cal, *width, *height, cfg->scene.length * 1000.0, cfg->scene.compression,
                              cfg->camera.margin_px);
    else if (cfg->camera.roi == RIG_ROI_RECT) {
        trial_roi r = {cfg->camera.roi_x, cfg->camera.roi_y, cfg->camera.roi_w, cfg->camera.roi_h};
        *roi = trial_roi_clip(r, *width, *height);
    }
    return 0;
}
