/* trial_session.c: one trial from request to stored result (see trial_session.h). */
#include "trial_session.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <errno.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <sys/stat.h>
#include <sys/statvfs.h>

#include "predict_ladder.h"
#include "trial_calibrate.h"
#include "rod_protocol.h"
#include "store.h"
#include "trial_camera_setup.h"
#include "trial_config_text.h"
#include "trial_disk_words.h"
#include "trial_fit_out.h"
#include "trial_live.h"
#include "trial_prediction.h"
#include "trial_publish.h"
#include "trial_record.h"
#include "trial_specimen.h"
#include "trial_specimen_calib.h"
#include "trial_video.h"
#include "twin.h"

#ifndef RIBBON_VERSION
#define RIBBON_VERSION "unknown"
#endif

struct trial_session {
    rig_config cfg;
    rail *compress, *shear;
    void (*log)(const char *line);
    store *st;              /* the trial thread's connection */
    store_samples *writer;
    int64_t trial_id;
    pthread_t thread;
    trial_prediction *prediction; /* the prediction beside the trial, once started */
    atomic_int cancel;      /* set by abort: stops the ladder and the prediction at their next step */
    trial_runner runner;
    int runner_ready;
    trial_result result;
    trial_video *video;
    trial_live *live;       /* rig mode: camera, capture pipeline, rail poller (trial_live.h) */
    char live_video[RIG_PATH_MAX + 64]; /* rig mode: the raw video the live pipeline records */
    trial_transcoder *tx;   /* may be NULL: takes the raw video after the trial (trial_transcoder.h) */
    pthread_mutex_t lock;
    session_status status;  /* under lock */
    int abort_pending;      /* under lock: an abort that came before the runner existed */
    char abort_reason[128];
    char note[256];
    vis_calib cal;          /* the camera calibration of this trial */
    trial_roi roi;          /* the saved video's region */
    int width, height;      /* frame size */
    live_bus *bus;          /* the live page's (may be NULL): published into, never waited on */
    rod_scene pred_scene;   /* the prediction's scene: the rig's with the specimen's creases */
    trial_calibrate *calib; /* the fit beside the trial (trial_calibrate.h), NULL when off */
    trial_fit_out *fit_out; /* its events and landings written off the loop (trial_fit_out.h) */
    trial_specimen_use use; /* which crease values it uses, where each came from */
    int64_t specimen_id;    /* the trial's specimen row */
    char specimen_calibration[STORE_SPECIMEN_CALIBRATION_MAX]; /* a named specimen's calibration at
                               the start (trial_specimen_calib.h); "" = none */
};

/* 1 when an abort arrived before the runner took over (the trial then ends before moving). */
static int aborted_early(trial_session *s, char *why, size_t why_len)
{
    pthread_mutex_lock(&s->lock);
    int a = s->abort_pending;
    if (a) snprintf(why, why_len, "aborted before the rails moved: %s", s->abort_reason);
    pthread_mutex_unlock(&s->lock);
    return a;
}

