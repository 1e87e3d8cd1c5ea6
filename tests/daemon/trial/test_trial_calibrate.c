/* test_trial_calibrate: the fit beside a trial (issue 32 B, daemon/trial/trial_calibrate.h).
 *
 *   1. compute_recovers_strip: frames of the hold filmed from a strip the scene does not know
 *      (creases -87 and -84.5 deg against the scene's -90, with the tracker's noise) give fitted
 *      angles within 3 standard errors of the strip's, and a calibrated snap that is closer to
 *      the strip's own predicted snap than the scene's prediction is, inside 3 sigma of it.
 *   2. compute_bad_input: too few frames, the lower state, an unknown fit key, a key the scene
 *      cannot fit, frames no parameter set fits (misfit), frames that ask for an angle beyond the
 *      bounds (at_bound), a cancelled fit (stopped at its first evaluation): each a named failure
 *      with no number.
 *   3. session_mock_trial: a whole mock trial (config/mock.ini's rig: mock rails on a virtual
 *      clock, the [twin] strip filmed and tracked) with a short shear: the fit starts when the
 *      hold ends, lands (an event says when, before or after the shear started), refreshes during
 *      the shear, and the trial's row holds snap_dw_calibrated with its band and regime and the
 *      fit's parameters; an unknown fit key is stored as the trial's named fit failure while the
 *      trial runs to done with its scene prediction.
 *   4. session_abort_joins: a trial aborted while its fit runs ends with the worker cancelled and
 *      joined (the process's threads back to their count) well within the abort cap.
 *   5. refresh_frames_below_cut: a refresh during the shear fits the shear frames only up to
 *      TRIAL_CALIBRATE_SHEAR_CUT of the latest predicted snap (the calibrated one, else the
 *      scene's, else all of them).
 *   6. worker_class: the worker of a rig-mode def (idle = 1) runs its fit and band in SCHED_IDLE,
 *      read back on its thread, and says so when it lands; a mock-mode def's (idle = 0) does not;
 *      the runner's thread (this test's) stays in its own class either way.
 *   7. shapes_picked_as_they_come: sim.fit_shape's centrelines picked as the frames come, in a
 *      fixed set of slots, the same as the old rule over every frame, none of a long hold mapped.
 *   8. refresh_without_centrelines: a refresh after a fit 0 with centrelines leaves them out and
 *      fits the crease positions with fit 0's values and standard errors (at least
 *      ROD_FIT_CARRY_FLOOR) as their prior, at fit 0's strip: its positions' standard errors
 *      within that floor, not the specimen's tolerance; without fit 0's, that tolerance. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>

#include "rig_daemon.h"
#include "rod_fit_carry.h"
#include "rod_protocol.h"
#include "scene_file.h"
#include "store.h"
#include "trial.h"
#include "trial_calibrate.h"
#include "thread_class.h"
#include "trial_session.h"
#include "twin.h"

#include <jansson.h>

#define NHOLD 30

static rod_scene mock_scene(int nodes)
{
    rod_scene sc;
    cfg_error err;
    char n[32];
    snprintf(n, sizeof n, "mesh.nodes=%d", nodes);
    const char *ov[] = {n};
    if (cfg_scene_load(RIBBON_SOURCE_DIR "/config/scenes/mock-gamma013.ini", ov, 1, &sc, &err) != CFG_OK)
        fail_msg("scene: %s", err.message);
    return sc;
}

/* The hold's frames of the strip u (at Delta L = the scene's compression), with noise of the
 * tracker's order (a fixed +-1.2 sigma pattern, so the test is repeatable). */
static void hold_frames(const rod_scene *sc, const double u[ROD_FIT_NKEYS], rod_fit_obs *obs, int n)
{
    for (int k = 0; k < n; k++) obs[k] = (rod_fit_obs){sc->compression, 0.0, 0.0, 0.0};
    rod_fit_model *m = NULL;
    char why[256];
    assert_int_equal(rod_fit_model_alloc(sc, obs, n, 0, &m, why, sizeof why), ROD_OK);
    double *y = malloc(sizeof *y * 2 * (size_t)n);
    assert_non_null(y);
    assert_int_equal(rod_fit_model_eval(m, u, NULL, y, NULL, why, sizeof why), ROD_OK);
    for (int k = 0; k < n; k++) {
        double s = (k % 3 == 0 ? 1.2 : k % 3 == 1 ? -1.2 : 0.0);
        obs[k].dz = y[2 * k] + s * 0.002;
        obs[k].a = y[2 * k + 1] - s * 0.015;
    }
    free(y);
    rod_fit_model_free(m);
}

static double snap_of(const rod_scene *base, const double u[ROD_FIT_NKEYS])
{
    rod_scene s = *base;
    rod_fit_scene_apply(&s, u);
    rod_predict_opts o = rod_predict_opts_fast(&s);
    rod_prediction p;
    char why[256];
    assert_int_equal(rod_predict(&s, &o, &p, why, sizeof why), ROD_OK);
    assert_true(p.snapped);
    return p.snap_dw;
}

