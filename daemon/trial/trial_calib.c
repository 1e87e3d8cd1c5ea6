/* trial_calib.c: the calibration record kept with each trial (see trial_calib.h). */
#include "trial_calib.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "twin_camera.h"

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

static json_t *darray(const double *v, size_t n)
{
    json_t *a = json_array();
    for (size_t k = 0; k < n; k++) json_array_append_new(a, json_real(v[k]));
    return a;
}

char *trial_calib_json(const rig_config *cfg, const vis_calib *cal, trial_roi roi, char *why, size_t why_len)
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
    json_object_set_new(root, "compression", json_real(cfg->scene.compression));
    json_object_set_new(root, "min_quality", json_real(cfg->detect.min_quality));
    json_object_set_new(root, "fold_angle_deg", json_real(cfg->scene.fold_angle_deg));
    json_object_set_new(root, "fold_position", json_real(cfg->scene.fold_position));
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
    out->camera.has_intrinsics = json_is_true(json_object_get(cam, "has_intrinsics"));
    out->calib.compress_sign = cs < 0 ? -1 : 1;
    out->calib.shear_sign = ss < 0 ? -1 : 1;
    out->calib.camera_side = side && strcmp(side, "back") == 0 ? RIG_CAMERA_BACK : RIG_CAMERA_FRONT;
    out->roi.x = (int)roi[0];
    out->roi.y = (int)roi[1];
    out->roi.w = (int)roi[2];
    out->roi.h = (int)roi[3];
    out->snap.settle_frames = snap_params_default().settle_frames;
    rc = 0;
done:
    json_decref(root);
    return rc;
}

/* Appends the file's text (or a note that it could not be read) to a growing buffer. */
static int append_file(char **buf, size_t *len, size_t *cap, const char *label, const char *path)
{
    FILE *f = fopen(path, "rb");
    char head[1200];
    int hn = snprintf(head, sizeof head, "# %s %s\n", label, path);
    size_t need = (size_t)hn + 1;
    long size = 0;
    if (f && fseek(f, 0, SEEK_END) == 0) size = ftell(f);
    if (size < 0 || size > (1 << 20)) size = 0;
    if (f) rewind(f);
    need += (size_t)size + 64;
    if (*len + need > *cap) {
        size_t nc = (*len + need) * 2;
        char *nb = realloc(*buf, nc);
        if (!nb) {
            if (f) fclose(f);
            return -1;
        }
        *buf = nb;
        *cap = nc;
    }
    memcpy(*buf + *len, head, (size_t)hn);
    *len += (size_t)hn;
    if (!f) {
        *len += (size_t)snprintf(*buf + *len, 64, "# (could not be read)\n");
    } else {
        *len += fread(*buf + *len, 1, (size_t)size, f);
        fclose(f);
        if (*len > 0 && (*buf)[*len - 1] != '\n') (*buf)[(*len)++] = '\n';
    }
    (*buf)[*len] = '\0';
    return 0;
}

char *trial_config_text(const rig_config *cfg, const char *note)
{
    char *buf = NULL;
    size_t len = 0, cap = 0;
    if (append_file(&buf, &len, &cap, "rig file", cfg->path) ||
        append_file(&buf, &len, &cap, "scene file", cfg->scene_path)) {
        free(buf);
        return NULL;
    }
    if (note && *note) {
        size_t n = strlen(note) + 16;
        char *nb = realloc(buf, len + n + 1);
        if (!nb) {
            free(buf);
            return NULL;
        }
        buf = nb;
        snprintf(buf + len, n + 1, "# note: %s\n", note);
    }
    return buf;
}

void trial_state_times(store *st, int64_t id, double *t_check, double *t_shear, double *t_return)
{
    *t_check = *t_shear = *t_return = NAN;
    store_event *ev = NULL;
    size_t n = 0;
    char why[256];
    if (store_events_get(st, id, &ev, &n, why, sizeof why) != STORE_OK) return;
    for (size_t k = 0; k < n; k++) {
        if (ev[k].kind != STORE_EVENT_STATE) continue;
        if (!strncmp(ev[k].message, "state checking", 14) && isnan(*t_check)) *t_check = ev[k].t_s;
        if (!strncmp(ev[k].message, "state shearing", 14) && isnan(*t_shear)) *t_shear = ev[k].t_s;
        if (!strncmp(ev[k].message, "state returning", 15) && isnan(*t_return)) *t_return = ev[k].t_s;
    }
    free(ev);
}

void trial_specimen_from_config(const rig_config *cfg, store_specimen *sp)
{
    *sp = store_specimen_default();
    snprintf(sp->name, sizeof sp->name, "%s", cfg->specimen.name[0] ? cfg->specimen.name : "unnamed");
    sp->length_m = cfg->scene.length;
    sp->width_m = cfg->scene.width;
    sp->thickness_m = cfg->scene.thickness;
    sp->youngs_modulus_pa = cfg->scene.youngs_modulus;
    sp->density_kg_m3 = cfg->scene.density;
    snprintf(sp->material, sizeof sp->material, "%.31s", cfg->specimen.material);
    sp->crease_angle_left_deg = cfg->specimen.crease_angle_left_deg;
    sp->crease_angle_right_deg = cfg->specimen.crease_angle_right_deg;
    sp->fold_position = cfg->scene.fold_position;
    snprintf(sp->crease_orientation, sizeof sp->crease_orientation, "%s",
             cfg->specimen.crease_orientation == RIG_CREASE_UP     ? "up"
             : cfg->specimen.crease_orientation == RIG_CREASE_DOWN ? "down"
                                                                   : "");
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
