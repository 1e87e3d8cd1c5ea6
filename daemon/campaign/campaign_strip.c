/* campaign_strip.c: the lab strip pooled from the specimens' fits, its scene, its trace's key and
 * its boundary at a design phi (campaign_strip.h). */
#include "campaign_strip.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* No fit's standard error counts below SE_FLOOR times the median of the pooled fits' (so no one
 * fit weighs more than 1 / SE_FLOOR^2 = 4 typical ones): the trials share one protocol, and a fit
 * stating an error twenty times below the others' is more likely overconfident than better
 * informed (measured: the hinge bench, seed 3, a twin at phi 60 fitted 59.5 +- 0.4 deg and k
 * 2.3e-3 +- 1% where the twin had 53.5 deg and 5e-3, and the others +- 20-75%; unfloored it set
 * the lab strip's hinge to 2.34e-3 +- 2%). */
#define SE_FLOOR 0.5

static void fit_clear(campaign_strip_fit *f, double design_phi_deg)
{
    *f = (campaign_strip_fit){.design_phi_deg = design_phi_deg, .angle_mean_deg = NAN, .angle_se_deg = NAN,
                              .angle_scene_deg = NAN, .ln_hinge = NAN, .ln_hinge_se = NAN, .hinge_scene = NAN, .ln_youngs = NAN,
                              .ln_youngs_se = NAN};
}

/* One parameter as the fit left it: usable when fitted, determined, not at a bound, with a finite
 * standard error > 0. */
typedef struct par {
    int usable;
    double scene, fitted, se; /* key units; se absolute (angles) or relative (log keys) */
} par;

/* The pooled parameters of one fit from its per-key values (angles left/right, hinge, hinges
 * left/right, E); 1 when any is usable. */
static int fill(campaign_strip_fit *f, const par *al, const par *ar, const par *h, const par *hl, const par *hr,
                const par *e)
{
    if (al->usable && ar->usable) {
        f->angle_mean_deg = 0.5 * (fabs(al->fitted) + fabs(ar->fitted));
        f->angle_se_deg = 0.5 * (al->se + ar->se);
        f->angle_scene_deg = 0.5 * (fabs(al->scene) + fabs(ar->scene));
    } else if (al->usable || ar->usable) {
        const par *p = al->usable ? al : ar;
        f->angle_mean_deg = fabs(p->fitted);
        f->angle_se_deg = p->se;
        f->angle_scene_deg = fabs(p->scene);
    }
    if (h->usable && h->fitted > 0) {
        f->ln_hinge = log(h->fitted);
        f->ln_hinge_se = h->se;
        f->hinge_scene = h->scene;
    } else if (hl->usable && hr->usable && hl->fitted > 0 && hr->fitted > 0) {
        f->ln_hinge = 0.5 * (log(hl->fitted) + log(hr->fitted));
        f->ln_hinge_se = 0.5 * (hl->se + hr->se);
        f->hinge_scene = sqrt(hl->scene * hr->scene);
    }
    if (e->usable && e->fitted > 0) {
        f->ln_youngs = log(e->fitted);
        f->ln_youngs_se = e->se;
    }
    return isfinite(f->angle_mean_deg) || isfinite(f->ln_hinge) || isfinite(f->ln_youngs);
}

/* The parameters array of a record whose entries name their start value scene_key and their
 * fitted value value_key (a trial's fit: "scene", "fitted"; a specimen's calibration: "start",
 * "value", either may be null there) into out; what as fit_parse's. */
static int parse_parameters(const json_t *ps, const char *what, const char *scene_key, int nullable,
                            const char *value_key, campaign_strip_fit *out, char *why, size_t why_len)
{
    if (!json_is_array(ps)) {
        snprintf(why, why_len, "%s: \"parameters\" is not an array", what);
        return -1;
    }
    par p[ROD_FIT_NKEYS];
    memset(p, 0, sizeof p);
    size_t i;
    json_t *v;
    json_array_foreach(ps, i, v) {
        const char *key = json_string_value(json_object_get(v, "key"));
        if (!key) {
            snprintf(why, why_len, "%s: parameter %zu has no \"key\"", what, i);
            return -1;
        }
        int k = rod_fit_key_parse(key);
        if (k < 0) continue; /* a key this build does not know: not pooled */
        json_t *sc = json_object_get(v, scene_key), *fv = json_object_get(v, value_key), *se = json_object_get(v, "se");
        json_t *det = json_object_get(v, "determined"), *ab = json_object_get(v, "at_bound");
        int sc_ok = json_is_number(sc) || (nullable && json_is_null(sc));
        int fv_ok = json_is_number(fv) || (nullable && json_is_null(fv));
        if (!sc_ok || !fv_ok) {
            snprintf(why, why_len, "%s: parameter %s has no numeric \"%s\" and \"%s\"", what, key, scene_key,
                     value_key);
            return -1;
        }
        p[k].scene = json_is_number(sc) ? json_number_value(sc) : NAN;
        p[k].fitted = json_is_number(fv) ? json_number_value(fv) : NAN;
        p[k].se = json_is_number(se) ? json_number_value(se) : INFINITY; /* null: not determined */
        p[k].usable = json_is_true(det) && (!ab || json_integer_value(ab) == 0) && isfinite(p[k].se) &&
                      p[k].se > 0 && isfinite(p[k].fitted);
    }
    return fill(out, &p[ROD_FIT_ANGLE_LEFT], &p[ROD_FIT_ANGLE_RIGHT], &p[ROD_FIT_HINGE], &p[ROD_FIT_HINGE_LEFT],
                &p[ROD_FIT_HINGE_RIGHT], &p[ROD_FIT_YOUNGS]);
}

int campaign_strip_fit_parse(const json_t *fit, double design_phi_deg, campaign_strip_fit *out, char *why,
                             size_t why_len)
{
    fit_clear(out, design_phi_deg);
    if (!json_is_object(fit)) {
        snprintf(why, why_len, "fit: not a JSON object");
        return -1;
    }
    json_t *ok = json_object_get(fit, "ok");
    if (!json_is_true(ok)) return 0; /* a failed fit stores its reason, no numbers */
    return parse_parameters(json_object_get(fit, "parameters"), "fit", "scene", 0, "fitted", out, why, why_len);
}

int campaign_strip_calibration_parse(const json_t *cal, double design_phi_deg, campaign_strip_fit *out, char *why,
                                     size_t why_len)
{
    fit_clear(out, design_phi_deg);
    out->from_calibration = 1;
    if (!json_is_object(cal)) {
        snprintf(why, why_len, "calibration: not a JSON object");
        return -1;
    }
    json_t *after = json_object_get(cal, "after_trial");
    if (json_is_integer(after)) out->trial_id = json_integer_value(after);
    return parse_parameters(json_object_get(cal, "parameters"), "calibration", "start", 1, "value", out, why,
                            why_len);
}

int campaign_strip_fit_from_result(const rod_fit_result *r, double design_phi_deg, campaign_strip_fit *out)
{
    fit_clear(out, design_phi_deg);
    par p[ROD_FIT_NKEYS];
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        int lg = rod_fit_key_log(k);
        p[k].scene = lg ? exp(r->u0[k]) : r->u0[k];
        p[k].fitted = lg ? exp(r->u[k]) : r->u[k];
        p[k].se = r->se[k];
        p[k].usable = r->fitted[k] && r->determined[k] && !r->at_bound[k] && isfinite(r->se[k]) && r->se[k] > 0;
    }
    return fill(out, &p[ROD_FIT_ANGLE_LEFT], &p[ROD_FIT_ANGLE_RIGHT], &p[ROD_FIT_HINGE], &p[ROD_FIT_HINGE_LEFT],
                &p[ROD_FIT_HINGE_RIGHT], &p[ROD_FIT_YOUNGS]);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The floor of the standard errors pooled: SE_FLOOR times their median. */
static double se_floor(const double *x, const double *s, size_t n)
{
    double *v = malloc((n ? n : 1) * sizeof *v);
    if (!v) return 0;
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(x[i]) && isfinite(s[i]) && s[i] > 0) v[m++] = s[i];
    double f = 0;
    if (m) {
        qsort(v, m, sizeof *v, cmp_double);
        f = SE_FLOOR * (m % 2 ? v[m / 2] : 0.5 * (v[m / 2 - 1] + v[m / 2]));
    }
    free(v);
    return f;
}

