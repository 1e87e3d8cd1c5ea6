/* trial_pool.h: stored trials pooled into one fit's input (trial_pool.c): one strip's scene and
 * the observations of it in several trials, with a named refusal for every trial that cannot be
 * calibrated. Used by `ribbonctl calibrate` and by ribbond's refit of a specimen after each of
 * its trials (trial_specimen_calib.h). */
#ifndef RIBBON_TRIAL_POOL_H
#define RIBBON_TRIAL_POOL_H

#include <stddef.h>
#include <stdint.h>

#include "rod_fit.h"
#include "store.h"

typedef struct trial_pool_select {
    double dw_max;      /* last Delta W used; NaN: 0.8 of the measured snap (the whole shear when
                           the trial did not snap); never at or past the measured snap */
    double dl_min;      /* first Delta L used; NaN: 0.8 of the trial's largest Delta L (the hold) */
    int max_samples;    /* per trial, thinned evenly in time beyond it */
    int min_samples;    /* per trial: fewer is "too few samples" */
    const char *const *sets; /* "section.key=value" applied to the reconstructed scene */
    int n_sets;
} trial_pool_select;

trial_pool_select trial_pool_select_default(void);

/* One trial's part in the fit. */
typedef struct trial_pool_trial {
    int64_t id;
    char mode[8], status[16];
    int64_t specimen_id;
    char specimen[64];
    int64_t prediction_of;  /* the trial whose prediction gave the creases (a replay: its source); 0: none */
    long frames;            /* camera frames with Delta L, Delta W, Delta Z and A measured */
    int used;               /* observations taken */
    double dl_min, dw_max;  /* the cut applied */
    double dl_hold;         /* the largest Delta L filmed */
    double snap_measured;   /* NaN: did not snap (or not measured) */
    double snap_predicted;  /* the stored prediction's; NaN: none */
    const char *regime_measured; /* "symmetric", ...; "-" */
    double fit_hinge;       /* its in-trial fit's sim.fit_hinge (N m/rad; 0: the scene's creases) */
    char fit_keys[256];     /* its in-trial fit's sim.fit_keys ("": the default keys) */
    char fit_unread[256];   /* why those two could not be read from its stored rig file ("": read;
                               then 0 and "", the rig defaults) */
} trial_pool_trial;

typedef struct trial_pool {
    rod_scene scene;        /* the strip: the first trial's reconstructed scene (its fit setup,
                               trials[0].fit_hinge and fit_keys, is the pool's: trial_calibrate_setup) */
    rod_fit_obs *obs;       /* every trial's observations, in trial order (malloc'ed) */
    int nobs;
    trial_pool_trial *trials;/* malloc'ed, ntrials */
    int ntrials;
} trial_pool;

/* Reads trials ids[0..n) from st into out. Returns 0, or -1 with the reason in why (named: no
 * such trial, an unfinished trial, a trial's stored scene unreadable or refused by the
 * overrides, too few samples, a strip in the lower state, trials of different specimens or
 * strips). out is freed on failure. */
int trial_pool_load(store *st, const int64_t *ids, int n, const trial_pool_select *sel, trial_pool *out,
                   char *why, size_t why_len);
void trial_pool_free(trial_pool *d);

#endif
