/* trial_report.c: report figures from the store (see trial_report.h). */
#include "trial_report.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <jansson.h>

#include "plot.h"
#include "rod_protocol.h"

trial_err trial_report_png(store *st, int64_t id, const char *png_path, char *why, size_t why_len)
{
    store_trial t;
    store_err e = store_trial_get(st, id, &t, why, why_len);
    if (e != STORE_OK) return e == STORE_E_NOTFOUND ? TRIAL_E_NOTFOUND : TRIAL_E_FAILED;
    store_curve meas = {0}, pred = {0};
    if (store_trial_curve(st, id, &meas, why, why_len) != STORE_OK) return TRIAL_E_FAILED;
    /* Only the shear: frames from the start of shearing to the return (the compression's frames
     * are at Delta W = 0 and the return's retrace the lower branch). */
    double t_check, t_shear, t_return;
    store_events_state_times(st, id, &t_check, &t_shear, &t_return);
    if (isfinite(t_shear)) {
        size_t m = 0;
        for (size_t k = 0; k < meas.n; k++) {
            if (meas.t_s[k] < t_shear || (isfinite(t_return) && meas.t_s[k] >= t_return)) continue;
            meas.t_s[m] = meas.t_s[k];
            meas.dw[m] = meas.dw[k];
            meas.dz[m] = meas.dz[k];
            meas.a[m] = meas.a[k];
            m++;
        }
        meas.n = m;
    }
    store_prediction p = store_prediction_default();
    int have_pred = store_prediction_get_by_trial(st, id, &p, why, why_len) == STORE_OK;
    if (have_pred) pred = p.curve;
    char title[160];
    snprintf(title, sizeof title, "trial %lld (%s%s%s)", (long long)id, store_mode_name(t.mode),
             t.specimen_name[0] ? ", " : "", t.specimen_name);
    plot_trial_data d;
    plot_trial_data_default(&d);
    d.title = title;
    d.measured.dw = meas.dw;
    d.measured.dz = meas.dz;
    d.measured.a = meas.a;
    d.measured.n = meas.n;
    d.predicted.dw = pred.dw;
    d.predicted.dz = pred.dz;
    d.predicted.a = pred.a;
    d.predicted.n = pred.n;
    d.snap_dw_measured = t.snapped == 1 ? t.snap_dw_measured : NAN;
    d.snap_dw_predicted = have_pred && p.snapped ? p.snap_dw : NAN;
    d.regime_measured = store_regime_name(t.regime_measured);
    d.regime_predicted = have_pred ? store_regime_name(p.regime) : NULL;
    /* The calibrated prediction beside the scene's (issue 32 B), from the trial's JSON view. */
    json_t *tj = NULL;
    char w2[256];
    char reg_cal[16] = "";
    if (store_trial_json(st, id, &tj, w2, sizeof w2) == STORE_OK) {
        json_t *c = json_object_get(tj, "snap_dw_calibrated"), *sd = json_object_get(tj, "snap_sd_calibrated");
        if (json_is_number(c)) d.snap_dw_calibrated = json_number_value(c);
        if (json_is_number(c) && json_is_number(sd)) d.snap_sd_calibrated = json_number_value(sd);
        const char *rc = json_string_value(json_object_get(tj, "regime_calibrated"));
        if (rc) snprintf(reg_cal, sizeof reg_cal, "%s", rc);
        d.regime_calibrated = rc ? reg_cal : NULL;
        json_decref(tj);
    }
    plot_status ps = plot_trial_report(png_path, &d, why, why_len);
    store_curve_free(&meas);
    if (have_pred) store_prediction_free(&p);
    return ps == PLOT_OK ? TRIAL_OK : TRIAL_E_FAILED;
}

/* What a figure drawn to a file is as bytes: draw(...) into a temporary file, read it back. */
typedef struct png_job {
    store *st;
    int64_t id;             /* the trial report's */
    const phase_grid *grid; /* the phase report's */
} png_job;

static trial_err draw_trial(const png_job *j, const char *path, char *why, size_t why_len)
{
    return trial_report_png(j->st, j->id, path, why, why_len);
}

static trial_err draw_phase(const png_job *j, const char *path, char *why, size_t why_len)
{
    return trial_phase_report_png(j->st, j->grid, path, why, why_len) == 0 ? TRIAL_OK : TRIAL_E_FAILED;
}