static void compute_recovers_strip(void **state)
{
    (void)state;
    rod_scene sc = mock_scene(31);
    double u0[ROD_FIT_NKEYS], u[ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, u0);
    memcpy(u, u0, sizeof u);
    u[ROD_FIT_ANGLE_LEFT] = -87.0;
    u[ROD_FIT_ANGLE_RIGHT] = -84.5;
    rod_fit_obs obs[NHOLD];
    hold_frames(&sc, u, obs, NHOLD);
    trial_calibrated r;
    memset(&r, 0, sizeof r);
    trial_calibrate_compute(&sc, "", obs, NHOLD, 0, NULL, &r);
    if (!r.ok) fail_msg("%s: %s", r.reason_key, r.reason);
    double truth = snap_of(&sc, u), scene = snap_of(&sc, u0);
    printf("fit: left %.3f +- %.3f (strip %.1f), right %.3f +- %.3f (strip %.1f), rms %.3g, %d iterations, %.2f s\n",
           r.fit.u[ROD_FIT_ANGLE_LEFT], r.fit.se[ROD_FIT_ANGLE_LEFT], u[ROD_FIT_ANGLE_LEFT],
           r.fit.u[ROD_FIT_ANGLE_RIGHT], r.fit.se[ROD_FIT_ANGLE_RIGHT], u[ROD_FIT_ANGLE_RIGHT], r.fit.rms,
           r.fit.iterations, r.wall_s);
    printf("snap: calibrated %.5f +- %.5f (%s, P(other) %.3g), strip %.5f, scene %.5f\n", r.snap_dw, r.snap_sd,
           r.asymmetric ? "asymmetric" : "symmetric", r.p_other, truth, scene);
    for (int k = ROD_FIT_ANGLE_LEFT; k <= ROD_FIT_ANGLE_RIGHT; k++) {
        assert_true(r.fit.fitted[k] && r.fit.determined[k]);
        assert_true(isfinite(r.fit.se[k]) && r.fit.se[k] > 0.0);
        assert_true(fabs(r.fit.u[k] - u[k]) <= 3.0 * r.fit.se[k]);
    }
    assert_true(r.snapped && isfinite(r.snap_dw) && isfinite(r.snap_sd) && r.snap_sd > 0.0);
    assert_true(fabs(r.snap_dw - truth) < fabs(scene - truth));
    assert_true(fabs(r.snap_dw - truth) <= 3.0 * r.snap_sd);
    assert_true(r.p_other >= 0.0 && r.p_other <= 1.0);
    char js[2048];
    assert_int_equal(trial_calibrated_json(&r, js, sizeof js), 0);
    assert_non_null(strstr(js, "\"key\":\"folds.angle_left_deg\""));
    assert_null(strstr(js, "nan"));
    assert_null(strstr(js, "inf"));
}

static void expect_failure(const rod_scene *sc, const char *keys, const rod_fit_obs *obs, int n, const char *key)
{
    trial_calibrated r;
    memset(&r, 0, sizeof r);
    trial_calibrate_compute(sc, keys, obs, n, 0, NULL, &r);
    printf("%-14s -> %s: %s\n", key, r.reason_key, r.reason);
    assert_false(r.ok);
    assert_string_equal(r.reason_key, key);
    assert_true(strlen(r.reason) > 10);
    assert_true(isnan(r.snap_dw) && isnan(r.snap_sd));
    char js[2048];
    assert_int_equal(trial_calibrated_json(&r, js, sizeof js), 0);
    assert_null(strstr(js, "nan"));
}


/* ---- the refresh's frames: below TRIAL_CALIBRATE_SHEAR_CUT of the latest predicted snap ------- */

#define NLANDED 8
static trial_calibrated landed_r[NLANDED];
static int n_landed;
static double scene_snap_value = NAN;

static void record_landed(void *user, const trial_calibrated *r)
{
    (void)user;
    if (n_landed < NLANDED) landed_r[n_landed] = *r;
    n_landed++;
}

static double scene_snap_of(void *user)
{
    (void)user;
    return scene_snap_value;
}

