/* trial_calibrate.c: the fit beside a trial (see trial_calibrate.h).
 *
 * Ownership: the runner's thread owns the trial_calibrate and its frame buffers; each worker owns
 * a job holding its own copy of the scene, the keys and the observations, and writes only into the
 * job. The job's state (running, done, abandoned) is the one word both threads touch: whoever
 * moves it second frees the job (the owner after a done worker is joined; the worker itself when
 * the owner abandoned it at a cap). */
#include "trial_calibrate.h"

#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "rod_fit_carry.h"
#include "thread_class.h"

enum { JOB_RUNNING = 0, JOB_DONE, JOB_ABANDONED };

typedef struct calib_job {
    atomic_int state;
    atomic_int cancel;
    int idle;
    pthread_t thread;
    rod_scene scene;
    char keys[256];
    rod_fit_obs *obs;
    int nobs_before, nobs_shear;
    rod_fit_shape shapes[TRIAL_CALIBRATE_SHAPES];
    int nshapes;
    int positions;            /* a refresh after fit 0 took the centrelines: the positions fitted
                                 with fit 0's values and standard errors as their prior
                                 (rod_fit_carry.h; NaN: the scene's, TRIAL_CALIBRATE_PRIOR_POSITION) */
    double u0[ROD_FIT_NKEYS], se0[ROD_FIT_NKEYS]; /* fit 0's values and standard errors */
    trial_calibrated res;
} calib_job;

/* A measured frame's centreline, resampled, with the frame's observation and its place among the
 * centrelines handed in (seq: 0, 1, ...). */
typedef struct shape_frame {
    rod_fit_obs o;
    rod_fit_shape s;
    long seq;
} shape_frame;

/* The first fit's choice (choose_shapes) as the frames come: TRIAL_CALIBRATE_SHAPES - 1 targets in
 * Delta L, from the first centreline handed in (lo) to the hold's (the scene's protocol.compression),
 * each with the TRIAL_CALIBRATE_SHAPES frames nearest it so far (ties: the earlier), and the last frame
 * (the hold's last). The choice takes the last, then for each target the nearest frame not taken:
 * at most TRIAL_CALIBRATE_SHAPES - 1 are taken before a target's turn, so its nearest untaken frame
 * is among its TRIAL_CALIBRATE_SHAPES nearest, and the choice from these slots is the choice from
 * every frame. A frame that enters no slot is never needed: the runner maps only the ones that do. */
#define SHAPE_TARGETS (TRIAL_CALIBRATE_SHAPES - 1)
typedef struct shape_slots {
    shape_frame near[SHAPE_TARGETS][TRIAL_CALIBRATE_SHAPES]; /* by distance to the target, then seq */
    int nnear[SHAPE_TARGETS];
    shape_frame last;
    int have_last;
    long handed;              /* centrelines handed in and kept (the next seq) */
    double lo;                /* Delta L of the first one (NaN: none yet) */
} shape_slots;

typedef struct obs_buf {
    rod_fit_obs *v;
    int n, cap;
} obs_buf;

struct trial_calibrate {
    trial_calibrate_def def;
    obs_buf before, shear;
    shape_slots shapes;       /* the centrelines the first fit may take (def.fit_shape): a fixed set */
    rod_fit_shape chosen[TRIAL_CALIBRATE_SHAPES]; /* the ones the first fit took, kept by refreshes */
    rod_fit_obs chosen_obs[TRIAL_CALIBRATE_SHAPES];
    int nchosen;
    double fit0_u[ROD_FIT_NKEYS]; /* fit 0's values when it took the centrelines and fitted both
                                     positions (NaN: none) */
    double fit0_se[ROD_FIT_NKEYS];  /* and their standard errors */
    long dropped;             /* frames not kept (out of memory) */
    calib_job *job;           /* the running worker, or NULL */
    int started;              /* the first fit was started */
    int refreshes;            /* refreshes started */
    int shear_used;           /* shear frames below its limit when the last fit started */
    double t_last_start;
    double t_shear;           /* NaN before the shear */
    double t_snap;            /* NaN before the snap */
    double dw_snap;           /* the snap's onset Delta W (NaN: unknown) */
    int ended;
    trial_calibrated kept, last;
    int have_kept, have_last;
};

trial_calibrate_def trial_calibrate_def_default(void)
{
    trial_calibrate_def d;
    memset(&d, 0, sizeof d);
    d.scene = rod_scene_default();
    d.refresh_s = 0.5;
    d.cap_s = 20.0;
    return d;
}

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void failed(trial_calibrated *r, const char *key, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static void failed(trial_calibrated *r, const char *key, const char *fmt, ...)
{
    r->ok = 0;
    snprintf(r->reason_key, sizeof r->reason_key, "%s", key);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->reason, sizeof r->reason, fmt, ap);
    va_end(ap);
}

/* The keys into o->fit: "" = both crease angles (and the hinge when compliant). 0, or -1 with
 * reason_key and reason (unknown_key, key_not_usable). */
