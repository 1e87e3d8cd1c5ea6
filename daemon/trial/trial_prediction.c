/* trial_prediction.c: the prediction beside a trial (see trial_prediction.h). The curve keeps a
 * sample each 1/2000 of the shear range and every step where Delta Z moves fast; a failed
 * allocation thins the curve instead of failing the prediction. */
#include "trial_prediction.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rod_protocol.h"
#include "thread_class.h"
#include "trial_record.h"

struct trial_prediction {
    trial_prediction_def def;
    pthread_t thread;
    size_t n, cap;           /* the curve being recorded */
    double *t, *dw, *dz, *a;
    double last_dw, last_dz;
};

static int curve_grow(trial_prediction *j)
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

static int on_sample(void *user, const rod_sample *smp, const rod *r)
{
    (void)r;
    trial_prediction *j = user;
    if (j->def.cancel && atomic_load(j->def.cancel)) return 1; /* stops rod_predict */
    double step = j->def.scene.shear_max / 2000.0;
    if (j->n > 0 && smp->dw - j->last_dw < step && fabs(smp->dz - j->last_dz) < 2e-3) return 0;
    if (j->n == j->cap && curve_grow(j)) return 0; /* a thinner curve, not a failure */
    j->t[j->n] = smp->t;
    j->dw[j->n] = smp->dw;
    j->dz[j->n] = smp->dz;
    j->a[j->n] = smp->a;
    j->n++;
    j->last_dw = smp->dw;
    j->last_dz = smp->dz;
    return 0;
}

/* The warning event of a failed prediction, on the prediction's own connection. */
static void store_failure(store *st, int64_t trial_id, const char *msg)
{
    store_event ev;
    memset(&ev, 0, sizeof ev);
    ev.trial_id = trial_id;
    ev.t_s = NAN;
    ev.wall_s = store_wall_now();
    ev.kind = STORE_EVENT_WARNING;
    snprintf(ev.message, sizeof ev.message, "%s", msg);
    char why[256];
    store_event_append(st, &ev, why, sizeof why);
}

/* The row's fields every prediction has, done or failed: trial, hash, resolution, creases. */
static store_prediction row_of(const trial_prediction_def *def)
{
    const rod_scene *sc = &def->scene;
    store_prediction sp = store_prediction_default();
    sp.trial_id = def->trial_id;
    snprintf(sp.scene_hash, sizeof sp.scene_hash, "%s", def->hash);
    sp.nodes = sc->nodes;
    sp.dt = sc->dt;
    sp.adaptive = def->adaptive;
    sp.imperfection = sc->fold_angle_rel;
    sp.est_error = def->est_error;
    sp.creases = def->creases;
    sp.calibration_json = def->calibration_json[0] ? (char *)def->calibration_json : NULL;
    return sp;
}

int trial_prediction_store_failed(store *st, const trial_prediction_def *def, const char *reason, double wall_s,
                                  char *why, size_t why_len)
{
    char msg[512];
    snprintf(msg, sizeof msg, "prediction failed: %s", reason);
    store_failure(st, def->trial_id, msg);
    store_prediction sp = row_of(def);
    sp.status = STORE_PREDICTION_FAILED;
    snprintf(sp.failure, sizeof sp.failure, "%s", reason);
    sp.regime = STORE_REGIME_UNKNOWN;
    sp.wall_s = isfinite(wall_s) && wall_s >= 0.0 ? wall_s : 0.0;
    int64_t pid = 0;
    return store_prediction_insert(st, &sp, &pid, why, why_len) == STORE_OK ? 0 : -1;
}

