/* ctl_calibrate_out.c: the output pieces `ribbonctl calibrate` shares between one strip and the
 * joint fit (ctl_calibrate_out.h). */
#include "ctl_calibrate_out.h"

#include <math.h>
#include <stdio.h>

double ctl_calib_natural(int k, double u)
{
    return rod_fit_key_log(k) ? exp(u) : u;
}

json_t *ctl_calib_num_or_null(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

json_t *ctl_calib_trial_json(const trial_pool_trial *t)
{
    return json_pack("{s:I, s:s, s:s, s:s, s:I, s:I, s:o, s:o, s:o, s:o, s:o, s:s}", "id", (json_int_t)t->id, "mode",
                     t->mode, "status", t->status, "specimen", t->specimen, "frames", (json_int_t)t->frames, "samples",
                     (json_int_t)t->used, "dl_min", ctl_calib_num_or_null(t->dl_min), "dw_max",
                     ctl_calib_num_or_null(t->dw_max), "snap_dw_measured", ctl_calib_num_or_null(t->snap_measured),
                     "snap_dw_predicted", ctl_calib_num_or_null(t->snap_predicted), "prediction_of",
                     t->prediction_of ? json_integer(t->prediction_of) : json_null(), "regime_measured",
                     t->regime_measured);
}

json_t *ctl_calib_snap_json(const rod_fit_snap *s)
{
    json_t *o = json_object();
    json_object_set_new(o, "snapped", json_boolean(s->snapped));
    if (s->snapped) {
        json_object_set_new(o, "snap_dw", json_real(s->snap_dw));
        json_object_set_new(o, "regime", json_string(s->asymmetric ? "asymmetric" : "symmetric"));
    }
    json_object_set_new(o, "band", json_boolean(s->band_ok));
    if (s->snapped && s->band_ok) {
        json_object_set_new(o, "snap_sd", json_real(s->snap_sd));
        json_object_set_new(o, "snap_lo_2sigma", json_real(s->snap_dw - 2.0 * s->snap_sd));
        json_object_set_new(o, "snap_hi_2sigma", json_real(s->snap_dw + 2.0 * s->snap_sd));
        json_object_set_new(o, "p_other_regime", json_real(s->p_other));
    }
    if (s->note[0]) json_object_set_new(o, "note", json_string(s->note));
    return o;
}

void ctl_calib_se_text(int k, const rod_fit_result *r, char *se, size_t len)
{
    if (!isfinite(r->se[k])) snprintf(se, len, "not determined by these data");
    else if (rod_fit_key_log(k)) snprintf(se, len, "%.3g%% (relative)", 100.0 * r->se[k]);
    else snprintf(se, len, "%.3g%s", r->se[k], r->determined[k] ? "" : " (prior only: not determined by these data)");
}

void ctl_calib_print_snap(const rod_fit_snap *s, const trial_pool *d, const char *indent)
{
    if (!s->snapped) {
        printf("%scalibrated   none before protocol.shear_max (%s)\n", indent, s->note);
        return;
    }
    const char *reg = s->asymmetric ? "asymmetric" : "symmetric", *other = s->asymmetric ? "symmetric" : "asymmetric";
    if (s->band_ok)
        printf("%scalibrated   snap Delta W %.5f +- %.5f (1 sigma; 2 sigma %.5f .. %.5f), %s; P(%s) = %.3g%s%s\n", indent,
               s->snap_dw, s->snap_sd, s->snap_dw - 2.0 * s->snap_sd, s->snap_dw + 2.0 * s->snap_sd, reg, other,
               s->p_other, s->note[0] ? "; " : "", s->note);
    else
        printf("%scalibrated   snap Delta W %.5f, %s (no band: %s)\n", indent, s->snap_dw, reg, s->note);
    for (int k = 0; k < d->ntrials; k++) {
        const trial_pool_trial *t = &d->trials[k];
        if (!isfinite(t->snap_measured)) {
            printf("%s  trial %-5lld measured: no snap\n", indent, (long long)t->id);
            continue;
        }
        printf("%s  trial %-5lld measured %.5f (%s): calibrated %+.2f%%", indent, (long long)t->id, t->snap_measured,
               t->regime_measured, 100.0 * (s->snap_dw - t->snap_measured) / t->snap_measured);
        if (s->band_ok && s->snap_sd > 0.0) printf(" (%.1f sigma)", fabs(s->snap_dw - t->snap_measured) / s->snap_sd);
        if (isfinite(t->snap_predicted))
            printf(", scene's prediction %.5f (%+.2f%%)", t->snap_predicted,
                   100.0 * (t->snap_predicted - t->snap_measured) / t->snap_measured);
        printf("\n");
    }
}
