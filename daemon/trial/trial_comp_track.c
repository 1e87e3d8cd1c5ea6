/* trial_comp_track.c: the compression frames' calibration and their measurement
 * (trial_comp_track.h). */
#include "trial_comp_track.h"

#include <math.h>
#include <string.h>

double trial_comp_track_from_dl(double compression)
{
    return fmax(0.5 * compression, compression - 0.05);
}

int trial_comp_track_calib(const vis_calib *base, rig_camera_side side, double length_m, double dl_target,
                           double dl, vis_calib *out)
{
    if (!base || !out || !(base->px_per_mm > 0.0) || !(length_m > 0.0) || !isfinite(dl_target) || !isfinite(dl) ||
        dl > dl_target + 1e-9)
        return -1;
    const double *fixed = side == RIG_CAMERA_BACK ? base->clamp_right_px : base->clamp_left_px;
    const double *moving = side == RIG_CAMERA_BACK ? base->clamp_left_px : base->clamp_right_px;
    double du = moving[0] - fixed[0], dv = moving[1] - fixed[1];
    double d = hypot(du, dv);
    if (!(d > 0.0)) return -1;
    double shift_px = 1000.0 * length_m * (dl_target - dl) * base->px_per_mm;
    vis_calib c = *base;
    double *mv = side == RIG_CAMERA_BACK ? c.clamp_left_px : c.clamp_right_px;
    mv[0] = moving[0] + shift_px * du / d;
    mv[1] = moving[1] + shift_px * dv / d;
    *out = c;
    return 0;
}

vis_status trial_comp_track_measure(const vis_track_params *tp, const vis_calib *base, rig_camera_side side,
                                    double length_m, double dl_target, double dl, const vis_frame *f,
                                    vis_measure *m, vis_error *err)
{
    return trial_comp_track_measure_curve(tp, base, side, length_m, dl_target, dl, f, m, NULL, 0, NULL, NULL, err);
}

vis_status trial_comp_track_measure_curve(const vis_track_params *tp, const vis_calib *base, rig_camera_side side,
                                          double length_m, double dl_target, double dl, const vis_frame *f,
                                          vis_measure *m, double *uv, size_t max_uv, size_t *n_uv, vis_calib *cal_out,
                                          vis_error *err)
{
    memset(m, 0, sizeof *m);
    if (n_uv) *n_uv = 0;
    vis_calib cal;
    if (trial_comp_track_calib(base, side, length_m, dl_target, dl, &cal)) {
        m->reason = VIS_REASON_CLAMP_NOT_FOUND;
        return VIS_OK;
    }
    if (cal_out) *cal_out = cal;
    vis_tracker *t = vis_tracker_create(tp, &cal, err);
    if (!t) return err && err->code ? err->code : VIS_ERR_ARG;
    vis_status vs = vis_tracker_process(t, f, 0.0, m, err);
    if (vs == VIS_OK && uv && n_uv && m->reason == VIS_REASON_NONE) {
        size_t n = vis_tracker_samples(t, uv, max_uv);
        *n_uv = n > max_uv ? max_uv : n;
    }
    vis_tracker_free(t);
    return vs;
}
