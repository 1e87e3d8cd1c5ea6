/* trial_replay.c: replay of a recording, stored or outside (see trial_replay.h). */
#include "trial_replay.h"
#include "cfg_ini.h"
#include "cfg_number.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <jansson.h>

#include "replay_rails_csv.h"
#include "snap_detect.h"
#include "trial_comp_track.h"
#include "trial_config_text.h"
#include "trial_publish.h"
#include "trial_record.h"
#include "trial_specimen.h"
#include "vision.h"

#define REPLAY_SHEAR_START_MM 0.05

struct trial_replay {
    char video[RIG_PATH_MAX];
    trial_record rec;
    char *calib_json;
    char *config_text;
    int64_t source_id;
    store_trial src;       /* the stored trial replayed (from_trial) */
    double source_snap_dw; /* NaN = none */
    int64_t specimen_id;
    store_specimen specimen; /* files: recorded when the trial is created */
    int has_specimen;
    /* A stored trial's frame samples. */
    store_sample *smp;
    size_t ns, next;
    /* An outside recording's rail readings. */
    rail_reading *rails;
    size_t nr, at;
    double fps, t_offset;
    double *frame_t;   /* an outside video's per-frame times (VIDEO.frames.csv), from its first frame; NULL = f / fps */
    long n_frame_t;
    double t_check, t_shear, t_return; /* NaN = none */
    long frames_total;
    int64_t new_id;
    char note[256];
    live_bus *bus; /* NULL: nothing published */
};

void trial_replay_set_bus(trial_replay *r, live_bus *bus) { r->bus = bus; }

void trial_replay_free(trial_replay *r)
{
    if (!r) return;
    free(r->calib_json);
    free(r->config_text);
    free(r->smp);
    free(r->rails);
    free(r->frame_t);
    free(r);
}

int64_t trial_replay_source(const trial_replay *r) { return r->source_id; }
long trial_replay_frame_count(const trial_replay *r) { return r->frames_total; }
const char *trial_replay_video(const trial_replay *r) { return r->video; }

static trial_replay *replay_new(char *why, size_t why_len)
{
    trial_replay *r = calloc(1, sizeof *r);
    if (!r) {
        snprintf(why, why_len, "out of memory");
        return NULL;
    }
    r->source_snap_dw = NAN;
    r->t_check = r->t_shear = r->t_return = NAN;
    r->frames_total = -1;
    return r;
}

/* "video PATH: reason" from a vision error: its message as it is when it names the video already,
 * and never an empty reason (issue 33). */
static void video_why(char *why, size_t why_len, const char *path, const char *msg)
{
    if (!strncmp(msg, "video ", 6)) snprintf(why, why_len, "%s", msg);
    else snprintf(why, why_len, "video %.300s: %s", path, msg[0] ? msg : "cannot be read (no reason given)");
}

static int check_video_belongs(trial_replay *r, char *why, size_t why_len);

int trial_replay_from_trial(store *st, int64_t source_id, const char *video, trial_replay **out, char *why,
                            size_t why_len)
{
    *out = NULL;
    trial_replay *r = replay_new(why, why_len);
    if (!r) return -1;
    store_trial src;
    char *config = NULL;
    if (store_trial_get(st, source_id, &src, why, why_len) != STORE_OK ||
        store_trial_texts(st, source_id, &config, &r->calib_json, why, why_len) != STORE_OK)
        goto fail;
    /* Issue 33, item 4: a trial that has not ended is still writing its video and samples. */
    if (src.status == STORE_STATUS_CREATED || src.status == STORE_STATUS_RUNNING) {
        snprintf(why, why_len, "trial %lld is not finished (status %s%s%s): only a finished trial can be replayed; "
                 "wait for its end or abort it first", (long long)source_id, store_status_name(src.status),
                 src.state[0] ? ", state " : "", src.state);
        free(config);
        trial_replay_free(r);
        return TRIAL_REPLAY_UNFINISHED;
    }
    r->src = src;
    r->source_id = source_id;
    r->specimen_id = src.specimen_id;
    if (src.snapped) r->source_snap_dw = src.snap_dw_measured;
    if (!r->calib_json) {
        snprintf(why, why_len, "trial %lld has no calibration record to replay with", (long long)source_id);
        goto fail;
    }
    if (trial_record_parse(r->calib_json, &r->rec, why, why_len)) goto fail;
    if (!video || !*video) video = src.video_path;
    if (!*video) {
        snprintf(why, why_len, "trial %lld has no video to replay", (long long)source_id);
        goto fail;
    }
    snprintf(r->video, sizeof r->video, "%s", video);
    /* A raw video transcoded by hand (ribbonctl transcode) left the store naming the .avi. */
    size_t vl = strlen(r->video);
    if (vl > 4 && strcmp(r->video + vl - 4, ".avi") == 0 && access(r->video, F_OK) != 0 &&
        vl < sizeof r->video) {
        char mkv[sizeof r->video];
        snprintf(mkv, sizeof mkv, "%.*s.mkv", (int)(vl - 4), r->video);
        if (access(mkv, F_OK) == 0) snprintf(r->video, sizeof r->video, "%s", mkv);
    }
    size_t tl = (config ? strlen(config) : 0) + 64;
    r->config_text = malloc(tl);
    if (!r->config_text) {
        snprintf(why, why_len, "out of memory");
        goto fail;
    }
    snprintf(r->config_text, tl, "%s# replay of trial %lld\n", config ? config : "", (long long)source_id);
    if (store_samples_get(st, source_id, &r->smp, &r->ns, why, why_len) != STORE_OK) goto fail;
    if (check_video_belongs(r, why, why_len)) goto fail;
    store_events_state_times(st, source_id, &r->t_check, &r->t_shear, &r->t_return);
    free(config);
    *out = r;
    return 0;
fail:
    free(config);
    trial_replay_free(r);
    return -1;
}