/* The stored prediction: outcome, resolution and the solver's settings as JSON, the curve. */
static store_err store_result(trial_prediction *j, store *st, const rod_prediction *p, store_regime regime,
                              char *why, size_t why_len)
{
    const rod_scene *sc = &j->def.scene;
    store_prediction sp = row_of(&j->def);
    sp.snapped = p->snapped;
    sp.snap_dw = p->snapped ? p->snap_dw : NAN;
    sp.regime = regime;
    sp.peak_abs_a = p->peak_abs_a;
    sp.wall_s = p->wall_s;
    char solver[512];
    snprintf(solver, sizeof solver,
             "{\"nodes\":%d,\"dt\":%.17g,\"adaptive\":%s,\"adapt_scale\":%.17g,\"tolerance\":%.17g,"
             "\"max_iterations\":%d,"
             "\"damping\":%.17g,\"route\":%d,\"fold_angle_rel\":%.17g,\"snap_speed\":%.17g,"
             "\"asym_threshold\":%.17g,\"steps\":%ld,\"rejected\":%ld}",
             sc->nodes, sc->dt, j->def.adaptive ? "true" : "false", j->def.adapt_scale, sc->tolerance,
             sc->max_iterations, sc->damping,
             (int)sc->route, sc->fold_angle_rel, sc->snap_speed, sc->asym_threshold, p->steps, p->rejected);
    sp.solver_json = solver;
    sp.curve.n = j->n;
    sp.curve.t_s = j->t;
    sp.curve.dw = j->dw;
    sp.curve.dz = j->dz;
    sp.curve.a = j->a;
    int64_t pid = 0;
    return store_prediction_insert(st, &sp, &pid, why, why_len);
}

static void *prediction_main(void *arg)
{
    trial_prediction *j = arg;
    if (j->def.idle) thread_class_idle_enter(NULL, 0); /* refused: nice 19, the prediction merely slower */
    const rod_scene *sc = &j->def.scene;
    trial_prediction_report rep = {.outcome = TRIAL_PREDICTION_NOT_STORED, .snap_dw = NAN,
                                   .regime = STORE_REGIME_UNKNOWN};
    rod_predict_opts o = rod_predict_opts_default();
    o.adaptive = j->def.adaptive;
    o.adapt_scale = j->def.adapt_scale;
    o.on_sample = on_sample;
    o.user = j;
    rod_prediction p;
    char err[256] = "", why[256] = "";
    rod_status rs = rod_predict(sc, &o, &p, err, sizeof err);
    if (rs != ROD_OK && j->def.cancel && atomic_load(j->def.cancel))
        snprintf(err, sizeof err, "cancelled (the trial ended)");
    store *st = NULL;
    if (store_open(j->def.store_path, &st, why, sizeof why) != STORE_OK) {
        snprintf(rep.message, sizeof rep.message, "prediction not stored: %s", why);
    } else if (rs != ROD_OK) {
        rep.outcome = TRIAL_PREDICTION_FAILED;
        snprintf(rep.message, sizeof rep.message, "prediction failed: %s", err);
        if (trial_prediction_store_failed(st, &j->def, err, p.wall_s, why, sizeof why))
            snprintf(rep.message, sizeof rep.message, "prediction failed: %.200s (not stored: %.200s)", err, why);
    } else {
        store_regime regime = trial_regime_of(p.snapped, p.snapped, p.asymmetric);
        if (store_result(j, st, &p, regime, why, sizeof why) != STORE_OK) {
            snprintf(rep.message, sizeof rep.message, "prediction not stored: %s", why);
        } else {
            rep.outcome = TRIAL_PREDICTION_STORED;
            rep.snap_dw = p.snapped ? p.snap_dw : NAN;
            rep.regime = regime;
            rep.n = j->n;
            rep.dw = j->dw;
            rep.dz = j->dz;
            rep.a = j->a;
            snprintf(rep.message, sizeof rep.message,
                     "predicted: %s at Delta W = %.5f (N = %d, dt = %g s%s, %.2f s wall)", store_regime_name(regime),
                     p.snap_dw, sc->nodes, sc->dt, j->def.adaptive ? ", fast" : "", p.wall_s);
        }
    }
    store_close(st);
    if (j->def.done) j->def.done(j->def.user, &rep);
    return NULL;
}

int trial_prediction_start(const trial_prediction_def *def, trial_prediction **out, char *why, size_t why_len)
{
    *out = NULL;
    trial_prediction *j = calloc(1, sizeof *j);
    if (!j) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    j->def = *def;
    if (pthread_create(&j->thread, NULL, prediction_main, j) != 0) {
        free(j);
        snprintf(why, why_len, "the prediction's thread could not start");
        return -1;
    }
    *out = j;
    return 0;
}

void trial_prediction_join(trial_prediction *p)
{
    if (!p) return;
    pthread_join(p->thread, NULL);
    free(p->t);
    free(p->dw);
    free(p->dz);
    free(p->a);
    free(p);
}