/* Inverse-variance weighted mean of x (se s, floored at se_floor) over n values, its standard
 * error with the Birge ratio (above 1 only). Values with a non-finite x or s are skipped; *used
 * gets how many. */
static void pool(const double *x, const double *s_in, size_t n, double *mean, double *se, int *used)
{
    double sw = 0, swx = 0, fl = se_floor(x, s_in, n);
    int m = 0;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(x[i]) || !isfinite(s_in[i]) || !(s_in[i] > 0)) continue;
        double si = fmax(s_in[i], fl), w = 1 / (si * si);
        sw += w, swx += w * x[i], m++;
    }
    *used = m;
    if (!m) {
        *mean = *se = NAN;
        return;
    }
    *mean = swx / sw;
    double chi2 = 0;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(x[i]) || !isfinite(s_in[i]) || !(s_in[i] > 0)) continue;
        double z = (x[i] - *mean) / fmax(s_in[i], fl);
        chi2 += z * z;
    }
    double birge = m > 1 ? sqrt(chi2 / (m - 1)) : 1;
    *se = (birge > 1 ? birge : 1) / sqrt(sw);
}

/* v rounded to 3 significant digits (the trace cache's key). */
static double round3(double v)
{
    char b[32];
    snprintf(b, sizeof b, "%.2e", v);
    return strtod(b, NULL);
}