static trial_err png_bytes(trial_err (*draw)(const png_job *, const char *, char *, size_t), const png_job *j,
                           unsigned char **png, size_t *len, char *why, size_t why_len)
{
    char path[] = "/tmp/ribbon-report-XXXXXX.png";
    int fd = mkstemps(path, 4);
    if (fd < 0) {
        snprintf(why, why_len, "report: no temporary file: %m");
        return TRIAL_E_FAILED;
    }
    close(fd);
    trial_err rc = draw(j, path, why, why_len);
    if (rc == TRIAL_OK) {
        FILE *f = fopen(path, "rb");
        long n = -1;
        if (f && fseek(f, 0, SEEK_END) == 0) n = ftell(f);
        if (f) rewind(f);
        *png = n > 0 ? malloc((size_t)n) : NULL;
        if (!f || n <= 0 || !*png || fread(*png, 1, (size_t)n, f) != (size_t)n) {
            free(*png);
            *png = NULL;
            snprintf(why, why_len, "report: could not read the image back");
            rc = TRIAL_E_FAILED;
        } else {
            *len = (size_t)n;
        }
        if (f) fclose(f);
    }
    unlink(path);
    return rc;
}

trial_err trial_report_png_bytes(store *st, int64_t id, unsigned char **png, size_t *len, char *why, size_t why_len)
{
    png_job j = {.st = st, .id = id};
    return png_bytes(draw_trial, &j, png, len, why, why_len);
}

int trial_phase_report_png_bytes(store *st, const phase_grid *grid, unsigned char **png, size_t *len, char *why,
                                 size_t why_len)
{
    png_job j = {.st = st, .grid = grid};
    return png_bytes(draw_phase, &j, png, len, why, why_len) == TRIAL_OK ? 0 : -1;
}

int trial_phase_report_png(store *st, const phase_grid *grid, const char *png_path, char *why, size_t why_len)
{
    store_trial *list = NULL;
    size_t n = 0;
    if (store_trial_list(st, &list, &n, why, why_len) != STORE_OK) return -1;
    plot_phase_trial *pts = calloc(n ? n : 1, sizeof *pts);
    if (!pts) {
        free(list);
        snprintf(why, why_len, "phase report: out of memory");
        return -1;
    }
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        if (list[k].snapped < 0) continue; /* not measured */
        char *cal = NULL;
        char w[256];
        if (store_trial_texts(st, list[k].id, NULL, &cal, w, sizeof w) != STORE_OK || !cal) {
            free(cal);
            continue;
        }
        json_error_t je;
        json_t *o = json_loads(cal, 0, &je);
        free(cal);
        json_t *phi = json_object_get(o, "fold_angle_deg"), *g = json_object_get(o, "fold_position");
        if (json_is_number(phi) && json_is_number(g)) {
            pts[m].gamma = json_number_value(g);
            pts[m].phi_deg = fabs(json_number_value(phi));
            pts[m].regime = list[k].regime_measured == STORE_REGIME_ASYMMETRIC ? PLOT_REGIME_ASYMMETRIC
                            : list[k].regime_measured == STORE_REGIME_SYMMETRIC ? PLOT_REGIME_SYMMETRIC
                            : list[k].regime_measured == STORE_REGIME_NO_SNAP   ? PLOT_REGIME_NO_SNAP
                                                                                : PLOT_REGIME_UNKNOWN;
            m++;
        }
        json_decref(o);
    }
    free(list);
    plot_phase_data d;
    plot_phase_data_default(&d);
    d.title = "measured regimes on the predicted phase diagram";
    plot_regime *codes = NULL;
    if (grid && grid->n_phi > 0) {
        codes = calloc(grid->n_phi * grid->n_gamma, sizeof *codes);
        if (codes) {
            for (size_t k = 0; k < grid->n_phi * grid->n_gamma; k++) codes[k] = (plot_regime)grid->regime[k];
            d.gamma = grid->gamma;
            d.n_gamma = grid->n_gamma;
            d.phi_deg = grid->phi_deg;
            d.n_phi = grid->n_phi;
            d.grid = codes;
        }
    }
    d.trials = pts;
    d.n_trials = m;
    plot_status ps = plot_phase_report(png_path, &d, why, why_len);
    free(codes);
    free(pts);
    return ps == PLOT_OK ? 0 : -1;
}