/* The video must be the trial's (issue 17, item 12: any video was accepted): its frames the size
 * of the recorded region of interest, and, when its container gives a count, as many frames as the
 * trial stored frame samples. A video shorter than the store says (cut by a kill or a full disk)
 * is refused here too, never replayed as if whole. */
static int check_video_belongs(trial_replay *r, char *why, size_t why_len)
{
    long recorded = 0, last = -1;
    for (size_t k = 0; k < r->ns; k++)
        if (r->smp[k].kind == STORE_SAMPLE_FRAME && r->smp[k].frame > last) {
            recorded++;
            last = r->smp[k].frame;
        }
    vis_error ve = {0};
    vis_source *vs = vis_source_open_video(r->video, &ve);
    vis_frame *frame = vs ? vis_frame_alloc(16, 16, 1, &ve) : NULL;
    int rc = -1;
    if (!vs || !frame) {
        video_why(why, why_len, r->video, ve.message);
    } else if (vis_source_read(vs, frame, NULL, &ve) != VIS_OK) {
        snprintf(why, why_len, "video %.300s: no first frame: %s", r->video, ve.message);
    } else if (r->rec.roi.w > 0 && r->rec.roi.h > 0 &&
               (vis_frame_width(frame) != r->rec.roi.w || vis_frame_height(frame) != r->rec.roi.h)) {
        snprintf(why, why_len, "video %.300s has %dx%d frames; trial %lld recorded %dx%d: not this trial's video",
                 r->video, vis_frame_width(frame), vis_frame_height(frame), (long long)r->source_id,
                 r->rec.roi.w, r->rec.roi.h);
    } else if (r->src.mode == STORE_MODE_REPLAY && r->src.source_trial_id > 0 && recorded > 0 &&
               vis_source_frame_count(vs) > last + 1) {
        /* A replay that ended early (aborted, failed) measured only the start of its source's video. */
        snprintf(why, why_len, "trial %lld is a replay of trial %lld that ended %s after %ld of the video's %d frames: "
                 "it measured only part of %.300s; replay trial %lld instead", (long long)r->source_id,
                 (long long)r->src.source_trial_id, store_status_name(r->src.status), last + 1,
                 vis_source_frame_count(vs), r->video, (long long)r->src.source_trial_id);
    } else if (vis_source_frame_count(vs) > 0 && recorded > 0 && vis_source_frame_count(vs) != last + 1) {
        snprintf(why, why_len, "video %.300s has %d frames; trial %lld recorded %ld (frames 0..%ld): %s",
                 r->video, vis_source_frame_count(vs), (long long)r->source_id, recorded, last,
                 vis_source_frame_count(vs) < last + 1 ? "the video is incomplete" : "not this trial's video");
    } else {
        r->frames_total = vis_source_frame_count(vs);
        rc = 0;
    }
    vis_frame_free(frame);
    vis_source_close(vs);
    return rc;
}

/* Reads the rails CSV (replay_rails_csv.h) into r->rails. */
static int read_rails(trial_replay *r, const char *path, char *why, size_t why_len)
{
    char open_why[160];
    FILE *f = cfg_open_regular(path, open_why, sizeof open_why);
    if (!f) {
        snprintf(why, why_len, "rails CSV %.300s: %s", path, open_why);
        return -1;
    }
    int rc = replay_rails_csv_read(f, path, &r->rails, &r->nr, why, why_len);
    fclose(f);
    return rc;
}

/* An outside video's frame-times file (VIDEO.frames.csv, as rig mode's recorder writes it:
 * video_frame,capture_index,camera_id,camera_t_s,host_t_s,t_s): each frame's time, taken from its
 * first frame (the video's frame 0 is at t = 0, as f / fps would put it). No file: 0 and f / fps.
 * A transcoded rig video (NAME.mkv, trial_transcode.h) keeps its recording's file, NAME.avi.frames.csv. */
