/* trial_specimen_calib.c: a specimen's own calibration, refreshed after each of its trials and
 * used by its next prediction (see trial_specimen_calib.h).
 *
 * Why here: the refit needs the trial room's reading of stored trials (trial_pool.c, shared with
 * `ribbonctl calibrate`, so the lab can reproduce the daemon's numbers by hand) and runs on the
 * trial's thread after the trial's record is stored (trial_session.c); the prediction's scene is
 * built here too. The record it writes (store_specimen.calibration_json) is the one place the
 * calibration lives: the API and ribbonctl show it as stored.
 *
 * The stored calibration is a JSON object: at (ISO-8601 UTC), after_trial, trials (used, newest
 * first), skipped ([{trial, why}]), frames, nodes, hinge_guess (sim.fit_hinge when the strip's
 * rigid creases were fitted as hinges from it: their start; null otherwise), keys (fitted), parameters ([{key, start, value,
 * se, se_kind, determined, at_bound}]: start the measured strip's value the fit started from, se
 * null when not determined; hinge stiffness and E in N m/rad and Pa with a relative se), not_determined
 * (names), rms and rms_start (noise units), iterations, iterations_capped, wall_s. A failure is
 * {reason_key, reason, after_trial, at, trials}. */
#include "trial_specimen_calib.h"

#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "rod_fit.h"
#include "trial_calibrate.h"
#include "trial_pool.h"

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void failed(trial_specimen_refit *r, const char *key, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void failed(trial_specimen_refit *r, const char *key, const char *fmt, ...)
{
    r->ok = 0;
    snprintf(r->reason_key, sizeof r->reason_key, "%s", key);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->reason, sizeof r->reason, fmt, ap);
    va_end(ap);
}

static double natural(int k, double u)
{
    return rod_fit_key_log(k) ? exp(u) : u;
}

/* Parameter k's value in sc in its natural units, read from the scene's own fields (not through
 * the fit's logarithms, so a value reads back bit for bit). */
static double scene_value(const rod_scene *sc, int k)
{
    switch (k) {
    case ROD_FIT_ANGLE_LEFT: return rod_scene_crease_angle_deg(sc, 0);
    case ROD_FIT_ANGLE_RIGHT: return rod_scene_crease_angle_deg(sc, 1);
    case ROD_FIT_POSITION_LEFT: return rod_scene_crease_position(sc, 0);
    case ROD_FIT_POSITION_RIGHT: return rod_scene_crease_position(sc, 1);
    case ROD_FIT_HINGE: return sc->fold_hinge_stiffness;
    case ROD_FIT_HINGE_LEFT: return rod_scene_hinge_k(sc, 0);
    case ROD_FIT_HINGE_RIGHT: return rod_scene_hinge_k(sc, 1);
    case ROD_FIT_YOUNGS: return sc->youngs_modulus;
    default: return 0.0; /* view.dz_offset: 0 at the scene's values */
    }
}

/* ---- the refit ---------------------------------------------------------------------------------- */

static int cmp_id_desc(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return x < y ? 1 : x > y ? -1 : 0;
}

/* The specimen's finished trials (done; rig or mock: a replay repeats its recording's frames),
 * newest first, at most cap. -1 with why when the store cannot list them. */
static int finished_trials(store *st, int64_t specimen_id, int64_t *ids, int cap, int *n, char *why, size_t why_len)
{
    store_trial *t = NULL;
    size_t nt = 0;
    *n = 0;
    if (store_trial_list(st, &t, &nt, why, why_len) != STORE_OK) return -1;
    int64_t *all = malloc(sizeof *all * (nt ? nt : 1));
    size_t m = 0;
    for (size_t k = 0; all && k < nt; k++)
        if (t[k].specimen_id == specimen_id && t[k].status == STORE_STATUS_DONE && t[k].mode != STORE_MODE_REPLAY)
            all[m++] = t[k].id;
    free(t);
    if (!all) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    qsort(all, m, sizeof *all, cmp_id_desc);
    for (size_t k = 0; k < m && *n < cap; k++) ids[(*n)++] = all[k];
    free(all);
    return 0;
}