static void logf_(trial_session *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void logf_(trial_session *s, const char *fmt, ...)
{
    char line[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    pthread_mutex_lock(&s->lock);
    snprintf(s->status.message, sizeof s->status.message, "%.255s", line);
    pthread_mutex_unlock(&s->lock);
    if (s->log) {
        char full[600];
        snprintf(full, sizeof full, "trial %lld: %s", (long long)s->trial_id, line);
        s->log(full);
    }
}

/* A trial event as the session stores it: its trial, times, the state it happened in, kind, text. */
static void session_event_fill(trial_session *s, double t_s, store_event_kind kind, const char *msg, store_event *ev)
{
    memset(ev, 0, sizeof *ev);
    ev->trial_id = s->trial_id;
    ev->t_s = t_s;
    ev->wall_s = store_wall_now();
    pthread_mutex_lock(&s->lock);
    snprintf(ev->state, sizeof ev->state, "%s", trial_state_name(s->status.state));
    pthread_mutex_unlock(&s->lock);
    ev->kind = kind;
    snprintf(ev->message, sizeof ev->message, "%s", msg);
}

static void session_event(trial_session *s, double t_s, store_event_kind kind, const char *msg)
{
    store_event ev;
    session_event_fill(s, t_s, kind, msg, &ev);
    trial_publish_event(s->bus, s->trial_id, t_s, store_event_kind_name(kind), msg);
    char why[256];
    if (store_event_append(s->st, &ev, why, sizeof why) != STORE_OK) logf_(s, "event not stored: %s", why);
    logf_(s, "%s", msg);
}

/* ---- the prediction's report ------------------------------------------------------------- */

/* The prediction's one report (on its thread): the status the API shows, and the log. */
static void prediction_done(void *user, const trial_prediction_report *r)
{
    trial_session *s = user;
    pthread_mutex_lock(&s->lock);
    if (r->outcome == TRIAL_PREDICTION_FAILED) s->status.prediction_failed = 1;
    if (r->outcome == TRIAL_PREDICTION_STORED) {
        s->status.prediction_done = 1;
        s->status.snap_dw_predicted = r->snap_dw;
        snprintf(s->status.regime_predicted, sizeof s->status.regime_predicted, "%s", store_regime_name(r->regime));
    }
    pthread_mutex_unlock(&s->lock);
    if (r->outcome == TRIAL_PREDICTION_STORED)
        trial_publish_prediction(s->bus, s->trial_id, 1, isfinite(r->snap_dw), r->snap_dw, store_regime_name(r->regime),
                              r->n, r->dw, r->dz, r->a, NULL);
    else
        trial_publish_prediction(s->bus, s->trial_id, 0, 0, NAN, NULL, 0, NULL, NULL, NULL, r->message);
    logf_(s, "%s", r->message);
}

/* ---- resolution ----------------------------------------------------------------------------- */

/* The prediction's scene hash: the scene's text hash, the program, the step control and the ladder's
 * kind ("l2": the ladder refines dt with N; a cache of the N-only ladder is not reused). */
static void scene_hash_text(const rod_scene *sc, int fast, char *hash, size_t hash_len)
{
    char h[17];
    predict_scene_hash(sc, h);
    snprintf(hash, hash_len, "%s-v%s-%s-l2", h, RIBBON_VERSION, fast ? "fast" : "fixed");
}

/* Picks nodes, dt and (fast mode) the step control's scale for the prediction (the mock twin takes
 * nodes and dt). Returns 0, or -1 with why. */
static int choose_resolution(trial_session *s, rod_scene *sc, double *adapt_scale, double *est_error, char *hash,
                             size_t hash_len, char *why, size_t why_len)
{
    const rig_sim *sim = &s->cfg.sim;
    scene_hash_text(sc, sim->fast, hash, hash_len);
    *est_error = NAN;
    *adapt_scale = 0.0;
    if (sim->explicit_resolution) {
        if (sim->nodes > 0) sc->nodes = sim->nodes;
        if (sim->dt > 0) sc->dt = sim->dt;
        return 0;
    }
    store_ladder_rung *cached = NULL;
    size_t n = 0;
    predict_ladder_rung r[PREDICT_LADDER_MAX_RUNGS];
    rod_ladder_verdict v;
    int nr = 0;
    if (store_ladder_get(s->st, hash, &cached, &n, why, why_len) == STORE_OK && n > 0) {
        for (size_t k = 0; k < n && nr < PREDICT_LADDER_MAX_RUNGS; k++) {
            memset(&r[nr], 0, sizeof r[nr]);
            r[nr].nodes = cached[k].nodes;
            r[nr].dt = cached[k].dt;
            r[nr].adaptive = cached[k].adaptive;
            r[nr].adapt_scale = cached[k].adaptive && sc->dt > 0 ? cached[k].dt / sc->dt : 0.0;
            r[nr].snap_dw = cached[k].snap_dw;
            r[nr].wall_s = cached[k].wall_s;
            nr++;
        }
        free(cached);
        predict_ladder_estimate_errors(r, nr, &v); /* the same estimate as when it was computed, and its verdict */
        session_event(s, NAN, STORE_EVENT_INFO, "resolution ladder taken from the store's cache");
    } else {
        free(cached);
        char msg[128];
        snprintf(msg, sizeof msg, "computing the resolution ladder (%d rungs), once for this scene", sim->n_ladder);
        session_event(s, NAN, STORE_EVENT_INFO, msg);
        if (predict_ladder_compute(sc, sim->ladder_nodes, sim->n_ladder, sim->fast, r, &v, NULL, NULL, &s->cancel,
                                   why, why_len))
            return -1;
        nr = sim->n_ladder;
        store_ladder_rung sr[PREDICT_LADDER_MAX_RUNGS];
        for (int k = 0; k < nr; k++) {
            sr[k].nodes = r[k].nodes;
            sr[k].dt = r[k].dt;
            sr[k].adaptive = r[k].adaptive;
            sr[k].snap_dw = r[k].snapped ? r[k].snap_dw : NAN;
            sr[k].est_error = r[k].est_error >= 0 ? r[k].est_error : NAN;
            sr[k].wall_s = r[k].wall_s;
        }
        char w2[256];
        if (store_ladder_put(s->st, hash, sr, (size_t)nr, w2, sizeof w2) != STORE_OK)
            session_event(s, NAN, STORE_EVENT_WARNING, w2);
    }
    if (v.asymptotic) {
        char msg[160];
        snprintf(msg, sizeof msg,
                 "resolution ladder in the asymptotic range: observed order %.2f (expected %.1f to %.1f)", v.order,
                 ROD_LADDER_ORDER_LO, ROD_LADDER_ORDER_HI);
        session_event(s, NAN, STORE_EVENT_INFO, msg);
    } else {
        char msg[260];
        snprintf(msg, sizeof msg, "resolution ladder %s", v.note);
        session_event(s, NAN, STORE_EVENT_WARNING, msg);
    }
    int k = predict_ladder_choose(r, nr, sim->target_error);
    sc->nodes = r[k].nodes;
    sc->dt = r[k].dt;
    *adapt_scale = r[k].adapt_scale;
    *est_error = r[k].est_error >= 0 ? r[k].est_error : NAN;
    char msg[200];
    snprintf(msg, sizeof msg, "prediction resolution N = %d, dt = %g s: estimated error %.2g (target %.2g)", sc->nodes,
             sc->dt, *est_error, sim->target_error);
    session_event(s, NAN, STORE_EVENT_INFO, msg);
    return 0;
}

/* ---- the runner's sink ------------------------------------------------------------------------ */

/* A trial ending in final is followed by its specimen's refit (session_refit_specimen). */
static int refit_due(const trial_session *s, trial_state final)
{
    return final == TRIAL_DONE && s->cfg.sim.specimen_fit && s->cfg.specimen.name[0] && s->specimen_id > 0;
}

static int sink_state(void *user, trial_state st, double t_s, const char *why)
{
    trial_session *s = user;
    pthread_mutex_lock(&s->lock);
    s->status.state = st;
    /* Done, with the specimen's refit to come: said from the same instant (status.refitting), so
     * no one reads a bare "done" and starts the specimen's next trial, or reads the specimen,
     * before its new calibration is stored. */
    if (refit_due(s, st)) snprintf(s->status.refitting, sizeof s->status.refitting, "%s", s->cfg.specimen.name);
    pthread_mutex_unlock(&s->lock);
    trial_publish_state(s->bus, s->trial_id, st, t_s, why);
    char w[256];
    store_trial_set_state(s->st, s->trial_id, trial_state_name(st), w, sizeof w);
    char msg[400];
    snprintf(msg, sizeof msg, "state %s%s%s", trial_state_name(st), why && *why ? ": " : "", why ? why : "");
    session_event(s, t_s, STORE_EVENT_STATE, msg);
    return 0;
}

static int sink_event(void *user, double t_s, const char *kind, const char *message)
{
    trial_session *s = user;
    store_event_kind k = STORE_EVENT_INFO;
    store_event_kind_parse(kind, &k);
    session_event(s, t_s, k, message);
    return 0;
}

static int sink_sample(void *user, const trial_sample *smp, char *why, size_t why_len)
{
    trial_session *s = user;
    store_sample x = store_sample_default();
    x.t_s = smp->t_s;
    x.kind = smp->kind ? STORE_SAMPLE_FRAME : STORE_SAMPLE_RAIL;
    x.frame = smp->kind ? smp->frame : -1;
    x.compress_mm = smp->compress_mm;
    x.shear_mm = smp->shear_mm;
    x.dl = smp->dl;
    x.dw = smp->dw;
    if (smp->kind) {
        x.quality = smp->quality;
        if (smp->measured) {
            x.dz = smp->dz;
            x.a = smp->a;
        } else if (smp->not_tracked) {
            snprintf(x.reason, sizeof x.reason, "%s",
                     smp->not_tracked == 2   ? "dropped (pipeline full, not in the video)"
                     : smp->not_tracked == 3 ? "not tracked (compression frame over the tracking budget)"
                                             : "not tracked (the trial loop was behind)");
        } else {
            snprintf(x.reason, sizeof x.reason, "%s",
                     smp->reason == VIS_REASON_NONE ? "low quality" : vis_reason_str(smp->reason));
        }
        pthread_mutex_lock(&s->lock);
        s->status.frames++;
        s->status.t_s = smp->t_s;
        s->status.dl = smp->dl;
        s->status.dw = smp->dw;
        if (smp->measured) {
            s->status.measured++;
            s->status.dz = smp->dz;
            s->status.a = smp->a;
        }
        pthread_mutex_unlock(&s->lock);
    }
    trial_publish_sample(s->bus, s->trial_id, smp);
    if (store_samples_add(s->writer, &x, why, why_len) != STORE_OK) return -1;
    return 0;
}

static int sink_frame(void *user, const vis_frame *f, long index, char *why, size_t why_len)
{
    trial_session *s = user;
    trial_publish_frame(s->bus, f, s->runner.tracker, index, s->status.t_s); /* t_s: written by this thread */
    return s->video ? trial_video_add(s->video, f, why, why_len) : 0;
}

/* ---- cameras ------------------------------------------------------------------------------------ */

typedef struct live_camera {
    vis_source *src;
    rail_clock clock;
} live_camera;

static vis_status live_grab(void *ctx, double t_s, double dl, double dw, vis_frame *out, double *t_frame,
                            vis_error *err)
{
    (void)t_s;
    (void)dl;
    (void)dw;
    live_camera *c = ctx;
    vis_status st = vis_source_read(c->src, out, NULL, err);
    *t_frame = rail_clock_now(c->clock);
    return st;
}

/* ---- the trial thread's steps ------------------------------------------------------------------- */

/* What the trial thread opens; session_release closes whatever is open. */
typedef struct session_parts {
    rod_scene sc;           /* the mock twin's scene: the rig's, at the prediction's resolution */
    rod_scene pred;         /* the prediction's: the specimen's creases in the rig's scene */
    mock_camera *mock;
    live_camera live;
    trial_camera cam;
    vis_tracker *trk;
} session_parts;

/* Rig mode: stops the live pipeline and stores its counts (and a failure of the video) as events. */
/* Rig mode, after the live pipeline closed: the raw video's size into the store, then the video
 * handed to the transcoder (which only queues it: the next trial can start at once). A video
 * that did not close complete is kept raw, as evidence. */
static void session_video_handover(trial_session *s, int video_ok)
{
    struct stat sb;
    char w[512] = "";
    if (!s->live_video[0] || stat(s->live_video, &sb) != 0) return; /* no video (removed on an early failure) */
    if (store_trial_set_video_file(s->st, s->trial_id, s->live_video, (int64_t)sb.st_size, NULL, w, sizeof w) !=
        STORE_OK)
        session_event(s, NAN, STORE_EVENT_WARNING, w);
    if (s->cfg.camera.transcode != RIG_TRANSCODE_FFV1 || !s->tx) return;
    if (!video_ok) {
        session_event(s, NAN, STORE_EVENT_WARNING, "video not transcoded: it did not close complete; the raw video is kept");
        return;
    }
    int crop[4], rec[4], *cp = NULL, *rp = NULL;
    if (s->cfg.camera.transcode_keep == RIG_KEEP_TRACKER) {
        /* The tracker's region (roi = auto's), inside the recorded one, in the recording's pixels. */
        trial_roi a = trial_roi_auto(&s->cal, s->width, s->height, s->cfg.scene.length * 1000.0,
                                     s->cfg.scene.compression, s->cfg.camera.margin_px);
        int x0 = a.x > s->roi.x ? a.x : s->roi.x, y0 = a.y > s->roi.y ? a.y : s->roi.y;
        int x1 = a.x + a.w < s->roi.x + s->roi.w ? a.x + a.w : s->roi.x + s->roi.w;
        int y1 = a.y + a.h < s->roi.y + s->roi.h ? a.y + a.h : s->roi.y + s->roi.h;
        if (x1 - x0 >= 16 && y1 - y0 >= 16 && (x1 - x0 < s->roi.w || y1 - y0 < s->roi.h)) {
            crop[0] = x0 - s->roi.x, crop[1] = y0 - s->roi.y, crop[2] = (x1 - x0) & ~1, crop[3] = (y1 - y0) & ~1;
            rec[0] = x0, rec[1] = y0, rec[2] = crop[2], rec[3] = crop[3];
            cp = crop, rp = rec;
        }
    }
    if (trial_transcoder_submit(s->tx, s->trial_id, s->live_video, cp, rp, w, sizeof w))
        session_event(s, NAN, STORE_EVENT_WARNING, w);
    else
        logf_(s, "video %s queued for its lossless transcode", s->live_video);
}

static void session_live_close(trial_session *s)
{
    char summary[512], w[256] = "";
    trial_capture_counts k;
    int rc = trial_live_close(s->live, &k, summary, sizeof summary, w, sizeof w);
    s->live = NULL;
    session_event(s, NAN, k.lost || k.incomplete || k.dropped ? STORE_EVENT_WARNING : STORE_EVENT_INFO, summary);
    if (rc) session_event(s, NAN, STORE_EVENT_FAULT, w);
    session_video_handover(s, rc == 0);
}

/* The final state and status into the store. When the store refuses them (issue 33, item 3: a
 * full disk left trials "running" forever), the session's status carries what to write, and the
 * daemon writes it when the store takes writes again. */
static void session_store_final(trial_session *s, trial_state final, const char *reason)
{
    char w[256] = "";
    double wall = store_wall_now();
    store_status fin = final == TRIAL_DONE      ? STORE_STATUS_DONE
                       : final == TRIAL_ABORTED ? STORE_STATUS_ABORTED
                                                : STORE_STATUS_FAILED;
    store_err e = store_trial_set_state(s->st, s->trial_id, trial_state_name(final), w, sizeof w);
    if (e == STORE_OK) e = store_trial_set_status(s->st, s->trial_id, fin, reason, wall, w, sizeof w);
    if (e == STORE_OK || e == STORE_E_STATE) return; /* STATE: already final */
    pthread_mutex_lock(&s->lock);
    s->status.final_unstored = 1;
    s->status.final_state = final;
    snprintf(s->status.final_reason, sizeof s->status.final_reason, "%s", reason ? reason : "");
    s->status.final_wall_s = wall;
    snprintf(s->status.final_why, sizeof s->status.final_why, "%s", w);
    pthread_mutex_unlock(&s->lock);
    logf_(s, "the store refused the final status %s: %s (written when it takes writes again)", store_status_name(fin),
          w);
}

static void fail_early(trial_session *s, const char *why)
{
    int aborted = strncmp(why, "aborted", 7) == 0;
    session_event(s, NAN, aborted ? STORE_EVENT_INFO : STORE_EVENT_FAULT, why);
    session_store_final(s, aborted ? TRIAL_ABORTED : TRIAL_FAILED, why);
    s->result.final = aborted ? TRIAL_ABORTED : TRIAL_FAILED;
    snprintf(s->result.reason, sizeof s->result.reason, "%s", why);
    trial_publish_stored(s->bus, s->trial_id, s->result.final);
    pthread_mutex_lock(&s->lock);
    s->status.state = s->result.final;
    pthread_mutex_unlock(&s->lock);
}

/* Step 1: the video directory exists and has trial.min_free_disk_mb free. */
static int session_check_disk(trial_session *s, char *why, size_t why_len)
{
    const rig_config *cfg = &s->cfg;
    struct statvfs fs;
    if (mkdir(cfg->camera.video_dir, 0775) != 0 && errno != EEXIST) {
        snprintf(why, why_len, "video directory %.300s cannot be created: %m", cfg->camera.video_dir);
        return -1;
    }
    if (statvfs(cfg->camera.video_dir, &fs) != 0) {
        snprintf(why, why_len, "video directory %.300s cannot be read: %m", cfg->camera.video_dir);
        return -1;
    }
    double free_bytes = (double)fs.f_bavail * (double)fs.f_frsize;
    if (free_bytes / 1e6 < cfg->trial.min_free_disk_mb) {
        trial_disk_words(why, why_len, free_bytes, cfg->trial.min_free_disk_mb, cfg->camera.video_dir);
        return -1;
    }
    return 0;
}

/* One event saying which crease values the prediction uses, where each came from, and the
 * creases' hinge (rigid or its stiffness). */
static void note_specimen_use(trial_session *s)
{
    const store_creases *c = &s->use.creases;
    char msg[400], hinge[48];
    if (isinf(c->hinge_stiffness))
        snprintf(hinge, sizeof hinge, "rigid");
    else
        snprintf(hinge, sizeof hinge, "%g N m/rad", c->hinge_stiffness);
    snprintf(msg, sizeof msg,
             "prediction's creases: left %g deg (%s) at %g (%s), right %g deg (%s) at %g (%s), hinges %s",
             c->angle_deg[0], store_source_name(c->angle_from[0]), c->position[0],
             store_source_name(c->position_from[0]), c->angle_deg[1], store_source_name(c->angle_from[1]),
             c->position[1], store_source_name(c->position_from[1]), hinge);
    session_event(s, NAN, STORE_EVENT_INFO, msg);
}

/* A prediction that cannot run: stored as failed with its reason (a warning event and the
 * prediction row); the trial goes on, the strip on the rig being the ground truth. */
static void prediction_failed_early(trial_session *s, const trial_prediction_def *def, const char *reason)
{
    char w[256];
    if (trial_prediction_store_failed(s->st, def, reason, 0.0, w, sizeof w))
        session_event(s, NAN, STORE_EVENT_FAULT, w);
    pthread_mutex_lock(&s->lock);
    s->status.prediction_failed = 1;
    snprintf(s->status.message, sizeof s->status.message, "prediction failed: %.230s", reason);
    pthread_mutex_unlock(&s->lock);
    trial_publish_prediction(s->bus, s->trial_id, 0, 0, NAN, NULL, 0, NULL, NULL, NULL, reason);
}

/* The named specimen's calibration (if it has one) in the prediction's scene, at the resolution the
 * measured strip's ladder chose (the ladder is cached per measured strip: a calibration refreshed
 * after every trial would otherwise compute one per trial); said in an event, recorded with the
 * prediction (its calibration_json, its scene hash the calibrated strip's). The in-trial fit keeps
 * the measured strip as its start and prior (p->pred), an estimate of this trial's own. */
static void specimen_calibration_in(trial_session *s, trial_prediction_def *def)
{
    trial_specimen_calib_use cu;
    rod_scene sc = def->scene;
    trial_specimen_calib_apply(s->specimen_calibration, &s->pred_scene, &s->use.creases, &sc, &cu);
    if (cu.message[0]) session_event(s, NAN, cu.warning ? STORE_EVENT_WARNING : STORE_EVENT_INFO, cu.message);
    if (!cu.applied) return;
    def->scene = sc;
    snprintf(def->calibration_json, sizeof def->calibration_json, "%s", cu.record);
    rod_scene at_own = sc; /* hashed as the measured strip is: at the scene's own resolution */
    at_own.nodes = s->pred_scene.nodes;
    at_own.dt = s->pred_scene.dt;
    scene_hash_text(&at_own, s->cfg.sim.fast, def->hash, sizeof def->hash);
}

/* Step 2: the prediction's resolution, then the prediction on its own thread beside the trial.
 * Only an abort stops the trial here: a prediction that cannot be made (the ladder found no snap,
 * the simulator refused the scene) is stored as failed and the trial runs without it; the mock
 * twin then runs at the scene's own mesh.nodes. */
static int session_start_prediction(trial_session *s, session_parts *p, char *why, size_t why_len)
{
    double est = NAN, adapt_scale = 0.0;
    char hash[72] = "";
    char w[400];
    note_specimen_use(s);
    trial_prediction_def def = {.adaptive = s->cfg.sim.fast, .trial_id = s->trial_id, .cancel = &s->cancel,
                                .done = prediction_done, .user = s, .creases = s->use.creases,
                                .idle = s->cfg.mode == RIG_MODE_RIG};
    snprintf(def.store_path, sizeof def.store_path, "%s", s->cfg.store_path);
    int failed = choose_resolution(s, &p->pred, &adapt_scale, &est, hash, sizeof hash, w, sizeof w);
    if (failed && atomic_load(&s->cancel)) {
        aborted_early(s, why, why_len);
        return -1;
    }
    if (aborted_early(s, why, why_len)) return -1;
    def.scene = p->pred;
    def.est_error = est;
    def.adapt_scale = adapt_scale;
    snprintf(def.hash, sizeof def.hash, "%s", hash);
    specimen_calibration_in(s, &def);
    if (failed) {
        char reason[480];
        snprintf(reason, sizeof reason, "no prediction resolution: %s", w);
        prediction_failed_early(s, &def, reason);
        return 0;
    }
    p->sc.nodes = p->pred.nodes; /* the twin at the prediction's resolution */
    p->sc.dt = p->pred.dt;
    pthread_mutex_lock(&s->lock);
    s->status.nodes = p->pred.nodes;
    s->status.dt = p->pred.dt;
    pthread_mutex_unlock(&s->lock);
    if (trial_prediction_start(&def, &s->prediction, w, sizeof w)) {
        char reason[480];
        snprintf(reason, sizeof reason, "the prediction's thread could not start: %s", w);
        prediction_failed_early(s, &def, reason);
    }
    return 0;
}

/* Step 3a: the camera: mock mode's twin at the prediction's resolution, mounted at the compression
 * rail's current position; rig mode's live camera. */
static int session_open_camera(trial_session *s, session_parts *p, char *why, size_t why_len)
{
    const rig_config *cfg = &s->cfg;
    rail_status rs;
    if (rail_status_poll(s->compress, &rs) != RAIL_OK) {
        snprintf(why, why_len, "compression rail: %s", rail_last_error(s->compress));
        return -1;
    }
    if (cfg->mode == RIG_MODE_MOCK) {
        twin_camera_params cp = twin_camera_params_default();
        cp.width_px = s->width;
        cp.height_px = s->height;
        double dl0 = rig_calib_dl(&cfg->calib, p->sc.length, rs.position_mm);
        /* The strip on the bench: [twin]'s own (the trial's scene with its keys, at its own mesh
         * and step), or without [twin] the prediction's scene at the prediction's resolution. */
        const rod_scene *tsc = cfg->twin.present ? &cfg->twin.scene : &p->sc;
        const char *keys[RIG_TWIN_KEYS_MAX];
        for (int i = 0; i < cfg->twin.n; i++) keys[i] = cfg->twin.keys[i];
        char msg[sizeof cfg->twin.keys + 128];
        twin_truth_params(tsc, keys, cfg->twin.present ? cfg->twin.n : 0, msg, sizeof msg);
        session_event(s, NAN, STORE_EVENT_INFO, msg);
        if (mock_camera_open(tsc, dl0, &cp, cfg->camera.noise_sigma, cfg->camera.blur_sigma_px,
                             (uint64_t)s->trial_id, &p->mock, why, why_len))
            return -1;
        p->cam.grab = mock_camera_grab;
        p->cam.ctx = p->mock;
        /* The twin's shear force is the mock shear drive's load (its force sensor): the runner's
         * second witness when detect.torque_witness is on. */
        if (cfg->detect.torque_witness && mock_camera_feed_load(p->mock, s->shear, why, why_len)) return -1;
        return 0;
    }
    /* Rig mode: the live pipeline (trial_live.h) opens the camera and records the video (raw Y800
     * AVI); the runner takes its frames, so cam.grab is never called. */
    char vpath[RIG_PATH_MAX + 64];
    snprintf(vpath, sizeof vpath, "%s/trial-%lld.avi", cfg->camera.video_dir, (long long)s->trial_id);
    if (trial_live_open(cfg, s->compress, s->shear, vpath, s->roi, s->width, s->height, &s->cal, &s->live, why, why_len))
        return -1;
    snprintf(s->live_video, sizeof s->live_video, "%s", vpath);
    char w[256];
    store_trial_set_video(s->st, s->trial_id, vpath, w, sizeof w);
    p->live.clock = rail_get_clock(s->compress);
    p->cam.grab = live_grab;
    p->cam.ctx = &p->live;
    return 0;
}

/* Step 3b: the tracker (with the calibration stored with the trial) and the cropped video. */
static int session_open_tracker_and_video(trial_session *s, session_parts *p, char *why, size_t why_len)
{
    const rig_config *cfg = &s->cfg;
    vis_error ve = {0};
    /* Sized to the ribbon's face, which a strip twisted under shear shows (docs/vision.md). */
    vis_track_params tp = vis_track_params_for_ribbon(p->sc.width * 1000.0, s->cal.px_per_mm);
    tp.length_mm = p->sc.length * 1000.0;
    p->trk = vis_tracker_create(&tp, &s->cal, &ve);
    if (!p->trk) {
        snprintf(why, why_len, "tracker: %s", ve.message);
        return -1;
    }
    if (s->live) return 0; /* the live pipeline records */
    char video_path[RIG_PATH_MAX + 64];
    snprintf(video_path, sizeof video_path, "%s/trial-%lld.mkv", cfg->camera.video_dir, (long long)s->trial_id);
    s->video = trial_video_open(video_path, s->roi, cfg->camera.fps, why, why_len);
    if (!s->video) return -1;
    char w[256];
    store_trial_set_video(s->st, s->trial_id, video_path, w, sizeof w);
    return 0;
}

/* Mock mode: the twin's own snap (from its own states, rod_twin_snap), stored beside the measured
 * one as an event before the result, so whoever reads the finished trial finds it. */
static void session_twin_truth(trial_session *s, session_parts *p)
{
    if (!p->mock) return;
    rod_snap_report r;
    double dw_now = NAN;
    mock_camera_truth(p->mock, &r, &dw_now);
    const rod_scene *sc = &s->cfg.scene;
    char msg[400];
    twin_truth_snap(&r, sc->shear_rate / sc->length, dw_now, msg, sizeof msg);
    session_event(s, NAN, STORE_EVENT_INFO, msg);
}

/* The runner's plan: the rig file's trial, detection and camera settings. */
static trial_plan session_plan(const rig_config *cfg)
{
    trial_plan plan;
    memset(&plan, 0, sizeof plan);
    plan.scene = cfg->scene;
    plan.calib = cfg->calib;
    plan.compress_speed_mm_s = cfg->trial.compress_speed_mm_s;
    plan.return_speed_mm_s = cfg->trial.return_speed_mm_s;
    plan.hold_s = cfg->trial.hold_s;
    plan.upper_dz_min = cfg->trial.upper_dz_min;
    plan.post_snap_s = cfg->trial.post_snap_s;
    plan.min_quality = cfg->detect.min_quality;
    plan.snap = snap_params_default();
    plan.snap.snap_speed = cfg->scene.snap_speed;
    plan.snap.asym_threshold = cfg->scene.asym_threshold;
    plan.snap.dz_jump = cfg->detect.dz_jump;
    plan.snap.post_snap_s = cfg->trial.post_snap_s;
    plan.frozen_frames = cfg->camera.frozen_frames;
    plan.frozen_move_mm = cfg->camera.frozen_move_mm;
    plan.fps = cfg->camera.fps;
    plan.torque_witness = cfg->detect.torque_witness;
    plan.load_jump = cfg->detect.load_jump;
    plan.paced_by_camera = cfg->mode == RIG_MODE_RIG;
    if (cfg->mode == RIG_MODE_RIG) {
        plan.cam_offset_window_s = cfg->camera.time_offset_window_s;
        plan.cam_offset_measure = cfg->camera.time_offset_measure;
    }
    return plan;
}

/* The calibrated prediction that landed (on the trial thread): posted to the fit's writer
 * (trial_fit_out.h), which stores it in the trial's row beside the scene's prediction (a later fit
 * replaces an earlier one; a failure replaces nothing that landed ok) and publishes it on the live
 * bus; the loop does not wait on the store for it. */
static void calibrated_landed(void *user, const trial_calibrated *r)
{
    trial_session *s = user;
    const trial_calibrated *kept = trial_calibrate_kept(s->calib);
    if (!r->ok && kept) return; /* an earlier fit stands */
    if (trial_fit_out_calibrated(s->fit_out, r))
        session_event(s, r->t_landed, STORE_EVENT_WARNING, "calibration: out of memory: its landed result is not stored");
}

/* The fit's events (on the trial thread): posted to its writer, which stores, publishes and logs
 * them as session_event does. */
static int calib_event(void *user, double t_s, const char *kind, const char *message)
{
    trial_session *s = user;
    store_event_kind k = STORE_EVENT_INFO;
    store_event_kind_parse(kind, &k);
    store_event ev;
    session_event_fill(s, t_s, k, message, &ev);
    if (trial_fit_out_event(s->fit_out, &ev)) session_event(s, t_s, ev.kind, message);
    return 0;
}

static void fit_out_log(void *user, const char *line)
{
    logf_((trial_session *)user, "%s", line);
}

/* The scene's predicted snap so far, for the fit's refreshes (on the runner's thread): NaN until
 * the prediction is stored. */
static double calib_scene_snap(void *user)
{
    trial_session *s = user;
    pthread_mutex_lock(&s->lock);
    double dw = s->status.prediction_done ? s->status.snap_dw_predicted : NAN;
    pthread_mutex_unlock(&s->lock);
    return dw;
}

/* The fit beside the trial (sim.fit), on the prediction's scene at its resolution. A fit that
 * cannot be set up is said in an event; the trial runs without it. */
static void session_open_calibrate(trial_session *s, session_parts *p)
{
    if (!s->cfg.sim.fit) return;
    char wo[300];
    s->fit_out = trial_fit_out_open(s->cfg.store_path, s->trial_id, s->bus, fit_out_log, s, wo, sizeof wo);
    if (!s->fit_out) {
        char m[400];
        snprintf(m, sizeof m, "calibration off for this trial: its writer could not start: %s", wo);
        session_event(s, NAN, STORE_EVENT_WARNING, m);
        return;
    }
    trial_calibrate_def d = trial_calibrate_def_default();
    d.scene = p->pred;
    /* A rigid crease is not a model of a real one (a PET crease is a compliant hinge, DESIGN.md
     * section 9): sim.fit_hinge makes the fit's creases hinges of that stiffness, its start and
     * its prior's centre, while the scene's prediction keeps the scene's creases.
     * The setup is the specimen refit's too (trial_calibrate_setup); a key it refuses is the
     * fit's named failure when it runs (trial_calibrate_compute). */
    rod_fit_opts o;
    char rk[24], rw[320];
    int rigid = rod_scene_hinge_rigid(&d.scene);
    trial_calibrate_setup(&d.scene, s->cfg.sim.fit_hinge, s->cfg.sim.fit_keys, &o, rk, rw, sizeof rw);
    if (rigid && !rod_scene_hinge_rigid(&d.scene)) {
        char m[200];
        snprintf(m, sizeof m,
                 "calibration: the scene's creases are rigid; the fit makes them hinges of %g N m/rad (sim.fit_hinge: "
                 "its start and its prior's centre)",
                 s->cfg.sim.fit_hinge);
        session_event(s, NAN, STORE_EVENT_INFO, m);
    }
    snprintf(d.keys, sizeof d.keys, "%s", s->cfg.sim.fit_keys);
    d.refresh_s = s->cfg.sim.fit_refresh_s;
    d.fit_shape = s->cfg.sim.fit_shape;
    d.idle = s->cfg.mode == RIG_MODE_RIG;
    d.event = calib_event;
    d.landed = calibrated_landed;
    d.scene_snap = calib_scene_snap;
    d.user = s;
    char w[256];
    s->calib = trial_calibrate_new(&d, w, sizeof w);
    if (!s->calib) session_event(s, NAN, STORE_EVENT_WARNING, w);
    trial_runner_set_calibrate(&s->runner, s->calib);
}

/* Step 4: the runner, storing every sample (batched), event and state; the trial is running (and
 * counted for its specimen) from here. */
static int session_run(trial_session *s, session_parts *p, char *why, size_t why_len)
{
    trial_plan plan = session_plan(&s->cfg);
    plan.clamp_tol_mm = trial_clamp_tol_mm(s->cal.px_per_mm);
    /* The compression's last part tracked with the clamp points moved (trial_comp_track.h); live,
     * within TRIAL_COMP_TRACK_LIVE_BUDGET of the loop's time (a fresh tracker per frame). */
    if (plan.clamp_tol_mm > 0.0) {
        plan.comp_track_from_dl = trial_comp_track_from_dl(plan.scene.compression);
        plan.comp_calib = s->cal;
        if (s->live) plan.comp_track_budget = TRIAL_COMP_TRACK_LIVE_BUDGET;
    }
    for (int k = 0; k < 2; k++) {
        plan.cam_clamp_px[0][k] = s->cal.clamp_left_px[k];
        plan.cam_clamp_px[1][k] = s->cal.clamp_right_px[k];
    }
    if (store_samples_begin(s->st, s->trial_id, NULL, &s->writer, why, why_len) != STORE_OK) return -1;
    trial_sink sink = {sink_state, sink_event, sink_sample, sink_frame, s};
    if (trial_runner_init(&s->runner, &plan, s->compress, s->shear, p->cam, p->trk, sink, why, why_len)) return -1;
    if (s->live) trial_live_attach(s->live, &s->runner);
    session_open_calibrate(s, p);
    pthread_mutex_lock(&s->lock);
    s->runner_ready = 1;
    if (s->abort_pending) trial_runner_abort(&s->runner, s->abort_reason);
    pthread_mutex_unlock(&s->lock);
    if (store_trial_set_status(s->st, s->trial_id, STORE_STATUS_RUNNING, NULL, store_wall_now(), why, why_len) !=
        STORE_OK)
        return -1;
    char w[256];
    store_trial tr;
    if (store_trial_get(s->st, s->trial_id, &tr, w, sizeof w) == STORE_OK && tr.specimen_id > 0)
        store_specimen_count_trial(s->st, tr.specimen_id, w, sizeof w);
    trial_runner_run(&s->runner, &s->result);
    trial_publish_result(s->bus, s->trial_id, &s->result);
    pthread_mutex_lock(&s->lock);
    s->runner_ready = 0;
    pthread_mutex_unlock(&s->lock);
    return 0;
}

/* Step 5: the measured result and the final status, then (rig mode) the live pipeline closed.
 * Samples first, so a stored result always has its samples. */
static void session_store_result(trial_session *s)
{
    char w[256];
    /* The rails have stopped: what the fit posted (a done trial's last landing included) is
     * written before the final status, as when the loop wrote it itself. */
    trial_fit_out_drain(s->fit_out);
    if (store_samples_end(s->writer, w, sizeof w) != STORE_OK) session_event(s, NAN, STORE_EVENT_FAULT, w);
    s->writer = NULL;
    if (trial_video_close(s->video, w, sizeof w) < 0) { /* the video lost frames: a fault, not done */
        session_event(s, NAN, STORE_EVENT_FAULT, w);
        if (s->result.final == TRIAL_DONE) s->result.final = TRIAL_FAILED;
        if (!s->result.reason[0]) snprintf(s->result.reason, sizeof s->result.reason, "%s", w);
    }
    s->video = NULL;
    store_regime reg = trial_regime_of(s->result.snapped, s->result.vision_snapped && !s->result.regime_undecided,
                                       s->result.asymmetric);
    if (s->result.final == TRIAL_DONE || s->result.snapped)
        store_trial_set_result(s->st, s->trial_id, s->result.snapped, s->result.snapped ? s->result.snap_dw : NAN, reg,
                               w, sizeof w);
    if (isfinite(s->result.stop_cmd_latency_s) &&
        store_trial_set_latency(s->st, s->trial_id, s->result.stop_cmd_latency_s, s->result.stop_stand_latency_s, w,
                                sizeof w) != STORE_OK)
        session_event(s, NAN, STORE_EVENT_FAULT, w);
    if (isfinite(s->result.camera_offset_s) &&
        store_trial_set_camera_offset(s->st, s->trial_id, s->result.camera_offset_s, s->result.camera_offset_sd_s, w,
                                      sizeof w) != STORE_OK)
        session_event(s, NAN, STORE_EVENT_FAULT, w);
    session_store_final(s, s->result.final, s->result.reason[0] ? s->result.reason : NULL);
    trial_publish_stored(s->bus, s->trial_id, s->result.final);
    /* A failed or aborted trial's fit beside it: cancelled and waited for (at most its abort cap)
     * after the final status, which does not wait for it (trial_runner.h). A done trial's ended
     * in the runner. */
    if (s->result.final != TRIAL_DONE) trial_calibrate_end(s->calib, s->result.duration_s, 1);
    logf_(s, "%s%s%s; measured %s at Delta W = %.5f", trial_state_name(s->result.final),
          s->result.reason[0] ? ": " : "", s->result.reason, s->result.regime, s->result.snap_dw);
    /* Rig mode: the camera and the pipeline after the final status (issue 33, item 13): closing a
     * camera that died with its rig waits out its link's timeouts, seconds in which the store
     * said "running" for a trial that had failed. Its counts and a video failure follow as events. */
    if (s->live) session_live_close(s);
}

/* Whatever the steps opened, closed; the prediction waited for (it stops at once when the trial
 * was aborted). */
static void session_release(trial_session *s, session_parts *p)
{
    char w[256];
    if (s->writer) {
        store_samples_end(s->writer, w, sizeof w);
        s->writer = NULL;
    }
    if (s->video) {
        trial_video_close(s->video, w, sizeof w);
        s->video = NULL;
    }
    if (s->live) session_live_close(s);
    trial_prediction_join(s->prediction);
    s->prediction = NULL;
    trial_calibrate_free(s->calib); /* ended by the runner; else waited for at most its abort cap */
    s->calib = NULL;
    trial_fit_out_close(s->fit_out); /* what the fit posted, written */
    s->fit_out = NULL;
    trial_runner_free(&s->runner);
    vis_tracker_free(p->trk);
    mock_camera_close(p->mock);
    if (p->live.src) vis_source_close(p->live.src);
}

/* Step 7: a done trial of a named specimen (sim.specimen_fit): the specimen refitted from all its
 * finished trials, this one included (trial_specimen_calib.h), and the outcome said in an event.
 * After the rails stopped, the record was stored and everything was closed; before the session
 * says it finished, so the specimen's next trial (the queue's, or a start that waits for this one)
 * predicts with the new calibration. An abort (ribbond's shutdown: the API refuses one once the
 * trial has ended) cancels the fit at its next evaluation; a refit that fails keeps the
 * calibration before it. */
static void session_refit_specimen(trial_session *s)
{
    if (!refit_due(s, s->result.final)) {
        pthread_mutex_lock(&s->lock); /* the runner said done, but the trial did not end so */
        s->status.refitting[0] = 0;
        pthread_mutex_unlock(&s->lock);
        return;
    }
    /* The trial is done and stored, but the session has not ended: the page is told what it
     * still does (the API says it from the runner's done on: sink_state). */
    char busy[RIG_NAME_MAX + 32];
    snprintf(busy, sizeof busy, "done, refitting specimen %s", s->cfg.specimen.name);
    pthread_mutex_lock(&s->lock);
    snprintf(s->status.refitting, sizeof s->status.refitting, "%s", s->cfg.specimen.name);
    pthread_mutex_unlock(&s->lock);
    trial_publish_state_name(s->bus, s->trial_id, busy, NAN, "its next trial predicts with the new calibration");
    logf_(s, "refitting specimen %s from its finished trials", s->cfg.specimen.name);
    trial_specimen_refit r;
    trial_specimen_calib_refit(s->st, s->specimen_id, s->cfg.specimen.name, s->trial_id, s->cfg.sim.fit_keys,
                               s->cfg.sim.fit_hinge, &s->cancel, &r);
    session_event(s, NAN, r.ok ? STORE_EVENT_INFO : STORE_EVENT_WARNING, r.message);
    pthread_mutex_lock(&s->lock);
    s->status.refitting[0] = 0;
    pthread_mutex_unlock(&s->lock);
    trial_publish_state(s->bus, s->trial_id, TRIAL_DONE, NAN, r.ok ? "specimen refitted" : "specimen not refitted");
}

static void session_mark_finished(trial_session *s)
{
    pthread_mutex_lock(&s->lock);
    s->status.finished = 1;
    if (!trial_state_final(s->status.state)) s->status.state = s->result.final;
    pthread_mutex_unlock(&s->lock);
}

static void *session_main(void *arg)
{
    trial_session *s = arg;
    session_parts p = {.sc = s->cfg.scene, .pred = s->pred_scene};
    char why[512] = "";
    int failed = session_check_disk(s, why, sizeof why) || session_start_prediction(s, &p, why, sizeof why) ||
                 session_open_camera(s, &p, why, sizeof why) ||
                 session_open_tracker_and_video(s, &p, why, sizeof why) || session_run(s, &p, why, sizeof why);
    session_twin_truth(s, &p);
    if (failed)
        fail_early(s, why);
    else
        session_store_result(s);
    session_release(s, &p);
    session_refit_specimen(s);
    session_mark_finished(s);
    return NULL;
}

/* The longest computation a start may ask for before its trial moves: the ladder when the store
 * has none cached for the scene, or the prediction at an explicit resolution. A start whose
 * estimate exceeds TRIAL_PREDICTION_MAX_S is refused with the estimate (nothing is recorded). */
static trial_err check_prediction_cost(const rig_config *cfg, char *why, size_t why_len)
{
    const rig_sim *sim = &cfg->sim;
    rod_scene sc = cfg->scene;
    double est;
    const char *what;
    if (sim->explicit_resolution) {
        if (sim->nodes > 0) sc.nodes = sim->nodes;
        if (sim->dt > 0) sc.dt = sim->dt;
        est = predict_estimate_s(&sc, sim->fast);
        what = "the prediction";
    } else {
        est = predict_ladder_estimate_s(&sc, sim->ladder_nodes, sim->n_ladder, sim->fast);
        what = "the resolution ladder (if not cached)";
    }
    if (est <= TRIAL_PREDICTION_MAX_S) return TRIAL_OK;
    snprintf(why, why_len,
             "%s would take about %.3g s (estimated: N = %d, dt = %g s, shear to Delta W = %g at %g m/s); a start "
             "may ask for at most %g s: use a smaller sim.nodes or a larger solver.dt", what, est, sc.nodes, sc.dt,
             sc.shear_max, sc.shear_rate, TRIAL_PREDICTION_MAX_S);
    return TRIAL_E_REFUSED;
}

trial_err trial_session_start(const rig_config *cfg, rail *compress, rail *shear, const char *note,
                              void (*log)(const char *line), live_bus *bus, trial_session **out, int64_t *trial_id,
                              char *why, size_t why_len)
{
    return trial_session_start_tx(cfg, NULL, 0, compress, shear, note, log, bus, NULL, out, trial_id, why, why_len);
}

trial_err trial_session_start_tx(const rig_config *cfg, const char *const *sets, int n_sets, rail *compress, rail *shear, const char *note,
                                 void (*log)(const char *line), live_bus *bus, trial_transcoder *tx,
                                 trial_session **out, int64_t *trial_id, char *why, size_t why_len)
{
    *out = NULL;
    trial_err te = check_prediction_cost(cfg, why, why_len);
    if (te != TRIAL_OK) return te;
    rod_scene pred_scene;
    trial_specimen_use use;
    double created = store_wall_now(), crease_age = NAN;
    if (trial_specimen_scene(cfg, &pred_scene, &use, why, why_len) ||
        trial_specimen_crease_age(cfg, created, &crease_age, why, why_len))
        return TRIAL_E_REFUSED; /* the specimen's measurements are bad input: nothing recorded */
    trial_session *s = calloc(1, sizeof *s);
    if (!s) {
        snprintf(why, why_len, "out of memory");
        return TRIAL_E_FAILED;
    }
    s->pred_scene = pred_scene;
    s->use = use;
    s->cfg = *cfg;
    s->compress = compress;
    s->shear = shear;
    s->log = log;
    s->bus = bus;
    s->tx = tx;
    snprintf(s->note, sizeof s->note, "%s", note ? note : "");
    pthread_mutex_init(&s->lock, NULL);
    s->status.snap_dw_predicted = NAN;
    if (store_open(cfg->store_path, &s->st, why, why_len) != STORE_OK) goto fail;

    /* The specimen and the trial row. */
    store_specimen sp;
    trial_specimen_from_config(cfg, &sp);
    int64_t spid = 0;
    if (store_specimen_upsert(s->st, &sp, &spid, why, why_len) != STORE_OK) goto fail;
    s->specimen_id = spid;
    store_specimen now;
    char w0[256];
    if (cfg->sim.specimen_fit && cfg->specimen.name[0] && store_specimen_get(s->st, spid, &now, w0, sizeof w0) == STORE_OK)
        memcpy(s->specimen_calibration, now.calibration_json, sizeof s->specimen_calibration);
    if (trial_camera_setup(cfg, &s->cal, &s->width, &s->height, &s->roi, why, why_len)) goto fail;
    char *config_text = trial_config_text(cfg, sets, n_sets, s->note);
    char *calib = trial_record_json(cfg, &s->cal, s->roi, why, why_len);
    if (!calib) {
        free(config_text);
        goto fail;
    }
    store_trial_def def = store_trial_def_default();
    def.mode = cfg->mode == RIG_MODE_RIG ? STORE_MODE_RIG : STORE_MODE_MOCK;
    def.config_text = config_text ? config_text : "";
    def.calibration_json = calib;
    def.specimen_id = spid;
    def.created_wall_s = created;
    def.crease_age_s = crease_age;
    store_err se = store_trial_create(s->st, &def, &s->trial_id, why, why_len);
    free(config_text);
    free(calib);
    if (se != STORE_OK) goto fail;
    s->status.trial_id = s->trial_id;
    s->status.state = TRIAL_IDLE;
    trial_publish_begin(bus, s->trial_id, cfg->mode == RIG_MODE_RIG ? "rig" : "mock", s->note);
    if (pthread_create(&s->thread, NULL, session_main, s) != 0) {
        snprintf(why, why_len, "could not start the trial thread");
        char w[256];
        store_trial_set_status(s->st, s->trial_id, STORE_STATUS_FAILED, why, store_wall_now(), w, sizeof w);
        goto fail;
    }
    *trial_id = s->trial_id;
    *out = s;
    return TRIAL_OK;
fail:
    store_close(s->st);
    pthread_mutex_destroy(&s->lock);
    free(s);
    return TRIAL_E_FAILED;
}

void trial_session_abort(trial_session *s, const char *reason)
{
    atomic_store(&s->cancel, 1); /* the ladder or the prediction, if computing, stop at their next step */
    pthread_mutex_lock(&s->lock);
    if (s->runner_ready)
        trial_runner_abort(&s->runner, reason);
    else if (!s->abort_pending) {
        s->abort_pending = 1;
        snprintf(s->abort_reason, sizeof s->abort_reason, "%s", reason && *reason ? reason : "abort requested");
    }
    pthread_mutex_unlock(&s->lock);
}

void trial_session_status(trial_session *s, session_status *out)
{
    pthread_mutex_lock(&s->lock);
    *out = s->status;
    pthread_mutex_unlock(&s->lock);
}

void trial_session_join(trial_session *s, trial_result *result) { trial_session_join_status(s, result, NULL); }

void trial_session_join_status(trial_session *s, trial_result *result, session_status *status)
{
    if (!s) return;
    pthread_join(s->thread, NULL);
    if (result) *result = s->result;
    if (status) *status = s->status;
    store_close(s->st);
    pthread_mutex_destroy(&s->lock);
    free(s);
}
