/* trial_specimen_calib.h: a specimen's own calibration (issue 35 A): its strip fitted to all its
 * finished trials, refreshed by ribbond after each of them, and put into its next trial's
 * prediction (trial_specimen_calib.c).
 *
 * The refit (trial_specimen_calib_refit) pools the specimen's finished trials (status done, rig
 * or mock, newest first, at most TRIAL_SPECIMEN_CALIB_MAX_TRIALS of them) through the trial
 * room's pool (trial_pool.h, as `ribbonctl calibrate` reads them: each trial's strip and its
 * camera frames of the upper state, at most TRIAL_SPECIMEN_CALIB_MAX_FRAMES each and
 * TRIAL_SPECIMEN_CALIB_MAX_FRAMES_TOTAL in all: the fit's cost is a static solve per frame per
 * evaluation, so it stays bounded however often the specimen is trialled), skips a trial
 * the pool refuses (too few frames, the lower state, a strip different from the newest one's: a
 * re-measured specimen) with its reason, and fits one strip (sim/rod_fit.h) set up as the fit
 * beside a trial is (trial_calibrate_setup: sim.fit_keys, sim.fit_hinge, the priors). A new calibration replaces the specimen's; a refit that fails
 * (reason_key: no_trials, unknown_key, key_not_usable, fit_failed, at_bound, misfit, cancelled,
 * not_stored) keeps the one before and stores why beside it. Either way `message` is the
 * sentence for the trial's event.
 *
 * Its use (trial_specimen_calib_apply): the fitted strip values the data determined replace the
 * measured (or scene) ones in the prediction's scene; a value not determined, and the camera's
 * view.dz_offset (not the strip), keep the measured or scene value. A hinge fitted from
 * sim.fit_hinge's guess on rigid creases makes the prediction's rigid creases hinges of the fitted
 * stiffness (its start was the guess, not a measured value: not a sign of a re-measure). A calibration made from a
 * strip other than the one the trial measures (the specimen re-measured since) is not applied,
 * and the message says which value changed. */
#ifndef RIBBON_TRIAL_SPECIMEN_CALIB_H
#define RIBBON_TRIAL_SPECIMEN_CALIB_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "scene.h"
#include "store.h"

#define TRIAL_SPECIMEN_CALIB_MAX_TRIALS 8   /* newest trials pooled (each costs its frames' solves) */
#define TRIAL_SPECIMEN_CALIB_MAX_FRAMES 40  /* frames per trial, thinned evenly (as the in-trial fit's
                                               TRIAL_CALIBRATE_MAX_HOLD_OBS) ... */
#define TRIAL_SPECIMEN_CALIB_MAX_FRAMES_TOTAL 120 /* ... and in all: with more than 3 trials each
                                               gives 120 / n (`ribbonctl calibrate --max-samples M`
                                               with M = min(40, 120 / n) pools the same frames;
                                               it fits them without the priors) */
#define TRIAL_SPECIMEN_CALIB_MAX_EXAMINED 16 /* newest trials looked at, used or skipped */

typedef struct trial_specimen_refit {
    int ok;                 /* 1: a new calibration stored; 0: failed (reason_key, reason) */
    char reason_key[24];
    char reason[480];
    int ntrials;            /* trials pooled */
    int nobs;               /* frames fitted */
    double hinge_guess;     /* N m/rad: the strip's rigid creases were fitted as hinges from this
                               guess (sim.fit_hinge); NaN: the strip's own creases */
    double wall_s;          /* wall time of the whole refit */
    char message[1000];     /* the trial's event: what was fitted, or why not and what stands */
} trial_specimen_refit;

/* Refits specimen specimen_id (named name, for the message) after its trial after_trial ended,
 * from its finished trials, set up as the fit beside a trial is (trial_calibrate_setup: keys as
 * sim.fit_keys, "" = both crease angles and the hinge when the strip's creases are compliant;
 * rigid creases made hinges of fit_hinge, sim.fit_hinge, when > 0; the same priors), and stores the outcome in the specimen's record (st must be
 * writable). cancel (may be NULL): non-zero stops the fit at its next evaluation (cancelled). */
void trial_specimen_calib_refit(store *st, int64_t specimen_id, const char *name, int64_t after_trial,
                                const char *keys, double fit_hinge, const atomic_int *cancel,
                                trial_specimen_refit *out);

/* What a trial's prediction took from its specimen's calibration. */
typedef struct trial_specimen_calib_use {
    int applied;            /* values put into the scene (0: the scene untouched) */
    char record[2048];      /* the prediction's calibration_json when applied; "" otherwise */
    char message[1000];     /* the trial's event ("" when the specimen has no calibration) */
    int warning;            /* 1: the calibration could not be used (unreadable, or fitted from a
                               strip other than this trial's): the event is a warning */
} trial_specimen_calib_use;

/* calibration_json: the specimen's (store_specimen.calibration_json; "" = none). measured: the
 * prediction's scene as measured (trial_specimen_scene), creases: where its creases came from;
 * sc (in: that scene at the prediction's resolution) gets the calibrated values. Returns the
 * number of values applied; a calibration that cannot be read or is stale applies none and says
 * why in use->message. */
int trial_specimen_calib_apply(const char *calibration_json, const rod_scene *measured, const store_creases *creases,
                               rod_scene *sc, trial_specimen_calib_use *use);

#endif