typedef struct pooled {
    int64_t used[TRIAL_SPECIMEN_CALIB_MAX_TRIALS];
    int nused;
    int64_t skipped[TRIAL_SPECIMEN_CALIB_MAX_EXAMINED];
    char skipped_why[TRIAL_SPECIMEN_CALIB_MAX_EXAMINED][320];
    int nskipped;
    trial_pool pool; /* of used[] (newest first: its scene is the newest trial's strip) */
} pooled;

/* Adds the candidates one by one, newest first: one the pool refuses with those already in (its
 * own frames, or a strip that differs from theirs) is skipped with the pool's reason. */
static void pool_trials(store *st, const int64_t *cand, int n, pooled *p)
{
    trial_pool_select sel = trial_pool_select_default();
    sel.max_samples = TRIAL_SPECIMEN_CALIB_MAX_FRAMES;
    for (int k = 0; k < n && p->nused < TRIAL_SPECIMEN_CALIB_MAX_TRIALS; k++) {
        int64_t ids[TRIAL_SPECIMEN_CALIB_MAX_TRIALS + 1];
        memcpy(ids, p->used, sizeof ids[0] * (size_t)p->nused);
        ids[p->nused] = cand[k];
        trial_pool next;
        char why[512];
        if (trial_pool_load(st, ids, p->nused + 1, &sel, &next, why, sizeof why)) {
            snprintf(p->skipped_why[p->nskipped], sizeof p->skipped_why[0], "%.319s", why);
            p->skipped[p->nskipped++] = cand[k];
            continue;
        }
        trial_pool_free(&p->pool);
        p->pool = next;
        p->used[p->nused++] = cand[k];
    }
}

static json_t *num_or_null(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

static json_t *ids_json(const int64_t *ids, int n)
{
    json_t *a = json_array();
    for (int k = 0; k < n; k++) json_array_append_new(a, json_integer(ids[k]));
    return a;
}

static void ids_text(const int64_t *ids, int n, char *out, size_t len)
{
    size_t u = 0;
    out[0] = '\0';
    for (int k = 0; k < n && u < len; k++)
        u += (size_t)snprintf(out + u, len - u, "%s%lld", k ? ", " : "", (long long)ids[k]);
}

/* The calibration record (see the file's comment). NULL when out of memory. */
static json_t *calibration_json(const pooled *p, const rod_fit_result *fr, int64_t after_trial, const char *at,
                                double wall_s, double hinge_guess)
{
    /* start: the strip's own value (fr->u0 is it through the fit's logarithms). */
    json_t *j = json_object(), *sk = json_array(), *keys = json_array(), *ps = json_array(), *nd = json_array();
    for (int k = 0; k < p->nskipped; k++)
        json_array_append_new(sk, json_pack("{s:I, s:s}", "trial", (json_int_t)p->skipped[k], "why", p->skipped_why[k]));
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        if (!fr->fitted[k]) continue;
        json_array_append_new(keys, json_string(rod_fit_key_name(k)));
        if (!fr->determined[k]) json_array_append_new(nd, json_string(rod_fit_key_name(k)));
        json_array_append_new(ps, json_pack("{s:s, s:o, s:o, s:o, s:s, s:b, s:i}", "key", rod_fit_key_name(k), "start",
                                            num_or_null(scene_value(&p->pool.scene, k)), "value",
                                            num_or_null(natural(k, fr->u[k])), "se",
                                            fr->determined[k] ? num_or_null(fr->se[k]) : json_null(), "se_kind",
                                            rod_fit_key_log(k) ? "relative" : "absolute", "determined",
                                            fr->determined[k] != 0, "at_bound", fr->at_bound[k]));
    }
    json_object_set_new(j, "at", json_string(at));
    json_object_set_new(j, "after_trial", json_integer(after_trial));
    json_object_set_new(j, "trials", ids_json(p->used, p->nused));
    json_object_set_new(j, "skipped", sk);
    json_object_set_new(j, "frames", json_integer(p->pool.nobs));
    int per = TRIAL_SPECIMEN_CALIB_MAX_FRAMES_TOTAL / (p->nused ? p->nused : 1);
    json_object_set_new(j, "frames_per_trial_max",
                        json_integer(per < TRIAL_SPECIMEN_CALIB_MAX_FRAMES ? per : TRIAL_SPECIMEN_CALIB_MAX_FRAMES));
    json_object_set_new(j, "nodes", json_integer(p->pool.scene.nodes));
    json_object_set_new(j, "hinge_guess", num_or_null(hinge_guess));
    json_object_set_new(j, "keys", keys);
    json_object_set_new(j, "parameters", ps);
    json_object_set_new(j, "not_determined", nd);
    json_object_set_new(j, "rms", num_or_null(fr->rms));
    json_object_set_new(j, "rms_start", num_or_null(fr->rms_start));
    json_object_set_new(j, "iterations", json_integer(fr->iterations));
    json_object_set_new(j, "iterations_capped", json_boolean(fr->capped));
    json_object_set_new(j, "wall_s", json_real(wall_s));
    return j;
}