static int parse_keys(const rod_scene *sc, const char *keys, rod_fit_opts *o, char *reason_key, char *reason,
                      size_t reason_len)
{
    for (int k = 0; k < ROD_FIT_NKEYS; k++) o->fit[k] = 0;
    if (!keys || !*keys) {
        o->fit[ROD_FIT_ANGLE_LEFT] = o->fit[ROD_FIT_ANGLE_RIGHT] = 1;
        o->fit[ROD_FIT_HINGE] = !rod_scene_hinge_rigid(sc);
        return 0;
    }
    char buf[256];
    snprintf(buf, sizeof buf, "%s", keys);
    char *save = NULL;
    for (char *t = strtok_r(buf, ", ", &save); t; t = strtok_r(NULL, ", ", &save)) {
        int k = rod_fit_key_parse(t);
        if (k < 0) {
            snprintf(reason_key, 24, "unknown_key");
            snprintf(reason, reason_len,
                     "unknown fit key: %.64s is not a fit parameter (folds.angle_left_deg, folds.angle_right_deg, "
                     "folds.position_left, folds.position_right, folds.hinge_stiffness, ribbon.youngs_modulus)", t);
            return -1;
        }
        char why[200];
        if (rod_fit_key_usable(sc, (rod_fit_key)k, why, sizeof why)) {
            snprintf(reason_key, 24, "key_not_usable");
            snprintf(reason, reason_len, "fit key %s cannot be fitted on this strip: %s", rod_fit_key_name(k), why);
            return -1;
        }
        o->fit[k] = 1;
    }
    return 0;
}

