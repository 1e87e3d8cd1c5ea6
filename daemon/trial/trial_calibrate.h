/* trial_calibrate.h: the fit beside a trial (issue 32 B): the trial's own strip fitted to what the
 * camera measured before the shear, and its snap predicted with the fitted strip, while the trial
 * goes on.
 *
 * The runner feeds every measured frame (Delta L, Delta W, Delta Z, A) and says when the shear
 * ended; from then on a worker thread fits the prediction's scene (the specimen-mapped scene,
 * start and prior of the fit) to the compression and hold frames (sim/rod_fit.h) and predicts the
 * fitted strip's snap with its band (sim/rod_fit_snap.h). The shear never waits for it: the runner
 * polls once a frame (trial_calibrate_tick), and a fit that lands is reported once through the
 * def's `landed` callback on the runner's thread (the session stores it beside the scene's
 * prediction and publishes it) and said in an event with the trial time it landed at and whether
 * that was before or after the shear started. During the shear the fit is refreshed every
 * def.refresh_s of trial time with the shear frames up to TRIAL_CALIBRATE_SHEAR_CUT of the latest
 * predicted snap (the last calibrated one, else the scene's; all of them while neither is known),
 * and only when the count of frames below that limit changed since the last; never two at once (one
 * still running is waited for, not doubled); none starts after the snap, so the last one to land
 * is the last one made from data before the snap.
 *
 * Bad input is a named failure (trial_calibrated.reason_key, and a sentence in reason), never a
 * number: too_few_frames, lower_state, unknown_key, key_not_usable, misfit, at_bound, fit_failed,
 * prediction_failed, cancelled, after_snap, thread. A fitted strip that does not snap before protocol.shear_max
 * is a prediction (ok, snapped = 0), not a failure. The trial goes on; the scene's prediction is kept.
 *
 * An abort or a failure cancels the worker: the fit stops at its next evaluation (rod_fit_opts.
 * cancel) and the prediction is skipped; a prediction already running cannot be interrupted (it is
 * capped: the predictor's steps, 1 + 2 p of them). So the end of the trial waits for a running
 * worker at most def.cap_s of wall time (TRIAL_CALIBRATE_ABORT_CAP_S after an abort or a
 * failure), after the rails stopped, and only past that leaves it to free itself, saying so in an
 * event. The worker touches nothing but its own copy of the data. */
#ifndef RIBBON_DAEMON_TRIAL_CALIBRATE_H
#define RIBBON_DAEMON_TRIAL_CALIBRATE_H

#include <stdatomic.h>
#include <stddef.h>

#include "rod_fit.h"
#include "rod_fit_snap.h"

#define TRIAL_CALIBRATE_MIN_FRAMES 10      /* measured frames before the shear a fit needs */
#define TRIAL_CALIBRATE_MAX_HOLD_OBS 40    /* frames of the compression and hold a fit uses at most
                                              (evenly thinned: each observation costs a static
                                              solve per evaluation) */
#define TRIAL_CALIBRATE_MAX_SHEAR_OBS 40   /* the same for the shear frames of a refresh */
/* A refresh fits the shear frames up to this fraction of the latest predicted snap (the last
 * calibrated one that landed, else the scene's): near the snap the camera's Delta Z and A drift
 * from the model's (the rehearsal, refitted offline with the in-trial setup: +0.4% at 0.8 of the
 * way, +7.3% at 0.9, +9.1% at 0.95; docs/calibration.md "In every trial"). ribbonctl calibrate's
 * default cut is the same fraction of the measured snap. */