/* j as compact text shorter than cap: without the skipped trials' reasons (only their ids) when
 * they make it too long. NULL when it still does not fit. */
static char *dump_within(json_t *j, size_t cap)
{
    char *t = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(17));
    if (t && strlen(t) < cap) return t;
    free(t);
    json_t *sk = json_object_get(j, "skipped");
    for (size_t k = 0; k < json_array_size(sk); k++) json_object_del(json_array_get(sk, k), "why");
    t = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(17));
    if (t && strlen(t) < cap) return t;
    free(t);
    return NULL;
}

/* The success sentence: the fitted values, what was skipped, what the next trial does. */
static void say_fitted(trial_specimen_refit *r, const char *name, const pooled *p, const rod_fit_result *fr)
{
    char ids[160], *m = r->message;
    size_t n = sizeof r->message, u = 0;
    ids_text(p->used, p->nused, ids, sizeof ids);
#define PUT(...) (u += u < n ? (size_t)snprintf(m + u, n - u, __VA_ARGS__) : 0)
    PUT("calibration of specimen %s from trial%s %s (%d frames, N = %d, %.2f s): ", name, p->nused == 1 ? "" : "s", ids,
        p->pool.nobs, p->pool.scene.nodes, r->wall_s);
    int first = 1;
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        if (!fr->fitted[k]) continue;
        PUT("%s%s = %.6g", first ? "" : ", ", rod_fit_key_name(k), natural(k, fr->u[k]));
        if (!fr->determined[k]) PUT(" (not determined by these data: kept at the measured value)");
        else if (rod_fit_key_log(k)) PUT(" +- %.3g%%", 100.0 * fr->se[k]);
        else PUT(" +- %.3g", fr->se[k]);
        first = 0;
    }
    if (isfinite(r->hinge_guess))
        PUT(" (the strip's rigid creases fitted as hinges from sim.fit_hinge = %g N m/rad)", r->hinge_guess);
    PUT("; residual %.3g noise units RMS (%.3g at the measured strip)", fr->rms, fr->rms_start);
    if (p->nskipped) {
        ids_text(p->skipped, p->nskipped, ids, sizeof ids);
        PUT("; skipped trial%s %s (first: %.200s)", p->nskipped == 1 ? "" : "s", ids, p->skipped_why[0]);
    }
    PUT("; the specimen's next trial predicts with it");
#undef PUT
}

