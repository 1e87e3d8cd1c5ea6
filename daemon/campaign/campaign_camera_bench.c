/* campaign_camera_bench.c: the simulated campaign through the camera (campaign_camera_bench.h):
 * the planner, the approval, the queue with its operator step and real mock trials, in process,
 * one specimen at a time. The harness owns the mock rails (one virtual clock for the campaign), the
 * session of the running trial (started by the queue's thread through start_trial below, joined
 * here) and a table of each specimen's twin keys. Every wait is bounded by trial_timeout_s; a
 * trial still running then is aborted (its rails stop) and joined before the campaign fails. */
#include "campaign_camera_bench.h"

#include <jansson.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "campaign_edge.h"
#include "campaign_phase.h"
#include "campaign_plan.h"
#include "campaign_queue.h"
#include "campaign_routes.h"
#include "campaign_specimen.h"
#include "rail_open.h"
#include "rig_config.h"
#include "store.h"
#include "trial.h"
#include "twin.h"

campaign_camera_opts campaign_camera_opts_default(void)
{
    campaign_camera_opts o;
    memset(&o, 0, sizeof o);
    o.bench = campaign_bench_opts_default();
    o.bench.twin_hinge = 5e-3;
    o.name = "campaign";
    o.trial_timeout_s = 1200;
    o.strip = 1;
    return o;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

#define TWIN_KEY_LEN 96
#define TWIN_KEYS 2

/* The harness: what the queue's ops reach through their user pointer. */
typedef struct cam_run {
    const campaign_camera_opts *o;
    char store_path[600], video_dir[600];
    char base_text[CAMPAIGN_CAMERA_MAX_SETS + 3][700]; /* o->sets, then the store, videos and hinge */
    const char *base[CAMPAIGN_CAMERA_MAX_SETS + 3];
    int n_base;
    int scene_sign;              /* the scene's crease orientation, +1 or -1 */
    rail_vclock vclock;
    rail *compress, *shear;
    pthread_mutex_t lock;        /* guards what follows (the queue's thread and the harness) */
    trial_session *session;      /* the running or finished, not yet joined, trial */
    int64_t session_trial;
    struct {
        char name[16];
        char keys[TWIN_KEYS][TWIN_KEY_LEN];
    } twin[CAMPAIGN_CAMERA_MAX_SPECIMENS];
    int n_twin;
} cam_run;

/* The rig file with the base overrides and extra ones after them. */
static int load_rig(const cam_run *h, const char *const *extra, int n_extra, rig_config *cfg, const char **all,
                    int *n_all, char *why, size_t why_len)
{
    int n = 0;
    for (int k = 0; k < h->n_base; k++) all[n++] = h->base[k];
    for (int k = 0; k < n_extra; k++) all[n++] = extra[k];
    *n_all = n;
    cfg_error ce;
    if (rig_config_load(h->o->rig_path, all, n, cfg, &ce) != CFG_OK) {
        cfg_error_format(&ce, why, why_len);
        return -1;
    }
    if (cfg->mode != RIG_MODE_MOCK) {
        snprintf(why, why_len, "%s: the campaign through the camera runs in mock mode only (rig.mode = mock)",
                 h->o->rig_path);
        return -1;
    }
    return 0;
}

/* The queue's start_trial: the rig file with the specimen's keys, then its twin's (the bench's
 * table), on the harness's rails. */
static int start_trial(void *user, const store_specimen *sp, const char *const *set, int n_set, const char *note,
                       int64_t *trial_id, char *why, size_t why_len)
{
    cam_run *h = user;
    campaign_overrides sov;
    if (campaign_specimen_overrides(sp, h->scene_sign, &sov, why, why_len)) return -1;
    const char *extra[CAMPAIGN_MAX_OVERRIDES + TWIN_KEYS + 8];
    int ne = 0;
    for (int k = 0; k < sov.n; k++) extra[ne++] = sov.ptr[k];
    for (int k = 0; k < n_set && ne < (int)(sizeof extra / sizeof extra[0]) - TWIN_KEYS; k++) extra[ne++] = set[k];
    pthread_mutex_lock(&h->lock);
    int found = 0;
    for (int i = 0; i < h->n_twin; i++)
        if (!strcmp(h->twin[i].name, sp->name)) {
            for (int k = 0; k < TWIN_KEYS; k++) extra[ne++] = h->twin[i].keys[k];
            found = 1;
        }
    int busy = h->session != NULL;
    pthread_mutex_unlock(&h->lock);
    if (!found) {
        snprintf(why, why_len, "specimen %s is not one of the bench's: it has no twin", sp->name);
        return -1;
    }
    if (busy) {
        snprintf(why, why_len, "a trial of the campaign has not been joined yet");
        return -1;
    }
    rig_config *cfg = malloc(sizeof *cfg);
    const char *all[CAMPAIGN_CAMERA_MAX_SETS + 3 + CAMPAIGN_MAX_OVERRIDES + TWIN_KEYS + 8];
    int n_all = 0;
    if (!cfg) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    if (load_rig(h, extra, ne, cfg, all, &n_all, why, why_len)) {
        free(cfg);
        return -1;
    }
    trial_session *s = NULL;
    trial_err te = trial_session_start_tx(cfg, all, n_all, h->compress, h->shear, note, NULL, NULL, NULL, &s, trial_id,
                                          why, why_len);
    free(cfg);
    if (te != TRIAL_OK) return -1;
    pthread_mutex_lock(&h->lock);
    h->session = s;
    h->session_trial = *trial_id;
    pthread_mutex_unlock(&h->lock);
    return 0;
}

static int trial_running(void *user, int64_t trial_id)
{
    cam_run *h = user;
    int running = 0;
    pthread_mutex_lock(&h->lock);
    if (h->session && (trial_id == 0 || trial_id == h->session_trial)) {
        session_status ss;
        trial_session_status(h->session, &ss);
        running = !ss.finished;
    }
    pthread_mutex_unlock(&h->lock);
    return running;
}

/* Joins the campaign's trial, if one was started (abort first: its rails stop). */
static void join_session(cam_run *h, const char *abort_reason)
{
    pthread_mutex_lock(&h->lock);
    trial_session *s = h->session;
    h->session = NULL;
    pthread_mutex_unlock(&h->lock);
    if (!s) return;
    if (abort_reason) trial_session_abort(s, abort_reason);
    trial_result tr;
    trial_session_join(s, &tr);
}

static void say(void (*progress)(void *, const char *), void *u, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void say(void (*progress)(void *, const char *), void *u, const char *fmt, ...)
{
    if (!progress) return;
    char line[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    progress(u, line);
}

int campaign_camera_truth_trace(const campaign_camera_opts *o, int dynamic, campaign_camera_truth *t, char *why,
                                size_t why_len)
{
    memset(t, 0, sizeof *t);
    double t0 = now_s();
    size_t n = o->bench.nphi;
    if (n < 1 || n > CAMPAIGN_BENCH_MAX_PHI) {
        snprintf(why, why_len, "1..%d phi values", CAMPAIGN_BENCH_MAX_PHI);
        return -1;
    }
    const char *all[CAMPAIGN_CAMERA_MAX_SETS + 1];
    char hinge[64];
    int na = 0;
    for (int k = 0; k < o->n_sets && k < CAMPAIGN_CAMERA_MAX_SETS; k++) all[na++] = o->sets[k];
    snprintf(hinge, sizeof hinge, "twin.folds.hinge_stiffness=%.9g", o->bench.twin_hinge);
    if (o->bench.twin_hinge > 0) all[na++] = hinge;
    rig_config *cfg = malloc(sizeof *cfg);
    if (!cfg) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    cfg_error ce;
    if (rig_config_load(o->rig_path, all, na, cfg, &ce) != CFG_OK) {
        cfg_error_format(&ce, why, why_len);
        free(cfg);
        return -1;
    }
    /* The twins' mean strip: the twin (its mesh, step, hinge) with equal creases at phi - relax
     * (the scene's imperfection seed, not the twin file's difference). */
    rod_scene mean = cfg->twin.present ? cfg->twin.scene : cfg->scene;
    if (!cfg->twin.present && o->bench.twin_hinge > 0) mean.fold_hinge_stiffness = o->bench.twin_hinge;
    mean.fold_angle_rel = cfg->scene.fold_angle_rel;
    mean.fold_angle_left_deg = mean.fold_angle_right_deg = NAN;
    mean.fold_position_left = mean.fold_position_right = NAN;
    rod_scene model = cfg->scene;
    free(cfg);
    t->nodes = mean.nodes;
    double relaxed[CAMPAIGN_BENCH_MAX_PHI];
    for (size_t j = 0; j < n; j++) {
        relaxed[j] = o->bench.phi_deg[j] - o->bench.relax_deg;
        t->dynamic[j] = NAN;
    }
    char w[700];
    if (campaign_bench_trace(&model, o->bench.phi_deg, n, t->predicted, w, sizeof w)) {
        snprintf(why, why_len, "the model's boundary: %s", w);
        return -1;
    }
    if (campaign_bench_trace(&mean, relaxed, n, t->statik, w, sizeof w)) {
        snprintf(why, why_len, "the twins' static boundary: %s", w);
        return -1;
    }
    for (size_t j = 0; dynamic && j < n; j++)
        if (campaign_bench_dynamic_switch(&mean, relaxed[j], t->statik[j], &t->dynamic[j], w, sizeof w)) {
            snprintf(why, why_len, "the twins' dynamic switch: %s", w);
            return -1;
        }
    t->wall_s = now_s() - t0;
    return 0;
}

/* Every phi's experimental interval closed and at most stop_width wide? */
static int intervals_closed(const campaign_obs *obs, size_t nobs, const campaign_bench_opts *b)
{
    for (size_t j = 0; j < b->nphi; j++) {
        campaign_edge e;
        campaign_edge_fit(obs, nobs, b->phi_deg[j], &e);
        if (!(e.method == CAMPAIGN_EDGE_BRACKET || e.method == CAMPAIGN_EDGE_PROBIT) || !(e.hi - e.lo <= b->stop_width))
            return 0;
    }
    return 1;
}

/* The measured regimes so far, from the store (nothing measured yet: none). */
static int read_obs(store *st, campaign_phase *ph, char *why, size_t why_len)
{
    memset(ph, 0, sizeof *ph);
    int rc = campaign_phase_collect(st, ph, why, why_len);
    if (rc == -2) {
        memset(ph, 0, sizeof *ph);
        return 0;
    }
    return rc;
}

/* Waits until queue item id is in one of the states of mask (bits of store_queue_status) or
 * deadline: 0 and *it, or -1 with why. */
static int wait_item(store *st, int64_t id, unsigned mask, double deadline, double timeout_s, store_queue_item *it,
                     char *why, size_t why_len)
{
    for (;;) {
        if (store_queue_get(st, id, it, why, why_len) != STORE_OK) return -1;
        if (mask & (1u << it->status)) return 0;
        if (now_s() > deadline) {
            snprintf(why, why_len, "queue item %lld still %s after the specimen's %.0f s", (long long)id,
                     store_queue_status_name(it->status), timeout_s);
            return -1;
        }
        usleep(50 * 1000);
    }
}

/* One specimen's way from the proposal to its measured regime. */
static int one_specimen(cam_run *h, store *st, campaign_queue *q, const campaign_ctx *ctx, const campaign_proposal *prop,
                        const campaign_plan_result *res, unsigned *rng, campaign_camera_specimen *cs, char *why,
                        size_t why_len)
{
    const campaign_camera_opts *o = h->o;
    double t0 = now_s(), deadline = t0 + o->trial_timeout_s;
    char w[600];
    /* plan: stored as ribbonctl plan stores it */
    store_plan_proposal row = {.phi_deg = prop->phi_deg, .gamma = prop->gamma, .sd_before = prop->sd_before,
                               .predicted_gamma = NAN, .offset_mean = res->offset_mean, .offset_sd = res->offset_sd,
                               .calibrated = o->bench.calibrate};
    for (size_t j = 0; j < o->bench.nphi; j++)
        if (o->bench.phi_deg[j] == prop->phi_deg) row.predicted_gamma = res->beliefs[j].predicted;
    if (store_plan_add_batch(st, &row, 1, store_wall_now(), w, sizeof w) != STORE_OK) {
        snprintf(why, why_len, "storing the proposal: %s", w);
        return -1;
    }
    cs->proposal_id = row.id;
    cs->phi_deg = prop->phi_deg;
    cs->gamma = prop->gamma;
    /* fold: the twin's keys, before the queue can reach its trial */
    campaign_twin_draw d;
    campaign_bench_draw(rng, o->bench.spread, prop->phi_deg - o->bench.relax_deg, &d);
    double base = prop->phi_deg - o->bench.relax_deg;
    cs->twin_left_deg = base * (1 + d.ul);
    cs->twin_right_deg = base * (1 + d.ur);
    cs->twin_mean_deg = d.mean_deg;
    cs->twin_rel = d.rel;
    cs->measured_left_deg = prop->phi_deg * (1 + d.ul);
    cs->measured_right_deg = prop->phi_deg * (1 + d.ur);
    pthread_mutex_lock(&h->lock);
    if (h->n_twin == CAMPAIGN_CAMERA_MAX_SPECIMENS) {
        pthread_mutex_unlock(&h->lock);
        snprintf(why, why_len, "at most %d specimens", CAMPAIGN_CAMERA_MAX_SPECIMENS);
        return -1;
    }
    snprintf(h->twin[h->n_twin].name, sizeof h->twin[0].name, "%s", cs->name);
    snprintf(h->twin[h->n_twin].keys[0], TWIN_KEY_LEN, "twin.folds.angle_deg=%.9g", h->scene_sign * d.mean_deg);
    snprintf(h->twin[h->n_twin].keys[1], TWIN_KEY_LEN, "twin.imperfection.fold_angle_rel=%.9g", d.rel);
    h->n_twin++;
    pthread_mutex_unlock(&h->lock);
    /* approve: the daemon's route */
    char path[64];
    snprintf(path, sizeof path, "/plan/%lld/approve", (long long)row.id);
    json_t *body = json_pack("{s:s}", "name", cs->name), *out = NULL;
    int http = 0;
    int rc = campaign_route(ctx, "POST", path, body, &out, &http, w, sizeof w);
    json_decref(body);
    json_decref(out);
    if (rc) {
        snprintf(why, why_len, "approving proposal %lld: %d %s", (long long)row.id, http, w);
        return -1;
    }
    store_plan_proposal p;
    if (store_plan_get(st, row.id, &p, w, sizeof w) != STORE_OK) {
        snprintf(why, why_len, "proposal %lld: %s", (long long)row.id, w);
        return -1;
    }
    json_t *jo = NULL;
    if (campaign_queue_set_running(q, true, &jo, &http, w, sizeof w)) {
        snprintf(why, why_len, "starting the queue: %s", w);
        return -1;
    }
    json_decref(jo);
    /* confirm: the operator step, with the angles measured at folding */
    store_queue_item it;
    unsigned running_or_end = ~(1u << STORE_QUEUE_QUEUED);
    if (wait_item(st, p.operator_item_id, running_or_end, deadline, o->trial_timeout_s, &it, w, sizeof w)) {
        snprintf(why, why_len, "%s's operator step: %s", cs->name, w);
        return -1;
    }
    if (it.status != STORE_QUEUE_RUNNING) {
        snprintf(why, why_len, "%s's operator step ended %s before it was confirmed: %s", cs->name,
                 store_queue_status_name(it.status), it.reason);
        return -1;
    }
    json_t *cb = json_pack("{s:{s:f,s:f,s:s}}", "values", "crease_angle_left_deg", cs->measured_left_deg,
                           "crease_angle_right_deg", cs->measured_right_deg, "folded_at", "2026-12-01T09:00:00Z");
    rc = campaign_queue_confirm(q, p.operator_item_id, cb, &jo, &http, w, sizeof w);
    json_decref(cb);
    json_decref(jo);
    if (rc) {
        snprintf(why, why_len, "confirming %s's operator step: %d %s", cs->name, http, w);
        return -1;
    }
    /* trial: the queue starts it; wait for its item's end */
    unsigned ended = (1u << STORE_QUEUE_DONE) | (1u << STORE_QUEUE_FAILED) | (1u << STORE_QUEUE_ABORTED) |
                     (1u << STORE_QUEUE_SKIPPED) | (1u << STORE_QUEUE_UNKNOWN);
    if (wait_item(st, p.trial_item_id, ended, deadline, o->trial_timeout_s, &it, w, sizeof w)) {
        join_session(h, "the campaign's wait for this trial ran out");
        snprintf(why, why_len, "%s's trial: %s (aborted)", cs->name, w);
        return -1;
    }
    join_session(h, NULL);
    cs->wall_s = now_s() - t0;
    cs->trial_id = it.trial_id;
    if (it.status != STORE_QUEUE_DONE) {
        snprintf(why, why_len, "%s's trial (queue item %lld, trial %lld) ended %s: %s", cs->name,
                 (long long)it.id, (long long)it.trial_id, store_queue_status_name(it.status), it.reason);
        return -1;
    }
    /* read: the measured regime from the stored trial, the twin's truth from its event */
    store_trial tr;
    if (store_trial_get(st, it.trial_id, &tr, w, sizeof w) != STORE_OK) {
        snprintf(why, why_len, "trial %lld: %s", (long long)it.trial_id, w);
        return -1;
    }
    if (!o->keep_videos && tr.video_path[0]) unlink(tr.video_path);
    /* a snap whose passage the camera could not decide is stored without a regime (trials.md): the
       planner skips it (it counts asymmetric and symmetric only), the bench says "undecided" */
    const char *rn = tr.snapped == 1 ? store_regime_name(tr.regime_measured) : tr.snapped == 0 ? "no snap" : NULL;
    snprintf(cs->regime, sizeof cs->regime, "%s", rn ? rn : tr.snapped == 1 ? "undecided" : "unknown");
    cs->snap_dw = tr.snapped == 1 ? tr.snap_dw_measured : NAN;
    cs->truth[0] = '\0';
    cs->truth_dw = NAN;
    cs->truth_peak_a = NAN;
    store_event *ev = NULL;
    size_t nev = 0;
    if (store_events_get(st, it.trial_id, &ev, &nev, w, sizeof w) == STORE_OK) {
        for (size_t k = 0; k < nev; k++)
            if (!strncmp(ev[k].message, TWIN_TRUTH_PREFIX, strlen(TWIN_TRUTH_PREFIX))) {
                char reg[16] = "";
                if (twin_truth_parse(ev[k].message, &cs->truth_dw, reg, sizeof reg) || reg[0])
                    snprintf(cs->truth, sizeof cs->truth, "%s", reg);
                const char *pk = strstr(ev[k].message, "peak |A| ");
                double a;
                if (pk && sscanf(pk + 9, "%lf", &a) == 1 && isfinite(a)) cs->truth_peak_a = a;
            }
    }
    free(ev);
    return 0;
}

/* The base overrides: the caller's, then the campaign's store, videos and the twins' hinge. */
static int base_overrides(cam_run *h, char *why, size_t why_len)
{
    const campaign_camera_opts *o = h->o;
    const char *stem = o->name && o->name[0] ? o->name : "campaign";
    const char *tag = o->bench.calibrate ? "cal" : "uncal";
    char *dir = realpath(o->dir ? o->dir : ".", NULL);
    if (!dir) {
        snprintf(why, why_len, "the campaign's directory %s does not exist", o->dir ? o->dir : ".");
        return -1;
    }
    snprintf(h->store_path, sizeof h->store_path, "%.300s/%.60s-%s.db", dir, stem, tag);
    snprintf(h->video_dir, sizeof h->video_dir, "%.300s/%.60s-%s-videos", dir, stem, tag);
    free(dir);
    if (access(h->store_path, F_OK) == 0) {
        snprintf(why, why_len, "%s exists: a campaign starts from an empty store (remove it, or another --dir)",
                 h->store_path);
        return -1;
    }
    int n = 0;
    for (int k = 0; k < o->n_sets && k < CAMPAIGN_CAMERA_MAX_SETS; k++)
        snprintf(h->base_text[n++], sizeof h->base_text[0], "%s", o->sets[k]);
    snprintf(h->base_text[n++], sizeof h->base_text[0], "store.path=%s", h->store_path);
    snprintf(h->base_text[n++], sizeof h->base_text[0], "camera.video_dir=%s", h->video_dir);
    if (o->bench.twin_hinge > 0)
        snprintf(h->base_text[n++], sizeof h->base_text[0], "twin.folds.hinge_stiffness=%.9g", o->bench.twin_hinge);
    for (int k = 0; k < n; k++) h->base[k] = h->base_text[k];
    h->n_base = n;
    return 0;
}

/* The lab strip's model for the calibrated campaign (opts.strip): the scene's curve, traced once,
 * or the strip's (traced again when its hinge or E moved by more than a quarter of their standard
 * errors), read at phi - relaxation; as campaign_bench.c's lab_model, from the store's records
 * (campaign_strip_collect: the specimens' calibrations first). */
typedef struct cam_strip {
    campaign_predicted scene_curve, strip_curve;
    int have_scene, have_strip;
    double traced_hinge, traced_youngs;
} cam_strip;

static int strip_moved(double traced, double now, double se_rel)
{
    if (isnan(traced) != isnan(now)) return 1;
    if (isnan(now)) return 0;
    return fabs(log(now / traced)) > fmax(0.25 * se_rel, 1e-3);
}

/* 0 with model[] the strip's; 1 when it could not be made (model kept, r->strip_failure says
 * why); -1 with why when the store cannot be read. */
static int strip_model(const rod_scene *scene, const campaign_bench_opts *b, store *st, cam_strip *ss,
                       double offset, double *model, campaign_camera_result *r, char *why, size_t why_len)
{
    campaign_strip_fit *fits = NULL;
    size_t nf = 0;
    int failed = 0;
    if (campaign_strip_collect(st, &fits, &nf, &failed, why, why_len)) return -1;
    campaign_strip_pool(fits, nf, &r->strip);
    free(fits);
    const campaign_lab_strip *ls = &r->strip;
    double lo = 180, hi = 0;
    for (size_t j = 0; j < b->nphi; j++) lo = fmin(lo, b->phi_deg[j]), hi = fmax(hi, b->phi_deg[j]);
    lo -= 25, hi += 5; /* relaxations up to 25 deg, 5 the other way (campaign_bench.c) */
    char w[1200];
    const campaign_predicted *curve;
    if (!campaign_strip_needs_trace(ls)) {
        if (!ss->have_scene) {
            r->strip_traces++;
            if (campaign_predicted_trace(scene, lo, hi, &ss->scene_curve, w, sizeof w)) {
                r->strip_failures++;
                snprintf(r->strip_failure, sizeof r->strip_failure, "the scene's trace: %.560s", w);
                return 1;
            }
            ss->have_scene = 1;
        }
        curve = &ss->scene_curve;
    } else {
        if (!ss->have_strip || strip_moved(ss->traced_hinge, ls->hinge, ls->hinge_se_rel) ||
            strip_moved(ss->traced_youngs, ls->youngs, ls->youngs_se_rel)) {
            rod_scene lab;
            campaign_strip_apply(scene, ls, &lab);
            size_t near = 0;
            double ps = fabs(scene->fold_angle_deg);
            for (size_t j = 1; j < b->nphi; j++)
                if (fabs(b->phi_deg[j] - ps) < fabs(b->phi_deg[near] - ps)) near = j;
            double g0 = model[near] + offset;
            double starts[] = {g0, g0 + 0.005, g0 - 0.005, g0 + 0.01};
            campaign_predicted next;
            r->strip_traces++;
            int rc = campaign_strip_trace(&lab, ls, b->phi_deg[near] - (ls->n_relax ? ls->relax_deg : 0), starts, 4,
                                          lo, hi, b->phi_deg, b->nphi, &next, w, sizeof w);
            ss->traced_hinge = ls->hinge, ss->traced_youngs = ls->youngs; /* not tried again until it moves */
            if (rc) {
                r->strip_failures++;
                snprintf(r->strip_failure, sizeof r->strip_failure, "the strip's trace: %.560s", w);
                return 1;
            }
            if (ss->have_strip) campaign_predicted_free(&ss->strip_curve);
            ss->strip_curve = next;
            ss->have_strip = 1;
        }
        if (!ss->have_strip) return 1;
        curve = &ss->strip_curve;
    }
    double m[CAMPAIGN_BENCH_MAX_PHI];
    for (size_t j = 0; j < b->nphi; j++)
        if (campaign_strip_at(curve, ls, b->phi_deg[j], &m[j], w, sizeof w)) {
            r->strip_failures++;
            snprintf(r->strip_failure, sizeof r->strip_failure, "%.590s", w);
            return 1;
        }
    memcpy(model, m, b->nphi * sizeof m[0]);
    return 0;
}

static int run_campaign(cam_run *h, const rig_config *cfg, const campaign_camera_truth *truth,
                        campaign_camera_result *r, void (*progress)(void *, const char *), void *u, char *why,
                        size_t why_len)
{
    const campaign_camera_opts *o = h->o;
    const campaign_bench_opts *b = &o->bench;
    size_t n = b->nphi;
    store *st = NULL;
    campaign_queue *q = NULL;
    int rc = -1;
    char w[700];
    if (store_open(h->store_path, &st, w, sizeof w) != STORE_OK) {
        snprintf(why, why_len, "store %s: %s", h->store_path, w);
        return -1;
    }
    campaign_queue_ops ops = {.start_trial = start_trial, .trial_running = trial_running};
    if (campaign_queue_open(h->store_path, &ops, h, NULL, &q, w, sizeof w)) {
        snprintf(why, why_len, "the queue: %s", w);
        store_close(st);
        return -1;
    }
    campaign_ctx ctx = {.st = st, .q = q, .defaults = store_specimen_default(), .scene = &cfg->scene};
    ctx.defaults.length_m = cfg->scene.length;
    ctx.defaults.width_m = cfg->scene.width;
    ctx.defaults.thickness_m = cfg->scene.thickness;
    ctx.defaults.youngs_modulus_pa = cfg->scene.youngs_modulus;
    ctx.defaults.density_kg_m3 = cfg->scene.density;
    snprintf(ctx.defaults.material, sizeof ctx.defaults.material, "%.31s", cfg->specimen.material);
    campaign_plan_opts po = campaign_plan_opts_default();
    po.calibrate = b->calibrate;
    campaign_belief beliefs[CAMPAIGN_BENCH_MAX_PHI];
    campaign_proposal prop;
    campaign_plan_result res = {.beliefs = beliefs, .proposals = &prop};
    unsigned rng = b->seed ? b->seed : 1;
    r->asym_threshold = cfg->scene.asym_threshold;
    campaign_phase ph;
    memset(&ph, 0, sizeof ph);
    cam_strip ss;
    memset(&ss, 0, sizeof ss);
    ss.traced_hinge = ss.traced_youngs = NAN;
    int use_strip = o->strip && b->calibrate;
    memcpy(r->model, truth->predicted, n * sizeof r->model[0]);
    res.offset_mean = 0;
    for (;;) {
        campaign_phase_free(&ph);
        if (read_obs(st, &ph, w, sizeof w)) {
            snprintf(why, why_len, "reading the measured regimes: %s", w);
            goto out;
        }
        if (intervals_closed(ph.obs, ph.n_obs, b)) {
            r->converged = 1;
            break;
        }
        if (r->specimens >= b->max_specimens || r->specimens >= CAMPAIGN_CAMERA_MAX_SPECIMENS) break;
        if (use_strip) {
            int src = strip_model(&cfg->scene, b, st, &ss, res.offset_mean, r->model, r, w, sizeof w);
            if (src < 0) {
                snprintf(why, why_len, "the lab strip: %s", w);
                goto out;
            }
            char d[400];
            campaign_strip_describe(&r->strip, d, sizeof d);
            say(progress, u, "lab strip: %s (%d specimen calibrations); model %.5f, %.5f, %.5f%s%s", d,
                r->strip.n_calibrations, r->model[0], n > 1 ? r->model[1] : NAN, n > 2 ? r->model[2] : NAN,
                src ? "; kept: " : "", src ? r->strip_failure : "");
        }
        if (campaign_plan_run(b->phi_deg, r->model, n, ph.obs, ph.n_obs, &po, 1, &res, why, why_len)) goto out;
        campaign_camera_specimen *cs = &r->sp[r->specimens];
        snprintf(cs->name, sizeof cs->name, "C-%d", r->specimens + 1);
        if (one_specimen(h, st, q, &ctx, &prop, &res, &rng, cs, why, why_len)) goto out;
        r->specimens++;
        r->trials_s += cs->wall_s;
        int agrees = !strcmp(cs->regime, cs->truth), undecided = !strcmp(cs->regime, "undecided");
        r->agree += agrees;
        r->undecided += undecided;
        if (isfinite(cs->truth_peak_a) && (cs->truth_peak_a < r->asym_threshold / CAMPAIGN_CAMERA_CLEAR ||
                                           cs->truth_peak_a > r->asym_threshold * CAMPAIGN_CAMERA_CLEAR)) {
            r->clear++;
            r->clear_agree += agrees;
            r->clear_undecided += undecided;
        }
        say(progress, u,
            "%s: phi %g Gamma %.5f (twin's creases %.3f, %.3f deg; measured %.3f, %.3f) -> trial %lld %s "
            "(snap %.5f), twin truth %s (%.5f, peak |A| %.3f rad)%s, offset %+.4f, %.1f s",
            cs->name, cs->phi_deg, cs->gamma, cs->twin_left_deg, cs->twin_right_deg, cs->measured_left_deg,
            cs->measured_right_deg, (long long)cs->trial_id, cs->regime, cs->snap_dw, cs->truth[0] ? cs->truth : "?",
            cs->truth_dw, cs->truth_peak_a, agrees ? "" : " DIFFERS", res.offset_mean, cs->wall_s);
    }
    /* the located boundary: as plan-bench locates it */
    if (campaign_plan_run(b->phi_deg, r->model, n, ph.obs, ph.n_obs, &po, 0, &res, why, why_len)) goto out;
    r->offset_mean = res.offset_mean;
    r->spread_mean = res.spread_mean;
    for (size_t j = 0; j < n; j++) r->offsets[j] = beliefs[j].offset_mean;
    r->err_static = 0;
    r->err_dynamic = isfinite(truth->dynamic[0]) ? 0 : NAN;
    for (size_t j = 0; j < n; j++) {
        campaign_edge e;
        campaign_edge_fit(ph.obs, ph.n_obs, b->phi_deg[j], &e);
        r->located[j] = isfinite(e.gamma) ? e.gamma : beliefs[j].median;
        r->err_static = fmax(r->err_static, fabs(r->located[j] - truth->statik[j]));
        if (isfinite(r->err_dynamic)) r->err_dynamic = fmax(r->err_dynamic, fabs(r->located[j] - truth->dynamic[j]));
    }
    rc = 0;
out:
    campaign_phase_free(&ph);
    if (ss.have_scene) campaign_predicted_free(&ss.scene_curve);
    if (ss.have_strip) campaign_predicted_free(&ss.strip_curve);
    join_session(h, rc ? "the campaign stopped" : NULL);
    campaign_queue_close(q);
    store_close(st);
    return rc;
}

void campaign_camera_per_phi(const campaign_camera_result *r, const double *phi, size_t n, int *used, int *agree)
{
    for (size_t j = 0; j < n; j++) used[j] = agree[j] = 0;
    for (int k = 0; k < r->specimens && k < CAMPAIGN_CAMERA_MAX_SPECIMENS; k++)
        for (size_t j = 0; j < n; j++)
            if (fabs(r->sp[k].phi_deg - phi[j]) < 1e-9) {
                used[j]++;
                agree[j] += r->sp[k].truth[0] && !strcmp(r->sp[k].regime, r->sp[k].truth);
            }
}

int campaign_camera_run(const campaign_camera_opts *o, const campaign_camera_truth *truth, campaign_camera_result *r,
                        void (*progress)(void *u, const char *line), void *u, char *why, size_t why_len)
{
    memset(r, 0, sizeof *r);
    double t0 = now_s();
    const campaign_bench_opts *b = &o->bench;
    if (b->nphi < 1 || b->nphi > CAMPAIGN_BENCH_MAX_PHI || b->max_specimens < 1 || !o->rig_path ||
        o->n_sets > CAMPAIGN_CAMERA_MAX_SETS || !(o->trial_timeout_s > 0)) {
        snprintf(why, why_len, "campaign: a rig file, 1..%d phi values, at least one specimen, at most %d overrides, "
                 "a positive timeout", CAMPAIGN_BENCH_MAX_PHI, CAMPAIGN_CAMERA_MAX_SETS);
        return -1;
    }
    cam_run *h = calloc(1, sizeof *h);
    rig_config *cfg = malloc(sizeof *cfg);
    if (!h || !cfg) {
        free(h);
        free(cfg);
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    h->o = o;
    pthread_mutex_init(&h->lock, NULL);
    int rc = -1;
    const char *all[CAMPAIGN_CAMERA_MAX_SETS + 3];
    int n_all;
    if (base_overrides(h, why, why_len) || load_rig(h, NULL, 0, cfg, all, &n_all, why, why_len)) goto out;
    h->scene_sign = cfg->scene.fold_angle_deg < 0 ? -1 : 1;
    rail_clock clk = cfg->clock == RIG_CLOCK_VIRTUAL ? rail_clock_virtual(&h->vclock) : rail_clock_real();
    if (rail_open_pair(&cfg->compress, &cfg->shear, clk, &h->compress, &h->shear, why, why_len) != RAIL_OK) goto out;
    say(progress, u, "%s campaign: store %s", b->calibrate ? "calibrated" : "uncalibrated", h->store_path);
    rc = run_campaign(h, cfg, truth, r, progress, u, why, why_len);
out:
    if (h->compress) {
        rail_stop(h->compress);
        rail_close(h->compress);
    }
    if (h->shear) {
        rail_stop(h->shear);
        rail_close(h->shear);
    }
    pthread_mutex_destroy(&h->lock);
    free(h);
    free(cfg);
    r->wall_s = now_s() - t0;
    return rc;
}
