/* ctl_calibrate_joint.h: `ribbonctl calibrate ID [ID ...] --share-hinge` (ctl_calibrate_joint.c):
 * trials of several specimens grouped per specimen, each group one strip with its own
 * parameters, the hinge stiffness per unit width shared (sim/rod_fit_joint.h). */
#ifndef RIBBON_CTL_CALIBRATE_JOINT_H
#define RIBBON_CTL_CALIBRATE_JOINT_H

#include <stdint.h>

#include "trial.h"
#include "rod_fit.h"
#include "store.h"

typedef struct ctl_calib_joint_args {
    const int64_t *ids;
    int nids;
    const trial_pool_select *sel;  /* the cuts and --set, for every trial */
    const char *fit_keys;         /* --fit's list, or NULL: each specimen's first trial's sim.fit_keys
                                     (as without --share-hinge; folds.hinge_stiffness there: the
                                     shared one). Every specimen must come to the same keys. */
    rod_fit_opts fit;             /* noise, scale_covariance (fit[] is set from fit_keys) */
    int json, no_snap;
    const char *write_scene;      /* NULL, or FILE: one scene per specimen, FILE's name with
                                     "-specimen<ID>" before its extension */
} ctl_calib_joint_args;

/* Reads, fits and prints. Returns the exit code (0; 1 with the reason on stderr). */
int ctl_calibrate_joint(store *st, const ctl_calib_joint_args *a);

#endif