/* The failure sentence and record, the calibration before it kept. */
static void store_failure(store *st, int64_t specimen_id, const char *name, int64_t after_trial, const char *at,
                          const pooled *p, trial_specimen_refit *r)
{
    store_specimen sp;
    char w[300], kept[300] = "it has no calibration yet: its next trial predicts with the measured strip";
    if (store_specimen_get(st, specimen_id, &sp, w, sizeof w) == STORE_OK && sp.calibration_json[0]) {
        json_t *old = json_loads(sp.calibration_json, 0, NULL);
        char ids[160] = "?";
        json_t *tr = json_object_get(old, "trials");
        int64_t v[TRIAL_SPECIMEN_CALIB_MAX_TRIALS];
        int nv = 0;
        for (size_t k = 0; k < json_array_size(tr) && nv < TRIAL_SPECIMEN_CALIB_MAX_TRIALS; k++)
            v[nv++] = json_integer_value(json_array_get(tr, k));
        if (nv) ids_text(v, nv, ids, sizeof ids);
        snprintf(kept, sizeof kept, "its calibration from trial%s %s (%s) stands", nv == 1 ? "" : "s", ids,
                 json_string_value(json_object_get(old, "at")) ? json_string_value(json_object_get(old, "at")) : "?");
        json_decref(old);
    }
    json_t *f = json_pack("{s:s, s:s, s:I, s:s, s:o}", "reason_key", r->reason_key, "reason", r->reason,
                          "after_trial", (json_int_t)after_trial, "at", at, "trials", ids_json(p->used, p->nused));
    char *t = f ? json_dumps(f, JSON_COMPACT) : NULL;
    json_decref(f);
    const char *stored = "";
    if (!t || store_specimen_set_calibration(st, specimen_id, NULL, t, w, sizeof w) != STORE_OK) stored = " (not stored)";
    free(t);
    snprintf(r->message, sizeof r->message, "calibration of specimen %s not refitted: %s: %s%s; %s", name, r->reason_key,
             r->reason, stored, kept);
}

