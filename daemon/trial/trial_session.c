/* trial_session.c: one trial from request to stored result (see trial_session.h). */
#include "trial_session.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <errno.h>
#include <sys/stat.h>
#include <sys/statvfs.h>

#include <jansson.h>

#include "mock_camera.h"
#include "predict_ladder.h"
#include "rod_protocol.h"
#include "store.h"
#include "trial_calib.h"
#include "trial_video.h"

#ifndef RIBBON_VERSION
#define RIBBON_VERSION "unknown"
#endif

/* The prediction that runs beside the trial. */
typedef struct pred_job {
    rod_scene scene;        /* at the chosen resolution */
    int adaptive;
    double est_error;       /* NaN when unknown */
    char hash[72];
    char store_path[RIG_PATH_MAX];
    int64_t trial_id;
    trial_session *s;
    /* curve being recorded */
    size_t n, cap;
    double *t, *dw, *dz, *a;
    double last_dw, last_dz;
} pred_job;

struct trial_session {
    rig_config cfg;
    rail *compress, *shear;
    void (*log)(const char *line);
    store *st;              /* the trial thread's connection */
    store_samples *writer;
    int64_t trial_id;
    pthread_t thread, pred_thread;
    int pred_started;
    pred_job pred;
    trial_runner runner;
    int runner_ready;
    trial_result result;
    trial_video *video;
    pthread_mutex_t lock;
    session_status status;  /* under lock */
    int abort_pending;      /* under lock: an abort that came before the runner existed */
    char abort_reason[128];
    char note[256];
    vis_calib cal;          /* the camera calibration of this trial */
    trial_roi roi;          /* the saved video's region */
    int width, height;      /* frame size */
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

static void session_event(trial_session *s, double t_s, store_event_kind kind, const char *msg)
{
    store_event ev;
    memset(&ev, 0, sizeof ev);
    ev.trial_id = s->trial_id;
    ev.t_s = t_s;
    ev.wall_s = store_wall_now();
    pthread_mutex_lock(&s->lock);
    snprintf(ev.state, sizeof ev.state, "%s", trial_state_name(s->status.state));
    pthread_mutex_unlock(&s->lock);
    ev.kind = kind;
    snprintf(ev.message, sizeof ev.message, "%s", msg);
    char why[256];
    if (store_event_append(s->st, &ev, why, sizeof why) != STORE_OK) logf_(s, "event not stored: %s", why);
    logf_(s, "%s", msg);
}

/* ---- the prediction thread ---------------------------------------------------------------- */

static int pred_grow(pred_job *j)
{
    size_t cap = j->cap ? 2 * j->cap : 1024;
    double *t = realloc(j->t, cap * sizeof *t);
    if (t) j->t = t;
    double *dw = realloc(j->dw, cap * sizeof *dw);
    if (dw) j->dw = dw;
    double *dz = realloc(j->dz, cap * sizeof *dz);
    if (dz) j->dz = dz;
    double *a = realloc(j->a, cap * sizeof *a);
    if (a) j->a = a;
    if (!t || !dw || !dz || !a) return -1;
    j->cap = cap;
    return 0;
}

/* Keeps a sample each 1/2000 of the shear range, and every step where Delta Z moves fast. */
static int pred_sample(void *user, const rod_sample *smp, const rod *r)
{
    (void)r;
    pred_job *j = user;
    double step = j->scene.shear_max / 2000.0;
    if (j->n > 0 && smp->dw - j->last_dw < step && fabs(smp->dz - j->last_dz) < 2e-3) return 0;
    if (j->n == j->cap && pred_grow(j)) return 0; /* a thinner curve, not a failure */
    j->t[j->n] = smp->t;
    j->dw[j->n] = smp->dw;
    j->dz[j->n] = smp->dz;
    j->a[j->n] = smp->a;
    j->n++;
    j->last_dw = smp->dw;
    j->last_dz = smp->dz;
    return 0;
}

static void *pred_main(void *arg)
{
    pred_job *j = arg;
    trial_session *s = j->s;
    rod_predict_opts o = rod_predict_opts_default();
    o.adaptive = j->adaptive;
    o.on_sample = pred_sample;
    o.user = j;
    rod_prediction p;
    char err[256] = "", why[256] = "";
    rod_status rs = rod_predict(&j->scene, &o, &p, err, sizeof err);
    store *st = NULL;
    if (store_open(j->store_path, &st, why, sizeof why) != STORE_OK) {
        logf_(s, "prediction not stored: %s", why);
        goto out;
    }
    if (rs != ROD_OK) {
        char msg[400];
        snprintf(msg, sizeof msg, "prediction failed: %s", err);
        store_event ev;
        memset(&ev, 0, sizeof ev);
        ev.trial_id = j->trial_id;
        ev.t_s = NAN;
        ev.wall_s = store_wall_now();
        ev.kind = STORE_EVENT_WARNING;
        snprintf(ev.message, sizeof ev.message, "%s", msg);
        store_event_append(st, &ev, why, sizeof why);
        pthread_mutex_lock(&s->lock);
        s->status.prediction_failed = 1;
        pthread_mutex_unlock(&s->lock);
        logf_(s, "%s", msg);
        goto out;
    }
    store_prediction sp = store_prediction_default();
    sp.trial_id = j->trial_id;
    snprintf(sp.scene_hash, sizeof sp.scene_hash, "%s", j->hash);
    sp.snapped = p.snapped;
    sp.snap_dw = p.snapped ? p.snap_dw : NAN;
    sp.regime = !p.snapped ? STORE_REGIME_NO_SNAP : p.asymmetric ? STORE_REGIME_ASYMMETRIC : STORE_REGIME_SYMMETRIC;
    sp.peak_abs_a = p.peak_abs_a;
    sp.nodes = j->scene.nodes;
    sp.dt = j->scene.dt;
    sp.adaptive = j->adaptive;
    sp.imperfection = j->scene.fold_angle_rel;
    sp.est_error = j->est_error;
    sp.wall_s = p.wall_s;
    char solver[512];
    snprintf(solver, sizeof solver,
             "{\"nodes\":%d,\"dt\":%.17g,\"adaptive\":%s,\"tolerance\":%.17g,\"max_iterations\":%d,"
             "\"damping\":%.17g,\"route\":%d,\"fold_angle_rel\":%.17g,\"snap_speed\":%.17g,"
             "\"asym_threshold\":%.17g,\"steps\":%ld,\"rejected\":%ld}",
             j->scene.nodes, j->scene.dt, j->adaptive ? "true" : "false", j->scene.tolerance,
             j->scene.max_iterations, j->scene.damping, (int)j->scene.route, j->scene.fold_angle_rel,
             j->scene.snap_speed, j->scene.asym_threshold, p.steps, p.rejected);
    sp.solver_json = solver;
    sp.curve.n = j->n;
    sp.curve.t_s = j->t;
    sp.curve.dw = j->dw;
    sp.curve.dz = j->dz;
    sp.curve.a = j->a;
    int64_t pid = 0;
    if (store_prediction_insert(st, &sp, &pid, why, sizeof why) != STORE_OK) {
        logf_(s, "prediction not stored: %s", why);
        goto out;
    }
    pthread_mutex_lock(&s->lock);
    s->status.prediction_done = 1;
    s->status.snap_dw_predicted = p.snapped ? p.snap_dw : NAN;
    snprintf(s->status.regime_predicted, sizeof s->status.regime_predicted, "%s",
             store_regime_name(sp.regime));
    pthread_mutex_unlock(&s->lock);
    logf_(s, "predicted: %s at Delta W = %.5f (N = %d, dt = %g s%s, %.2f s wall)", store_regime_name(sp.regime),
          p.snap_dw, j->scene.nodes, j->scene.dt, j->adaptive ? ", fast" : "", p.wall_s);
out:
    store_close(st);
    return NULL;
}

/* ---- resolution ----------------------------------------------------------------------------- */

/* Picks nodes and dt for the prediction (and the mock twin). Returns 0, or -1 with why. */
static int choose_resolution(trial_session *s, rod_scene *sc, double *est_error, char *hash, size_t hash_len,
                             char *why, size_t why_len)
{
    const rig_sim *sim = &s->cfg.sim;
    char h[17];
    scene_hash(sc, h);
    snprintf(hash, hash_len, "%s-v%s-%s", h, RIBBON_VERSION, sim->fast ? "fast" : "fixed");
    *est_error = NAN;
    if (sim->explicit_resolution) {
        if (sim->nodes > 0) sc->nodes = sim->nodes;
        if (sim->dt > 0) sc->dt = sim->dt;
        return 0;
    }
    store_ladder_rung *cached = NULL;
    size_t n = 0;
    ladder_rung r[LADDER_MAX_RUNGS];
    int nr = 0;
    if (store_ladder_get(s->st, hash, &cached, &n, why, why_len) == STORE_OK && n > 0) {
        for (size_t k = 0; k < n && nr < LADDER_MAX_RUNGS; k++) {
            memset(&r[nr], 0, sizeof r[nr]);
            r[nr].nodes = cached[k].nodes;
            r[nr].dt = cached[k].dt;
            r[nr].adaptive = cached[k].adaptive;
            r[nr].snap_dw = cached[k].snap_dw;
            r[nr].est_error = isfinite(cached[k].est_error) ? cached[k].est_error : -1.0;
            r[nr].wall_s = cached[k].wall_s;
            nr++;
        }
        free(cached);
        session_event(s, NAN, STORE_EVENT_INFO, "resolution ladder taken from the store's cache");
    } else {
        free(cached);
        char msg[128];
        snprintf(msg, sizeof msg, "computing the resolution ladder (%d rungs), once for this scene", sim->n_ladder);
        session_event(s, NAN, STORE_EVENT_INFO, msg);
        if (ladder_compute(sc, sim->ladder_nodes, sim->n_ladder, sim->fast, r, NULL, NULL, why, why_len)) return -1;
        nr = sim->n_ladder;
        store_ladder_rung sr[LADDER_MAX_RUNGS];
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
    int k = ladder_choose(r, nr, sim->target_error);
    sc->nodes = r[k].nodes;
    *est_error = r[k].est_error >= 0 ? r[k].est_error : NAN;
    char msg[200];
    snprintf(msg, sizeof msg, "prediction resolution N = %d, dt = %g s: estimated error %.2g (target %.2g)", sc->nodes,
             sc->dt, *est_error, sim->target_error);
    session_event(s, NAN, STORE_EVENT_INFO, msg);
    return 0;
}

/* ---- the runner's sink ------------------------------------------------------------------------ */

static int sink_state(void *user, trial_state st, double t_s, const char *why)
{
    trial_session *s = user;
    pthread_mutex_lock(&s->lock);
    s->status.state = st;
    pthread_mutex_unlock(&s->lock);
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
    if (store_samples_add(s->writer, &x, why, why_len) != STORE_OK) return -1;
    return 0;
}

static int sink_frame(void *user, const vis_frame *f, long index, char *why, size_t why_len)
{
    (void)index;
    trial_session *s = user;
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

/* ---- the trial thread ----------------------------------------------------------------------------- */

static void fail_early(trial_session *s, const char *why)
{
    char w[256];
    int aborted = strncmp(why, "aborted", 7) == 0;
    session_event(s, NAN, aborted ? STORE_EVENT_INFO : STORE_EVENT_FAULT, why);
    store_trial_set_status(s->st, s->trial_id, aborted ? STORE_STATUS_ABORTED : STORE_STATUS_FAILED, why,
                           store_wall_now(), w, sizeof w);
    s->result.final = aborted ? TRIAL_ABORTED : TRIAL_FAILED;
    snprintf(s->result.reason, sizeof s->result.reason, "%s", why);
    pthread_mutex_lock(&s->lock);
    s->status.state = s->result.final;
    pthread_mutex_unlock(&s->lock);
}

static void *session_main(void *arg)
{
    trial_session *s = arg;
    const rig_config *cfg = &s->cfg;
    char why[512] = "";
    mock_camera *mock = NULL;
    live_camera live = {0};
    vis_tracker *trk = NULL;
    rod_scene sc = cfg->scene;
    vis_error ve = {0};
    trial_camera cam = {0};

    /* 1. Disk space for the video. */
    struct statvfs fs;
    if (mkdir(cfg->camera.video_dir, 0775) != 0 && errno != EEXIST) {
        snprintf(why, sizeof why, "video directory %.300s cannot be created: %m", cfg->camera.video_dir);
        fail_early(s, why);
        goto end;
    }
    if (statvfs(cfg->camera.video_dir, &fs) != 0) {
        snprintf(why, sizeof why, "video directory %.300s cannot be read: %m", cfg->camera.video_dir);
        fail_early(s, why);
        goto end;
    }
    double free_mb = (double)fs.f_bavail * (double)fs.f_frsize / 1e6;
    if (free_mb < cfg->trial.min_free_disk_mb) {
        snprintf(why, sizeof why, "only %.0f MB free in %.300s; a trial needs %.0f MB (trial.min_free_disk_mb)", free_mb,
                 cfg->camera.video_dir, cfg->trial.min_free_disk_mb);
        fail_early(s, why);
        goto end;
    }

    /* 2. Resolution and the prediction beside the trial. */
    double est = NAN;
    char hash[72];
    if (choose_resolution(s, &sc, &est, hash, sizeof hash, why, sizeof why)) {
        char msg[600];
        snprintf(msg, sizeof msg, "no prediction resolution: %s", why);
        fail_early(s, msg);
        goto end;
    }
    if (aborted_early(s, why, sizeof why)) {
        fail_early(s, why);
        goto end;
    }
    pthread_mutex_lock(&s->lock);
    s->status.nodes = sc.nodes;
    s->status.dt = sc.dt;
    pthread_mutex_unlock(&s->lock);
    s->pred.scene = sc;
    s->pred.adaptive = cfg->sim.fast;
    s->pred.est_error = est;
    snprintf(s->pred.hash, sizeof s->pred.hash, "%s", hash);
    snprintf(s->pred.store_path, sizeof s->pred.store_path, "%s", cfg->store_path);
    s->pred.trial_id = s->trial_id;
    s->pred.s = s;
    if (pthread_create(&s->pred_thread, NULL, pred_main, &s->pred) == 0)
        s->pred_started = 1;
    else
        session_event(s, NAN, STORE_EVENT_WARNING, "prediction thread could not start: no prediction for this trial");

    /* 3. Camera, tracker, video. */
    rail_status rs;
    if (rail_status_poll(s->compress, &rs) != RAIL_OK) {
        snprintf(why, sizeof why, "compression rail: %s", rail_last_error(s->compress));
        fail_early(s, why);
        goto end;
    }
    int width = s->width, height = s->height;
    if (cfg->mode == RIG_MODE_MOCK) {
        twin_camera_params cp = twin_camera_params_default();
        cp.width_px = width;
        cp.height_px = height;
        double dl0 = rig_calib_dl(&cfg->calib, sc.length, rs.position_mm);
        if (mock_camera_open(&sc, dl0, &cp, cfg->camera.noise_sigma, cfg->camera.blur_sigma_px,
                             (uint64_t)s->trial_id, &mock, why, sizeof why)) {
            fail_early(s, why);
            goto end;
        }
        cam.grab = mock_camera_grab;
        cam.ctx = mock;
        /* The twin's shear force is the mock shear drive's load (its force sensor): the runner's
         * second witness when detect.torque_witness is on. */
        if (cfg->detect.torque_witness && mock_camera_feed_load(mock, s->shear, why, sizeof why)) {
            fail_early(s, why);
            goto end;
        }
    } else {
        vis_camera_settings cs = vis_camera_settings_default();
        cs.index = cfg->camera.index;
        cs.path = cfg->camera.source == RIG_SOURCE_DEVICE ? cfg->camera.device : NULL;
        cs.width_px = cfg->camera.width_px;
        cs.height_px = cfg->camera.height_px;
        cs.fps = cfg->camera.fps;
        live.src = vis_source_open_camera(&cs, &ve);
        if (!live.src) {
            snprintf(why, sizeof why, "camera: %s", ve.message);
            fail_early(s, why);
            goto end;
        }
        live.clock = rail_get_clock(s->compress);
        cam.grab = live_grab;
        cam.ctx = &live;
    }
    vis_track_params tp = vis_track_params_default();
    tp.length_mm = sc.length * 1000.0;
    trk = vis_tracker_create(&tp, &s->cal, &ve); /* the calibration stored with the trial */
    if (!trk) {
        snprintf(why, sizeof why, "tracker: %s", ve.message);
        fail_early(s, why);
        goto end;
    }
    trial_roi roi = s->roi;
    char video_path[RIG_PATH_MAX + 64];
    snprintf(video_path, sizeof video_path, "%s/trial-%lld.mkv", cfg->camera.video_dir, (long long)s->trial_id);
    s->video = trial_video_open(video_path, roi, cfg->camera.fps, why, sizeof why);
    if (!s->video) {
        fail_early(s, why);
        goto end;
    }
    {
        char w[256];
        store_trial_set_video(s->st, s->trial_id, video_path, w, sizeof w);
    }

    /* 4. The runner. */
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
    plan.fps = cfg->camera.fps;
    plan.torque_witness = cfg->detect.torque_witness;
    plan.load_jump = cfg->detect.load_jump;
    plan.paced_by_camera = cfg->mode == RIG_MODE_RIG;
    if (store_samples_begin(s->st, s->trial_id, NULL, &s->writer, why, sizeof why) != STORE_OK) {
        fail_early(s, why);
        goto end;
    }
    trial_sink sink = {sink_state, sink_event, sink_sample, sink_frame, s};
    if (trial_runner_init(&s->runner, &plan, s->compress, s->shear, cam, trk, sink, why, sizeof why)) {
        fail_early(s, why);
        goto end;
    }
    pthread_mutex_lock(&s->lock);
    s->runner_ready = 1;
    if (s->abort_pending) trial_runner_abort(&s->runner, s->abort_reason);
    pthread_mutex_unlock(&s->lock);
    {
        char w[256];
        if (store_trial_set_status(s->st, s->trial_id, STORE_STATUS_RUNNING, NULL, store_wall_now(), w, sizeof w) !=
            STORE_OK) {
            fail_early(s, w);
            goto end;
        }
        int64_t spid = 0;
        store_trial tr;
        if (store_trial_get(s->st, s->trial_id, &tr, w, sizeof w) == STORE_OK && tr.specimen_id > 0) {
            spid = tr.specimen_id;
            store_specimen_count_trial(s->st, spid, w, sizeof w);
        }
    }
    trial_runner_run(&s->runner, &s->result);
    pthread_mutex_lock(&s->lock);
    s->runner_ready = 0;
    pthread_mutex_unlock(&s->lock);

    /* 5. Result. Samples first, so a stored result always has its samples. */
    {
        char w[256];
        if (store_samples_end(s->writer, w, sizeof w) != STORE_OK) session_event(s, NAN, STORE_EVENT_FAULT, w);
        s->writer = NULL;
        long frames = trial_video_close(s->video, w, sizeof w);
        s->video = NULL;
        if (frames < 0) { /* the video lost frames: a fault, and the trial is not done */
            session_event(s, NAN, STORE_EVENT_FAULT, w);
            if (s->result.final == TRIAL_DONE) s->result.final = TRIAL_FAILED;
            if (!s->result.reason[0]) snprintf(s->result.reason, sizeof s->result.reason, "%s", w);
        }
        store_regime reg = !s->result.snapped          ? STORE_REGIME_NO_SNAP
                           : !s->result.vision_snapped ? STORE_REGIME_UNKNOWN /* load witness only */
                           : s->result.asymmetric      ? STORE_REGIME_ASYMMETRIC
                                                  : STORE_REGIME_SYMMETRIC;
        if (s->result.final == TRIAL_DONE || s->result.snapped)
            store_trial_set_result(s->st, s->trial_id, s->result.snapped, s->result.snapped ? s->result.snap_dw : NAN,
                                   reg, w, sizeof w);
        store_status fin = s->result.final == TRIAL_DONE      ? STORE_STATUS_DONE
                           : s->result.final == TRIAL_ABORTED ? STORE_STATUS_ABORTED
                                                              : STORE_STATUS_FAILED;
        store_trial_set_status(s->st, s->trial_id, fin, s->result.reason[0] ? s->result.reason : NULL,
                               store_wall_now(), w, sizeof w);
        logf_(s, "%s%s%s; measured %s at Delta W = %.5f", trial_state_name(s->result.final),
              s->result.reason[0] ? ": " : "", s->result.reason, s->result.regime, s->result.snap_dw);
    }
end:
    if (s->writer) {
        char w[256];
        store_samples_end(s->writer, w, sizeof w);
        s->writer = NULL;
    }
    if (s->video) {
        char w[256];
        trial_video_close(s->video, w, sizeof w);
        s->video = NULL;
    }
    if (s->pred_started) {
        pthread_join(s->pred_thread, NULL);
        s->pred_started = 0;
    }
    trial_runner_free(&s->runner);
    vis_tracker_free(trk);
    mock_camera_close(mock);
    if (live.src) vis_source_close(live.src);
    pthread_mutex_lock(&s->lock);
    s->status.finished = 1;
    if (!trial_state_final(s->status.state)) s->status.state = s->result.final;
    pthread_mutex_unlock(&s->lock);
    return NULL;
}

int trial_session_start(const rig_config *cfg, rail *compress, rail *shear, const char *note,
                        void (*log)(const char *line), trial_session **out, int64_t *trial_id, char *why,
                        size_t why_len)
{
    *out = NULL;
    trial_session *s = calloc(1, sizeof *s);
    if (!s) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    s->cfg = *cfg;
    s->compress = compress;
    s->shear = shear;
    s->log = log;
    snprintf(s->note, sizeof s->note, "%s", note ? note : "");
    pthread_mutex_init(&s->lock, NULL);
    s->status.snap_dw_predicted = NAN;
    if (store_open(cfg->store_path, &s->st, why, why_len) != STORE_OK) goto fail;

    /* The specimen and the trial row. */
    store_specimen sp;
    trial_specimen_from_config(cfg, &sp);
    int64_t spid = 0;
    if (store_specimen_upsert(s->st, &sp, &spid, why, why_len) != STORE_OK) goto fail;
    if (trial_camera_setup(cfg, &s->cal, &s->width, &s->height, &s->roi, why, why_len)) goto fail;
    char *config_text = trial_config_text(cfg, s->note);
    char *calib = trial_calib_json(cfg, &s->cal, s->roi, why, why_len);
    if (!calib) {
        free(config_text);
        goto fail;
    }
    store_trial_def def = store_trial_def_default();
    def.mode = cfg->mode == RIG_MODE_RIG ? STORE_MODE_RIG : STORE_MODE_MOCK;
    def.config_text = config_text ? config_text : "";
    def.calibration_json = calib;
    def.specimen_id = spid;
    def.created_wall_s = store_wall_now();
    store_err se = store_trial_create(s->st, &def, &s->trial_id, why, why_len);
    free(config_text);
    free(calib);
    if (se != STORE_OK) goto fail;
    s->status.trial_id = s->trial_id;
    s->status.state = TRIAL_IDLE;
    if (pthread_create(&s->thread, NULL, session_main, s) != 0) {
        snprintf(why, why_len, "could not start the trial thread");
        char w[256];
        store_trial_set_status(s->st, s->trial_id, STORE_STATUS_FAILED, why, store_wall_now(), w, sizeof w);
        goto fail;
    }
    *trial_id = s->trial_id;
    *out = s;
    return 0;
fail:
    store_close(s->st);
    pthread_mutex_destroy(&s->lock);
    free(s);
    return -1;
}

void trial_session_abort(trial_session *s, const char *reason)
{
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

void trial_session_join(trial_session *s, trial_result *result)
{
    if (!s) return;
    pthread_join(s->thread, NULL);
    if (result) *result = s->result;
    store_close(s->st);
    free(s->pred.t);
    free(s->pred.dw);
    free(s->pred.dz);
    free(s->pred.a);
    pthread_mutex_destroy(&s->lock);
    free(s);
}
