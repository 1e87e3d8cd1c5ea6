/* trial_record.c: the record kept with each trial so that it can be understood and replayed
 * without the rig file (see trial_record.h): written as JSON at the trial's creation, parsed back
 * by replay, and the camera calibration moved into the saved video's pixels. */
#include "trial_record.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

static json_t *darray(const double *v, size_t n)
{
    json_t *a = json_array();
    for (size_t k = 0; k < n; k++) json_array_append_new(a, json_real(v[k]));
    return a;
}

char *trial_record_json(const rig_config *cfg, const vis_calib *cal, trial_roi roi, char *why, size_t why_len)
{
    char *rig = rig_calibration_json(cfg);
    json_error_t je;
    json_t *root = rig ? json_loads(rig, 0, &je) : NULL;
    free(rig);
    if (!root) {
        snprintf(why, why_len, "calibration record: out of memory");
        return NULL;
    }
    json_t *cam = json_pack("{s:f, s:o, s:o, s:o, s:f, s:f, s:b, s:o, s:o}", "px_per_mm", cal->px_per_mm,
                            "clamp_left_px", darray(cal->clamp_left_px, 2), "clamp_right_px",
                            darray(cal->clamp_right_px, 2), "principal_px", darray(cal->principal_px, 2),
                            "camera_distance_mm", cal->camera_distance_mm, "camera_tilt_rad", cal->camera_tilt_rad,
                            "has_intrinsics", cal->has_intrinsics, "camera_matrix", darray(cal->camera_matrix, 9),
                            "dist", darray(cal->dist, 5));
    json_t *r = json_pack("[iiii]", roi.x, roi.y, roi.w, roi.h);
    json_t *snap = json_pack("{s:f, s:f, s:f, s:f}", "snap_speed", cfg->scene.snap_speed, "dz_jump",
                             cfg->detect.dz_jump, "asym_threshold", cfg->scene.asym_threshold, "post_snap_s",
                             cfg->trial.post_snap_s);
    if (!cam || !r || !snap) {
        json_decref(cam);
        json_decref(r);
        json_decref(snap);
        json_decref(root);
        snprintf(why, why_len, "calibration record: out of memory");
        return NULL;
    }
    json_object_set_new(root, "camera", cam);
    json_object_set_new(root, "roi", r);
    json_object_set_new(root, "snap", snap);
    json_object_set_new(root, "fps", json_real(cfg->camera.fps));
    json_object_set_new(root, "length_m", json_real(cfg->scene.length));
    json_object_set_new(root, "width_m", json_real(cfg->scene.width)); /* sizes a replay's tracker */
    json_object_set_new(root, "compression", json_real(cfg->scene.compression));
    json_object_set_new(root, "min_quality", json_real(cfg->detect.min_quality));
    json_object_set_new(root, "fold_angle_deg", json_real(cfg->scene.fold_angle_deg));
    json_object_set_new(root, "fold_position", json_real(cfg->scene.fold_position));
    /* The crease model (folds.hinge_stiffness, N m/rad, or "rigid"): the trial's prediction ran it
     * (its row keeps the same beside the creases it used). */
    json_object_set_new(root, "fold_hinge_stiffness", rod_scene_hinge_rigid(&cfg->scene)
                                                          ? json_string("rigid")
                                                          : json_real(cfg->scene.fold_hinge_stiffness));
    char *text = json_dumps(root, JSON_COMPACT | JSON_REAL_PRECISION(17));
    json_decref(root);
    if (!text) snprintf(why, why_len, "calibration record: out of memory");
    return text;
}

static int num(json_t *o, const char *key, double *out, char *why, size_t why_len)
{
    json_t *v = json_object_get(o, key);
    if (!json_is_number(v)) {
        snprintf(why, why_len, "calibration record: \"%s\" missing or not a number", key);
        return -1;
    }
    *out = json_number_value(v);
    return 0;
}

static int nums(json_t *o, const char *key, double *out, size_t n, char *why, size_t why_len)
{
    json_t *a = json_object_get(o, key);
    if (!json_is_array(a) || json_array_size(a) != n) {
        snprintf(why, why_len, "calibration record: \"%s\" must be an array of %zu numbers", key, n);
        return -1;
    }
    for (size_t k = 0; k < n; k++) {
        json_t *v = json_array_get(a, k);
        if (!json_is_number(v)) {
            snprintf(why, why_len, "calibration record: \"%s\"[%zu] is not a number", key, k);
            return -1;
        }
        out[k] = json_number_value(v);
    }
    return 0;
}

