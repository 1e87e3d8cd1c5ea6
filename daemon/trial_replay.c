/* trial_replay.c: replay of a recorded trial (see trial_replay.h). */
#include "trial_replay.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "snap_detect.h"
#include "trial_calib.h"
#include "vision.h"

static void add_event(store *st, int64_t id, double t, store_event_kind kind, const char *msg)
{
    store_event ev;
    memset(&ev, 0, sizeof ev);
    ev.trial_id = id;
    ev.t_s = t;
    ev.wall_s = store_wall_now();
    ev.kind = kind;
    snprintf(ev.state, sizeof ev.state, "replay");
    snprintf(ev.message, sizeof ev.message, "%s", msg);
    char why[256];
    store_event_append(st, &ev, why, sizeof why);
}

int trial_replay_run(store *st, int64_t source_id, const char *video, int64_t *new_id, trial_result *res,
                     void (*progress)(void *u, long frame, long total), void *u, char *why, size_t why_len)
{
    memset(res, 0, sizeof *res);
    snprintf(res->regime, sizeof res->regime, "no snap");
    *new_id = 0;
    store_trial src;
    if (store_trial_get(st, source_id, &src, why, why_len) != STORE_OK) return -1;
    char *config = NULL, *calib = NULL;
    if (store_trial_texts(st, source_id, &config, &calib, why, why_len) != STORE_OK) return -1;
    trial_record rec;
    int rc = -1;
    store_sample *smp = NULL;
    size_t ns = 0;
    vis_source *vs = NULL;
    vis_tracker *trk = NULL;
    vis_frame *frame = NULL;
    store_samples *w = NULL;
    char *text = NULL;
    if (trial_record_parse(calib, &rec, why, why_len)) goto done;
    if (!video || !*video) video = src.video_path;
    if (!*video) {
        snprintf(why, why_len, "trial %lld has no video to replay", (long long)source_id);
        goto done;
    }
    if (store_samples_get(st, source_id, &smp, &ns, why, why_len) != STORE_OK) goto done;
    vis_error ve = {0};
    vs = vis_source_open_video(video, &ve);
    if (!vs) {
        snprintf(why, why_len, "video %s: %s", video, ve.message);
        goto done;
    }
    /* The tracker sees the cropped frames: move the calibration into the region's pixels. */
    vis_calib cal = rec.camera;
    cal.clamp_left_px[0] -= rec.roi.x;
    cal.clamp_left_px[1] -= rec.roi.y;
    cal.clamp_right_px[0] -= rec.roi.x;
    cal.clamp_right_px[1] -= rec.roi.y;
    if (cal.principal_px[0] >= 0) {
        cal.principal_px[0] -= rec.roi.x;
        cal.principal_px[1] -= rec.roi.y;
    }
    if (cal.has_intrinsics) {
        cal.camera_matrix[2] -= rec.roi.x;
        cal.camera_matrix[5] -= rec.roi.y;
    }
    vis_track_params tp = vis_track_params_default();
    tp.length_mm = rec.length_m * 1000.0;
    trk = vis_tracker_create(&tp, &cal, &ve);
    frame = vis_frame_alloc(16, 16, 1, &ve);
    if (!trk || !frame) {
        snprintf(why, why_len, "tracker: %s", ve.message);
        goto done;
    }
    /* The new trial. */
    size_t tl = (config ? strlen(config) : 0) + 64;
    text = malloc(tl);
    if (!text) {
        snprintf(why, why_len, "out of memory");
        goto done;
    }
    snprintf(text, tl, "%s# replay of trial %lld\n", config ? config : "", (long long)source_id);
    store_trial_def def = store_trial_def_default();
    def.mode = STORE_MODE_REPLAY;
    def.config_text = text;
    def.calibration_json = calib;
    def.specimen_id = src.specimen_id;
    def.source_trial_id = source_id;
    def.video_path = video;
    def.created_wall_s = store_wall_now();
    if (store_trial_create(st, &def, new_id, why, why_len) != STORE_OK) goto done;
    char w2[256];
    store_trial_set_status(st, *new_id, STORE_STATUS_RUNNING, NULL, store_wall_now(), w2, sizeof w2);
    if (store_samples_begin(st, *new_id, NULL, &w, why, why_len) != STORE_OK) goto fail;
    double t_check, t_shear, t_return;
    trial_state_times(st, source_id, &t_check, &t_shear, &t_return);
    snap_detect det;
    snap_detect_init(&det, &rec.snap);
    long total = vis_source_frame_count(vs);
    size_t next = 0;
    int reset_done = 0;
    for (long f = 0;; f++) {
        vis_status s = vis_source_read(vs, frame, NULL, &ve);
        if (s == VIS_ERR_END) break;
        if (s != VIS_OK) {
            snprintf(why, why_len, "video %s: %s", video, ve.message);
            goto fail;
        }
        /* This frame's recorded rail positions. */
        while (next < ns && !(smp[next].kind == STORE_SAMPLE_FRAME && smp[next].frame >= f)) next++;
        if (next >= ns || smp[next].frame != f) {
            snprintf(why, why_len, "frame %ld of the video has no recorded rail positions", f);
            goto fail;
        }
        const store_sample *r = &smp[next];
        if (!reset_done && isfinite(t_check) && r->t_s >= t_check) {
            vis_tracker_reset(trk);
            reset_done = 1;
        }
        vis_measure m;
        if (vis_tracker_process(trk, frame, r->dw * rec.length_m * 1000.0, &m, &ve) != VIS_OK) {
            snprintf(why, why_len, "tracker: %s", ve.message);
            goto fail;
        }
        int measured = m.reason == VIS_REASON_NONE && m.quality >= rec.min_quality && isfinite(m.dz) &&
                       isfinite(m.a);
        double a = rig_calib_a_sign(&rec.calib) * m.a;
        store_sample x = store_sample_default();
        x.t_s = r->t_s;
        x.kind = STORE_SAMPLE_FRAME;
        x.frame = f;
        x.compress_mm = r->compress_mm;
        x.shear_mm = r->shear_mm;
        x.dl = r->dl;
        x.dw = r->dw;
        x.quality = isfinite(m.quality) ? m.quality : 0.0;
        if (measured) {
            x.dz = m.dz;
            x.a = a;
            res->measured_frames++;
        } else {
            snprintf(x.reason, sizeof x.reason, "%s",
                     m.reason == VIS_REASON_NONE ? "low quality" : vis_reason_str(m.reason));
        }
        if (store_samples_add(w, &x, why, why_len) != STORE_OK) goto fail;
        res->frames++;
        int in_shear = isfinite(t_shear) ? (r->t_s >= t_shear && (!isfinite(t_return) || r->t_s < t_return)) : 1;
        if (in_shear) snap_detect_add(&det, f, r->t_s, r->dw, x.dz, x.a, measured);
        res->duration_s = r->t_s;
        if (progress && f % 50 == 0) progress(u, f, total);
    }
    if (store_samples_end(w, why, why_len) != STORE_OK) {
        w = NULL;
        goto fail;
    }
    w = NULL;
    res->snapped = snap_detect_snapped(&det);
    res->snap_dw = res->snapped ? snap_detect_dw(&det) : 0.0;
    res->asymmetric = snap_detect_asymmetric(&det);
    res->peak_abs_a = det.peak_abs_a;
    snprintf(res->regime, sizeof res->regime, "%s", snap_detect_regime(&det));
    store_regime reg = !res->snapped ? STORE_REGIME_NO_SNAP
                       : res->asymmetric ? STORE_REGIME_ASYMMETRIC
                                         : STORE_REGIME_SYMMETRIC;
    store_trial_set_result(st, *new_id, res->snapped, res->snapped ? res->snap_dw : NAN, reg, w2, sizeof w2);
    char msg[256];
    snprintf(msg, sizeof msg, "replayed %ld frames of trial %lld: %s at Delta W = %.5f (source: %.5f)", res->frames,
             (long long)source_id, res->regime, res->snap_dw, src.snap_dw_measured);
    add_event(st, *new_id, res->duration_s, STORE_EVENT_INFO, msg);
    store_trial_set_status(st, *new_id, STORE_STATUS_DONE, NULL, store_wall_now(), w2, sizeof w2);
    res->final = TRIAL_DONE;
    rc = 0;
    goto done;
fail:
    if (w) {
        store_samples_end(w, w2, sizeof w2);
        w = NULL;
    }
    if (*new_id) {
        add_event(st, *new_id, NAN, STORE_EVENT_FAULT, why);
        store_trial_set_status(st, *new_id, STORE_STATUS_FAILED, why, store_wall_now(), w2, sizeof w2);
    }
    res->final = TRIAL_FAILED;
    snprintf(res->reason, sizeof res->reason, "%s", why);
done:
    free(text);
    free(smp);
    free(config);
    free(calib);
    vis_frame_free(frame);
    vis_tracker_free(trk);
    if (vs) vis_source_close(vs);
    return rc;
}
