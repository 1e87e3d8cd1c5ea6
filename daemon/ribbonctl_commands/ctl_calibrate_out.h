/* ctl_calibrate_out.h: what `ribbonctl calibrate` prints and writes as JSON for one strip's fit,
 * shared by the one-strip path (ctl_calibrate.c) and the joint one (ctl_calibrate_joint.c), so the
 * two outputs cannot drift apart (ctl_calibrate_out.c). */
#ifndef RIBBON_CTL_CALIBRATE_OUT_H
#define RIBBON_CTL_CALIBRATE_OUT_H

#include <jansson.h>
#include <stddef.h>

#include "rod_fit.h"
#include "rod_fit_snap.h"
#include "trial.h"

/* A parameter's value in its natural units (exp of the fit's ln for a log key). */
double ctl_calib_natural(int k, double u);
/* v, or JSON null when it is not finite (never NaN in JSON). */
json_t *ctl_calib_num_or_null(double v);
/* One pooled trial's record in the JSON output. */
json_t *ctl_calib_trial_json(const trial_pool_trial *t);
/* The calibrated snap with its band and P(other) in the JSON output. */
json_t *ctl_calib_snap_json(const rod_fit_snap *s);
/* A parameter's standard error as text: relative for a log key, "not determined by these data",
 * or "prior only" when only its prior bounds it. */
void ctl_calib_se_text(int k, const rod_fit_result *r, char *se, size_t len);
/* The calibrated snap's lines and, per trial of d, the measured snap against it and against the
 * trial's stored prediction; each line starts with indent. */
void ctl_calib_print_snap(const rod_fit_snap *s, const trial_pool *d, const char *indent);

#endif