#define TRIAL_CALIBRATE_SHEAR_CUT 0.8
#define TRIAL_CALIBRATE_ABORT_CAP_S 10.0   /* s of wall time an aborted trial waits for its worker
                                              (a band's predictions under load; a fit stops at once) */
#define TRIAL_CALIBRATE_PRIOR_ANGLE_DEG 10.0 /* prior width of each crease angle around the scene's */
/* The tracker's error on A common to a phase of the protocol (compression, hold, shear), rad: the
 * fit's covariance is a sandwich with it (sim/rod_fit_sandwich.h), values unchanged. 0.003 is the RMS
 * of the per-phase mean error the family's films measured at 640 x 480 (-0.0037, +0.0024, +0.0026
 * on twin 18, each 3-4 se of its mean; docs/calibration.md); the residuals cannot estimate it (the
 * parameters absorb it). ribbon-fit-family uses the same value by default. */
#define TRIAL_CALIBRATE_BIAS_A 0.003
#define TRIAL_CALIBRATE_PRIOR_DZ_OFFSET 0.005 /* prior width of view.dz_offset (over l) around 0: 2.5 px at
                                              the rigs' 2.5 px/mm, where a lab calibration's clamp points
                                              are within 1.5 px (vision.md) */
#define TRIAL_CALIBRATE_PRIOR_HINGE_LN 0.88  /* prior width of ln k of a fitted hinge around the scene's:
                                              the spread of a hand-made crease's bending length E I1 / k
                                              over 1-20% of l, log-uniform (the family's, calibration.md) */

/* The tracked centreline as the fit's observable (sim.fit_shape; sim/rod_fit.h opts.shapes): the
 * fit takes TRIAL_CALIBRATE_SHAPES measured compression and hold frames' centrelines, mapped to the
 * plane (vis_calib_curve_to_plane, over l, relative to the simulator's left clamp point): the hold's
 * last, and the frames nearest TRIAL_CALIBRATE_SHAPES - 1 targets evenly in Delta L from the first
 * one handed in to the hold's (the scene's protocol.compression), each resampled at
 * TRIAL_CALIBRATE_SHAPE_POINTS points, with noise TRIAL_CALIBRATE_SIGMA_SHAPE (over l: the
 * tracker's centreline error the family's films measured, docs/calibration.md); each shape's frame
 * joins the observations. The choice is made as the frames come, in a fixed set of slots (the
 * TRIAL_CALIBRATE_SHAPES nearest each target and the last: at most TRIAL_CALIBRATE_SHAPES^2 - 
 * TRIAL_CALIBRATE_SHAPES + 1 kept), and the runner maps a frame's centreline only when it enters one
 * (trial_calibrate_shape_wanted), not every frame of the hold. Fit 0 weights each centreline's
 * error as a deformation of its own besides the independent noise (rod_fit_opts.shape_common_mode).
 * The refreshes leave the centrelines out (with them the band at 80% of the way held the family's
 * snaps in 85%, without them 90%: docs/calibration.md) and fit the positions fit 0 found with them
 * with fit 0's values and standard errors as their prior (at least ROD_FIT_CARRY_FLOOR, at most
 * TRIAL_CALIBRATE_PRIOR_POSITION: sim/rod_fit_carry.h). */
#define TRIAL_CALIBRATE_SHAPES 4
#define TRIAL_CALIBRATE_SHAPE_POINTS 24
#define TRIAL_CALIBRATE_SIGMA_SHAPE 0.0016
#define TRIAL_CALIBRATE_PRIOR_POSITION 0.006 /* over l: the specimen record's -+ 1% of l (uniform: sd
                                                0.0058), ribbon-fit-family's prior on the positions */

typedef struct trial_calibrated {
    int ok;                 /* 1: fitted and its snap predicted; 0: failed (reason_key, reason) */
    char reason_key[24];    /* failed: one of the names in the header comment */
    char reason[320];       /* failed: the sentence */
    int refresh;            /* 0: the fit from the compression and hold; k: the k-th refresh */
    int nobs_before, nobs_shear; /* observations used (before the shear, of the shear) */
    int nshapes;            /* centrelines the fit took (sim.fit_shape), 0: none */
    double dw_cut;          /* the largest Delta W among them */
    double dw_limit;        /* a refresh: the shear frames' limit, TRIAL_CALIBRATE_SHEAR_CUT of the
                               snap in limit_of (NaN: no predicted snap known, the whole shear) */
    double limit_snap;      /* that snap */
    char limit_of[16];      /* "calibrated" or "scene" ("" without a limit) */
    double t_started, t_landed; /* trial time the fit started and landed (s) */
    double t_shear;         /* trial time the shear started (s) */
    int snapped;            /* ok: the fitted strip snaps before protocol.shear_max */
    double snap_dw, snap_sd; /* ok and snapped: its snap Delta W and the 1-sigma band (NaN when the
                               band could not be made) */
    int asymmetric;
    double p_other;         /* probability of the other regime (NaN without a band) */
    char note[256];         /* the band's note (partial band, undetermined parameters) */
    rod_fit_result fit;     /* the fitted values with their standard errors (valid when the fit ran) */
    int fit_ran;
    double wall_s;          /* the worker's wall time */
    int idle;               /* the worker ran in SCHED_IDLE (def.idle, the class read back; the
                               landing event says "in SCHED_IDLE") */
} trial_calibrated;

typedef struct trial_calibrate_def {
    rod_scene scene;        /* the prediction's scene (start and prior), at its resolution */
    char keys[256];         /* comma-separated fit keys (rod_fit_param.h); "" = both crease angles,
                               and the hinge stiffness when the scene's creases are compliant */
    double refresh_s;       /* trial time between refreshes in the shear; 0 = no refresh */
    double cap_s;           /* wall time the trial's end waits for a running worker */
    /* The scene's predicted snap Delta W so far (NaN: not known yet), asked on the runner's thread
     * when a refresh starts without a calibrated snap; NULL: never known. */
    double (*scene_snap)(void *user);
    int fit_shape;          /* 1: the fit takes the centrelines handed in (trial_calibrate_add_shape) */
    int idle;               /* 1: the worker runs in SCHED_IDLE (thread_class.h): rig mode, where the
                               trial's loop, capture and poller share the cores and must never wait
                               for it; 0 in mock mode, whose virtual clock runs the twin flat out
                               and would starve it */
    /* The trial's event sink (the runner's), and the landing report; both on the runner's thread. */
    int (*event)(void *user, double t_s, const char *kind, const char *message);
    void (*landed)(void *user, const trial_calibrated *r);
    void *user;
} trial_calibrate_def;

trial_calibrate_def trial_calibrate_def_default(void);

typedef struct trial_calibrate trial_calibrate;

/* NULL with why when out of memory. */
trial_calibrate *trial_calibrate_new(const trial_calibrate_def *def, char *why, size_t why_len);
/* Waits (def.cap_s) for a worker still running, then frees. NULL is a no-op. */
void trial_calibrate_free(trial_calibrate *c);

/* A measured frame: shear = 0 for the compression and hold, 1 for the shear. */
void trial_calibrate_add(trial_calibrate *c, int shear, double dl, double dw, double dz, double a);
/* 1 while centrelines are wanted (def.fit_shape and the first fit not started yet). 0 on NULL. */
int trial_calibrate_wants_shape(const trial_calibrate *c);
/* 1 when a measured compression or hold frame at Delta L dl, handed in next, would enter the set the
 * first fit chooses from (the header comment above): the runner maps its centreline only then, and
 * always the last one's (the hold's last, once the hold ends). Frames are offered in their order. */
int trial_calibrate_shape_wanted(const trial_calibrate *c, double dl);
/* The centreline of a measured compression or hold frame (dl, dw, dz, a: the frame's observation,
 * handed to trial_calibrate_add too): n points (x, z) over l relative to the simulator's left clamp
 * point (2 n values), kept resampled where it enters the set; last = 1 for the last frame before the
 * fit starts (the hold's last: always kept). A polyline that cannot be resampled is ignored. */
void trial_calibrate_add_shape(trial_calibrate *c, double dl, double dw, double dz, double a, const double *xz,
                               int n, int last);
/* Tests: the centrelines kept (at most TRIAL_CALIBRATE_SHAPES (TRIAL_CALIBRATE_SHAPES - 1) + 1), and
 * the ones the first fit would take now (their frames into obs, TRIAL_CALIBRATE_SHAPES at most; the
 * count returned). */
int trial_calibrate_shapes_kept(const trial_calibrate *c);
int trial_calibrate_shapes_choose(trial_calibrate *c, rod_fit_obs *obs);
/* The hold ended at trial time t: the fit from the compression and hold starts now. */
void trial_calibrate_start(trial_calibrate *c, double t);
/* The shear started at trial time t (landings are said before or after it). */
void trial_calibrate_shear_started(trial_calibrate *c, double t);
/* Once a frame: a landed fit is reported; in the shear (shearing = 1) a refresh may start. */
void trial_calibrate_tick(trial_calibrate *c, double t, int shearing);
/* The snap was seen at trial time t, its onset at Delta W dw_onset (NaN: unknown): no refresh
 * starts after it, and one whose frames reach the onset (frames of the snapping strip, taken
 * before the detector fired) is not kept (reason_key after_snap). */
void trial_calibrate_snap(trial_calibrate *c, double t, double dw_onset);
/* The trial ended at trial time t (aborted = 1 after an abort or a failure): waits for a running
 * worker (def.cap_s, TRIAL_CALIBRATE_ABORT_CAP_S when aborted), reports it, and says which fit is
 * the one kept. */
void trial_calibrate_end(trial_calibrate *c, double t, int aborted);

/* Every call below is a no-op on NULL (a trial without the fit). */

/* The last fit that landed ok (NULL: none), and the last one that landed at all. */
const trial_calibrated *trial_calibrate_kept(const trial_calibrate *c);
const trial_calibrated *trial_calibrate_last(const trial_calibrate *c);

/* r as the JSON object stored with the trial (fit_json): which fit, its frames, the fitted
 * parameters with their standard errors (null: not determined), the residual. 0, or -1 when out
 * is too small (then {"truncated":true}). */
int trial_calibrated_json(const trial_calibrated *r, char *out, size_t out_len);

/* The fit's setup from the rig config, the one both the fit beside a trial (trial_session.c) and
 * the specimen's refit after it (trial_specimen_calib.c) use: sc is the strip to fit (the
 * prediction's scene, or the pooled trials' strip); when its creases are rigid and fit_hinge > 0
 * (sim.fit_hinge, N m/rad) they become hinges of that stiffness, the fit's start and its prior's
 * centre (a rigid crease is not a model of a real one, DESIGN.md section 9). o gets keys
 * (sim.fit_keys; "" = both crease angles, and the hinge stiffness when sc's creases are
 * compliant, after the above) and the priors around sc's values (TRIAL_CALIBRATE_PRIOR_*).
 * Returns 1 when it made the creases hinges, 0 when sc was kept, -1 with reason_key (unknown_key,
 * key_not_usable, at most 24 bytes with its NUL) and reason when a key cannot be fitted. */
int trial_calibrate_setup(rod_scene *sc, double fit_hinge, const char *keys, rod_fit_opts *o, char reason_key[24],
                          char *reason, size_t reason_len);

/* The fit and the snap of one set of observations, on the caller's thread (the worker's body;
 * tests call it directly). keys as in the def. Fills r (ok or a named failure). cancel (may be
 * NULL): non-zero skips the prediction. */
void trial_calibrate_compute(const rod_scene *sc, const char *keys, const rod_fit_obs *obs, int nobs_before,
                             int nobs_shear, const atomic_int *cancel, trial_calibrated *r);
/* The same with nshapes centrelines (each at one observation's state, TRIAL_CALIBRATE_SIGMA_SHAPE; with
 * the default keys both crease positions too), as fit 0 with sim.fit_shape. */
void trial_calibrate_compute_shapes(const rod_scene *sc, const char *keys, const rod_fit_obs *obs, int nobs_before,
                                    int nobs_shear, const rod_fit_shape *shapes, int nshapes,
                                    const atomic_int *cancel, trial_calibrated *r);
/* A refresh after such a fit 0: no centrelines, and with the default keys both crease positions
 * with fit 0's values and standard errors (u0, se0: its result's, fit units) as their prior, the
 * model at fit 0's strip, the other priors on sc's values (rod_fit_carry_positions: the width se0
 * between ROD_FIT_CARRY_FLOOR and TRIAL_CALIBRATE_PRIOR_POSITION); u0 NULL or its positions not
 * finite: a prior of TRIAL_CALIBRATE_PRIOR_POSITION around sc's. */
void trial_calibrate_compute_refresh(const rod_scene *sc, const char *keys, const rod_fit_obs *obs, int nobs_before,
                                     int nobs_shear, const double u0[ROD_FIT_NKEYS], const double se0[ROD_FIT_NKEYS],
                                     const atomic_int *cancel, trial_calibrated *r);

#endif