void campaign_strip_pool(const campaign_strip_fit *fits, size_t n, campaign_lab_strip *out)
{
    *out = (campaign_lab_strip){.relax_deg = 0, .relax_se = NAN, .hinge = NAN, .hinge_se_rel = NAN,
                                .youngs = NAN, .youngs_se_rel = NAN};
    double *x = malloc(3 * (n ? n : 1) * sizeof *x), *s = malloc(3 * (n ? n : 1) * sizeof *s);
    if (!x || !s) { /* out of memory: the scene's strip, said by n_fits 0 */
        free(x), free(s);
        return;
    }
    for (size_t i = 0; i < n; i++) {
        const campaign_strip_fit *f = &fits[i];
        double design = isfinite(f->design_phi_deg) ? f->design_phi_deg : f->angle_scene_deg;
        x[i] = design - f->angle_mean_deg, s[i] = f->angle_se_deg;
        x[n + i] = f->ln_hinge, s[n + i] = f->ln_hinge_se;
        x[2 * n + i] = f->ln_youngs, s[2 * n + i] = f->ln_youngs_se;
        if ((isfinite(x[i]) && isfinite(s[i])) || (isfinite(x[n + i]) && isfinite(s[n + i])) ||
            (isfinite(x[2 * n + i]) && isfinite(s[2 * n + i]))) {
            out->n_fits++;
            out->n_calibrations += f->from_calibration != 0;
        }
    }
    double m, se;
    pool(x, s, n, &m, &se, &out->n_relax);
    if (out->n_relax) out->relax_deg = m, out->relax_se = se;
    pool(x + n, s + n, n, &m, &se, &out->n_hinge);
    if (out->n_hinge) out->hinge = round3(exp(m)), out->hinge_se_rel = se;
    pool(x + 2 * n, s + 2 * n, n, &m, &se, &out->n_youngs);
    if (out->n_youngs) out->youngs = round3(exp(m)), out->youngs_se_rel = se;
    free(x), free(s);
}