void trial_specimen_calib_refit(store *st, int64_t specimen_id, const char *name, int64_t after_trial,
                                const char *keys, double fit_hinge, const atomic_int *cancel,
                                trial_specimen_refit *out)
{
    double t0 = wall_now();
    memset(out, 0, sizeof *out);
    out->hinge_guess = NAN;
    char at[32] = "";
    store_wall_format(store_wall_now(), at, sizeof at);
    pooled *p = calloc(1, sizeof *p);
    if (!p) {
        failed(out, "fit_failed", "out of memory");
        snprintf(out->message, sizeof out->message, "calibration of specimen %s not refitted: out of memory", name);
        return;
    }
    int64_t cand[TRIAL_SPECIMEN_CALIB_MAX_EXAMINED];
    int ncand = 0;
    char why[512];
    rod_fit_result *fr = malloc(sizeof *fr);
    if (!fr) {
        failed(out, "fit_failed", "out of memory");
        goto fail;
    }
    if (finished_trials(st, specimen_id, cand, TRIAL_SPECIMEN_CALIB_MAX_EXAMINED, &ncand, why, sizeof why)) {
        failed(out, "no_trials", "its trials could not be listed: %s", why);
        goto fail;
    }
    pool_trials(st, cand, ncand, p);
    if (p->nused * TRIAL_SPECIMEN_CALIB_MAX_FRAMES > TRIAL_SPECIMEN_CALIB_MAX_FRAMES_TOTAL) {
        /* The same trials, fewer frames each (thinned evenly, as before). */
        trial_pool_select sel = trial_pool_select_default();
        sel.max_samples = TRIAL_SPECIMEN_CALIB_MAX_FRAMES_TOTAL / p->nused;
        trial_pool fewer;
        if (trial_pool_load(st, p->used, p->nused, &sel, &fewer, why, sizeof why)) {
            failed(out, "no_trials", "its trials could not be read again: %s", why);
            goto fail;
        }
        trial_pool_free(&p->pool);
        p->pool = fewer;
    }
    out->ntrials = p->nused;
    out->nobs = p->pool.nobs;
    if (!p->nused) {
        if (p->nskipped)
            failed(out, "no_trials", "none of its %d finished trial%s can be calibrated (trial %lld: %.300s)", ncand,
                   ncand == 1 ? "" : "s", (long long)p->skipped[0], p->skipped_why[0]);
        else
            failed(out, "no_trials", "it has no finished trial");
        goto fail;
    }
    /* The in-trial fit's setup (sim.fit_hinge on rigid creases, sim.fit_keys, the priors): the
     * record's hinge start is then the guess. */
    rod_fit_opts o;
    int rigid = rod_scene_hinge_rigid(&p->pool.scene);
    if (trial_calibrate_setup(&p->pool.scene, fit_hinge, keys, &o, out->reason_key, out->reason, sizeof out->reason) < 0)
        goto fail;
    out->hinge_guess = rigid && !rod_scene_hinge_rigid(&p->pool.scene) ? fit_hinge : NAN;
    o.cancel = cancel;
    rod_status fs = rod_fit_run(&p->pool.scene, p->pool.obs, p->pool.nobs, &o, fr, why, sizeof why);
    if (fs != ROD_OK) {
        if (cancel && atomic_load(cancel)) failed(out, "cancelled", "cancelled: ribbond stopped the refit (an abort or shutdown)");
        else failed(out, "fit_failed", "the fit failed: %s", why);
        goto fail;
    }
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (fr->fitted[k] && fr->at_bound[k]) {
            double b = fr->at_bound[k] > 0 ? fr->hi[k] : fr->lo[k];
            failed(out, "at_bound", "%s ran to its %s bound %g (the frames ask for a value outside it)",
                   rod_fit_key_name(k), fr->at_bound[k] > 0 ? "upper" : "lower", natural(k, b));
            goto fail;
        }
    if (fr->misfit) {
        failed(out, "misfit", "no parameter set fits these frames (residual %.3g noise units RMS, above %g; %.3g at the "
               "measured strip)", fr->rms, o.misfit, fr->rms_start);
        goto fail;
    }
    out->wall_s = wall_now() - t0;
    json_t *j = calibration_json(p, fr, after_trial, at, out->wall_s, out->hinge_guess);
    char *text = j ? dump_within(j, STORE_SPECIMEN_CALIBRATION_MAX) : NULL;
    json_decref(j);
    char w[300] = "out of memory, or the record too long";
    if (!text || store_specimen_set_calibration(st, specimen_id, text, NULL, w, sizeof w) != STORE_OK) {
        failed(out, "not_stored", "the calibration could not be stored: %s", w);
        free(text);
        goto fail;
    }
    free(text);
    out->ok = 1;
    say_fitted(out, name, p, fr);
    free(fr);
    trial_pool_free(&p->pool);
    free(p);
    return;
fail:
    out->wall_s = wall_now() - t0;
    store_failure(st, specimen_id, name, after_trial, at, p, out);
    free(fr);
    trial_pool_free(&p->pool);
    free(p);
}

/* ---- its use in a prediction -------------------------------------------------------------------- */

static const char *source_of(const store_creases *c, int k)
{
    const char *s = k == ROD_FIT_ANGLE_LEFT ? store_source_name(c->angle_from[0])
                    : k == ROD_FIT_ANGLE_RIGHT ? store_source_name(c->angle_from[1])
                    : k == ROD_FIT_POSITION_LEFT ? store_source_name(c->position_from[0])
                    : k == ROD_FIT_POSITION_RIGHT ? store_source_name(c->position_from[1])
                                                  : NULL;
    return s ? s : "scene";
}