/* Ticks at trial time t until `want` results have landed (at most 120 s of wall time). */
static void tick_until(trial_calibrate *c, double t, int shearing, int want)
{
    for (int k = 0; k < 12000 && n_landed < want; k++) {
        trial_calibrate_tick(c, t, shearing);
        if (n_landed >= want) break;
        struct timespec ts = {0, 10 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
    assert_true(n_landed >= want);
}

/* A trial's calibration fed the hold's frames and then shear frames of the strip u up to
 * dw_to, the refresh ticked once at t = 1 s of the shear: its result. */
static trial_calibrated refresh_of(const rod_scene *sc, const char *keys, int with_scene_snap, const rod_fit_obs *hold,
                                   const rod_fit_obs *shear, int nshear)
{
    n_landed = 0;
    trial_calibrate_def d = trial_calibrate_def_default();
    d.scene = *sc;
    snprintf(d.keys, sizeof d.keys, "%s", keys);
    d.refresh_s = 0.5;
    d.landed = record_landed;
    d.scene_snap = with_scene_snap ? scene_snap_of : NULL;
    char why[256];
    trial_calibrate *c = trial_calibrate_new(&d, why, sizeof why);
    assert_non_null(c);
    for (int k = 0; k < NHOLD; k++) trial_calibrate_add(c, 0, hold[k].dl, hold[k].dw, hold[k].dz, hold[k].a);
    trial_calibrate_start(c, 0.0);
    tick_until(c, 0.5, 0, 1); /* fit 0 */
    trial_calibrate_shear_started(c, 1.0);
    for (int k = 0; k < nshear; k++) trial_calibrate_add(c, 1, shear[k].dl, shear[k].dw, shear[k].dz, shear[k].a);
    tick_until(c, 2.0, 1, 2); /* refresh 1 */
    trial_calibrate_end(c, 3.0, 0);
    trial_calibrate_free(c);
    assert_int_equal(landed_r[1].refresh, 1);
    return landed_r[1];
}

/* The shear frames of strip u at Delta W = dw_to (k + 1) / n, k < n, from the model. */
static void shear_frames(const rod_scene *sc, const double u[ROD_FIT_NKEYS], double dw_to, rod_fit_obs *obs, int n)
{
    for (int k = 0; k < n; k++) obs[k] = (rod_fit_obs){sc->compression, dw_to * (k + 1) / n, 0.0, 0.0};
    rod_fit_model *m = NULL;
    char why[256];
    assert_int_equal(rod_fit_model_alloc(sc, obs, n, 0, &m, why, sizeof why), ROD_OK);
    double *y = malloc(sizeof *y * 2 * (size_t)n);
    assert_non_null(y);
    if (rod_fit_model_eval(m, u, NULL, y, NULL, why, sizeof why) != ROD_OK) fail_msg("shear frames: %s", why);
    for (int k = 0; k < n; k++) {
        obs[k].dz = y[2 * k];
        obs[k].a = y[2 * k + 1];
    }
    free(y);
    rod_fit_model_free(m);
}

/* A refresh fits the shear frames up to TRIAL_CALIBRATE_SHEAR_CUT of the latest predicted snap:
 * the calibrated one that landed (fit 0's here), else the scene's, else (neither known) all of
 * them. Frames of the shear close to the snap pulled the rehearsal's calibrated snap late (+9.35%
 * from the shear to 0.94 of the way, docs/calibration.md); before this a refresh took every shear
 * frame. The fit itself is not scored here (the frames are the model's own): which frames it got. */
static void refresh_frames_below_cut(void **state)
{
    (void)state;
    rod_scene sc = mock_scene(31);
    double u[ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, u);
    u[ROD_FIT_ANGLE_LEFT] = -87.0;
    u[ROD_FIT_ANGLE_RIGHT] = -84.5;
    rod_fit_obs hold[NHOLD], shear[60];
    hold_frames(&sc, u, hold, NHOLD);
    const double truth = snap_of(&sc, u), to = 0.95 * truth;
    shear_frames(&sc, u, to, shear, 60);
    const double step = to / 60.0;

    /* Fit 0 lands with a calibrated snap: refresh 1 takes the frames below 0.8 of it. */
    trial_calibrated r = refresh_of(&sc, "", 0, hold, shear, 60);
    const trial_calibrated f0 = landed_r[0];
    if (!f0.ok) fail_msg("fit 0: %s: %s", f0.reason_key, f0.reason);
    if (!r.ok) fail_msg("refresh 1: %s: %s", r.reason_key, r.reason);
    printf("fit 0: snap %.5f (strip %.5f); refresh 1: %d shear frames to %.5f (limit %.5f of the %s snap %.5f), "
           "snap %.5f\n", f0.snap_dw, truth, r.nobs_shear, r.dw_cut, r.dw_limit, r.limit_of, r.limit_snap, r.snap_dw);
    assert_true(f0.snapped && isfinite(f0.snap_dw));
    assert_string_equal(r.limit_of, "calibrated");
    assert_true(r.limit_snap == f0.snap_dw);
    assert_true(fabs(r.dw_limit - TRIAL_CALIBRATE_SHEAR_CUT * f0.snap_dw) < 1e-12);
    assert_true(r.dw_cut <= r.dw_limit);
    assert_true(r.dw_cut > r.dw_limit - step); /* the last frame below the limit is in */
    assert_true(r.nobs_shear > 0 && r.nobs_shear <= TRIAL_CALIBRATE_MAX_SHEAR_OBS);
    char js[2048];
    assert_int_equal(trial_calibrated_json(&r, js, sizeof js), 0);
    assert_non_null(strstr(js, "\"limit_of\":\"calibrated\""));

    /* No calibrated snap (fit 0 failed: a key that is not a parameter, so both fail at once, with
     * the frames chosen): the scene's snap sets the limit, and without it the whole shear. */
    scene_snap_value = 0.3;
    r = refresh_of(&sc, "no.such_key", 1, hold, shear, 60);
    assert_string_equal(r.reason_key, "unknown_key");
    assert_string_equal(r.limit_of, "scene");
    assert_true(fabs(r.dw_limit - TRIAL_CALIBRATE_SHEAR_CUT * 0.3) < 1e-12);
    assert_true(r.dw_cut <= r.dw_limit && r.dw_cut > r.dw_limit - step);
    scene_snap_value = NAN; /* the scene's prediction not done yet */
    r = refresh_of(&sc, "no.such_key", 1, hold, shear, 60);
    assert_true(isnan(r.dw_limit) && !r.limit_of[0]);
    assert_true(r.dw_cut == shear[59].dw);
}

static void compute_bad_input(void **state)
{
    (void)state;
    rod_scene sc = mock_scene(31);
    double u0[ROD_FIT_NKEYS], u[ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, u0);
    rod_fit_obs obs[NHOLD];
    hold_frames(&sc, u0, obs, NHOLD);
    expect_failure(&sc, "", obs, TRIAL_CALIBRATE_MIN_FRAMES - 1, "too_few_frames");
    expect_failure(&sc, "folds.angle_left_deg,folds.bogus", obs, NHOLD, "unknown_key");
    expect_failure(&sc, "folds.hinge_stiffness", obs, NHOLD, "key_not_usable"); /* rigid creases */
    rod_fit_obs low[NHOLD];
    for (int k = 0; k < NHOLD; k++) low[k] = (rod_fit_obs){obs[k].dl, 0.0, -obs[k].dz, -obs[k].a};
    expect_failure(&sc, "", low, NHOLD, "lower_state");
    /* Frames scattered 50 noise units about the strip's: no parameter set fits them. */
    rod_fit_obs wild[NHOLD];
    for (int k = 0; k < NHOLD; k++) wild[k] = (rod_fit_obs){obs[k].dl, 0.0, obs[k].dz + (k % 2 ? 0.1 : -0.1), obs[k].a};
    expect_failure(&sc, "", wild, NHOLD, "misfit");
    /* A strip with creases 30 deg more open than the scene's: beyond the fit's 20 deg bounds. */
    memcpy(u, u0, sizeof u);
    u[ROD_FIT_ANGLE_LEFT] = u[ROD_FIT_ANGLE_RIGHT] = -60.0;
    rod_fit_obs far[NHOLD];
    hold_frames(&sc, u, far, NHOLD);
    expect_failure(&sc, "", far, NHOLD, "at_bound");
    /* Cancelled (the trial ended): the fit stops at its first evaluation, nothing predicted. */
    atomic_int stop;
    atomic_init(&stop, 1);
    trial_calibrated r;
    memset(&r, 0, sizeof r);
    trial_calibrate_compute(&sc, "", obs, NHOLD, 0, &stop, &r);
    printf("cancelled      -> %s: %s (%d evaluations, %.3f s)\n", r.reason_key, r.reason, r.fit.evaluations, r.wall_s);
    assert_false(r.ok);
    assert_string_equal(r.reason_key, "cancelled");
    assert_int_equal(r.fit.evaluations, 0);
    assert_true(isnan(r.snap_dw));
}

/* ---- whole mock trials through the session ---------------------------------------------------- */

static char dir[64];

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int threads_now(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    char line[256];
    int n = -1;
    while (f && fgets(line, sizeof line, f))
        if (sscanf(line, "Threads: %d", &n) == 1) break;
    if (f) fclose(f);
    return n;
}

/* config/mock.ini with a store of its own, the prediction and the twin at N = 61 (dt 2 ms), the
 * twin a relaxed (-86 deg), unequal (2.5%) strip with rigid creases, the family the fit knows
 * (the shipped twin's compliant creases are not: see docs/calibration.md), on mock.ini's virtual
 * clock (the twin runs the trial as fast as the machine allows; the fit's worker beside it, at
 * niceness 0 in mock mode). extra: more overrides. */
static void open_rig(rig_daemon *d, const char *db, const char *const *extra, int n_extra)
{
    char set_store[160], set_video[160];
    snprintf(set_store, sizeof set_store, "store.path=%s/%s", dir, db);
    snprintf(set_video, sizeof set_video, "camera.video_dir=%s/videos", dir);
    const char *ov[24] = {set_store, set_video, "api.port=0", "sim.nodes=61", "sim.dt=2e-3",
                          "twin.mesh.nodes=61", "twin.solver.dt=2e-3",
                          "twin.folds.hinge_stiffness=rigid", "sim.fit_refresh_s=0.5",
                          "sim.fit_hinge=0"}; /* the fit's creases rigid too: mock.ini's hinge guess
                                                 is for its compliant twin (calibration.md) */
    int n = 10;
    for (int k = 0; k < n_extra && n < 24; k++) ov[n++] = extra[k];
    char why[512] = "";
    int rc = rig_daemon_open(d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, n, NULL, why, sizeof why);
    if (rc) fail_msg("rig: %s", why);
}

static json_t *trial_json(const char *db, int64_t id)
{
    char path[160], why[256];
    snprintf(path, sizeof path, "%s/%s", dir, db);
    store *st = NULL;
    assert_int_equal(store_open(path, &st, why, sizeof why), STORE_OK);
    json_t *t = NULL;
    assert_int_equal(store_trial_json(st, id, &t, why, sizeof why), STORE_OK);
    store_close(st);
    return t;
}

/* The events whose message contains what, counted; the last one into last (may be NULL). */
static int events_with(const json_t *t, const char *what, char *last, size_t last_len)
{
    const json_t *evs = json_object_get(t, "events");
    int n = 0;
    for (size_t k = 0; k < json_array_size(evs); k++) {
        const char *m = json_string_value(json_object_get(json_array_get(evs, k), "message"));
        if (!m || !strstr(m, what)) continue;
        n++;
        if (last) snprintf(last, last_len, "%s", m);
        printf("  event: %.300s\n", m);
    }
    return n;
}

static int64_t run_trial(rig_daemon *d, trial_result *r)
{
    trial_session *s = NULL;
    int64_t id = 0;
    char why[512] = "";
    if (trial_session_start(&d->cfg, d->compress, d->shear, "calibrate", NULL, NULL, &s, &id, why, sizeof why))
        fail_msg("start: %s", why);
    trial_session_join(s, r);
    return id;
}

static void session_mock_trial(void **state)
{
    (void)state;
    rig_daemon d;
    /* The fit from Delta Z and A alone (sim.fit_shape is on by default: session_mock_trial_shapes
     * is the default's run; docs/calibration.md compares the two) */
    const char *off[] = {"sim.fit_shape=off"};
    open_rig(&d, "fit.db", off, 1);
    trial_result r;
    double t0 = mono_s();
    int64_t id = run_trial(&d, &r);
    printf("trial %lld: %s (%s), %.1f s wall\n", (long long)id, trial_state_name(r.final), r.reason, mono_s() - t0);
    assert_int_equal(r.final, TRIAL_DONE);
    json_t *t = trial_json("fit.db", id);
    char last[600] = "";
    assert_int_equal(events_with(t, "calibration: fitting", NULL, 0), 1);
    assert_true(events_with(t, "calibrated prediction fit 0", last, sizeof last) == 1);
    assert_true(strstr(last, "after the shear started") || strstr(last, "before the shear started"));
    printf("%s\n", last);
    /* How many refreshes land depends on the machine (the worker runs in the process's class beside
     * the virtual-clock twin: mock mode's def.idle = 0): counted and printed; the stored one must be the last that landed ok. */
    int refreshes = events_with(t, "calibrated prediction refresh", last, sizeof last);
    int last_ok = 0;
    if (refreshes) assert_int_equal(sscanf(last, "calibrated prediction refresh %d", &last_ok), 1);
    printf("%d refreshes landed ok, the last: refresh %d\n", refreshes, last_ok);
    assert_int_equal(events_with(t, "calibrated prediction stored", NULL, 0), 1);
    events_with(t, "failed", NULL, 0);
    events_with(t, "snap detected", NULL, 0);
    events_with(t, "twin truth", NULL, 0);
    json_t *dw = json_object_get(t, "snap_dw_calibrated"), *sd = json_object_get(t, "snap_sd_calibrated");
    json_t *fit = json_object_get(t, "fit");
    const char *reg = json_string_value(json_object_get(t, "regime_calibrated"));
    double pred = json_number_value(json_object_get(t, "snap_dw_predicted"));
    double meas = json_number_value(json_object_get(t, "snap_dw_measured"));
    printf("calibrated %.5f +- %.5f %s (P(other) %.3g), scene's prediction %.5f, measured %.5f: calibrated - "
           "measured %+.5f (%+.2f%%, %.2f sigma), scene's - measured %+.5f (%+.2f%%)\n",
           json_number_value(dw), json_number_value(sd), reg ? reg : "-",
           json_number_value(json_object_get(t, "p_other_regime_calibrated")), pred, meas,
           json_number_value(dw) - meas, 100.0 * (json_number_value(dw) - meas) / meas,
           (json_number_value(dw) - meas) / json_number_value(sd), pred - meas, 100.0 * (pred - meas) / meas);
    assert_true(json_is_number(dw) && json_is_number(sd) && json_number_value(sd) > 0.0);
    assert_non_null(reg);
    /* The twin differs from the scene in the fit's family: the calibrated prediction is closer to the
     * measurement than the scene's, and the measurement inside its 3-sigma band widened by one
     * frame's Delta W (the measurement's own resolution: 0.01 / 30 / 0.2). */
    assert_true(fabs(json_number_value(dw) - meas) < fabs(pred - meas));
    assert_true(fabs(json_number_value(dw) - meas) <= 3.0 * json_number_value(sd) + 0.01 / 30.0 / 0.2);
    double truth = NAN;
    char treg[16] = "";
    const json_t *evs = json_object_get(t, "events");
    for (size_t k = 0; k < json_array_size(evs); k++)
        twin_truth_parse(json_string_value(json_object_get(json_array_get(evs, k), "message")), &truth, treg,
                         sizeof treg);
    printf("twin truth %.5f %s: calibrated - truth %+.5f, scene's - truth %+.5f\n", truth, treg,
           json_number_value(dw) - truth, pred - truth);
    assert_string_equal(reg, treg);
    assert_true(json_is_null(json_object_get(t, "fit_failure")));
    assert_true(json_is_object(fit));
    assert_true(json_is_true(json_object_get(fit, "ok")));
    assert_int_equal(json_array_size(json_object_get(fit, "parameters")), 2);
    assert_int_equal(json_integer_value(json_object_get(fit, "refresh")), last_ok); /* the last before the snap */
    /* The scene's prediction is kept beside it. */
    assert_true(json_is_number(json_object_get(t, "snap_dw_predicted")));
    json_decref(t);

    /* An unknown fit key: the trial's named failure, the trial done, the scene's prediction kept. */
    rig_daemon_close(&d, "test done");
    const char *bad[] = {"sim.fit_keys=folds.angle_left_deg,folds.crease_colour"};
    open_rig(&d, "fit.db", bad, 1);
    id = run_trial(&d, &r);
    rig_daemon_close(&d, "test done");
    assert_int_equal(r.final, TRIAL_DONE);
    t = trial_json("fit.db", id);
    const char *why = json_string_value(json_object_get(t, "fit_failure"));
    printf("fit_failure: %s\n", why ? why : "(none)");
    assert_non_null(why);
    assert_non_null(strstr(why, "unknown_key"));
    assert_non_null(strstr(why, "folds.crease_colour"));
    assert_true(json_is_null(json_object_get(t, "snap_dw_calibrated")));
    assert_true(json_is_number(json_object_get(t, "snap_dw_predicted")));
    assert_true(events_with(t, "no calibrated prediction", NULL, 0) == 1);
    json_decref(t);
}

/* sim.fit_shape = on: fit 0 takes the tracked centreline at 4 compression and hold frames (the
 * last at the hold) besides Delta Z and A, and with it the default set takes both crease positions,
 * which the centreline determines; the refreshes leave the centrelines out and keep the positions
 * (with a prior around fit 0's). The numbers are printed (docs/calibration.md "In every trial": the
 * mock trial's calibrated - measured with it on and off). */
static void session_mock_trial_shapes(void **state)
{
    (void)state;
    rig_daemon d;
    const char *on[] = {"sim.fit_shape=on"};
    open_rig(&d, "shape.db", on, 1);
    trial_result r;
    int64_t id = run_trial(&d, &r);
    rig_daemon_close(&d, "test done");
    assert_int_equal(r.final, TRIAL_DONE);
    json_t *t = trial_json("shape.db", id);
    char fit0[600] = "", last[600] = "";
    assert_int_equal(events_with(t, "calibrated prediction fit 0 (compression and hold", fit0, sizeof fit0), 1);
    assert_int_equal(events_with(t, "4 centrelines) landed", NULL, 0), 1);
    printf("%s\n", fit0);
    int refreshes = events_with(t, "calibrated prediction refresh", last, sizeof last);
    printf("%d refreshes landed ok%s%s\n", refreshes, refreshes ? ", the last: " : "", refreshes ? last : "");
    json_t *fit = json_object_get(t, "fit");
    assert_true(json_is_object(fit));
    char *dump = json_dumps(fit, JSON_COMPACT);
    printf("fit: %s\n", dump ? dump : "-");
    free(dump);
    /* fit 0 took the 4 centrelines; a refresh leaves them out and keeps the positions */
    int stored_refresh = (int)json_integer_value(json_object_get(fit, "refresh"));
    assert_int_equal(json_integer_value(json_object_get(fit, "centrelines")), stored_refresh ? 0 : 4);
    json_t *ps = json_object_get(fit, "parameters");
    assert_int_equal(json_array_size(ps), 4);
    int positions = 0;
    for (size_t k = 0; k < json_array_size(ps); k++) {
        json_t *q = json_array_get(ps, k);
        const char *key = json_string_value(json_object_get(q, "key"));
        if (key && strstr(key, "position")) {
            positions++;
            assert_true(json_is_number(json_object_get(q, "se")));
        }
    }
    assert_int_equal(positions, 2);
    double dw = json_number_value(json_object_get(t, "snap_dw_calibrated"));
    double sd = json_number_value(json_object_get(t, "snap_sd_calibrated"));
    double pred = json_number_value(json_object_get(t, "snap_dw_predicted"));
    double meas = json_number_value(json_object_get(t, "snap_dw_measured"));
    printf("with the centrelines: stored (refresh %d) calibrated %.5f +- %.5f, measured %.5f: calibrated - measured "
           "%+.5f (%+.2f%%, %.2f sigma); scene's - measured %+.5f\n",
           stored_refresh, dw, sd, meas, dw - meas, 100.0 * (dw - meas) / meas, (dw - meas) / sd, pred - meas);
    assert_true(isfinite(dw) && sd > 0.0);
    json_decref(t);
}

/* An abort as soon as the fit started: the trial ends aborted with the worker joined (the
 * process's thread count back where it was) within the abort cap. */
static void session_abort_joins(void **state)
{
    (void)state;
    rig_daemon d;
    open_rig(&d, "abort.db", NULL, 0);
    int before = threads_now();
    trial_session *s = NULL;
    int64_t id = 0;
    char why[512] = "";
    if (trial_session_start(&d.cfg, d.compress, d.shear, "abort", NULL, NULL, &s, &id, why, sizeof why))
        fail_msg("start: %s", why);
    session_status ss;
    for (int k = 0; k < 6000; k++) {
        trial_session_status(s, &ss);
        if (ss.state == TRIAL_CHECKING || ss.state == TRIAL_SHEARING || trial_state_final(ss.state)) break;
        struct timespec ts = {0, 5 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
    assert_true(ss.state == TRIAL_CHECKING || ss.state == TRIAL_SHEARING);
    double t0 = mono_s();
    trial_session_abort(s, "test abort");
    trial_result r;
    trial_session_join(s, &r);
    double waited = mono_s() - t0;
    int after = threads_now();
    printf("aborted in %s; joined %.2f s after the abort; threads %d before, %d after\n",
           trial_state_name(ss.state), waited, before, after);
    assert_int_equal(r.final, TRIAL_ABORTED);
    assert_true(waited < TRIAL_CALIBRATE_ABORT_CAP_S);
    assert_int_equal(after, before);
    json_t *t = trial_json("abort.db", id);
    int said = events_with(t, "calibrat", NULL, 0);
    assert_true(said >= 2); /* started, and landed / cancelled / left at the cap */
    assert_int_equal(events_with(t, "left to finish on its own", NULL, 0), 0);
    json_decref(t);
    rig_daemon_close(&d, "test done");
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/trial-calibrate-XXXXXX");
    assert_non_null(mkdtemp(dir));
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : -1;
}

/* The in-trial fit's error model (trial_calibrate_setup, shared with the specimen's refit): the
 * tracker's per-phase bias on A in the covariance (sigma_b, docs/calibration.md), none assumed on
 * Delta Z, and the hinge guess turning rigid creases into hinges. Without the bias the family's
 * twin 18 was confidently wrong (P(other) 0.0016 at 80%; 0.14 with it). */
static void setup_has_the_trackers_bias(void **state)
{
    (void)state;
    rod_scene sc = mock_scene(31);
    rod_fit_opts o;
    char key[24] = "", why[256] = "";
    assert_int_equal(trial_calibrate_setup(&sc, 0.0, "", &o, key, why, sizeof why), 0);
    assert_true(o.sigma_b_a == TRIAL_CALIBRATE_BIAS_A);
    assert_true(TRIAL_CALIBRATE_BIAS_A > 0.0);
    assert_true(o.sigma_b_dz == 0.0);
}

/* The landing report and event of a worker (the runner's thread: this test's). */
typedef struct class_seen {
    int landed, idle, ok;
    char event[600];
} class_seen;

static void class_landed(void *user, const trial_calibrated *r)
{
    class_seen *s = user;
    s->landed++;
    s->idle = r->idle;
    s->ok = r->ok;
}

static int class_event(void *user, double t_s, const char *kind, const char *message)
{
    (void)t_s;
    (void)kind;
    class_seen *s = user;
    if (strstr(message, " landed at") && !strstr(message, "stored:")) snprintf(s->event, sizeof s->event, "%s", message);
    return 0;
}

/* One fit 0 of the hold's frames on a worker with def.idle = idle, ticked until it lands. */
static class_seen run_worker(int idle)
{
    rod_scene sc = mock_scene(31);
    double u[ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, u);
    u[ROD_FIT_ANGLE_LEFT] = -87.0;
    rod_fit_obs obs[NHOLD];
    hold_frames(&sc, u, obs, NHOLD);
    class_seen seen;
    memset(&seen, 0, sizeof seen);
    trial_calibrate_def d = trial_calibrate_def_default();
    d.scene = sc;
    d.idle = idle;
    d.landed = class_landed;
    d.event = class_event;
    d.user = &seen;
    char why[256];
    trial_calibrate *c = trial_calibrate_new(&d, why, sizeof why);
    assert_non_null(c);
    for (int k = 0; k < NHOLD; k++) trial_calibrate_add(c, 0, obs[k].dl, obs[k].dw, obs[k].dz, obs[k].a);
    trial_calibrate_start(c, 0.0);
    double t0 = mono_s();
    while (!seen.landed && mono_s() - t0 < 60.0) { /* the fit takes about 1 s (N = 31) */
        struct timespec ts = {0, 10 * 1000 * 1000};
        nanosleep(&ts, NULL);
        trial_calibrate_tick(c, mono_s() - t0, 0);
    }
    trial_calibrate_end(c, mono_s() - t0, 0);
    trial_calibrate_free(c);
    printf("idle = %d: landed %d, ok %d, worker in SCHED_IDLE %d: %.160s\n", idle, seen.landed, seen.ok, seen.idle,
           seen.event);
    return seen;
}

static void worker_class(void **state)
{
    (void)state;
    class_seen rig = run_worker(1);
    assert_int_equal(rig.landed, 1);
    assert_int_equal(rig.ok, 1);
    assert_int_equal(rig.idle, 1);
    assert_non_null(strstr(rig.event, "in SCHED_IDLE)"));
    assert_int_equal(thread_class_is_idle(0), 0); /* the runner's thread keeps its class */
    class_seen mock = run_worker(0);
    assert_int_equal(mock.landed, 1);
    assert_int_equal(mock.idle, 0);
    assert_null(strstr(mock.event, "SCHED_IDLE"));
}

/* A refresh after a fit 0 that took the centrelines (trial_calibrate_compute_refresh): no
 * centrelines, both crease positions fitted with fit 0's values and standard errors (0.0003 l here,
 * the mock trial's fit 0's: the floor ROD_FIT_CARRY_FLOOR applies) as their prior, the model at fit
 * 0's strip: the positions' standard errors within the floor (the old flat prior of
 * TRIAL_CALIBRATE_PRIOR_POSITION left them 0.0026-0.0032 l on the mock trial). Without fit 0's
 * values, the flat prior around the scene's. */
static void refresh_without_centrelines(void **state)
{
    (void)state;
    rod_scene sc = mock_scene(31);
    double u[ROD_FIT_NKEYS], us[ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, u);
    u[ROD_FIT_ANGLE_LEFT] = -87.0;
    u[ROD_FIT_ANGLE_RIGHT] = -84.5;
    enum { NSH = 10 };
    rod_fit_obs obs[NHOLD + NSH];
    hold_frames(&sc, u, obs, NHOLD);
    shear_frames(&sc, u, 0.15, obs + NHOLD, NSH);
    /* fit 0's positions, 0.002 l off the strip's */
    memcpy(us, u, sizeof us);
    us[ROD_FIT_ANGLE_LEFT] = us[ROD_FIT_ANGLE_RIGHT] = -90.0;
    us[ROD_FIT_POSITION_LEFT] += 0.002;
    us[ROD_FIT_POSITION_RIGHT] -= 0.002;
    double se0[ROD_FIT_NKEYS];
    for (int k = 0; k < ROD_FIT_NKEYS; k++) se0[k] = INFINITY;
    se0[ROD_FIT_POSITION_LEFT] = se0[ROD_FIT_POSITION_RIGHT] = 0.0003;
    trial_calibrated r;
    memset(&r, 0, sizeof r);
    trial_calibrate_compute_refresh(&sc, "", obs, NHOLD, NSH, us, se0, NULL, &r);
    if (!r.ok) fail_msg("%s: %s", r.reason_key, r.reason);
    printf("refresh: positions %.5f +- %.5f, %.5f +- %.5f (prior around %.5f, %.5f; strip %.5f, %.5f); snap %.5f +- %.5f\n",
           r.fit.u[ROD_FIT_POSITION_LEFT], r.fit.se[ROD_FIT_POSITION_LEFT], r.fit.u[ROD_FIT_POSITION_RIGHT],
           r.fit.se[ROD_FIT_POSITION_RIGHT], us[ROD_FIT_POSITION_LEFT], us[ROD_FIT_POSITION_RIGHT],
           u[ROD_FIT_POSITION_LEFT], u[ROD_FIT_POSITION_RIGHT], r.snap_dw, r.snap_sd);
    assert_int_equal(r.nshapes, 0);
    assert_int_equal(r.fit.nshape_rows, 0);
    for (int k = ROD_FIT_POSITION_LEFT; k <= ROD_FIT_POSITION_RIGHT; k += ROD_FIT_POSITION_RIGHT - ROD_FIT_POSITION_LEFT) {
        assert_true(r.fit.fitted[k]);
        assert_true(fabs(r.fit.u0[k] - u[k]) < 1e-12); /* stored as the scene: the trial's, not fit 0's */
        assert_true(isfinite(r.fit.se[k]) && r.fit.se[k] > 0.0 && r.fit.se[k] <= ROD_FIT_CARRY_FLOOR);
    }
    assert_true(r.snapped && isfinite(r.snap_sd) && r.snap_sd > 0.0);
    /* Without fit 0's values: the specimen's tolerance around the scene's. */
    trial_calibrated r2;
    memset(&r2, 0, sizeof r2);
    trial_calibrate_compute_refresh(&sc, "", obs, NHOLD, NSH, NULL, NULL, NULL, &r2);
    if (!r2.ok) fail_msg("%s: %s", r2.reason_key, r2.reason);
    printf("refresh without fit 0's: positions +- %.5f, %.5f\n", r2.fit.se[ROD_FIT_POSITION_LEFT],
           r2.fit.se[ROD_FIT_POSITION_RIGHT]);
    for (int k = ROD_FIT_POSITION_LEFT; k <= ROD_FIT_POSITION_RIGHT; k += ROD_FIT_POSITION_RIGHT - ROD_FIT_POSITION_LEFT) {
        assert_true(r2.fit.fitted[k] && r2.fit.u0[k] == u[k]);
        assert_true(isfinite(r2.fit.se[k]) && r2.fit.se[k] <= TRIAL_CALIBRATE_PRIOR_POSITION);
    }
}

/* The old rule, on every frame (what the fit chose before the frames were picked as they came):
 * the last, then for targets 2, 1, 0 (evenly in Delta L from the first frame's to the last's) the
 * nearest not taken, the earlier on a tie. Into out (indices), their count. */
static int reference_choice(const double *dl, int n, int *out)
{
    int m = 0;
    double lo = dl[0], hi = dl[n - 1];
    for (int j = TRIAL_CALIBRATE_SHAPES - 1; j >= 0; j--) {
        int best = -1;
        if (j == TRIAL_CALIBRATE_SHAPES - 1) {
            best = n - 1;
        } else {
            double target = lo + (hi - lo) * j / (TRIAL_CALIBRATE_SHAPES - 1), err = INFINITY;
            for (int k = 0; k < n; k++) {
                int taken = 0;
                for (int u = 0; u < m; u++) taken |= out[u] == k;
                if (!taken && fabs(dl[k] - target) < err) {
                    err = fabs(dl[k] - target);
                    best = k;
                }
            }
        }
        if (best >= 0) out[m++] = best;
    }
    return m;
}

/* Offers the frames as the runner does (each one when the next comes, mapped only when wanted; the
 * last at the end), frame k's dz = k to name it; the count mapped, and the hold's (dl = hold) among
 * them before the last. Checks the choice against the old rule's and the kept set's bound. */
static void shapes_offered(const double *dl, int n, double hold, int *mapped, int *mapped_hold)
{
    trial_calibrate_def d = trial_calibrate_def_default();
    d.scene.compression = hold;
    d.fit_shape = 1;
    char why[256];
    trial_calibrate *c = trial_calibrate_new(&d, why, sizeof why);
    assert_non_null(c);
    *mapped = *mapped_hold = 0;
    for (int k = 0; k < n; k++) {
        int last = k == n - 1;
        trial_calibrate_add(c, 0, dl[k], 0.0, k, 0.0);
        if (!last && !trial_calibrate_shape_wanted(c, dl[k])) continue;
        double xz[6] = {0.0, 0.0, 0.5, 0.1 + 0.001 * k, 1.0, 0.0};
        trial_calibrate_add_shape(c, dl[k], 0.0, k, 0.0, xz, 3, last);
        if (!last) {
            (*mapped)++;
            *mapped_hold += dl[k] == hold;
        }
        assert_true(trial_calibrate_shapes_kept(c) <= TRIAL_CALIBRATE_SHAPES * (TRIAL_CALIBRATE_SHAPES - 1) + 1);
    }
    rod_fit_obs got[TRIAL_CALIBRATE_SHAPES];
    int want[TRIAL_CALIBRATE_SHAPES];
    int ng = trial_calibrate_shapes_choose(c, got), nw = reference_choice(dl, n, want);
    assert_int_equal(ng, nw);
    for (int s = 0; s < ng; s++) assert_int_equal((int)got[s].dz, want[s]);
    trial_calibrate_free(c);
}

/* The centrelines the first fit takes (sim.fit_shape) are picked as the frames come, in a fixed set:
 * the same four as the old rule picked from every frame, with only the frames that enter the set
 * mapped, none of a long hold's (which the runner mapped, resampled and stored one by one before). */
static void shapes_picked_as_they_come(void **state)
{
    (void)state;
    enum { NC = 120, NH = 250 };
    static double dl[NC + NH];
    uint64_t r = 12345;
    double x = 0.45;
    for (int k = 0; k < NC; k++) { /* uneven steps, some repeated: a compression under load */
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        int q = (int)(r >> 61);
        x += q == 0 ? 0.0 : 0.05 / NC * (0.25 * q);
        dl[k] = fmin(x, 0.4999);
    }
    for (int k = NC; k < NC + NH; k++) dl[k] = 0.5;
    int mapped, mapped_hold;
    shapes_offered(dl, NC + NH, 0.5, &mapped, &mapped_hold);
    printf("compression %d + hold %d frames: %d centrelines mapped before the last (%d of the hold)\n", NC, NH, mapped,
           mapped_hold);
    assert_int_equal(mapped_hold, 0);
    assert_true(mapped <= NC);
    /* The hold alone: every target at the hold's Delta L, ties to the earliest. */
    for (int k = 0; k < 30; k++) dl[k] = 0.5;
    shapes_offered(dl, 30, 0.5, &mapped, &mapped_hold);
    assert_true(mapped <= TRIAL_CALIBRATE_SHAPES * (TRIAL_CALIBRATE_SHAPES - 1));
    /* Three compression frames and a hold: the hold's frames are the nearest to some targets. */
    dl[0] = 0.45;
    dl[1] = 0.452;
    dl[2] = 0.48;
    for (int k = 3; k < 60; k++) dl[k] = 0.5;
    shapes_offered(dl, 60, 0.5, &mapped, &mapped_hold);
    assert_true(mapped_hold <= TRIAL_CALIBRATE_SHAPES * (TRIAL_CALIBRATE_SHAPES - 1));
    /* One frame: it is the last and the only choice. */
    shapes_offered(dl, 1, 0.45, &mapped, &mapped_hold);
}

/* `test_trial_calibrate session` runs the whole mock trials (3, 4) only; without an argument, the
 * fit's own tests (1, 2), seconds in either build. */
int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    if (argc > 1 && !strcmp(argv[1], "session")) {
        const struct CMUnitTest session[] = {
            cmocka_unit_test(session_mock_trial),
            cmocka_unit_test(session_mock_trial_shapes),
            cmocka_unit_test(session_abort_joins),
        };
        return cmocka_run_group_tests(session, setup, teardown);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(compute_recovers_strip),
        cmocka_unit_test(compute_bad_input),
        cmocka_unit_test(setup_has_the_trackers_bias),
        cmocka_unit_test(refresh_frames_below_cut),
        cmocka_unit_test(worker_class),
        cmocka_unit_test(shapes_picked_as_they_come),
        cmocka_unit_test(refresh_without_centrelines),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