void campaign_strip_apply(const rod_scene *sc, const campaign_lab_strip *ls, rod_scene *out)
{
    *out = *sc;
    if (isfinite(ls->hinge)) {
        out->fold_hinge_stiffness = ls->hinge;
        out->fold_hinge_stiffness_left = out->fold_hinge_stiffness_right = NAN;
    }
    if (isfinite(ls->youngs)) {
        out->shear_modulus *= ls->youngs / sc->youngs_modulus;
        out->youngs_modulus = ls->youngs;
    }
}

int campaign_strip_needs_trace(const campaign_lab_strip *ls)
{
    return isfinite(ls->hinge) || isfinite(ls->youngs);
}

void campaign_strip_key(const campaign_lab_strip *ls, char *out, size_t out_len)
{
    char h[32] = "scene", e[32] = "scene";
    if (isfinite(ls->hinge)) snprintf(h, sizeof h, "%.2e", ls->hinge);
    if (isfinite(ls->youngs)) snprintf(e, sizeof e, "%.2e", ls->youngs);
    snprintf(out, out_len, "hinge=%s youngs=%s", h, e);
}

void campaign_strip_describe(const campaign_lab_strip *ls, char *out, size_t out_len)
{
    if (!ls->n_fits) {
        snprintf(out, out_len, "the scene's (no usable calibration)");
        return;
    }
    char a[96] = "creases the scene's (no fit determined them)", h[96] = "hinge the scene's", e[64] = "E the scene's";
    if (ls->n_relax) snprintf(a, sizeof a, "creases relaxed %.2f +- %.2f deg (%d fits)", ls->relax_deg, ls->relax_se, ls->n_relax);
    if (ls->n_hinge) snprintf(h, sizeof h, "hinge %.2e N m/rad +- %.1f%% (%d fits)", ls->hinge, 100 * ls->hinge_se_rel, ls->n_hinge);
    if (ls->n_youngs) snprintf(e, sizeof e, "E %.3g Pa +- %.1f%% (%d fits)", ls->youngs, 100 * ls->youngs_se_rel, ls->n_youngs);
    snprintf(out, out_len, "%s, %s, %s", a, h, e);
}

int campaign_strip_at(const campaign_predicted *curve, const campaign_lab_strip *ls, double phi_deg, double *gamma,
                      char *why, size_t why_len)
{
    double at = phi_deg - (ls->n_relax ? ls->relax_deg : 0);
    char w[600];
    if (campaign_predicted_at(curve, at, gamma, w, sizeof w)) {
        if (ls->n_relax) snprintf(why, why_len, "phi %g deg (the lab strip's creases at %g deg): %s", phi_deg, at, w);
        else snprintf(why, why_len, "%s", w);
        return -1;
    }
    return 0;
}

int campaign_strip_trace(const rod_scene *lab, const campaign_lab_strip *ls, double phi0, const double *g, size_t ng,
                         double phi_lo, double phi_hi, const double *need, size_t nneed, campaign_predicted *out,
                         char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    size_t used = 0;
    why[0] = '\0';
    for (size_t i = 0; i < ng; i++) {
        rod_scene sc = *lab;
        sc.fold_angle_deg = (lab->fold_angle_deg < 0 ? -1.0 : 1.0) * phi0;
        sc.fold_angle_left_deg = sc.fold_angle_right_deg = NAN;
        sc.fold_position = g[i];
        sc.fold_position_left = sc.fold_position_right = NAN;
        char w[700];
        campaign_predicted c;
        int rc = campaign_predicted_trace(&sc, phi_lo, phi_hi, &c, w, sizeof w);
        if (rc == 0) {
            double gg;
            size_t j = 0;
            while (j < nneed && campaign_strip_at(&c, ls, need[j], &gg, w, sizeof w) == 0) j++;
            if (j == nneed) {
                *out = c;
                return 0;
            }
            campaign_predicted_free(&c);
        }
        int n = snprintf(why + used, why_len - used, "%sfrom (%g deg, Gamma %.4f): %.*s", i ? "; " : "", phi0, g[i],
                         i + 1 < ng ? 120 : 600, w);
        if (n > 0) used += (size_t)n < why_len - used ? (size_t)n : why_len - used - 1;
    }
    if (!ng) snprintf(why, why_len, "no start to trace the lab strip's boundary from");
    return -1;
}