static int read_frame_times(trial_replay *r, char *why, size_t why_len)
{
    char path[RIG_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s.frames.csv", r->video);
    FILE *f = fopen(path, "r");
    size_t vl = strlen(r->video);
    if (!f && vl > 4 && strcmp(r->video + vl - 4, ".mkv") == 0) {
        snprintf(path, sizeof path, "%.*s.avi.frames.csv", (int)(vl - 4), r->video);
        f = fopen(path, "r");
    }
    if (!f) return 0;
    char line[512];
    long n = 0, cap = 0, ln = 0;
    double t0 = NAN;
    int rc = 0;
    while (fgets(line, sizeof line, f)) {
        ln++;
        if (ln == 1 && strncmp(line, "video_frame", 11) == 0) continue;
        long vf, ci;
        unsigned long long id;
        double cam, host, t;
        char tail;
        if (sscanf(line, "%ld,%ld,%llu,%lf,%lf,%lf %c", &vf, &ci, &id, &cam, &host, &t, &tail) != 6 || vf != n ||
            !isfinite(t) || (n > 0 && !(t - t0 > r->frame_t[n - 1]))) {
            snprintf(why, why_len,
                     "frame times %.300s line %ld: not \"video_frame,capture_index,camera_id,camera_t_s,host_t_s,t_s\" "
                     "for frame %ld with its time after the previous frame's",
                     path, ln, n);
            rc = -1;
            break;
        }
        if (n == cap) {
            cap = cap ? 2 * cap : 1024;
            double *x = realloc(r->frame_t, (size_t)cap * sizeof *x);
            if (!x) {
                snprintf(why, why_len, "out of memory");
                rc = -1;
                break;
            }
            r->frame_t = x;
        }
        if (n == 0) t0 = t;
        r->frame_t[n++] = t - t0;
    }
    fclose(f);
    if (rc == 0 && n == 0) {
        snprintf(why, why_len, "frame times %.300s: no frame", path);
        rc = -1;
    }
    r->n_frame_t = rc == 0 ? n : 0;
    return rc;
}

/* Shearing: from the first reading off the first shear position to the reading of largest Delta W. */
static void shear_window(trial_replay *r)
{
    const rig_calibration *c = &r->rec.calib;
    size_t k0 = r->nr, kmax = 0;
    double best = -INFINITY;
    for (size_t k = 0; k < r->nr; k++) {
        if (k0 == r->nr && fabs(r->rails[k].shear_mm - r->rails[0].shear_mm) > REPLAY_SHEAR_START_MM) k0 = k;
        double dw = rig_calib_dw(c, r->rec.length_m, r->rails[k].shear_mm);
        if (dw > best) {
            best = dw;
            kmax = k;
        }
    }
    if (k0 < r->nr && kmax > k0) {
        r->t_check = r->t_shear = r->rails[k0 - (k0 > 0)].t;
        r->t_return = r->rails[kmax].t;
    }
}

int trial_replay_from_files(const rig_config *cfg, trial_replay **out, char *why, size_t why_len)
{
    *out = NULL;
    if (cfg->mode != RIG_MODE_REPLAY || !cfg->replay.video[0] || !cfg->replay.rails[0] || !cfg->camera.calibration[0]) {
        snprintf(why, why_len, "a replay of files needs a replay-mode rig file with replay.video, replay.rails and "
                               "camera.calibration");
        return -1;
    }
    trial_replay *r = replay_new(why, why_len);
    if (!r) return -1;
    vis_error ve = {0};
    vis_source *vs = NULL;
    vis_frame *frame = NULL;
    json_t *root = NULL;
    vis_calib cal;
    if (vis_calib_load(&cal, cfg->camera.calibration, &ve) != VIS_OK) {
        snprintf(why, why_len, "camera calibration %.300s: %s", cfg->camera.calibration, ve.message);
        goto fail;
    }
    snprintf(r->video, sizeof r->video, "%s", cfg->replay.video);
    vs = vis_source_open_video_prefetch(r->video, &ve);
    /* Only after a source opened: a frame allocated regardless cleared the open's reason (issue
     * 33: "video PATH: " with nothing after for a text file, /dev/zero, a FIFO, a directory). */
    frame = vs ? vis_frame_alloc(16, 16, 1, &ve) : NULL;
    if (!vs || !frame) {
        video_why(why, why_len, r->video, ve.message);
        goto fail;
    }
    if (vis_source_read(vs, frame, NULL, &ve) != VIS_OK) {
        snprintf(why, why_len, "video %.300s: no first frame: %s", r->video, ve.message);
        goto fail;
    }
    r->frames_total = vis_source_frame_count(vs);
    r->fps = vis_source_fps(vs);
    if (!(r->fps > 0)) r->fps = cfg->camera.fps;
    if (!(r->fps > 0 && isfinite(r->fps))) {
        snprintf(why, why_len, "video %.300s does not give its frame rate; set camera.fps", r->video);
        goto fail;
    }
    /* The record: the rig file's calibration and detection, the whole frame as the region. */
    trial_roi roi = {0, 0, vis_frame_width(frame), vis_frame_height(frame)};
    char *rec = trial_record_json(cfg, &cal, roi, why, why_len);
    json_error_t je;
    root = rec ? json_loads(rec, 0, &je) : NULL;
    free(rec);
    if (!root) goto fail;
    json_object_set_new(root, "fps", json_real(r->fps));
    r->calib_json = json_dumps(root, JSON_COMPACT);
    if (!r->calib_json) {
        snprintf(why, why_len, "out of memory");
        goto fail;
    }
    if (trial_record_parse(r->calib_json, &r->rec, why, why_len)) goto fail;
    r->t_offset = r->rec.calib.camera_time_offset_s;
    if (read_rails(r, cfg->replay.rails, why, why_len)) goto fail;
    if (read_frame_times(r, why, why_len)) goto fail;
    shear_window(r);
    r->config_text = trial_config_text(cfg, NULL, 0, NULL);
    if (!r->config_text) {
        snprintf(why, why_len, "out of memory");
        goto fail;
    }
    trial_specimen_from_config(cfg, &r->specimen);
    r->has_specimen = 1;
    json_decref(root);
    vis_frame_free(frame);
    vis_source_close(vs);
    *out = r;
    return 0;
fail:
    json_decref(root);
    vis_frame_free(frame);
    if (vs) vis_source_close(vs);
    trial_replay_free(r);
    return -1;
}

int trial_replay_create(trial_replay *r, store *st, const char *note, int64_t *new_id, char *why, size_t why_len)
{
    *new_id = 0;
    if (r->has_specimen && store_specimen_upsert(st, &r->specimen, &r->specimen_id, why, why_len) != STORE_OK)
        return -1;
    size_t tl = strlen(r->config_text) + (note ? strlen(note) : 0) + 16;
    char *text = malloc(tl);
    if (!text) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    snprintf(text, tl, "%s%s%s%s", r->config_text, note && *note ? "# note: " : "", note && *note ? note : "",
             note && *note ? "\n" : "");
    store_trial_def def = store_trial_def_default();
    def.mode = STORE_MODE_REPLAY;
    def.config_text = text;
    def.calibration_json = r->calib_json;
    def.specimen_id = r->specimen_id;
    def.source_trial_id = r->source_id;
    def.video_path = r->video;
    def.created_wall_s = store_wall_now();
    store_err e = store_trial_create(st, &def, new_id, why, why_len);
    free(text);
    if (e != STORE_OK) return -1;
    char w[256];
    store_trial_set_status(st, *new_id, STORE_STATUS_RUNNING, NULL, store_wall_now(), w, sizeof w);
    r->new_id = *new_id;
    snprintf(r->note, sizeof r->note, "%s", note ? note : "");
    return 0;
}

static void add_event(store *st, live_bus *bus, int64_t id, double t, store_event_kind kind, const char *msg)
{
    trial_publish_event(bus, id, t, store_event_kind_name(kind), msg);
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

/* Frame f's rail positions into x (t_s, compress_mm, shear_mm, dl, dw). 0 = found, 1 = the
 * recording has none for it (outside files' readings), -1 = error with why. */
static int frame_rails(trial_replay *r, long f, store_sample *x, char *why, size_t why_len)
{
    if (r->smp) {
        while (r->next < r->ns && !(r->smp[r->next].kind == STORE_SAMPLE_FRAME && r->smp[r->next].frame >= f))
            r->next++;
        if (r->next >= r->ns || r->smp[r->next].frame != f) {
            snprintf(why, why_len, "frame %ld of the video has no recorded rail positions", f);
            return -1;
        }
        const store_sample *s = &r->smp[r->next];
        x->t_s = s->t_s;
        x->compress_mm = s->compress_mm;
        x->shear_mm = s->shear_mm;
        x->dl = s->dl;
        x->dw = s->dw;
        return 0;
    }
    if (r->frame_t && f >= r->n_frame_t) {
        snprintf(why, why_len, "frame %ld of the video has no time in %.300s.frames.csv (%ld frames there)", f,
                 r->video, r->n_frame_t);
        return -1;
    }
    const double t = (r->frame_t ? r->frame_t[f] : (double)f / r->fps) + r->t_offset;
    const rail_reading *g = r->rails;
    if (t < g[0].t || t > g[r->nr - 1].t) return 1;
    while (r->at + 2 < r->nr && g[r->at + 1].t < t) r->at++;
    const size_t k = r->at;
    const double w = (t - g[k].t) / (g[k + 1].t - g[k].t);
    x->t_s = t;
    x->compress_mm = g[k].compress_mm + w * (g[k + 1].compress_mm - g[k].compress_mm);
    x->shear_mm = g[k].shear_mm + w * (g[k + 1].shear_mm - g[k].shear_mm);
    x->dl = rig_calib_dl(&r->rec.calib, r->rec.length_m, x->compress_mm);
    x->dw = rig_calib_dw(&r->rec.calib, r->rec.length_m, x->shear_mm);
    return 0;
}

static void add_event(store *st, live_bus *bus, int64_t id, double t, store_event_kind kind, const char *msg);

/* What the stored prediction ran with of its specimen's calibration (its calibration_json: the
 * record trial_specimen_calib_apply wrote), as a clause: "the specimen's calibration (trials 1,
 * 2026-...; after trial 1): KEY VALUE (was V), ..." or "no specimen calibration". */
static void calibration_clause(const char *cj, char *out, size_t n)
{
    json_t *j = cj && cj[0] ? json_loads(cj, 0, NULL) : NULL;
    if (!json_is_object(j)) {
        snprintf(out, n, cj && cj[0] ? "a calibration record that cannot be read" : "no specimen calibration: the strip as measured");
        json_decref(j);
        return;
    }
    char ids[64] = "";
    const json_t *tr = json_object_get(j, "trials");
    for (size_t k = 0; k < json_array_size(tr) && strlen(ids) < sizeof ids - 24; k++)
        snprintf(ids + strlen(ids), sizeof ids - strlen(ids), "%s%lld", k ? ", " : "",
                 (long long)json_integer_value(json_array_get(tr, k)));
    const char *at = json_string_value(json_object_get(j, "calibrated_at"));
    size_t u = (size_t)snprintf(out, n, "the specimen's calibration as it was then (trials %s, %s)", ids[0] ? ids : "?",
                                at ? at : "?");
    const json_t *ap = json_object_get(j, "applied");
    for (size_t k = 0; k < json_array_size(ap) && u < n; k++) {
        const json_t *a = json_array_get(ap, k);
        const char *key = json_string_value(json_object_get(a, "key"));
        u += (size_t)snprintf(out + u, n - u, "%s %s %.6g", k ? "," : ":", key ? key : "?",
                              json_number_value(json_object_get(a, "value")));
    }
    json_decref(j);
}

/* The source trial's stored prediction. A replay does not predict again: a prediction made now
 * would take the scene and the specimen's calibration as they are now (a refit after the trial
 * changes it), not what the trial ran with, and change its history. So the replay is compared
 * with the prediction its trial made, as stored: its record says which (an event naming the
 * trial, the snap and what the prediction ran with), and the page draws it beside the replay's
 * points. */
static void source_prediction(trial_replay *r, store *st)
{
    if (r->source_id <= 0) return; /* an outside recording: no stored trial, no prediction */
    store_prediction p = store_prediction_default();
    char w[256], msg[512], cal[360];
    store_err e = store_prediction_get_by_trial(st, r->source_id, &p, w, sizeof w);
    if (e == STORE_E_NOTFOUND) {
        snprintf(msg, sizeof msg, "prediction: none (a replay does not predict; trial %lld has none stored)",
                 (long long)r->source_id);
    } else if (e != STORE_OK) {
        snprintf(msg, sizeof msg, "prediction: trial %lld's cannot be read: %.300s", (long long)r->source_id, w);
    } else if (p.status == STORE_PREDICTION_FAILED) {
        snprintf(msg, sizeof msg, "prediction: trial %lld's failed (%.300s); a replay does not predict",
                 (long long)r->source_id, p.failure);
    } else {
        calibration_clause(p.calibration_json, cal, sizeof cal);
        char snap[64];
        if (p.snapped) snprintf(snap, sizeof snap, "%s at Delta W = %.5f", store_regime_name(p.regime), p.snap_dw);
        else snprintf(snap, sizeof snap, "no snap");
        snprintf(msg, sizeof msg, "prediction: trial %lld's as stored (%s; N = %d), made with %s; a replay does not "
                 "predict again", (long long)r->source_id, snap, p.nodes, cal);
    }
    add_event(st, r->bus, r->new_id, NAN, e == STORE_OK || e == STORE_E_NOTFOUND ? STORE_EVENT_INFO : STORE_EVENT_WARNING,
              msg);
    if (r->bus && e == STORE_OK) {
        int ok = p.status != STORE_PREDICTION_FAILED; /* a failed one is published with its reason */
        trial_publish_prediction(r->bus, r->new_id, ok, p.snapped, p.snap_dw, store_regime_name(p.regime), p.curve.n,
                                 p.curve.dw, p.curve.dz, p.curve.a, ok ? NULL : p.failure);
    }
    store_prediction_free(&p);
}

/* A stored frame sample as the page's sample message. */
static void publish_sample(live_bus *bus, int64_t id, const store_sample *x, int measured)
{
    if (!bus) return;
    trial_sample t;
    memset(&t, 0, sizeof t);
    t.kind = 1;
    t.frame = x->frame;
    t.t_s = x->t_s;
    t.compress_mm = x->compress_mm;
    t.shear_mm = x->shear_mm;
    t.dl = x->dl;
    t.dw = x->dw;
    t.measured = measured;
    t.dz = x->dz;
    t.a = x->a;
    t.quality = x->quality;
    trial_publish_sample(bus, id, &t);
}

/* The steps of the source the replay passes at frame time t (once each, in order). */
static void publish_steps(trial_replay *r, double t, int *step)
{
    const double at[3] = {r->t_check, r->t_shear, r->t_return};
    static const char *const name[3] = {"checking", "shearing", "returning"};
    while (*step < 3 && (!isfinite(at[*step]) || t >= at[*step])) {
        if (isfinite(at[*step])) trial_publish_state_name(r->bus, r->new_id, name[*step], t, NULL);
        (*step)++;
    }
}

/* One replay's frames between the tracking pipe and the store. */
typedef struct replay_loop {
    trial_replay *r;
    store_samples *w;
    trial_result *res;
    vis_track_pipe *pipe;
    store_sample *pending; /* the rails' sample of each frame in the pipe, by push count modulo cap */
    size_t cap, pushed, taken;
    vis_frame *shown;      /* a frame out of the pipe, for the live page */
    double uv[2 * LIVE_UV_MAX];
    snap_detect det;
    int step, snap_told;
    long total;
    void (*progress)(void *u, long frame, long total);
    void *u;
} replay_loop;

/* Whether any of the recording's rail readings has the compress rail within tol_mm of target_mm;
 * the range recorded in *lo, *hi, and the time of the first such reading in *t_arrive (the
 * compression's end: the frames before it off the compression are the compression's, those after
 * it the return's). */
static int compress_in_place(const trial_replay *r, double target_mm, double tol_mm, double *lo, double *hi,
                             double *t_arrive)
{
    int any = 0;
    const size_t n = r->smp ? r->ns : r->nr;
    for (size_t k = 0; k < n; k++) {
        const double c = r->smp ? r->smp[k].compress_mm : r->rails[k].compress_mm;
        if (!isfinite(c)) continue;
        *lo = fmin(*lo, c);
        *hi = fmax(*hi, c);
        if (!any && fabs(c - target_mm) <= tol_mm) *t_arrive = r->smp ? r->smp[k].t_s : r->rails[k].t;
        any = any || fabs(c - target_mm) <= tol_mm;
    }
    return any;
}

/* The compression's last part (trial_comp_track.h, as the trial tracked it): frames of the
 * compression (before the compress rail first reached the trial's compression) from Delta L
 * trial_comp_track_from_dl on, each measured by a fresh tracker with the clamp point moved to
 * where the recorded rail puts it. */
typedef struct replay_comp {
    double from_dl, t_arrive;
    long n, measured, failed;
    double dl_lo, dl_hi;
} replay_comp;

static int replay_comp_frame(const replay_comp *rc, const store_sample *x, double compression)
{
    return isfinite(rc->t_arrive) && x->t_s < rc->t_arrive && x->dl >= rc->from_dl && x->dl <= compression + 1e-9;
}

/* Frame x.frame measured as m (its centreline uv, n_uv pairs; the frame itself): the sample stored,
 * the live page told, the snap detector fed. 0, or -1 with `why` set. */
static int replay_record(replay_loop *L, store_sample x, const vis_measure *mp, const double *uv, size_t n_uv,
                         const vis_frame *shown, char *why, size_t why_len)
{
    const vis_measure m = *mp;
    trial_replay *r = L->r;
    const trial_record *rec = &r->rec;
    const int64_t id = r->new_id;
    const long f = x.frame;
    int measured = m.reason == VIS_REASON_NONE && m.quality >= rec->min_quality && isfinite(m.dz) && isfinite(m.a);
    x.kind = STORE_SAMPLE_FRAME;
    x.quality = isfinite(m.quality) ? m.quality : 0.0;
    if (measured) {
        x.dz = m.dz;
        x.a = rig_calib_a_sign(&rec->calib) * m.a;
        L->res->measured_frames++;
    } else {
        snprintf(x.reason, sizeof x.reason, "%s", m.reason == VIS_REASON_NONE ? "low quality" : vis_reason_str(m.reason));
    }
    if (store_samples_add(L->w, &x, why, why_len) != STORE_OK) return -1;
    L->res->frames++;
    publish_steps(r, x.t_s, &L->step);
    publish_sample(r->bus, id, &x, measured);
    trial_publish_frame_curve(r->bus, shown, uv, n_uv, f, x.t_s);
    int in_shear = isfinite(r->t_shear) ? (x.t_s >= r->t_shear && (!isfinite(r->t_return) || x.t_s < r->t_return)) : 1;
    if (in_shear) snap_detect_add(&L->det, f, x.t_s, x.dw, x.dz, x.a, measured);
    if (!L->snap_told && snap_detect_snapped(&L->det)) {
        trial_publish_state_name(r->bus, id, "snapped", x.t_s, NULL);
        L->snap_told = 1;
    }
    L->res->duration_s = x.t_s;
    if (L->progress && f % 50 == 0) L->progress(L->u, f, L->total);
    return 0;
}

/* The oldest frame's measurement out of the pipe (waiting for it when `wait`), recorded. 1 when a
 * frame was taken, 0 when none was ready, -1 with `why` set. */
static int replay_take(replay_loop *L, int wait, char *why, size_t why_len)
{
    vis_measure m;
    vis_error ve = {0};
    size_t n_uv = 0;
    const vis_status s = vis_track_pipe_pop(L->pipe, wait, &m, L->uv, LIVE_UV_MAX, &n_uv, L->shown, &ve);
    if (s == VIS_ERR_NOT_FOUND || s == VIS_ERR_END) return 0;
    if (s != VIS_OK) {
        snprintf(why, why_len, "tracker: %s", ve.message);
        return -1;
    }
    store_sample x = L->pending[L->taken++ % L->cap];
    return replay_record(L, x, &m, L->uv, n_uv, L->shown, why, why_len) ? -1 : 1;
}

int trial_replay_execute(trial_replay *r, store *st, const atomic_int *cancel,
                         void (*progress)(void *u, long frame, long total), void *u, trial_result *res, char *why,
                         size_t why_len)
{
    memset(res, 0, sizeof *res);
    snprintf(res->regime, sizeof res->regime, "no snap");
    const int64_t id = r->new_id;
    int rc = -1, aborted = 0;
    vis_source *vs = NULL;
    vis_tracker *trk = NULL;
    vis_track_pipe *pipe = NULL;
    replay_loop L = {0};
    vis_frame *frame = NULL;
    store_samples *w = NULL;
    char w2[256];
    if (!id) {
        snprintf(why, why_len, "replay: no trial was created");
        goto done;
    }
    vis_error ve = {0};
    vs = vis_source_open_video_prefetch(r->video, &ve);
    if (!vs) {
        video_why(why, why_len, r->video, ve.message);
        goto fail;
    }
    const trial_record *rec = &r->rec;
    vis_calib cal;
    trial_record_video_calib(rec, &cal);
    vis_track_params tp = trial_record_track_params(rec, &cal);
    trk = vis_tracker_create(&tp, &cal, &ve);
    frame = vis_frame_alloc(16, 16, 1, &ve);
    if (!trk || !frame) {
        snprintf(why, why_len, "tracker: %s", ve.message);
        goto fail;
    }
    if (store_samples_begin(st, id, NULL, &w, why, why_len) != STORE_OK) goto fail;
    L.r = r;
    L.w = w;
    L.res = res;
    L.progress = progress;
    L.u = u;
    snap_detect_init(&L.det, &rec->snap);
    L.total = vis_source_frame_count(vs);
    long skipped = 0;
    int reset_done = 0;
    trial_publish_begin(r->bus, id, "replay", r->note);
    trial_publish_state_name(r->bus, id, "replaying", NAN, r->video);
    source_prediction(r, st);
    /* Tracked on every core (vis_track_pipe: the results are the serial loop's); what follows a
     * frame's measurement happens as it comes out, in order. */
    pipe = vis_track_pipe_create(trk, 0, &ve);
    L.cap = pipe ? vis_track_pipe_capacity(pipe) : 0;
    L.pending = pipe ? calloc(L.cap, sizeof *L.pending) : NULL;
    L.shown = pipe ? vis_frame_alloc(16, 16, 1, &ve) : NULL;
    if (!pipe || !L.pending || !L.shown) {
        snprintf(why, why_len, "tracker: %s", pipe ? "out of memory" : ve.message);
        goto fail;
    }
    L.pipe = pipe;
    /* The calibration's clamp points are at the trial's compression: frames whose compress rail is
     * further from there than trial_clamp_tol_mm are stored untracked ("clamp not found"), as the
     * runner does. */
    const double target_mm = rig_calib_compress_mm(&rec->calib, rec->length_m, rec->compression);
    double tol_mm = trial_clamp_tol_mm(cal.px_per_mm);
    double lo_mm = INFINITY, hi_mm = -INFINITY;
    replay_comp comp = {trial_comp_track_from_dl(rec->compression), NAN, 0, 0, 0, INFINITY, -INFINITY};
    if (tol_mm > 0 && !compress_in_place(r, target_mm, tol_mm, &lo_mm, &hi_mm, &comp.t_arrive)) {
        /* A recording whose rails never put the clamps where the calibration has them (another rig
         * file's compression, or a CSV without the compression's readings): tracked as recorded,
         * and said so. */
        char note[300];
        snprintf(note, sizeof note, "the compress rail is never within %.2f mm of the trial's compression (Delta L "
                 "%.4f, %.2f mm; recorded %.2f to %.2f mm): every frame tracked against the calibrated clamp points",
                 tol_mm, rec->compression, target_mm, lo_mm, hi_mm);
        add_event(st, r->bus, id, NAN, STORE_EVENT_WARNING, note);
        tol_mm = 0.0;
    }
    long moving = 0;
    for (long f = 0;; f++) {
        if (cancel && atomic_load(cancel)) {
            snprintf(why, why_len, "replay aborted at frame %ld", f);
            aborted = 1;
            goto fail;
        }
        if (vis_track_pipe_held(pipe) >= L.cap && replay_take(&L, 1, why, why_len) < 0) goto fail;
        vis_status s = vis_source_read(vs, frame, NULL, &ve);
        if (s == VIS_ERR_END) break;
        if (s != VIS_OK) {
            video_why(why, why_len, r->video, ve.message);
            goto drain_and_fail;
        }
        store_sample x = store_sample_default();
        int fr = frame_rails(r, f, &x, why, why_len);
        if (fr < 0) goto drain_and_fail;
        if (fr > 0) {
            skipped++;
            continue;
        }
        x.frame = f;
        if (tol_mm > 0 && fabs(x.compress_mm - target_mm) > tol_mm) {
            /* Samples are stored in frame order: the frames in the pipe first. */
            for (int got = 1; got > 0;)
                if ((got = replay_take(&L, 1, why, why_len)) < 0) goto fail;
            vis_measure m;
            memset(&m, 0, sizeof m);
            m.reason = VIS_REASON_CLAMP_NOT_FOUND;
            if (replay_comp_frame(&comp, &x, rec->compression)) {
                comp.n++;
                if (trial_comp_track_measure(&tp, &cal, rec->calib.camera_side, rec->length_m, rec->compression, x.dl,
                                             frame, &m, &ve) != VIS_OK) {
                    if (!comp.failed++) {
                        char note[400];
                        snprintf(note, sizeof note, "compression frame %ld at Delta L %.4f not tracked: %s (later "
                                 "failures not noted)", f, x.dl, ve.message);
                        add_event(st, r->bus, id, x.t_s, STORE_EVENT_WARNING, note);
                    }
                    memset(&m, 0, sizeof m);
                    m.reason = VIS_REASON_CLAMP_NOT_FOUND;
                }
                if (m.reason == VIS_REASON_NONE && m.quality >= rec->min_quality && isfinite(m.dz) && isfinite(m.a)) {
                    comp.measured++;
                    comp.dl_lo = fmin(comp.dl_lo, x.dl);
                    comp.dl_hi = fmax(comp.dl_hi, x.dl);
                } else {
                    moving++;
                }
            } else {
                moving++;
            }
            if (replay_record(&L, x, &m, NULL, 0, frame, why, why_len)) goto fail;
            continue;
        }
        int reset = 0;
        if (!reset_done && isfinite(r->t_check) && x.t_s >= r->t_check) {
            reset = 1; /* frames during the moves are not trusted */
            reset_done = 1;
        }
        L.pending[L.pushed % L.cap] = x;
        if (vis_track_pipe_push(pipe, frame, x.dw * rec->length_m * 1000.0, reset, &ve) != VIS_OK) {
            snprintf(why, why_len, "tracker: %s", ve.message);
            goto fail;
        }
        L.pushed++;
        int got;
        while ((got = replay_take(&L, 0, why, why_len)) > 0) {
        }
        if (got < 0) goto fail;
    }
    for (int got = 1; got > 0;) {
        if (cancel && atomic_load(cancel)) {
            snprintf(why, why_len, "replay aborted at frame %ld", (long)L.taken);
            aborted = 1;
            goto fail;
        }
        if ((got = replay_take(&L, 1, why, why_len)) < 0) goto fail;
    }
    snap_detect det = L.det;
    if (store_samples_end(w, why, why_len) != STORE_OK) {
        w = NULL;
        goto fail;
    }
    w = NULL;
    if (res->frames == 0) {
        snprintf(why, why_len, "no frame of %.300s falls within the rail readings (check "
                               "calibration.camera_time_offset_s)", r->video);
        goto fail;
    }
    if (moving > 0) {
        char note[200];
        snprintf(note, sizeof note, "%ld frames with the compress rail away from the trial's compression stored "
                 "untracked (clamp not found)", moving);
        add_event(st, r->bus, id, NAN, STORE_EVENT_INFO, note);
    }
    if (comp.n > 0) {
        char note[300];
        if (comp.measured)
            snprintf(note, sizeof note, "compression frames from Delta L %.4f: %ld tracked with the clamp point moved, "
                     "%ld measured at Delta L %.4f to %.4f", comp.from_dl, comp.n, comp.measured, comp.dl_lo, comp.dl_hi);
        else
            snprintf(note, sizeof note, "compression frames from Delta L %.4f: %ld tracked with the clamp point moved, "
                     "none measured", comp.from_dl, comp.n);
        add_event(st, r->bus, id, NAN, STORE_EVENT_INFO, note);
    }
    res->snapped = snap_detect_snapped(&det);
    res->snap_dw = res->snapped ? snap_detect_dw(&det) : 0.0;
    snap_reading reading;
    snap_detect_read(&det, &reading);
    res->asymmetric = reading.regime == SNAP_REGIME_ASYMMETRIC;
    res->regime_undecided = res->snapped && reading.regime == SNAP_REGIME_UNDECIDED;
    res->peak_abs_a = det.peak_abs_a;
    snprintf(res->regime, sizeof res->regime, "%s", snap_detect_regime(&det));
    if (res->snapped) {
        char how[512];
        snap_reading_format(&reading, &det.p, how, sizeof how);
        add_event(st, r->bus, id, NAN, res->regime_undecided ? STORE_EVENT_WARNING : STORE_EVENT_INFO, how);
    }
    store_regime reg = trial_regime_of(res->snapped, res->snapped && !res->regime_undecided, res->asymmetric);
    store_trial_set_result(st, id, res->snapped, res->snapped ? res->snap_dw : NAN, reg, w2, sizeof w2);
    char msg[400];
    if (r->source_id)
        snprintf(msg, sizeof msg, "replayed %ld frames of trial %lld: %s at Delta W = %.5f (source: %.5f)", res->frames,
                 (long long)r->source_id, res->regime, res->snap_dw, r->source_snap_dw);
    else
        snprintf(msg, sizeof msg, "replayed %ld frames of %.200s (%ld outside the rail readings, skipped): %s at "
                 "Delta W = %.5f", res->frames, r->video, skipped, res->regime, res->snap_dw);
    add_event(st, r->bus, id, res->duration_s, STORE_EVENT_INFO, msg);
    store_trial_set_status(st, id, STORE_STATUS_DONE, NULL, store_wall_now(), w2, sizeof w2);
    res->final = TRIAL_DONE;
    rc = 0;
    trial_publish_result(r->bus, id, res);
    trial_publish_state(r->bus, id, TRIAL_DONE, res->duration_s, NULL);
    trial_publish_stored(r->bus, id, TRIAL_DONE);
    goto done;
drain_and_fail:
    /* The frames already in the pipe come before the failure: they are stored, as the serial loop
     * stored them (a tracker's error on one of them is the earlier failure, and said instead). */
    if (pipe) {
        char why2[256];
        int got;
        while ((got = replay_take(&L, 1, why2, sizeof why2)) > 0) {
        }
        if (got < 0) snprintf(why, why_len, "%s", why2);
    }
fail:
    if (w) {
        store_samples_end(w, w2, sizeof w2);
        w = NULL;
    }
    if (id) {
        add_event(st, r->bus, id, NAN, aborted ? STORE_EVENT_INFO : STORE_EVENT_FAULT, why);
        store_trial_set_status(st, id, aborted ? STORE_STATUS_ABORTED : STORE_STATUS_FAILED, why, store_wall_now(), w2,
                               sizeof w2);
    }
    res->final = aborted ? TRIAL_ABORTED : TRIAL_FAILED;
    snprintf(res->reason, sizeof res->reason, "%s", why);
    if (id) {
        trial_publish_result(r->bus, id, res);
        trial_publish_state(r->bus, id, res->final, NAN, why);
        trial_publish_stored(r->bus, id, res->final);
    }
done:
    vis_track_pipe_free(pipe);
    free(L.pending);
    vis_frame_free(L.shown);
    vis_frame_free(frame);
    vis_tracker_free(trk);
    if (vs) vis_source_close(vs);
    return rc;
}

int trial_replay_prepare(store *st, const rig_config *cfg, int64_t source, const char *video, trial_replay **out,
                         char *why, size_t why_len)
{
    *out = NULL;
    if (source > 0) return trial_replay_from_trial(st, source, video, out, why, why_len);
    if (cfg && cfg->replay.source_trial > 0)
        return trial_replay_from_trial(st, cfg->replay.source_trial, cfg->replay.video[0] ? cfg->replay.video : NULL,
                                       out, why, why_len);
    if (cfg && cfg->replay.video[0]) return trial_replay_from_files(cfg, out, why, why_len);
    snprintf(why, why_len, "which recording? give a trial id, or a replay rig file with [replay] source_trial, or "
                           "replay.video and replay.rails");
    return -1;
}

int trial_replay_run(trial_replay *r, store *st, const char *note, void (*progress)(void *u, long frame, long total),
                     void *u, int64_t *new_id, trial_result *res, char *why, size_t why_len)
{
    memset(res, 0, sizeof *res);
    snprintf(res->regime, sizeof res->regime, "no snap");
    if (trial_replay_create(r, st, note, new_id, why, why_len)) return -1;
    return trial_replay_execute(r, st, NULL, progress, u, res, why, why_len);
}