/* The scene fields parameter k writes (rod_fit_scene_apply), copied from src. */
static void copy_key(rod_scene *dst, const rod_scene *src, int k)
{
    switch (k) {
    case ROD_FIT_ANGLE_LEFT: dst->fold_angle_left_deg = src->fold_angle_left_deg; break;
    case ROD_FIT_ANGLE_RIGHT: dst->fold_angle_right_deg = src->fold_angle_right_deg; break;
    case ROD_FIT_POSITION_LEFT: dst->fold_position_left = src->fold_position_left; break;
    case ROD_FIT_POSITION_RIGHT: dst->fold_position_right = src->fold_position_right; break;
    case ROD_FIT_HINGE:
    case ROD_FIT_HINGE_LEFT:
    case ROD_FIT_HINGE_RIGHT:
        dst->fold_hinge_stiffness = src->fold_hinge_stiffness;
        dst->fold_hinge_stiffness_left = src->fold_hinge_stiffness_left;
        dst->fold_hinge_stiffness_right = src->fold_hinge_stiffness_right;
        break;
    case ROD_FIT_YOUNGS:
        dst->youngs_modulus = src->youngs_modulus;
        dst->shear_modulus = src->shear_modulus;
        break;
    default: break;
    }
}

int trial_specimen_calib_apply(const char *calibration_json, const rod_scene *measured, const store_creases *creases,
                               rod_scene *sc, trial_specimen_calib_use *use)
{
    memset(use, 0, sizeof *use);
    if (!calibration_json || !*calibration_json) return 0;
    json_error_t err;
    json_t *j = json_loads(calibration_json, 0, &err);
    if (!json_is_object(j)) {
        use->warning = 1;
        snprintf(use->message, sizeof use->message,
                 "calibration of the specimen not applied: its record cannot be read (%s); the measured strip predicts",
                 j ? "not an object" : err.text);
        json_decref(j);
        return 0;
    }
    char ids[160] = "";
    json_t *tr = json_object_get(j, "trials");
    for (size_t k = 0, iu = 0; k < json_array_size(tr) && iu < sizeof ids; k++)
        iu += (size_t)snprintf(ids + iu, sizeof ids - iu, "%s%lld", k ? ", " : "",
                              (long long)json_integer_value(json_array_get(tr, k)));
    const char *at = json_string_value(json_object_get(j, "at"));
    double u[ROD_FIT_NKEYS], val[ROD_FIT_NKEYS], hinge_start = NAN;
    int apply[ROD_FIT_NKEYS] = {0};
    json_t *applied = json_array(), *held = json_array(), *ps = json_object_get(j, "parameters");
    char what[700] = "", helds[300] = "";
    size_t wu = 0, hu = 0;
    for (size_t i = 0; i < json_array_size(ps); i++) {
        json_t *p = json_array_get(ps, i);
        const char *name = json_string_value(json_object_get(p, "key"));
        int k = name ? rod_fit_key_parse(name) : -1;
        if (k < 0) continue; /* a key this program does not know: not applied */
        const char *why = !rod_fit_key_strip(k)                                  ? "the camera's view, not the strip"
                          : !json_is_true(json_object_get(p, "determined"))      ? "not determined by these data"
                          : !json_is_number(json_object_get(p, "value"))         ? "no value"
                                                                                 : NULL;
        if (why) {
            json_array_append_new(held, json_pack("{s:s, s:s}", "key", name, "why", why));
            if (hu < sizeof helds) hu += (size_t)snprintf(helds + hu, sizeof helds - hu, "%s%s (%s)", hu ? ", " : "", name, why);
            continue;
        }
        double v = json_number_value(json_object_get(p, "value"));
        double start = json_number_value(json_object_get(p, "start")), now = scene_value(measured, k);
        /* A hinge fitted on rigid creases started from sim.fit_hinge's guess, not from the strip: it
         * replaces the rigid creases (a strip re-measured with compliant ones is compared below). */
        int hinge = k == ROD_FIT_HINGE || k == ROD_FIT_HINGE_LEFT || k == ROD_FIT_HINGE_RIGHT;
        int on_rigid = hinge && rod_scene_hinge_rigid(measured);
        if (on_rigid && !(start > 0.0 && isfinite(start))) {
            json_array_append_new(held, json_pack("{s:s, s:s}", "key", name, "why", "no hinge start"));
            if (hu < sizeof helds) hu += (size_t)snprintf(helds + hu, sizeof helds - hu, "%s%s (no hinge start)", hu ? ", " : "", name);
            continue;
        }
        if (!on_rigid && !(fabs(start - now) <= 1e-9 * fmax(1.0, fabs(now)))) {
            use->warning = 1;
            snprintf(use->message, sizeof use->message,
                     "calibration of the specimen (trials %s, %s) not applied: it was fitted from %s = %.6g and the "
                     "trial's strip has %.6g (the specimen was re-measured since; its next refit starts from the new "
                     "value): the measured strip predicts",
                     ids, at ? at : "?", name, start, now);
            json_decref(applied);
            json_decref(held);
            json_decref(j);
            return 0;
        }
        apply[k] = 1;
        val[k] = v;
        if (on_rigid) {
            hinge_start = start;
            json_array_append_new(applied, json_pack("{s:s, s:f, s:n, s:s}", "key", name, "value", v, "replaced",
                                                     "replaced_from", "rigid creases"));
            if (wu < sizeof what)
                wu += (size_t)snprintf(what + wu, sizeof what - wu, "%s%s %.6g (rigid creases)", wu ? ", " : "", name, v);
        } else {
            json_array_append_new(applied, json_pack("{s:s, s:f, s:f, s:s}", "key", name, "value", v, "replaced", now,
                                                     "replaced_from", source_of(creases, k)));
            if (wu < sizeof what)
                wu += (size_t)snprintf(what + wu, sizeof what - wu, "%s%s %.6g (%s %.6g)", wu ? ", " : "", name, v,
                                       source_of(creases, k), now);
        }
        use->applied++;
    }
    if (!use->applied) {
        snprintf(use->message, sizeof use->message,
                 "calibration of the specimen (trials %s, %s) determines none of the strip's values%s%s: the measured "
                 "strip predicts", ids, at ? at : "?", hu ? ": " : "", helds);
        json_decref(applied);
        json_decref(held);
        json_decref(j);
        return 0;
    }
    /* The record first: a prediction never runs a calibration its record cannot say. */
    json_t *rec = json_pack("{s:s?, s:O?, s:O?, s:o, s:o}", "calibrated_at", at, "after_trial",
                            json_object_get(j, "after_trial"), "trials", tr, "applied", applied, "held", held);
    char *t = rec ? json_dumps(rec, JSON_COMPACT | JSON_REAL_PRECISION(17)) : NULL;
    json_decref(rec);
    if (!t || strlen(t) >= sizeof use->record) {
        use->applied = 0;
        use->warning = 1;
        snprintf(use->message, sizeof use->message,
                 "calibration of the specimen (trials %.160s) not applied: its record for the prediction %s; the "
                 "measured strip predicts", ids, t ? "is too long" : "could not be made (out of memory)");
        free(t);
        json_decref(j);
        return 0;
    }
    snprintf(use->record, sizeof use->record, "%s", t);
    free(t);
    rod_scene fitted = *sc;
    if (isfinite(hinge_start) && rod_scene_hinge_rigid(&fitted)) {
        /* The fit's strip: the creases hinges of the guess it started from (per-crease keys are
           relative to it, rod_fit_param.h). */
        fitted.fold_hinge_stiffness = hinge_start;
        fitted.fold_hinge_stiffness_left = fitted.fold_hinge_stiffness_right = NAN;
    }
    rod_fit_scene_values(&fitted, u);
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (apply[k]) u[k] = rod_fit_key_log(k) ? log(val[k]) : val[k];
    rod_fit_scene_apply(&fitted, u);
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (apply[k]) copy_key(sc, &fitted, k);
    snprintf(use->message, sizeof use->message,
             "prediction's strip: the specimen's calibration (trials %.160s, %.40s): %.480s%s%.200s", ids,
             at ? at : "?", what, hu ? "; kept as measured: " : "", helds);
    json_decref(j); /* owns at */
    return use->applied;
}