/* The specimen's design angle by name (NaN: none, or no such specimen). */
static double design_of(const store_specimen *sp, size_t nsp, const char *name)
{
    for (size_t s = 0; name && s < nsp; s++)
        if (!strcmp(sp[s].name, name)) return sp[s].phi_deg;
    return NAN;
}

int campaign_strip_collect(store *st, campaign_strip_fit **out, size_t *n, int *n_failed, char *why, size_t why_len)
{
    *out = NULL;
    *n = 0;
    *n_failed = 0;
    json_t *trials = NULL;
    if (store_trials_json(st, &trials, why, why_len) != STORE_OK) return -1;
    store_specimen *sp = NULL;
    size_t nsp = 0;
    if (store_specimen_list(st, &sp, &nsp, why, why_len) != STORE_OK) {
        json_decref(trials);
        return -1;
    }
    size_t cap = json_array_size(trials) + nsp;
    campaign_strip_fit *f = calloc(cap ? cap : 1, sizeof *f);
    char *calibrated = calloc(nsp ? nsp : 1, 1); /* 1: the specimen's calibration stands for its trials */
    if (!f || !calibrated) {
        json_decref(trials), free(sp), free(f), free(calibrated);
        snprintf(why, why_len, "lab strip: out of memory");
        return -1;
    }
    char w[300];
    /* One record per specimen: its calibration (the newest: a refit replaces it, a failed refit
     * keeps the one before), when it determined some parameter. */
    for (size_t s = 0; s < nsp; s++) {
        if (!sp[s].calibration_json[0]) continue;
        json_t *cal = json_loads(sp[s].calibration_json, 0, NULL);
        int rc = cal ? campaign_strip_calibration_parse(cal, sp[s].phi_deg, &f[*n], w, sizeof w) : -1;
        if (!cal) snprintf(w, sizeof w, "not JSON");
        json_decref(cal);
        if (rc < 0) {
            snprintf(why, why_len, "specimen %s's stored calibration: %s", sp[s].name, w);
            json_decref(trials), free(sp), free(f), free(calibrated);
            *n = 0;
            return -1;
        }
        if (rc == 1) {
            calibrated[s] = 1;
            (*n)++;
        }
    }
    /* The trials of specimens without one (and without a specimen), each by its own fit. */
    size_t i;
    json_t *t;
    json_array_foreach(trials, i, t) {
        const char *name = json_string_value(json_object_get(t, "specimen"));
        size_t s = 0;
        while (name && s < nsp && strcmp(sp[s].name, name)) s++;
        if (name && s < nsp && calibrated[s]) continue;
        json_t *fit = json_object_get(t, "fit");
        if (!json_is_object(fit)) {
            if (json_is_string(json_object_get(t, "fit_failure"))) (*n_failed)++;
            continue;
        }
        int rc = campaign_strip_fit_parse(fit, design_of(sp, nsp, name), &f[*n], w, sizeof w);
        if (rc < 0) {
            snprintf(why, why_len, "trial %lld's stored fit: %s", (long long)json_integer_value(json_object_get(t, "id")), w);
            json_decref(trials), free(sp), free(f), free(calibrated);
            *n = 0;
            return -1;
        }
        if (rc == 0) {
            (*n_failed)++;
            continue;
        }
        f[*n].trial_id = json_integer_value(json_object_get(t, "id"));
        (*n)++;
    }
    json_decref(trials);
    free(sp), free(calibrated);
    *out = f;
    return 0;
}
