/* ctl_calibrate_trials.h: what stored trials give `ribbonctl calibrate` (ctl_calibrate_trials.c):
 * one strip's scene and the observations of it, with a named refusal for every trial that
 * cannot be calibrated. */
#ifndef RIBBON_CTL_CALIBRATE_TRIALS_H
#define RIBBON_CTL_CALIBRATE_TRIALS_H

#include <stddef.h>
#include <stdint.h>

#include "rod_fit.h"
#include "store.h"

typedef struct ctl_calib_select {
    double dw_max;      /* last Delta W used; NaN: 0.8 of the measured snap (the whole shear when
                           the trial did not snap); never at or past the measured snap */
    double dl_min;      /* first Delta L used; NaN: 0.8 of the trial's largest Delta L (the hold) */
    int max_samples;    /* per trial, thinned evenly in time beyond it */
    int min_samples;    /* per trial: fewer is "too few samples" */
    const char *const *sets; /* "section.key=value" applied to the reconstructed scene */
    int n_sets;
} ctl_calib_select;

ctl_calib_select ctl_calib_select_default(void);

/* One trial's part in the fit. */
typedef struct ctl_calib_trial {
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
} ctl_calib_trial;

typedef struct ctl_calib_data {
    rod_scene scene;        /* the strip: the first trial's reconstructed scene */
    rod_fit_obs *obs;       /* every trial's observations, in trial order (malloc'ed) */
    int nobs;
    ctl_calib_trial *trials;/* malloc'ed, ntrials */
    int ntrials;
} ctl_calib_data;

/* Reads trials ids[0..n) from st into out. Returns 0, or -1 with the reason in why (named: no
 * such trial, an unfinished trial, a trial's stored scene unreadable or refused by the
 * overrides, too few samples, a strip in the lower state, trials of different specimens or
 * strips). out is freed on failure. */
int ctl_calib_load(store *st, const int64_t *ids, int n, const ctl_calib_select *sel, ctl_calib_data *out,
                   char *why, size_t why_len);
void ctl_calib_data_free(ctl_calib_data *d);

#endif