int trial_record_parse(const char *text, trial_record *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    if (!text) {
        snprintf(why, why_len, "the trial has no calibration record");
        return -1;
    }
    json_error_t je;
    json_t *root = json_loads(text, 0, &je);
    if (!root) {
        snprintf(why, why_len, "calibration record: %s (line %d, column %d)", je.text, je.line, je.column);
        return -1;
    }
    int rc = -1;
    double cs = 1, ss = 1, roi[4], h = 0;
    json_t *cam = json_object_get(root, "camera"), *snap = json_object_get(root, "snap");
    const char *side = json_string_value(json_object_get(root, "camera_side"));
    if (!json_is_object(cam) || !json_is_object(snap)) {
        snprintf(why, why_len, "calibration record: no camera or snap settings (recorded by an older version?)");
        goto done;
    }
    if (num(root, "compress_zero_mm", &out->calib.compress_zero_mm, why, why_len) ||
        num(root, "shear_zero_mm", &out->calib.shear_zero_mm, why, why_len) ||
        num(root, "compress_sign", &cs, why, why_len) || num(root, "shear_sign", &ss, why, why_len) ||
        num(root, "camera_time_offset_s", &out->calib.camera_time_offset_s, why, why_len) ||
        num(root, "fps", &out->fps, why, why_len) || num(root, "length_m", &out->length_m, why, why_len) ||
        num(root, "compression", &out->compression, why, why_len) ||
        num(root, "min_quality", &out->min_quality, why, why_len) || nums(root, "roi", roi, 4, why, why_len) ||
        num(cam, "px_per_mm", &out->camera.px_per_mm, why, why_len) ||
        nums(cam, "clamp_left_px", out->camera.clamp_left_px, 2, why, why_len) ||
        nums(cam, "clamp_right_px", out->camera.clamp_right_px, 2, why, why_len) ||
        nums(cam, "principal_px", out->camera.principal_px, 2, why, why_len) ||
        num(cam, "camera_distance_mm", &out->camera.camera_distance_mm, why, why_len) ||
        num(cam, "camera_tilt_rad", &out->camera.camera_tilt_rad, why, why_len) ||
        nums(cam, "camera_matrix", out->camera.camera_matrix, 9, why, why_len) ||
        nums(cam, "dist", out->camera.dist, 5, why, why_len) ||
        num(snap, "snap_speed", &out->snap.snap_speed, why, why_len) ||
        num(snap, "dz_jump", &out->snap.dz_jump, why, why_len) ||
        num(snap, "asym_threshold", &out->snap.asym_threshold, why, why_len) ||
        num(snap, "post_snap_s", &out->snap.post_snap_s, why, why_len))
        goto done;
    (void)h;
    /* Optional: records from before it was kept have no width (their replays keep the tracker's
     * defaults). */
    json_t *wv = json_object_get(root, "width_m");
    out->width_m = json_is_number(wv) && json_number_value(wv) > 0 ? json_number_value(wv) : 0.0;
    out->camera.has_intrinsics = json_is_true(json_object_get(cam, "has_intrinsics"));
    out->calib.compress_sign = cs < 0 ? -1 : 1;
    out->calib.shear_sign = ss < 0 ? -1 : 1;
    out->calib.camera_side = side && strcmp(side, "back") == 0 ? RIG_CAMERA_BACK : RIG_CAMERA_FRONT;
    out->roi.x = (int)roi[0];
    out->roi.y = (int)roi[1];
    out->roi.w = (int)roi[2];
    out->roi.h = (int)roi[3];
    /* Not in the record: the detector's own settings (the departure's since issue 35 D). */
    snap_params dflt = snap_params_default();
    out->snap.settle_frames = dflt.settle_frames;
    out->snap.depart_frac = dflt.depart_frac;
    out->snap.depart_min_dz = dflt.depart_min_dz;
    out->snap.depart_at = dflt.depart_at;
    out->snap.depart_asym = dflt.depart_asym;
    out->snap.depart_sym = dflt.depart_sym;
    out->snap.peak_margin = dflt.peak_margin;
    rc = 0;
done:
    json_decref(root);
    return rc;
}

void trial_record_video_calib(const trial_record *rec, vis_calib *out)
{
    *out = rec->camera;
    out->clamp_left_px[0] -= rec->roi.x;
    out->clamp_left_px[1] -= rec->roi.y;
    out->clamp_right_px[0] -= rec->roi.x;
    out->clamp_right_px[1] -= rec->roi.y;
    if (out->principal_px[0] >= 0) {
        out->principal_px[0] -= rec->roi.x;
        out->principal_px[1] -= rec->roi.y;
    }
    if (out->has_intrinsics) {
        out->camera_matrix[2] -= rec->roi.x;
        out->camera_matrix[5] -= rec->roi.y;
    }
}

store_regime trial_regime_of(int snapped, int seen_by_camera, int asymmetric)
{
    return !snapped          ? STORE_REGIME_NO_SNAP
           : !seen_by_camera ? STORE_REGIME_UNKNOWN
           : asymmetric      ? STORE_REGIME_ASYMMETRIC
                             : STORE_REGIME_SYMMETRIC;
}

vis_track_params trial_record_track_params(const trial_record *rec, const vis_calib *video_cal)
{
    vis_track_params tp = vis_track_params_for_ribbon(rec->width_m * 1000.0, video_cal->px_per_mm);
    tp.length_mm = rec->length_m * 1000.0;
    return tp;
}