int trial_calibrate_setup(rod_scene *sc, double fit_hinge, const char *keys, rod_fit_opts *o, char reason_key[24],
                          char *reason, size_t reason_len)
{
    int hinged = 0;
    if (fit_hinge > 0.0 && isfinite(fit_hinge) && rod_scene_has_creases(sc) && rod_scene_hinge_rigid(sc)) {
        sc->fold_hinge_stiffness = fit_hinge;
        sc->fold_hinge_stiffness_left = sc->fold_hinge_stiffness_right = NAN;
        hinged = 1;
    }
    *o = rod_fit_opts_default();
    if (parse_keys(sc, keys, o, reason_key, reason, reason_len)) return -1;
    /* The strip's values are the start and the centre of a weak prior on each parameter. */
    o->prior_sigma[ROD_FIT_ANGLE_LEFT] = o->prior_sigma[ROD_FIT_ANGLE_RIGHT] = TRIAL_CALIBRATE_PRIOR_ANGLE_DEG;
    o->prior_sigma[ROD_FIT_HINGE] = o->prior_sigma[ROD_FIT_HINGE_LEFT] = o->prior_sigma[ROD_FIT_HINGE_RIGHT] =
        TRIAL_CALIBRATE_PRIOR_HINGE_LN;
    o->prior_sigma[ROD_FIT_DZ_OFFSET] = TRIAL_CALIBRATE_PRIOR_DZ_OFFSET;
    o->sigma_b_a = TRIAL_CALIBRATE_BIAS_A; /* the tracker's bias within a phase, in the covariance */
    return hinged;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median Delta Z of the n first observations (n > 0). */
static double median_dz(const rod_fit_obs *obs, int n)
{
    double *v = malloc(sizeof *v * (size_t)n);
    if (!v) return obs[n / 2].dz;
    for (int k = 0; k < n; k++) v[k] = obs[k].dz;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    double m = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    free(v);
    return m;
}

void trial_calibrate_compute(const rod_scene *sc, const char *keys, const rod_fit_obs *obs, int nobs_before,
                             int nobs_shear, const atomic_int *cancel, trial_calibrated *r)
{
    trial_calibrate_compute_shapes(sc, keys, obs, nobs_before, nobs_shear, NULL, 0, cancel, r);
}

static void compute(const rod_scene *sc, const char *keys, const rod_fit_obs *obs, int nobs_before, int nobs_shear,
                    const rod_fit_shape *shapes, int nshapes, int positions, const double *u0,
                    const double *se0, const atomic_int *cancel, trial_calibrated *r);

void trial_calibrate_compute_shapes(const rod_scene *sc, const char *keys, const rod_fit_obs *obs, int nobs_before,
                                    int nobs_shear, const rod_fit_shape *shapes, int nshapes,
                                    const atomic_int *cancel, trial_calibrated *r)
{
    compute(sc, keys, obs, nobs_before, nobs_shear, shapes, nshapes, 0, NULL, NULL, cancel, r);
}

void trial_calibrate_compute_refresh(const rod_scene *sc, const char *keys, const rod_fit_obs *obs, int nobs_before,
                                     int nobs_shear, const double u0[ROD_FIT_NKEYS],
                                     const double se0[ROD_FIT_NKEYS], const atomic_int *cancel, trial_calibrated *r)
{
    compute(sc, keys, obs, nobs_before, nobs_shear, NULL, 0, 1, u0, se0, cancel, r);
}

/* The fit and its snap (the header's trial_calibrate_compute_*): positions = 1 fits both crease
 * positions (default keys, where the strip has them) with fit 0's values u0 and standard errors
 * se0 as their prior, evaluated at fit 0's strip (rod_fit_carry_positions), or with
 * TRIAL_CALIBRATE_PRIOR_POSITION around sc's when u0 is NULL or its positions not finite. */
static void compute(const rod_scene *sc_in, const char *keys, const rod_fit_obs *obs, int nobs_before,
                    int nobs_shear, const rod_fit_shape *shapes, int nshapes, int positions, const double *u0,
                    const double *se0, const atomic_int *cancel, trial_calibrated *r)
{
    rod_scene carried = *sc_in; /* a refresh that carries fit 0's positions: fit 0's strip */
    double centre[ROD_FIT_NKEYS];   /* its priors' centres (rod_fit_carry_positions) */
    const rod_scene *sc = &carried;
    double t0 = wall_now();
    r->ok = 0;
    r->fit_ran = 0;
    r->nobs_before = nobs_before;
    r->nobs_shear = nobs_shear;
    r->snap_dw = r->snap_sd = r->p_other = NAN;
    r->dw_cut = 0.0;
    int nobs = nobs_before + nobs_shear;
    for (int k = 0; k < nobs; k++) r->dw_cut = fmax(r->dw_cut, obs[k].dw);
    rod_fit_opts o;
    rod_scene fit_scene = *sc; /* the def's scene already carries sim.fit_hinge (the session's setup) */
    if (trial_calibrate_setup(&fit_scene, 0.0, keys, &o, r->reason_key, r->reason, sizeof r->reason) < 0) goto done;
    if (nobs_before < TRIAL_CALIBRATE_MIN_FRAMES) {
        failed(r, "too_few_frames",
               "too few frames: %d measured in the compression and hold (the fit needs at least %d)", nobs_before,
               TRIAL_CALIBRATE_MIN_FRAMES);
        goto done;
    }
    double dz = median_dz(obs, nobs_before);
    if (!(dz > 0.0)) {
        failed(r, "lower_state",
               "lower state: the camera saw Delta Z = %.4f (median of %d frames) in the hold; the fit follows the "
               "upper state",
               dz, nobs_before);
        goto done;
    }
    o.cancel = cancel; /* the fit stops at its next evaluation when the trial ends early */
    r->nshapes = shapes && nshapes > 0 ? nshapes : 0;
    /* With the centrelines the cost is less convex (the family's twin 11 stopped in a second
     * minimum from the scene's values): the fit starts where the fit without them ends (cheap: the
     * same frames, its own keys), or at the scene's values when that one fails. */
    double start[ROD_FIT_NKEYS];
    int have_start = 0;
    if (r->nshapes) {
        rod_fit_result r0;
        char why0[320];
        if (rod_fit_run(sc, obs, nobs, &o, &r0, why0, sizeof why0) == ROD_OK && !r0.misfit) {
            memcpy(start, r0.u, sizeof start);
            have_start = 1;
        }
        if (cancel && atomic_load(cancel)) {
            failed(r, "cancelled", "cancelled: the trial ended while the fit ran");
            goto done;
        }
    }
    if (have_start) o.start = start;
    if ((r->nshapes || positions) && (!keys || !*keys)) {
        /* The centreline sees where the creases are (docs/calibration.md "The centreline as an
         * observable"): the default set takes both positions too, where the strip has them. A
         * refresh without the centrelines keeps them, with the specimen's tolerance as a prior
         * around fit 0's values (the scene's here), which the shear's frames then refine. */
        char unused[200];
        for (int k = ROD_FIT_POSITION_LEFT; k <= ROD_FIT_POSITION_RIGHT; k += ROD_FIT_POSITION_RIGHT - ROD_FIT_POSITION_LEFT)
            if (!rod_fit_key_usable(sc, (rod_fit_key)k, unused, sizeof unused)) {
                o.fit[k] = 1;
                if (positions) o.prior_sigma[k] = TRIAL_CALIBRATE_PRIOR_POSITION;
            }
        /* A sequential update on the positions only: fit 0's values and standard errors (at least
         * ROD_FIT_CARRY_FLOOR, at most the tolerance) carry what the centrelines told fit 0 about
         * them; the angles and the hinge keep their priors on the scene's values and are left to
         * the shear's frames; the model starts at fit 0's strip (docs/calibration.md). */
        if (positions && u0 && se0)
            rod_fit_carry_positions(u0, se0, ROD_FIT_CARRY_FLOOR, TRIAL_CALIBRATE_PRIOR_POSITION, &carried, &o,
                                    centre);
    }
    if (r->nshapes) {
        o.shapes = shapes;
        o.nshapes = nshapes;
        o.sigma_shape = TRIAL_CALIBRATE_SIGMA_SHAPE;
        o.shape_common_mode = 1; /* each centreline's error a deformation of its own (rod_fit.h) */
    }
    char why[320] = "";
    rod_status st = rod_fit_run(sc, obs, nobs, &o, &r->fit, why, sizeof why);
    if (o.prior_centre) rod_fit_scene_values(sc_in, r->fit.u0); /* stored as the scene: the trial's, not fit 0's */
    if (st != ROD_OK) {
        if (cancel && atomic_load(cancel))
            failed(r, "cancelled", "cancelled: the trial ended while the fit ran");
        else if (!strncmp(why, "too few observations", 20))
            failed(r, "too_few_frames", "too few frames: %s", why);
        else
            failed(r, "fit_failed", "the fit failed: %s", why);
        goto done;
    }
    r->fit_ran = 1;
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (r->fit.fitted[k] && r->fit.at_bound[k]) {
            double b = r->fit.at_bound[k] > 0 ? r->fit.hi[k] : r->fit.lo[k];
            failed(r, "at_bound", "at bound: %s ran to its %s bound %g (the frames ask for a value outside it)",
                   rod_fit_key_name(k), r->fit.at_bound[k] > 0 ? "upper" : "lower",
                   rod_fit_key_log(k) ? exp(b) : b);
            goto done;
        }
    if (r->fit.misfit) {
        failed(r, "misfit",
               "misfit: no parameter set fits these frames (residual %.3g noise units RMS, above %g; at the scene's "
               "values %.3g)",
               r->fit.rms, o.misfit, r->fit.rms_start);
        goto done;
    }
    if (cancel && atomic_load(cancel)) {
        failed(r, "cancelled", "cancelled: the trial ended before the fitted strip's snap was predicted");
        goto done;
    }
    rod_fit_snap snap;
    st = rod_fit_snap_predict(sc, &r->fit, &snap, why, sizeof why);
    if (st != ROD_OK) {
        failed(r, "prediction_failed", "the fitted strip's prediction failed: %s", why);
        goto done;
    }
    r->ok = 1;
    r->snapped = snap.snapped;
    r->asymmetric = snap.asymmetric;
    if (snap.snapped && isfinite(snap.snap_dw)) r->snap_dw = snap.snap_dw;
    if (snap.snapped && snap.band_ok && isfinite(snap.snap_sd)) {
        r->snap_sd = snap.snap_sd;
        r->p_other = isfinite(snap.p_other) ? snap.p_other : NAN;
    }
    snprintf(r->note, sizeof r->note, "%s", snap.note);
    if (snap.snapped && !isfinite(r->snap_dw)) failed(r, "prediction_failed", "the fitted strip's snap is not finite");
done:
    r->wall_s = wall_now() - t0;
}

/* ---- the worker ----------------------------------------------------------------------------- */

static void job_free(calib_job *j)
{
    if (!j) return;
    free(j->obs);
    free(j);
}

static void *job_main(void *arg)
{
    calib_job *j = arg;
    /* Below the trial's own threads (rig mode's loop, capture and poller share the cores):
     * SCHED_IDLE, the fit and its band's predictions on CPU time no one else wants (thread_class.h). */
    if (j->idle) thread_class_idle_enter(NULL, 0); /* refused: nice 19 (thread_class.h) */
    j->res.idle = thread_class_is_idle(0) == 1;        /* the class read back, said in the landing event */
    compute(&j->scene, j->keys, j->obs, j->nobs_before, j->nobs_shear, j->shapes, j->nshapes, j->positions, j->u0,
            j->se0, &j->cancel,
            &j->res);
    int expected = JOB_RUNNING;
    if (!atomic_compare_exchange_strong(&j->state, &expected, JOB_DONE)) job_free(j); /* abandoned */
    return NULL;
}

static int obs_push(obs_buf *b, rod_fit_obs o)
{
    if (b->n == b->cap) {
        int cap = b->cap ? 2 * b->cap : 1024;
        rod_fit_obs *v = realloc(b->v, sizeof *v * (size_t)cap);
        if (!v) return -1;
        b->v = v;
        b->cap = cap;
    }
    b->v[b->n++] = o;
    return 0;
}

/* m of the n observations of src, evenly spaced, the first and the last included. */
static int thin_into(rod_fit_obs *dst, const obs_buf *src, int m)
{
    int n = src->n;
    if (n <= m) {
        memcpy(dst, src->v, sizeof *dst * (size_t)n);
        return n;
    }
    for (int k = 0; k < m; k++) dst[k] = src->v[m > 1 ? (int)((long)k * (n - 1) / (m - 1)) : n - 1];
    return m;
}

static void say(trial_calibrate *c, double t, const char *kind, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void say(trial_calibrate *c, double t, const char *kind, const char *fmt, ...)
{
    if (!c->def.event) return;
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    c->def.event(c->def.user, t, kind, msg);
}

static void fit_name(const trial_calibrated *r, char *buf, size_t n)
{
    if (r->refresh == 0 && r->nshapes)
        snprintf(buf, n, "fit 0 (compression and hold, %d frames, %d centrelines)", r->nobs_before, r->nshapes);
    else if (r->refresh == 0)
        snprintf(buf, n, "fit 0 (compression and hold, %d frames)", r->nobs_before);
    else if (isfinite(r->dw_limit))
        snprintf(buf, n, "refresh %d (%d + %d frames, shear to Delta W = %.4f, below %g of the %s snap %.4f)",
                 r->refresh, r->nobs_before, r->nobs_shear, r->dw_cut, TRIAL_CALIBRATE_SHEAR_CUT, r->limit_of,
                 r->limit_snap);
    else
        snprintf(buf, n, "refresh %d (%d + %d frames, shear to Delta W = %.4f, no snap predicted yet)", r->refresh,
                 r->nobs_before, r->nobs_shear, r->dw_cut);
}

/* The shear frames' limit for a refresh: TRIAL_CALIBRATE_SHEAR_CUT of the last calibrated snap
 * that landed, else of the scene's; NaN when neither is known (the whole shear). */
static double shear_limit(const trial_calibrate *c, double *snap, const char **of)
{
    *snap = NAN;
    *of = "";
    if (c->have_kept && c->kept.snapped && isfinite(c->kept.snap_dw) && c->kept.snap_dw > 0.0) {
        *snap = c->kept.snap_dw;
        *of = "calibrated";
    } else if (c->def.scene_snap) {
        double s = c->def.scene_snap(c->def.user);
        if (isfinite(s) && s > 0.0) {
            *snap = s;
            *of = "scene";
        }
    }
    return isfinite(*snap) ? TRIAL_CALIBRATE_SHEAR_CUT * *snap : NAN;
}

/* The shear frames at or below limit (NaN: all of them). */
static int shear_below(const trial_calibrate *c, double limit)
{
    if (!isfinite(limit)) return c->shear.n;
    int n = 0;
    for (int k = 0; k < c->shear.n; k++) n += c->shear.v[k].dw <= limit;
    return n;
}

/* A landed result: said in an event, then reported. */
static void land(trial_calibrate *c, trial_calibrated *r, double t)
{
    r->t_landed = t;
    if (r->refresh == 0 && r->ok && r->nshapes && r->fit.fitted[ROD_FIT_POSITION_LEFT] &&
        r->fit.fitted[ROD_FIT_POSITION_RIGHT]) {
        memcpy(c->fit0_u, r->fit.u, sizeof c->fit0_u);
        memcpy(c->fit0_se, r->fit.se, sizeof c->fit0_se);
    }
    r->t_shear = c->t_shear;
    if (r->ok && r->nobs_shear > 0 && isfinite(c->dw_snap) && r->dw_cut >= c->dw_snap)
        failed(r, "after_snap",
               "its frames reach Delta W = %.5f, past the snap's onset at %.5f (frames of the snapping strip): not kept",
               r->dw_cut, c->dw_snap);
    char name[200], when[96];
    fit_name(r, name, sizeof name);
    if (isfinite(c->t_shear))
        snprintf(when, sizeof when, "%.2f s after the shear started", t - c->t_shear);
    else
        snprintf(when, sizeof when, "before the shear started");
    if (!r->ok) {
        say(c, t, "warning", "calibration %s failed (landed at t = %.2f s, %s, %.2f s wall%s): %s [%s]", name, t,
            when, r->wall_s, r->idle ? " in SCHED_IDLE" : "", r->reason, r->reason_key);
    } else {
        char params[256] = "";
        size_t used = 0;
        for (int k = 0; k < ROD_FIT_NKEYS && used < sizeof params; k++) {
            if (!r->fit.fitted[k]) continue;
            double v = rod_fit_key_log(k) ? exp(r->fit.u[k]) : r->fit.u[k];
            char se[48];
            if (!isfinite(r->fit.se[k])) snprintf(se, sizeof se, "not determined");
            else if (rod_fit_key_log(k)) snprintf(se, sizeof se, "+- %.2g%%", 100.0 * r->fit.se[k]);
            else snprintf(se, sizeof se, "+- %.3g", r->fit.se[k]);
            used += (size_t)snprintf(params + used, sizeof params - used, "%s%s = %.5g %s", used ? ", " : "",
                                     rod_fit_key_name(k), v, se);
        }
        char snap[160];
        if (!r->snapped)
            snprintf(snap, sizeof snap, "no snap before protocol.shear_max");
        else if (isfinite(r->snap_sd))
            snprintf(snap, sizeof snap, "snap Delta W = %.5f +- %.5f (1 sigma), %s, P(%s) = %.3g", r->snap_dw,
                     r->snap_sd, r->asymmetric ? "asymmetric" : "symmetric", r->asymmetric ? "symmetric" : "asymmetric",
                     r->p_other);
        else
            snprintf(snap, sizeof snap, "snap Delta W = %.5f (no band: %.80s), %s", r->snap_dw, r->note,
                     r->asymmetric ? "asymmetric" : "symmetric");
        char shp[64] = "";
        if (r->nshapes) snprintf(shp, sizeof shp, " (the centrelines' %.3g)", r->fit.shape_rms);
        say(c, t, "info", "calibrated prediction %s landed at t = %.2f s, %s: %s; %s; residual %.3g noise units RMS%s "
            "(%.2f s wall%s)", name, t, when, snap, params, r->fit.rms, shp, r->wall_s, r->idle ? " in SCHED_IDLE" : "");
    }
    c->last = *r;
    c->have_last = 1;
    if (r->ok) {
        c->kept = *r;
        c->have_kept = 1;
    }
    if (c->def.landed) c->def.landed(c->def.user, r);
}

/* Joins a done job and lands it. */
static void collect(trial_calibrate *c, double t)
{
    calib_job *j = c->job;
    pthread_join(j->thread, NULL);
    c->job = NULL;
    land(c, &j->res, t);
    job_free(j);
}

/* Target j's Delta L (j = 0 .. SHAPE_TARGETS - 1): evenly from the first centreline's to the hold's. */
static double shape_target(const trial_calibrate *c, int j)
{
    double hi = c->def.scene.compression;
    return c->shapes.lo + (hi - c->shapes.lo) * j / (TRIAL_CALIBRATE_SHAPES - 1);
}

/* 1 when frame f (at distance d of target j) comes before slot e in target j's order. */
static int shape_before(const trial_calibrate *c, int j, const rod_fit_obs *o, long seq, const shape_frame *e)
{
    double t = shape_target(c, j), d = fabs(o->dl - t), de = fabs(e->o.dl - t);
    return d < de || (d == de && seq < e->seq);
}

/* The first fit's centrelines: TRIAL_CALIBRATE_SHAPES of those handed in, the last one (the hold's
 * last), then for each target from the highest down the nearest not taken yet (ties: the earlier),
 * chosen from the slots (shape_slots). */
static void choose_shapes(trial_calibrate *c)
{
    c->nchosen = 0;
    const shape_slots *sl = &c->shapes;
    if (!c->def.fit_shape || sl->handed == 0) return;
    /* The last: the one handed in as last, else the latest in the slots. */
    const shape_frame *last = sl->have_last ? &sl->last : NULL;
    for (int j = 0; j < SHAPE_TARGETS; j++)
        for (int q = 0; q < sl->nnear[j]; q++)
            if (!last || sl->near[j][q].seq > last->seq) last = &sl->near[j][q];
    if (!last) return;
    long used[TRIAL_CALIBRATE_SHAPES];
    used[0] = last->seq;
    c->chosen[0] = last->s;
    c->chosen_obs[0] = last->o;
    c->nchosen = 1;
    for (int j = SHAPE_TARGETS - 1; j >= 0; j--)
        for (int q = 0; q < sl->nnear[j]; q++) { /* nearest first */
            const shape_frame *f = &sl->near[j][q];
            int taken = 0;
            for (int u = 0; u < c->nchosen; u++) taken |= used[u] == f->seq;
            if (taken) continue;
            used[c->nchosen] = f->seq;
            c->chosen[c->nchosen] = f->s;
            c->chosen_obs[c->nchosen] = f->o;
            c->nchosen++;
            break;
        }
}

/* Starts a worker on the frames so far (refresh 0: those before the shear only). */
static void launch(trial_calibrate *c, double t, int refresh)
{
    calib_job *j = calloc(1, sizeof *j);
    rod_fit_obs *obs = malloc(sizeof *obs *
                              (TRIAL_CALIBRATE_MAX_HOLD_OBS + TRIAL_CALIBRATE_SHAPES + TRIAL_CALIBRATE_MAX_SHEAR_OBS));
    trial_calibrated fail;
    memset(&fail, 0, sizeof fail);
    fail.refresh = refresh;
    fail.t_started = t;
    fail.snap_dw = fail.snap_sd = fail.p_other = fail.dw_limit = fail.limit_snap = NAN;
    if (!j || !obs) {
        free(j);
        free(obs);
        failed(&fail, "thread", "out of memory starting the fit");
        land(c, &fail, t);
        return;
    }
    double limit = NAN, limit_snap = NAN;
    const char *limit_of = "";
    if (refresh) limit = shear_limit(c, &limit_snap, &limit_of);
    j->scene = c->def.scene;
    j->idle = c->def.idle;
    snprintf(j->keys, sizeof j->keys, "%s", c->def.keys);
    j->obs = obs;
    j->nobs_before = thin_into(obs, &c->before, TRIAL_CALIBRATE_MAX_HOLD_OBS);
    if (refresh == 0) choose_shapes(c);
    /* The refreshes leave the centrelines out (the tracker's error on them is not independent
     * noise: with them the band at 80% of the way held the snap in 85% of the family, without them
     * 90%; docs/calibration.md); the positions fit 0 found with them stay fitted, with fit 0's
     * values and standard errors as their prior (compute). */
    j->positions = refresh > 0 && c->nchosen > 0;
    memcpy(j->u0, c->fit0_u, sizeof j->u0);
    memcpy(j->se0, c->fit0_se, sizeof j->se0);
    for (int s = 0; s < c->nchosen && refresh == 0; s++) {
        /* Each shape's frame among the observations (the shape is modelled at its state). */
        int have = 0;
        for (int k = 0; k < j->nobs_before && !have; k++)
            have = obs[k].dl == c->chosen_obs[s].dl && obs[k].dw == c->chosen_obs[s].dw;
        if (!have) obs[j->nobs_before++] = c->chosen_obs[s];
        j->shapes[s] = c->chosen[s];
    }
    j->nshapes = refresh == 0 ? c->nchosen : 0;
    j->nobs_shear = 0;
    int below = shear_below(c, limit);
    if (refresh && below > 0) {
        /* The frames below the limit, in their order, thinned evenly (the first and the last kept). */
        obs_buf sel = {malloc(sizeof *sel.v * (size_t)below), 0, below};
        if (!sel.v) {
            job_free(j);
            failed(&fail, "thread", "out of memory choosing the shear frames");
            land(c, &fail, t);
            return;
        }
        for (int k = 0; k < c->shear.n; k++)
            if (!isfinite(limit) || c->shear.v[k].dw <= limit) sel.v[sel.n++] = c->shear.v[k];
        j->nobs_shear = thin_into(obs + j->nobs_before, &sel, TRIAL_CALIBRATE_MAX_SHEAR_OBS);
        free(sel.v);
    }
    j->res.refresh = refresh;
    j->res.t_started = t;
    j->res.dw_limit = limit;
    j->res.limit_snap = limit_snap;
    snprintf(j->res.limit_of, sizeof j->res.limit_of, "%s", limit_of);
    atomic_init(&j->state, JOB_RUNNING);
    atomic_init(&j->cancel, 0);
    c->shear_used = below;
    c->t_last_start = t;
    if (refresh == 0) {
        char keys[300];
        snprintf(keys, sizeof keys, "%s",
                 c->def.keys[0]                         ? c->def.keys
                 : rod_scene_hinge_rigid(&c->def.scene) ? "both crease angles (the default)"
                                                        : "both crease angles and the hinge stiffness (the default)");
        say(c, t, "info",
            "calibration: fitting %s to %d of the %d frames measured in the compression and hold, on a worker "
            "thread (the shear does not wait)",
            keys, j->nobs_before, c->before.n);
    }
    if (pthread_create(&j->thread, NULL, job_main, j) != 0) {
        job_free(j);
        failed(&fail, "thread", "the fit's thread could not start");
        land(c, &fail, t);
        return;
    }
    c->job = j;
}

/* ---- the runner's calls --------------------------------------------------------------------- */

trial_calibrate *trial_calibrate_new(const trial_calibrate_def *def, char *why, size_t why_len)
{
    trial_calibrate *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(why, why_len, "out of memory");
        return NULL;
    }
    c->def = *def;
    c->t_shear = c->t_snap = c->dw_snap = NAN;
    for (int k = 0; k < ROD_FIT_NKEYS; k++) c->fit0_u[k] = c->fit0_se[k] = NAN;
    c->t_last_start = -INFINITY;
    return c;
}

void trial_calibrate_add(trial_calibrate *c, int shear, double dl, double dw, double dz, double a)
{
    if (!c || c->ended || !isfinite(dl) || !isfinite(dw) || !isfinite(dz) || !isfinite(a)) return;
    if (shear && isfinite(c->t_snap)) return;
    if (obs_push(shear ? &c->shear : &c->before, (rod_fit_obs){dl, dw, dz, a})) c->dropped++;
}

int trial_calibrate_wants_shape(const trial_calibrate *c)
{
    return c && c->def.fit_shape && !c->started && !c->ended;
}

int trial_calibrate_shape_wanted(const trial_calibrate *c, double dl)
{
    if (!trial_calibrate_wants_shape(c) || !isfinite(dl)) return 0;
    if (c->shapes.handed == 0) return 1;
    rod_fit_obs o = {dl, 0.0, 0.0, 0.0};
    for (int j = 0; j < SHAPE_TARGETS; j++)
        if (c->shapes.nnear[j] < TRIAL_CALIBRATE_SHAPES ||
            shape_before(c, j, &o, c->shapes.handed, &c->shapes.near[j][TRIAL_CALIBRATE_SHAPES - 1]))
            return 1;
    return 0;
}

void trial_calibrate_add_shape(trial_calibrate *c, double dl, double dw, double dz, double a, const double *xz,
                               int n, int last)
{
    if (!trial_calibrate_wants_shape(c) || !xz || n < 2 || !isfinite(dl)) return;
    shape_slots *sl = &c->shapes;
    shape_frame f;
    f.o = (rod_fit_obs){dl, dw, dz, a};
    f.s = (rod_fit_shape){.dl = dl, .dw = dw, .k = TRIAL_CALIBRATE_SHAPE_POINTS};
    if (rod_shape_resample(xz, n, TRIAL_CALIBRATE_SHAPE_POINTS, f.s.xz) != 0) return;
    f.seq = sl->handed++;
    if (f.seq == 0) sl->lo = dl;
    for (int j = 0; j < SHAPE_TARGETS; j++) {
        int m = sl->nnear[j], q = m;
        while (q > 0 && shape_before(c, j, &f.o, f.seq, &sl->near[j][q - 1])) q--;
        if (q >= TRIAL_CALIBRATE_SHAPES) continue;
        if (m == TRIAL_CALIBRATE_SHAPES) m--; /* the farthest leaves */
        memmove(&sl->near[j][q + 1], &sl->near[j][q], sizeof f * (size_t)(m - q));
        sl->near[j][q] = f;
        sl->nnear[j] = m + 1;
    }
    if (last) {
        sl->last = f;
        sl->have_last = 1;
    }
}

int trial_calibrate_shapes_kept(const trial_calibrate *c)
{
    if (!c) return 0;
    int n = c->shapes.have_last;
    for (int j = 0; j < SHAPE_TARGETS; j++) n += c->shapes.nnear[j];
    return n;
}

int trial_calibrate_shapes_choose(trial_calibrate *c, rod_fit_obs *obs)
{
    if (!c) return 0;
    choose_shapes(c);
    for (int s = 0; s < c->nchosen && obs; s++) obs[s] = c->chosen_obs[s];
    return c->nchosen;
}

void trial_calibrate_start(trial_calibrate *c, double t)
{
    if (!c || c->started || c->ended) return;
    c->started = 1;
    launch(c, t, 0);
}

void trial_calibrate_shear_started(trial_calibrate *c, double t)
{
    if (!c) return;
    c->t_shear = t;
}

void trial_calibrate_tick(trial_calibrate *c, double t, int shearing)
{
    if (!c || c->ended) return;
    if (c->job && atomic_load(&c->job->state) == JOB_DONE) collect(c, t);
    if (c->job || !c->started || !shearing || isfinite(c->t_snap) || !(c->def.refresh_s > 0.0)) return;
    if (t - c->t_last_start < c->def.refresh_s) return;
    /* Frames below the limit it has not fitted yet (or fewer: the limit came down). */
    double snap;
    const char *of;
    int below = shear_below(c, shear_limit(c, &snap, &of));
    if (below == 0 || below == c->shear_used) return;
    launch(c, t, ++c->refreshes);
}

void trial_calibrate_snap(trial_calibrate *c, double t, double dw_onset)
{
    if (!c || isfinite(c->t_snap)) return;
    c->t_snap = t;
    c->dw_snap = dw_onset;
}

void trial_calibrate_end(trial_calibrate *c, double t, int aborted)
{
    if (!c || c->ended) return;
    c->ended = 1;
    if (c->job) {
        if (aborted) atomic_store(&c->job->cancel, 1);
        double cap = aborted ? TRIAL_CALIBRATE_ABORT_CAP_S : c->def.cap_s, t0 = wall_now();
        while (atomic_load(&c->job->state) != JOB_DONE && wall_now() - t0 < cap) {
            struct timespec ts = {0, 10 * 1000 * 1000};
            nanosleep(&ts, NULL);
        }
        int expected = JOB_RUNNING;
        if (atomic_compare_exchange_strong(&c->job->state, &expected, JOB_ABANDONED)) {
            /* Still running at the cap: it frees itself when its capped computation ends. */
            pthread_detach(c->job->thread);
            say(c, t, "warning",
                "calibration: the running fit (started at t = %.2f s) did not end within %.1f s after the trial "
                "ended: left to finish on its own, not stored",
                c->job->res.t_started, cap);
            c->job = NULL;
        } else {
            collect(c, t);
        }
    }
    if (c->have_kept) {
        char name[200];
        fit_name(&c->kept, name, sizeof name);
        say(c, t, "info", "calibrated prediction stored: %s, landed at t = %.2f s%s", name, c->kept.t_landed,
            c->kept.refresh == c->refreshes || !c->refreshes ? ", the last made from frames before the snap"
                                                              : " (later fits failed)");
    } else if (c->have_last) {
        say(c, t, "warning", "no calibrated prediction: %s [%s]; the scene's prediction stands", c->last.reason,
            c->last.reason_key);
    } else if (!c->started) {
        say(c, t, "info", "no calibrated prediction: the trial ended before the hold did");
    }
}

const trial_calibrated *trial_calibrate_kept(const trial_calibrate *c)
{
    return c && c->have_kept ? &c->kept : NULL;
}

const trial_calibrated *trial_calibrate_last(const trial_calibrate *c)
{
    return c && c->have_last ? &c->last : NULL;
}

void trial_calibrate_free(trial_calibrate *c)
{
    if (!c) return;
    if (!c->ended) trial_calibrate_end(c, NAN, 1);
    free(c->before.v);
    free(c->shear.v);
    free(c);
}

/* ---- the stored record ---------------------------------------------------------------------- */

typedef struct jbuf {
    char *p;
    size_t n, used;
    int over;
} jbuf;

static void jb(jbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void jb(jbuf *b, const char *fmt, ...)
{
    if (b->over) return;
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(b->p + b->used, b->n - b->used, fmt, ap);
    va_end(ap);
    if (k < 0 || (size_t)k >= b->n - b->used) b->over = 1;
    else b->used += (size_t)k;
}

static void jb_num(jbuf *b, const char *key, double v)
{
    if (isfinite(v)) jb(b, "\"%s\":%.10g,", key, v);
    else jb(b, "\"%s\":null,", key);
}

static void jb_str(jbuf *b, const char *key, const char *v)
{
    jb(b, "\"%s\":\"", key);
    for (const unsigned char *q = (const unsigned char *)v; *q && !b->over; q++) {
        if (*q == '"' || *q == '\\') jb(b, "\\%c", *q);
        else if (*q < 0x20) jb(b, "\\u%04x", *q);
        else jb(b, "%c", *q);
    }
    jb(b, "\",");
}

int trial_calibrated_json(const trial_calibrated *r, char *out, size_t out_len)
{
    jbuf b = {out, out_len, 0, 0};
    jb(&b, "{\"refresh\":%d,\"frames_before\":%d,\"frames_shear\":%d,\"centrelines\":%d,", r->refresh,
       r->nobs_before, r->nobs_shear, r->nshapes);
    jb_num(&b, "dw_cut", r->dw_cut);
    if (r->refresh > 0) {
        jb_num(&b, "dw_limit", r->dw_limit);
        if (r->limit_of[0]) jb_str(&b, "limit_of", r->limit_of);
    }
    jb_num(&b, "t_started_s", r->t_started);
    jb_num(&b, "t_landed_s", r->t_landed);
    jb_num(&b, "t_shear_s", r->t_shear);
    jb_num(&b, "wall_s", r->wall_s);
    jb(&b, "\"ok\":%s,", r->ok ? "true" : "false");
    if (!r->ok) jb_str(&b, "reason_key", r->reason_key);
    if (r->ok && r->note[0]) jb_str(&b, "band_note", r->note);
    if (r->fit_ran) {
        jb_num(&b, "rms", r->fit.rms);
        jb_num(&b, "rms_start", r->fit.rms_start);
        jb(&b, "\"iterations\":%d,\"parameters\":[", r->fit.iterations);
        int first = 1;
        for (int k = 0; k < ROD_FIT_NKEYS; k++) {
            if (!r->fit.fitted[k]) continue;
            int lg = rod_fit_key_log(k);
            jb(&b, "%s{\"key\":\"%s\",", first ? "" : ",", rod_fit_key_name(k));
            jb_num(&b, "scene", lg ? exp(r->fit.u0[k]) : r->fit.u0[k]);
            jb_num(&b, "fitted", lg ? exp(r->fit.u[k]) : r->fit.u[k]);
            jb_num(&b, "se", r->fit.se[k]); /* INFINITY (not determined) -> null */
            jb(&b, "\"se_kind\":\"%s\",\"determined\":%s,\"at_bound\":%d}", lg ? "relative" : "absolute",
               r->fit.determined[k] ? "true" : "false", r->fit.at_bound[k]);
            first = 0;
        }
        jb(&b, "],");
    }
    if (!b.over && b.used > 0 && out[b.used - 1] == ',') b.used--;
    jb(&b, "}");
    if (b.over) {
        snprintf(out, out_len, "{\"truncated\":true}");
        return -1;
    }
    return 0;
}
