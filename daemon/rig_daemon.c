/* rig_daemon.c: ribbond's state and its control API operations (see rig_daemon.h). */
#include "rig_daemon.h"
#include "api.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "live.h"
#include "rail_open.h"
#include "trial.h"
#include "trial_report.h"

static void say(rig_daemon *d, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void say(rig_daemon *d, const char *fmt, ...)
{
    if (!d->log) return;
    char line[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    d->log(line);
}

static void unstored_add(rig_daemon *d, const session_status *ss);
static void unstored_write(rig_daemon *d);
static int queue_start_trial(void *user, const store_specimen *sp, const char *const *set, int n_set, const char *note,
                             int64_t *trial_id, char *why, size_t why_len);
static int queue_trial_running(void *user, int64_t trial_id);
static trial_session *running_session(rig_daemon *d);
static replay_job *running_replay(rig_daemon *d);
static int run_checks(rig_daemon *d, int reopen, int *fails, char *why, size_t why_len);

static void release_locks(rig_daemon *d)
{
    rail_locks_release(d->rails_lock);
    d->rails_lock = NULL;
    owner_lock_release(d->store_lock);
    d->store_lock = NULL;
}

/* The store's lock (STORE_PATH.lock beside it), then the rails' devices (rig and mock modes),
 * before anything is opened: a second daemon stops here, naming the first. */
static int take_locks(rig_daemon *d, char *why, size_t why_len)
{
    char what[RIG_PATH_MAX + 32], path[RIG_PATH_MAX + 8], w[900];
    snprintf(what, sizeof what, "ribbond on %s", d->config_path);
    snprintf(path, sizeof path, "%s.lock", d->cfg.store_path);
    int held = 0;
    /* A store path that is not a regular file (/dev/full, a directory) gets no lock file beside it:
     * store_open refuses it next, naming what it is. */
    struct stat sb;
    int special = stat(d->cfg.store_path, &sb) == 0 && !S_ISREG(sb.st_mode);
    d->store_lock = special ? NULL : owner_lock_take(path, what, &held, w, sizeof w);
    if (!d->store_lock && !special) {
        if (held)
            snprintf(why, why_len, "store %s is in use by another daemon: %s; stop that one first, or give this one "
                     "another store.path", d->cfg.store_path, w);
        else
            snprintf(why, why_len, "store %s: %s", d->cfg.store_path, w);
        return -1;
    }
    if (d->cfg.mode == RIG_MODE_REPLAY) return 0;
    if (rail_locks_take(&d->cfg.compress, &d->cfg.shear, what, &d->rails_lock, w, sizeof w) != RAIL_OK) {
        snprintf(why, why_len, "%s", w);
        release_locks(d);
        return -1;
    }
    return 0;
}

int rig_daemon_open(rig_daemon *d, const char *config_path, const char *const *overrides, int n_overrides,
                    void (*log)(const char *line), char *why, size_t why_len)
{
    memset(d, 0, sizeof *d);
    d->log = log;
    pthread_mutex_init(&d->lock, NULL);
    snprintf(d->config_path, sizeof d->config_path, "%s", config_path);
    if (n_overrides > RIG_DAEMON_MAX_OVERRIDES) {
        snprintf(why, why_len, "at most %d --set overrides", RIG_DAEMON_MAX_OVERRIDES);
        return -1;
    }
    for (int k = 0; k < n_overrides; k++) d->overrides[k] = overrides[k];
    d->n_overrides = n_overrides;
    cfg_error ce;
    if (rig_config_load(config_path, overrides, n_overrides, &d->cfg, &ce) != CFG_OK) {
        cfg_error_format(&ce, why, why_len);
        return -1;
    }
    if (take_locks(d, why, why_len)) return -1;
    if (store_open(d->cfg.store_path, &d->st, why, why_len) != STORE_OK) {
        release_locks(d);
        return -1;
    }
    int interrupted = 0;
    char w[256];
    if (store_trial_mark_interrupted(d->st, store_wall_now(), &interrupted, w, sizeof w) != STORE_OK)
        say(d, "could not mark interrupted trials: %s", w);
    else if (interrupted > 0)
        say(d, "%d unfinished trial(s) found at start-up marked interrupted (motion is never resumed)", interrupted);
    if (d->cfg.mode == RIG_MODE_REPLAY) return 0;
    rail_clock clk = d->cfg.clock == RIG_CLOCK_VIRTUAL ? rail_clock_virtual(&d->vclock) : rail_clock_real();
    rail_err re = RAIL_OK;
    /* Both rails from the same (checked) config the loader produced. */
    re = rail_open_pair(&d->cfg.compress, &d->cfg.shear, clk, &d->compress, &d->shear, why, why_len);
    if (re != RAIL_OK && d->cfg.mode == RIG_MODE_RIG) {
        /* A missing port, a controller the driver refuses: the daemon serves the reason (the
           checks) and opens the rails when the lab has fixed it and the checks run again. */
        snprintf(d->rails_why, sizeof d->rails_why, "%s", why);
        say(d, "rails not opened: %s; trials refused until the checks pass (POST /checks or SIGHUP)", why);
    } else if (re != RAIL_OK) {
        store_close(d->st);
        d->st = NULL;
        release_locks(d);
        return -1;
    }
    for (int r = 0; r < 2; r++) { /* a map let through by allow_unverified is said at every start */
        const rail_config *rc = r == 0 ? &d->cfg.compress : &d->cfg.shear;
        char warn[600];
        if (!strcmp(rc->driver, "modbus") && rail_modbus_map_warning(&rc->modbus.map, warn, sizeof warn))
            say(d, "warning: rail %s: %s; driven because allow_unverified = on", rc->params.name, warn);
    }
    if (d->cfg.mode == RIG_MODE_RIG) {
        /* The worker that transcodes each trial's raw video after the trial (camera.transcode). */
        trial_transcoder_params tp = trial_transcoder_params_default();
        tp.store_path = d->cfg.store_path;
        tp.codec.threads = d->cfg.camera.transcode_threads;
        tp.log = d->log;
        d->transcoder = trial_transcoder_start(&tp, w, sizeof w);
        if (!d->transcoder) say(d, "%s: trial videos stay raw", w);
        else if (d->cfg.camera.transcode == RIG_TRANSCODE_FFV1) {
            int queued = trial_transcoder_queue_left(d->transcoder, d->st, w, sizeof w);
            if (queued < 0) say(d, "raw videos of earlier trials not looked for: %s", w);
            else if (queued > 0)
                say(d, "%d raw trial video(s) an earlier run left queued for their lossless transcode", queued);
        }
    }
    d->check_hooks = check_env_default();
    run_checks(d, 0, NULL, w, sizeof w);
    return 0;
}

/* Rig mode, rails not open: take their locks again (a port that appeared since is locked under
 * its device's numbers, as another program would look for it) and open them. Caller holds lock. */
static void reopen_rails(rig_daemon *d)
{
    char w[900];
    rail_locks_release(d->rails_lock);
    d->rails_lock = NULL;
    char what[RIG_PATH_MAX + 32];
    snprintf(what, sizeof what, "ribbond on %s", d->config_path);
    if (rail_locks_take(&d->cfg.compress, &d->cfg.shear, what, &d->rails_lock, w, sizeof w) != RAIL_OK) {
        snprintf(d->rails_why, sizeof d->rails_why, "%s", w);
        return;
    }
    if (rail_open_pair(&d->cfg.compress, &d->cfg.shear, rail_clock_real(), &d->compress, &d->shear, w, sizeof w) !=
        RAIL_OK) {
        snprintf(d->rails_why, sizeof d->rails_why, "%s", w);
        return;
    }
    d->rails_why[0] = 0;
    say(d, "rails opened");
}

/* A trial or replay still runs (it owns the rails). Unlike running_session, reaps nothing: that
 * writes to the store, which is the API thread's, and SIGHUP's checks run on the main thread.
 * Caller holds lock. */
static int rails_busy(rig_daemon *d)
{
    session_status ss;
    replay_job_status rs;
    if (d->session && (trial_session_status(d->session, &ss), !ss.finished)) return 1;
    return d->replay && (replay_job_status_get(d->replay, &rs), !rs.finished);
}

/* The checks of the rig file's mode into d->checks, stamped, every line not ok logged. Caller
 * holds lock. */
static void checks_fill(rig_daemon *d, const check_env *env)
{
    check_report_init(&d->checks);
    check_rig_run(&d->cfg, env, &d->checks);
    time_t now = time(NULL);
    struct tm tm;
    gmtime_r(&now, &tm);
    strftime(d->checked_at, sizeof d->checked_at, "%Y-%m-%dT%H:%M:%SZ", &tm);
    for (int i = 0; i < d->checks.n; i++) {
        const check_item *it = &d->checks.items[i];
        if (it->level != CHECK_OK)
            say(d, "check: %s %s %s: %s", check_level_name(it->level), it->part, it->what, it->text);
    }
}

/* The checks; reopen: try rails that are not open first (not at start: they just failed). */
static int run_checks(rig_daemon *d, int reopen, int *fails, char *why, size_t why_len)
{
    pthread_mutex_lock(&d->lock);
    if (rails_busy(d)) {
        pthread_mutex_unlock(&d->lock);
        snprintf(why, why_len, "a trial or replay is running (it owns the rails): check again when it has ended");
        return -1;
    }
    if (reopen && d->cfg.mode == RIG_MODE_RIG && !d->compress) reopen_rails(d);
    check_env env = d->check_hooks;
    env.compress = d->compress;
    env.shear = d->shear;
    env.rails_why = d->rails_why[0] ? d->rails_why : NULL;
    checks_fill(d, &env);
    int n = d->checks.fails;
    say(d, "checks: %s (%d fail%s, %d warning%s)", n ? "NOT READY, trials refused" : "ready", n, n == 1 ? "" : "s",
        d->checks.warns, d->checks.warns == 1 ? "" : "s");
    pthread_mutex_unlock(&d->lock);
    if (fails) *fails = n;
    return 0;
}

int rig_daemon_check(rig_daemon *d, int *fails, char *why, size_t why_len)
{
    return run_checks(d, 1, fails, why, why_len);
}

int rig_daemon_serve(rig_daemon *d, unsigned *port, char *why, size_t why_len)
{
    api_server_config ac = api_server_config_default();
    ac.listen = d->cfg.api.listen;
    ac.port = (unsigned)d->cfg.api.port;
    ac.token = d->cfg.api.token[0] ? d->cfg.api.token : NULL;
    if (!d->bus && !(d->bus = live_bus_create())) {
        snprintf(why, why_len, "out of memory for the live page's buffers");
        return -1;
    }
    live_assets_load(&d->assets);
    if (d->assets.warning[0]) say(d, "%s", d->assets.warning);
    if (!d->phase && !(d->phase = phase_map_create(&d->cfg.scene))) {
        snprintf(why, why_len, "out of memory for the phase map");
        return -1;
    }
    ac.assets = d->assets.list;
    ac.n_assets = d->assets.n;
    if (d->cfg.mode != RIG_MODE_REPLAY && !d->queue) {
        campaign_queue_ops qo = {.start_trial = queue_start_trial, .trial_running = queue_trial_running};
        if (campaign_queue_open(d->cfg.store_path, &qo, d, d->log, &d->queue, why, why_len)) return -1;
    }
    api_ops ops = rig_daemon_ops();
    if (api_server_start(&ac, &ops, d, &d->api, why, why_len)) return -1;
    *port = api_server_port(d->api);
    return 0;
}

void rig_daemon_close(rig_daemon *d, const char *reason)
{
    /* The API first: no new trial can start while the running one is stopped (the bus is closed
     * first so every event stream ends at once). */
    live_bus_close(d->bus);
    api_server_stop(d->api);
    d->api = NULL;
    campaign_queue_close(d->queue); /* it starts nothing more; a running trial is stopped below */
    d->queue = NULL;
    campaign_trace_free(d->trace); /* waits for a trace still running (about a second at most idle) */
    d->trace = NULL;
    phase_map_free(d->phase); /* cancels a map being computed */
    d->phase = NULL;
    pthread_mutex_lock(&d->lock);
    trial_session *s = d->session;
    replay_job *rj = d->replay;
    d->session = NULL;
    d->replay = NULL;
    pthread_mutex_unlock(&d->lock);
    if (rj) {
        replay_job_abort(rj);
        replay_job_join(rj, NULL);
    }
    if (s) {
        trial_session_abort(s, reason);
        trial_result r;
        session_status ss;
        trial_session_join_status(s, &r, &ss);
        say(d, "trial ended %s%s%s", trial_state_name(r.final), r.reason[0] ? ": " : "", r.reason);
        unstored_add(d, &ss);
    }
    /* After the session (it may have queued its video), before the store closes: a transcode in
       progress stops at its next frame; every raw video not yet transcoded is kept (an event each). */
    trial_transcoder_stop(d->transcoder);
    d->transcoder = NULL;
    if (d->st && d->n_unstored) unstored_write(d);
    for (int k = 0; k < d->n_unstored; k++)
        say(d, "trial %lld: final status %s not stored (%s): the next start-up marks it interrupted",
            (long long)d->unstored[k].id, trial_state_name(d->unstored[k].final), d->unstored[k].why);
    d->n_unstored = 0;
    if (d->compress) rail_stop(d->compress);
    if (d->shear) rail_stop(d->shear);
    rail_close(d->compress);
    rail_close(d->shear);
    d->compress = d->shear = NULL;
    store_close(d->st);
    d->st = NULL;
    release_locks(d); /* after the rails are closed and the store's last write */
    live_bus_free(d->bus); /* after the session: it published until it ended */
    d->bus = NULL;
    live_assets_free(&d->assets);
    pthread_mutex_destroy(&d->lock);
}

/* Keeps a finished session's final status that the store refused (rig_unstored). */
static void unstored_add(rig_daemon *d, const session_status *ss)
{
    if (!ss->final_unstored) return;
    if (d->n_unstored >= RIG_DAEMON_MAX_UNSTORED) {
        say(d, "trial %lld: its final status (%s) could not be stored (%s) and %d others wait: the next start-up "
            "marks it interrupted", (long long)ss->trial_id, trial_state_name(ss->final_state), ss->final_why,
            d->n_unstored);
        return;
    }
    rig_unstored *u = &d->unstored[d->n_unstored++];
    u->id = ss->trial_id;
    u->final = ss->final_state;
    snprintf(u->reason, sizeof u->reason, "%s", ss->final_reason);
    u->wall_s = ss->final_wall_s;
    snprintf(u->why, sizeof u->why, "%s", ss->final_why);
}

/* Writes the final statuses the store refused, now that it may take them (state, status with the
 * trial's own end time, and an event saying it was written late); keeps those it still refuses.
 * On the API thread's connection; caller holds the lock (or the API has stopped). */
static void unstored_write(rig_daemon *d)
{
    int kept = 0;
    for (int k = 0; k < d->n_unstored; k++) {
        rig_unstored *u = &d->unstored[k];
        store_status fin = u->final == TRIAL_DONE      ? STORE_STATUS_DONE
                           : u->final == TRIAL_ABORTED ? STORE_STATUS_ABORTED
                                                       : STORE_STATUS_FAILED;
        char w[256];
        store_err e = store_trial_set_state(d->st, u->id, trial_state_name(u->final), w, sizeof w);
        if (e == STORE_OK) e = store_trial_set_status(d->st, u->id, fin, u->reason[0] ? u->reason : NULL, u->wall_s, w,
                                                      sizeof w);
        if (e == STORE_OK) {
            store_event ev;
            memset(&ev, 0, sizeof ev);
            ev.trial_id = u->id;
            ev.t_s = NAN;
            ev.wall_s = store_wall_now();
            snprintf(ev.state, sizeof ev.state, "%s", trial_state_name(u->final));
            ev.kind = STORE_EVENT_WARNING;
            snprintf(ev.message, sizeof ev.message,
                     "final status %s stored late: the store refused it when the trial ended (%.300s)",
                     store_status_name(fin), u->why);
            store_event_append(d->st, &ev, w, sizeof w);
            say(d, "trial %lld: final status %s stored (the store had refused it: %s)", (long long)u->id,
                store_status_name(fin), u->why);
            continue;
        }
        if (e == STORE_E_STATE || e == STORE_E_NOTFOUND) continue; /* already final, or gone */
        if (kept != k) d->unstored[kept] = *u;
        kept++;
    }
    d->n_unstored = kept;
}

/* The session if it still runs; reaps a finished one (keeping a final status the store refused).
 * Writes the refused final statuses first. Caller holds the lock. */
static trial_session *running_session(rig_daemon *d)
{
    if (d->n_unstored) unstored_write(d);
    if (!d->session) return NULL;
    session_status ss;
    trial_session_status(d->session, &ss);
    if (!ss.finished) return d->session;
    trial_session_join_status(d->session, NULL, &ss);
    d->session = NULL;
    unstored_add(d, &ss);
    if (d->n_unstored) unstored_write(d);
    return NULL;
}

/* The replay if it still runs; reaps a finished one. Caller holds the lock. */
static replay_job *running_replay(rig_daemon *d)
{
    if (!d->replay) return NULL;
    replay_job_status rs;
    replay_job_status_get(d->replay, &rs);
    if (!rs.finished) return d->replay;
    trial_result r;
    replay_job_join(d->replay, &r);
    d->replay = NULL;
    say(d, "replay trial %lld ended %s: %s%s%s", (long long)rs.trial_id, trial_state_name(r.final), r.regime,
        r.reason[0] ? ": " : "", r.reason);
    return NULL;
}

static json_t *num_or_null(double v) { return isfinite(v) ? json_real(v) : json_null(); }

static int op_status(void *user, json_t **out, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    rig_daemon *d = user;
    json_t *o = json_object();
    json_object_set_new(o, "mode", json_string(rig_mode_name(d->cfg.mode)));
    json_object_set_new(o, "config", json_string(d->config_path));
    json_object_set_new(o, "store", json_string(d->cfg.store_path));
    json_object_set_new(o, "version", json_string(RIBBON_VERSION));
    /* The queue's lock comes before the daemon's (rig_daemon.h). */
    json_object_set_new(o, "queue", d->queue ? campaign_queue_summary(d->queue) : json_null());
    pthread_mutex_lock(&d->lock);
    trial_session *s = running_session(d);
    replay_job *rj = running_replay(d);
    if (rj) {
        replay_job_status rs;
        replay_job_status_get(rj, &rs);
        json_object_set_new(o, "state", json_string("running"));
        json_object_set_new(o, "trial", json_pack("{s:I, s:s, s:I, s:i, s:i}", "id", (json_int_t)rs.trial_id, "state",
                                                  "replaying", "source_trial", (json_int_t)rs.source_id, "frames",
                                                  (int)rs.frame, "total_frames", (int)rs.total));
    } else if (s) {
        session_status ss;
        trial_session_status(s, &ss);
        /* Done but its specimen still being refitted (the session has not ended): say so. */
        char state[RIG_NAME_MAX + 48];
        snprintf(state, sizeof state, "%s%s%s", trial_state_name(ss.state), ss.refitting[0] ? ", refitting specimen " : "",
                 ss.refitting);
        json_t *t = json_pack("{s:I, s:s, s:i, s:i, s:o, s:o, s:o, s:o, s:o, s:b, s:o, s:s, s:i, s:o, s:s}", "id",
                              (json_int_t)ss.trial_id, "state", state, "frames", (int)ss.frames,
                              "measured_frames", (int)ss.measured, "t_s", num_or_null(ss.t_s), "dl",
                              num_or_null(ss.dl), "dw", num_or_null(ss.dw), "dz", num_or_null(ss.dz), "a",
                              num_or_null(ss.a), "prediction_done", ss.prediction_done, "snap_dw_predicted",
                              num_or_null(ss.prediction_done ? ss.snap_dw_predicted : NAN), "regime_predicted",
                              ss.regime_predicted, "nodes", ss.nodes, "dt", num_or_null(ss.dt), "message",
                              ss.message);
        if (t) json_object_set_new(t, "refitting_specimen", ss.refitting[0] ? json_string(ss.refitting) : json_null());
        json_object_set_new(o, "state", json_string("running"));
        json_object_set_new(o, "trial", t ? t : json_null());
    } else {
        json_object_set_new(o, "state", json_string("idle"));
        json_object_set_new(o, "trial", json_null());
        /* Idle: the API thread may read the rails (no trial owns them). */
        if (d->compress && d->shear) {
            rail_status sc, sh;
            rail_status_get(d->compress, &sc);
            rail_status_get(d->shear, &sh);
            json_object_set_new(o, "rails",
                                json_pack("{s:{s:s, s:f}, s:{s:s, s:f}}", "compress", "state",
                                          rail_state_name(sc.state), "position_mm", sc.position_mm, "shear",
                                          "state", rail_state_name(sh.state), "position_mm", sh.position_mm));
        }
    }
    json_t *ck = check_report_json(&d->checks);
    json_object_set_new(ck, "checked_at", json_string(d->checked_at));
    json_object_set_new(o, "checks", ck);
    json_object_set_new(o, "ready", json_boolean(d->checks.fails == 0 && (d->cfg.mode == RIG_MODE_REPLAY ||
                                                                          (d->compress && d->shear))));
    if (d->n_unstored) {
        json_t *a = json_array();
        for (int k = 0; k < d->n_unstored; k++)
            json_array_append_new(a, json_pack("{s:I, s:s, s:s}", "id", (json_int_t)d->unstored[k].id, "status",
                                               trial_state_name(d->unstored[k].final), "why", d->unstored[k].why));
        json_object_set_new(o, "unstored", a);
    }
    pthread_mutex_unlock(&d->lock);
    *out = o;
    return 0;
}

/* The 409 of a start refused while a check fails: which checks fail, then the first one's text
 * (the whole list is in GET /status). Caller holds lock. */
static void not_ready(rig_daemon *d, int *http_status, char *why, size_t why_len)
{
    char names[300] = "", first[480] = "";
    for (int i = 0; i < d->checks.n; i++) {
        const check_item *it = &d->checks.items[i];
        if (it->level != CHECK_FAIL) continue;
        size_t u = strlen(names);
        snprintf(names + u, sizeof names - u, "%s%s %s", u ? ", " : "", it->part, it->what);
        if (!first[0]) snprintf(first, sizeof first, "%s", it->text);
    }
    *http_status = 409;
    snprintf(why, why_len, "the rig is not ready: %d check%s fail (%s; checked %s): first: %.300s; fix it, then "
             "POST /checks or SIGHUP (GET /status lists them all)", d->checks.fails,
             d->checks.fails == 1 ? "" : "s", names, d->checked_at, first[0] ? first : d->rails_why);
}

/* Replay mode: the checks a replay needs (check_rig_run's replay part: the store writable, free
 * disk where it is), run again at each start: a few stats, a statvfs and a small write probe, so
 * the answer is today's and not the one from the daemon's start. Caller holds lock. */
static void replay_checks(rig_daemon *d)
{
    check_env env = d->check_hooks;
    checks_fill(d, &env);
}

/* Replay mode: POST /trials {"source_trial": ID} replays a stored trial; {} replays [replay]
 * source_trial, or the outside files the rig file names (replay.video, replay.rails). The replay
 * runs on a thread of its own; the answer (201) is the new trial, status running. */
static int replay_start(rig_daemon *d, const json_t *body, json_t **out, int *http_status, char *why, size_t why_len)
{
    api_start_body req;
    if (api_start_body_parse(body, 1, &req, why, why_len)) {
        *http_status = 400;
        return -1;
    }
    int64_t id = req.source_trial;
    pthread_mutex_lock(&d->lock);
    replay_job *rj = running_replay(d);
    if (rj) {
        replay_job_status rs;
        replay_job_status_get(rj, &rs);
        pthread_mutex_unlock(&d->lock);
        *http_status = 409;
        snprintf(why, why_len, "replay trial %lld is running (frame %ld); abort it first", (long long)rs.trial_id, rs.frame);
        return -1;
    }
    replay_checks(d);
    if (d->checks.fails) {
        not_ready(d, http_status, why, why_len);
        pthread_mutex_unlock(&d->lock);
        return -1;
    }
    trial_replay *r = NULL;
    int prc = trial_replay_prepare(d->st, &d->cfg, id, NULL, &r, why, why_len);
    if (prc) {
        pthread_mutex_unlock(&d->lock);
        /* 409: the source has not ended yet; 400: the recording named cannot be replayed */
        *http_status = prc == TRIAL_REPLAY_UNFINISHED ? 409 : 400;
        return -1;
    }
    trial_replay_set_bus(r, d->bus); /* the live page follows the replay */
    char what[320]; /* r belongs to the job once it starts */
    snprintf(what, sizeof what, "%.300s", trial_replay_video(r));
    int64_t nid = 0;
    int rc = replay_job_start(r, d->st, d->cfg.store_path, req.note, &d->replay, &nid,
                              why, why_len);
    pthread_mutex_unlock(&d->lock);
    if (rc) {
        *http_status = 500;
        return -1;
    }
    say(d, "replay of %s started as trial %lld", what, (long long)nid);
    return store_trial_json(d->st, nid, out, why, why_len) == STORE_OK ? 0 : -1;
}

/* Starts a trial of the rig file with overrides: the daemon's, then the specimen's record (sp,
 * may be NULL), then set. 0 and *id, or -1 with why and *http_status (400 the overrides or the
 * start refused, 409 a trial runs or the specimen the trial names is retired or broken, 500).
 * check (may be NULL: the caller has checked sp) is the connection on which the specimen the
 * loaded rig file names (specimen.name, from any override) is looked up: a retired or broken one
 * is refused, whichever way it was named. Takes the daemon's lock. */
static int start_trial(rig_daemon *d, store *check, const store_specimen *sp, const char *const *set, int n_set,
                       const char *note, int64_t *id, int *http_status, char *why, size_t why_len)
{
    const char *ov[RIG_DAEMON_MAX_OVERRIDES + CAMPAIGN_MAX_OVERRIDES + API_START_MAX_SET];
    int nov = 0;
    campaign_overrides sov;
    sov.n = 0;
    if (sp && campaign_specimen_overrides(sp, d->cfg.scene.fold_angle_deg < 0.0 ? -1 : 1, &sov, why, why_len)) {
        *http_status = 400;
        return -1;
    }
    if (n_set > API_START_MAX_SET) {
        *http_status = 400;
        snprintf(why, why_len, "at most %d overrides", API_START_MAX_SET);
        return -1;
    }
    for (int k = 0; k < d->n_overrides; k++) ov[nov++] = d->overrides[k];
    for (int k = 0; k < sov.n; k++) ov[nov++] = sov.ptr[k];
    for (int k = 0; k < n_set; k++) ov[nov++] = set[k];
    rig_config cfg;
    if (nov > d->n_overrides) {
        cfg_error ce;
        if (rig_config_load(d->config_path, ov, nov, &cfg, &ce) != CFG_OK) {
            *http_status = 400;
            cfg_error_format(&ce, why, why_len);
            return -1;
        }
        if (cfg.mode != d->cfg.mode || strcmp(cfg.store_path, d->cfg.store_path) != 0) {
            *http_status = 400;
            snprintf(why, why_len, "a trial may not change rig.mode or store.path");
            return -1;
        }
    } else {
        cfg = d->cfg;
    }
    store_specimen named;
    char w[256];
    if (check && cfg.specimen.name[0] &&
        store_specimen_get_by_name(check, cfg.specimen.name, &named, w, sizeof w) == STORE_OK &&
        (named.state == STORE_SPECIMEN_RETIRED || named.state == STORE_SPECIMEN_BROKEN)) {
        *http_status = 409;
        snprintf(why, why_len, "specimen '%.63s' is %s (%.120s, since %s): a trial may not use it; nothing started",
                 named.name, store_specimen_state_name(named.state), named.state_reason, named.state_at);
        return -1;
    }
    pthread_mutex_lock(&d->lock);
    trial_session *s = running_session(d);
    if (s) {
        session_status ss;
        trial_session_status(s, &ss);
        pthread_mutex_unlock(&d->lock);
        *http_status = 409;
        if (ss.refitting[0])
            snprintf(why, why_len, "trial %lld is done and specimen %.63s is being refitted from its finished trials "
                     "(its next trial predicts with the new calibration): start again when GET /status is idle",
                     (long long)ss.trial_id, ss.refitting);
        else
            snprintf(why, why_len, "trial %lld is running (%s); abort it first", (long long)ss.trial_id,
                     trial_state_name(ss.state));
        return -1;
    }
    if (d->checks.fails || !d->compress || !d->shear) {
        not_ready(d, http_status, why, why_len);
        pthread_mutex_unlock(&d->lock); /* after the text: a check re-run may rewrite what it reads */
        return -1;
    }
    trial_err te = trial_session_start_tx(&cfg, ov, nov, d->compress, d->shear, note, d->log, d->bus, d->transcoder,
                                          &d->session, id, why, why_len);
    pthread_mutex_unlock(&d->lock);
    if (te != TRIAL_OK) {
        *http_status = te == TRIAL_E_REFUSED ? 400 : 500;
        return -1;
    }
    say(d, "trial %lld started (%s mode%s%s)", (long long)*id, rig_mode_name(cfg.mode), sp ? ", specimen " : "",
        sp ? sp->name : "");
    return 0;
}

static int op_start(void *user, const json_t *body, json_t **out, int *http_status, char *why, size_t why_len)
{
    rig_daemon *d = user;
    if (d->cfg.mode == RIG_MODE_REPLAY) return replay_start(d, body, out, http_status, why, why_len);
    /* Body: {"specimen": NAME, "set": ["section.key=value", ...], "note": "..."} (api_start_body.h). */
    api_start_body req;
    if (api_start_body_parse(body, 0, &req, why, why_len)) {
        *http_status = 400;
        return -1;
    }
    store_specimen sp;
    if (req.specimen) {
        int u = campaign_specimen_usable(d->st, req.specimen, &sp, why, why_len);
        if (u) {
            *http_status = u == -2 ? 400 : 409;
            return -1;
        }
    }
    int64_t id = 0;
    if (start_trial(d, d->st, req.specimen ? &sp : NULL, req.set, req.n_set, req.note, &id, http_status, why,
                    why_len))
        return -1;
    store_err se = store_trial_json(d->st, id, out, why, why_len);
    if (se != STORE_OK) {
        *out = json_pack("{s:I, s:s}", "id", (json_int_t)id, "status", "created");
    }
    return 0;
}

/* The queue's way to start a trial (campaign_queue_ops): on the queue's thread. */
static int queue_start_trial(void *user, const store_specimen *sp, const char *const *set, int n_set, const char *note,
                             int64_t *trial_id, char *why, size_t why_len)
{
    int http = 0;
    return start_trial(user, NULL, sp, set, n_set, note, trial_id, &http, why, why_len);
}

static int queue_trial_running(void *user, int64_t trial_id)
{
    rig_daemon *d = user;
    int running = 0;
    pthread_mutex_lock(&d->lock);
    if (d->session) {
        session_status ss;
        trial_session_status(d->session, &ss);
        running = (trial_id == 0 || ss.trial_id == trial_id) && !ss.finished;
    }
    pthread_mutex_unlock(&d->lock);
    return running;
}

/* GET /checks: the last readiness checks; POST /checks: run them again (409 while a trial runs). */
static int checks_route(rig_daemon *d, const char *method, json_t **out, int *http_status, char *why, size_t why_len)
{
    if (!strcmp(method, "POST") && rig_daemon_check(d, NULL, why, why_len)) {
        *http_status = 409;
        return -1;
    }
    if (strcmp(method, "POST") && strcmp(method, "GET")) {
        *http_status = 405;
        snprintf(why, why_len, "method %s not allowed here (allowed: GET, POST)", method);
        return -1;
    }
    pthread_mutex_lock(&d->lock);
    *out = check_report_json(&d->checks);
    json_object_set_new(*out, "checked_at", json_string(d->checked_at));
    pthread_mutex_unlock(&d->lock);
    return 0;
}

/* /specimens and /queue (campaign_routes.h); a new specimen's size and material default to the
 * rig file's scene and specimen. */
static int op_campaign(void *user, const char *method, const char *path, const json_t *body, json_t **out,
                       int *http_status, char *why, size_t why_len)
{
    rig_daemon *d = user;
    if (!strcmp(path, "/checks")) return checks_route(d, method, out, http_status, why, why_len);
    if (!d->queue && (!strncmp(path, "/queue", 6) || !strncmp(path, "/plan/", 6))) {
        *http_status = 409;
        snprintf(why, why_len, "the queue runs trials on rails: a %s-mode daemon has none", rig_mode_name(d->cfg.mode));
        return -1;
    }
    campaign_ctx c = {.st = d->st, .q = d->queue, .defaults = store_specimen_default()};
    c.defaults.length_m = d->cfg.scene.length;
    c.defaults.width_m = d->cfg.scene.width;
    c.defaults.thickness_m = d->cfg.scene.thickness;
    c.defaults.youngs_modulus_pa = d->cfg.scene.youngs_modulus;
    c.defaults.density_kg_m3 = d->cfg.scene.density;
    snprintf(c.defaults.material, sizeof c.defaults.material, "%.31s", d->cfg.specimen.material);
    char cache[RIG_PATH_MAX + 16];
    snprintf(cache, sizeof cache, "%s.boundary.csv", d->cfg.store_path);
    c.scene = &d->cfg.scene;
    c.rig_path = d->cfg.path;
    c.scene_path = d->cfg.scene_path;
    c.boundary_cache = cache;
    if (!d->trace) d->trace = campaign_trace_new(); /* NULL (out of memory): traced here, as before */
    c.trace = d->trace;
    c.sets = d->overrides;
    c.n_sets = d->n_overrides;
    return campaign_route(&c, method, path, body, out, http_status, why, why_len);
}

/* POST /rails/{name}/home and /rails/{name}/confirm-zero, body {"confirm": true}: after a
 * controller lost its position (docs/rails.md) the rail refuses motion until it is homed or its
 * zero confirmed; ribbond holds the rails' locks, so this is the way to do it while it runs. Only
 * between trials: the daemon's lock is held throughout, so no trial starts meanwhile, and the
 * trial's thread (the rails' owner during a trial) is not running. */
static int op_rail(void *user, const char *path, const json_t *body, json_t **out, int *http_status, char *why,
                   size_t why_len)
{
    rig_daemon *d = user;
    char name[64] = "", action[32] = "";
    const char *p = path + 7; /* "/rails/" */
    const char *slash = strchr(p, '/');
    if (!slash || (size_t)(slash - p) >= sizeof name || strlen(slash + 1) >= sizeof action) {
        *http_status = 404;
        snprintf(why, why_len, "no such route %.100s: POST /rails/NAME/home or /rails/NAME/confirm-zero", path);
        return -1;
    }
    memcpy(name, p, (size_t)(slash - p));
    snprintf(action, sizeof action, "%s", slash + 1);
    int home = !strcmp(action, "home");
    if (!home && strcmp(action, "confirm-zero") != 0) {
        *http_status = 404;
        snprintf(why, why_len, "no such rail action '%.31s': home or confirm-zero", action);
        return -1;
    }
    const char *key;
    json_t *v;
    json_object_foreach((json_t *)body, key, v) {
        if (strcmp(key, "confirm") != 0) {
            *http_status = 400;
            snprintf(why, why_len, "unknown field \"%.60s\": the body is {\"confirm\": true}", key);
            return -1;
        }
    }
    json_t *c = json_object_get(body, "confirm");
    if (!json_is_true(c)) {
        *http_status = 400;
        snprintf(why, why_len,
                 "%s needs {\"confirm\": true}: %s", action,
                 home ? "homing drives the rail to its switch (a clamped specimen would be crushed)"
                      : "the controller's count is taken as right where the rail stands");
        return -1;
    }
    if (!d->compress || !d->shear) {
        *http_status = 409;
        snprintf(why, why_len, "a %s-mode daemon drives no rails", rig_mode_name(d->cfg.mode));
        return -1;
    }
    rail *r = !strcmp(name, rail_get_params(d->compress)->name) ? d->compress
              : !strcmp(name, rail_get_params(d->shear)->name)  ? d->shear
                                                                 : NULL;
    if (!r) {
        *http_status = 404;
        snprintf(why, why_len, "no rail named '%.63s' (this rig's rails: %s, %s)", name,
                 rail_get_params(d->compress)->name, rail_get_params(d->shear)->name);
        return -1;
    }
    pthread_mutex_lock(&d->lock);
    trial_session *s = running_session(d);
    if (s) {
        session_status ss;
        trial_session_status(s, &ss);
        pthread_mutex_unlock(&d->lock);
        *http_status = 409;
        snprintf(why, why_len, "trial %lld is running (%s): a rail is homed or its zero confirmed only between "
                 "trials (abort it first)", (long long)ss.trial_id, trial_state_name(ss.state));
        return -1;
    }
    rail_err e = home ? rail_home(r, true) : rail_gcode_confirm_zero(r, true);
    rail_status st;
    memset(&st, 0, sizeof st);
    if (e == RAIL_OK) rail_status_poll(r, &st);
    if (e != RAIL_OK) snprintf(why, why_len, "%s", rail_last_error(r));
    pthread_mutex_unlock(&d->lock);
    if (e != RAIL_OK) {
        *http_status = e == RAIL_E_STATE || e == RAIL_E_UNSUPPORTED ? 409 : e == RAIL_E_CONFIRM ? 400 : 502;
        return -1;
    }
    say(d, "rail %s: %s by the API", name, home ? "homing started" : "zero confirmed");
    if (home) *http_status = 202;
    json_t *o = json_object();
    json_object_set_new(o, "rail", json_string(name));
    json_object_set_new(o, "action", json_string(action));
    json_object_set_new(o, "state", json_string(rail_state_name(st.state)));
    json_object_set_new(o, "position_mm", num_or_null(st.position_mm));
    json_object_set_new(o, "message", json_string(st.message));
    *out = o;
    return 0;
}

static int op_abort(void *user, json_t **out, int *http_status, char *why, size_t why_len)
{
    rig_daemon *d = user;
    pthread_mutex_lock(&d->lock);
    replay_job *rj = running_replay(d);
    if (rj) {
        replay_job_status rs;
        replay_job_status_get(rj, &rs);
        replay_job_abort(rj);
        pthread_mutex_unlock(&d->lock);
        *out = json_pack("{s:I, s:s, s:s}", "id", (json_int_t)rs.trial_id, "state", "replaying", "abort", "requested");
        return 0;
    }
    trial_session *s = running_session(d);
    if (!s) {
        pthread_mutex_unlock(&d->lock);
        *http_status = 409;
        snprintf(why, why_len, "no trial is running");
        return -1;
    }
    session_status ss;
    trial_session_status(s, &ss);
    if (trial_state_final(ss.state)) {
        /* Ended (its rails stopped); the session is still closing its camera, video or prediction. */
        pthread_mutex_unlock(&d->lock);
        *http_status = 409;
        if (ss.refitting[0])
            snprintf(why, why_len, "trial %lld has already ended %s (its rails are stopped; specimen %.63s is being "
                     "refitted from its finished trials): nothing to abort", (long long)ss.trial_id,
                     trial_state_name(ss.state), ss.refitting);
        else
            snprintf(why, why_len, "trial %lld has already ended %s (its rails are stopped; it is closing its camera, "
                     "video and prediction): nothing to abort", (long long)ss.trial_id, trial_state_name(ss.state));
        return -1;
    }
    trial_session_abort(s, "abort requested through the API");
    pthread_mutex_unlock(&d->lock);
    *out = json_pack("{s:I, s:s, s:s}", "id", (json_int_t)ss.trial_id, "state", trial_state_name(ss.state),
                     "abort", "requested");
    return 0;
}

static int op_list(void *user, json_t **out, char *why, size_t why_len)
{
    rig_daemon *d = user;
    pthread_mutex_lock(&d->lock);
    running_session(d);
    pthread_mutex_unlock(&d->lock);
    return store_trials_json(d->st, out, why, why_len) == STORE_OK ? 0 : -1;
}

static int op_show(void *user, int64_t id, json_t **out, int *http_status, char *why, size_t why_len)
{
    rig_daemon *d = user;
    pthread_mutex_lock(&d->lock);
    running_session(d);
    pthread_mutex_unlock(&d->lock);
    store_err e = store_trial_json(d->st, id, out, why, why_len);
    if (e == STORE_OK) {
        trial_config_text_add_overrides(d->st, id, *out);
        return 0;
    }
    *http_status = e == STORE_E_NOTFOUND ? 404 : 500;
    return -1;
}

static int op_report(void *user, int64_t id, unsigned char **png, size_t *len, int *http_status, char *why,
                     size_t why_len)
{
    rig_daemon *d = user;
    trial_err te = trial_report_png_bytes(d->st, id, png, len, why, why_len);
    if (te != TRIAL_OK) {
        *http_status = te == TRIAL_E_NOTFOUND ? 404 : 500;
        return -1;
    }
    return 0;
}

/* The CSV `ribbonctl export ID --csv` writes: the store's one writer. */
static int op_samples_csv(void *user, int64_t id, char **csv, size_t *len, int *http_status, char *why,
                          size_t why_len)
{
    rig_daemon *d = user;
    store_err e = store_export_trial_csv_text(d->st, id, csv, len, why, why_len);
    if (e == STORE_OK) return 0;
    *http_status = e == STORE_E_NOTFOUND ? 404 : 500;
    return -1;
}

/* The phase report over the predicted map; the first request starts the map's computation, and
 * until it is ready the trials are drawn alone (map says how far it is). */
static int op_phase(void *user, unsigned char **png, size_t *len, char *map, size_t map_len, int *http_status,
                    char *why, size_t why_len)
{
    rig_daemon *d = user;
    char w[256];
    if (phase_map_start(d->phase, w, sizeof w) != 0) say(d, "phase map: %s", w);
    const phase_grid *g = phase_map_grid(d->phase);
    phase_map_state(d->phase, map, map_len);
    if (trial_phase_report_png_bytes(d->st, g, png, len, why, why_len) == 0) return 0;
    *http_status = 500;
    return -1;
}

static int op_events(void *user, api_stream *out, char *why, size_t why_len)
{
    rig_daemon *d = user; /* d->bus is set before the server starts and freed after it stops */
    return live_route_events(d->bus, out, why, why_len);
}

static int op_camera(void *user, unsigned char **jpg, size_t *len, int *http_status, char *why, size_t why_len)
{
    rig_daemon *d = user;
    return live_route_camera(d->bus, jpg, len, http_status, why, why_len);
}

static int op_prediction(void *user, json_t **out, int *http_status, char *why, size_t why_len)
{
    rig_daemon *d = user;
    return live_route_prediction(d->bus, out, http_status, why, why_len);
}

api_ops rig_daemon_ops(void)
{
    api_ops o;
    memset(&o, 0, sizeof o);
    o.status = op_status;
    o.start = op_start;
    o.abort_current = op_abort;
    o.list = op_list;
    o.show = op_show;
    o.report_png = op_report;
    o.samples_csv = op_samples_csv;
    o.phase_png = op_phase;
    o.events = op_events;
    o.camera_jpeg = op_camera;
    o.prediction = op_prediction;
    o.campaign = op_campaign;
    o.rail = op_rail;
    return o;
}
