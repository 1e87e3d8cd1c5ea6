/* trial_pool.c: stored trials turned into a fit's input (trial_pool.h); moved here from
 * ribbonctl's commands so that ribbond refits a specimen with the same reading.
 *
 * The strip: the scene file stored in the trial's config text with the scene overrides stored
 * there applied in order (trial_config_text_scene_load: the scene the trial ran), with the
 * creases its prediction used put back in (the specimen's measured angles and positions and the
 * hinge, store_creases: the prediction row is the record of what the trial's strip was
 * thought to be), then the user's --set overrides. A replay has no prediction of its own: its
 * source trial's is used. Several trials are one strip only when they are of one specimen and
 * their reconstructed strips agree (the protocol may differ); anything else is refused by name.
 *
 * The observations: camera frames with Delta L, Delta W, Delta Z and A all measured, before the
 * trial's return, from the hold's Delta L down to dl_min (the compression near the hold: at
 * small Delta L a strip under gravity may have no upper state, DESIGN.md section 9) and up to
 * the cut-off dw_max of the shear, never at or past the measured snap. A trial with more frames
 * than max_samples is thinned evenly (the fit's cost grows with its states; a hold of many
 * frames at one state adds noise averaging, not shape). */
#include "trial_pool.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_file.h"
#include "trial_config_text.h"

trial_pool_select trial_pool_select_default(void)
{
    trial_pool_select s;
    memset(&s, 0, sizeof s);
    s.dw_max = NAN;
    s.dl_min = NAN;
    s.max_samples = 200;
    s.min_samples = 4;
    return s;
}

void trial_pool_free(trial_pool *d)
{
    free(d->obs);
    free(d->trials);
    memset(d, 0, sizeof *d);
}

/* The trial's strip. */
static int trial_scene(store *st, const store_trial *t, const trial_pool_select *sel, rod_scene *out,
                       trial_pool_trial *ct, char *why, size_t why_len)
{
    char *text = NULL, w[512];
    if (store_trial_texts(st, t->id, &text, NULL, w, sizeof w) != STORE_OK) {
        snprintf(why, why_len, "trial %lld: %s", (long long)t->id, w);
        return -1;
    }
    char name[64];
    snprintf(name, sizeof name, "trial %lld's scene", (long long)t->id);
    rod_scene sc;
    cfg_error ce;
    int rc = trial_config_text_scene_load(text, name, &sc, w, sizeof w);
    /* The setup its in-trial fit had (the hinge guess, the keys), for a refit that reproduces it. */
    if (!rc && trial_config_text_fit(text, &ct->fit_hinge, ct->fit_keys, sizeof ct->fit_keys, ct->fit_unread,
                                     sizeof ct->fit_unread)) {
        ct->fit_hinge = 0.0;
        ct->fit_keys[0] = '\0';
    }
    free(text);
    if (rc) {
        snprintf(why, why_len, "trial %lld: %s", (long long)t->id, w);
        return -1;
    }
    int64_t *pred_of = &ct->prediction_of;
    double *snap_pred = &ct->snap_predicted;
    *pred_of = 0;
    *snap_pred = NAN;
    int64_t ids[2] = {t->id, t->source_trial_id};
    for (int k = 0; k < 2 && !*pred_of; k++) {
        store_prediction p;
        if (!ids[k] || store_prediction_get_by_trial(st, ids[k], &p, w, sizeof w) != STORE_OK) continue;
        const store_creases *c = &p.creases;
        double *angle[2] = {&sc.fold_angle_left_deg, &sc.fold_angle_right_deg};
        double *pos[2] = {&sc.fold_position_left, &sc.fold_position_right};
        for (int s = 0; s < 2; s++) {
            if (isfinite(c->angle_deg[s])) *angle[s] = c->angle_deg[s];
            if (isfinite(c->position[s])) *pos[s] = c->position[s];
        }
        if (!isnan(c->hinge_stiffness)) sc.fold_hinge_stiffness = c->hinge_stiffness;
        if (p.status == STORE_PREDICTION_DONE && p.snapped && k == 0) *snap_pred = p.snap_dw;
        *pred_of = ids[k];
        store_prediction_free(&p);
    }
    if (cfg_scene_apply(&sc, name, sel->sets, sel->n_sets, out, &ce) != CFG_OK) {
        cfg_error_format(&ce, w, sizeof w);
        snprintf(why, why_len, "trial %lld: %s", (long long)t->id, w);
        return -1;
    }
    return 0;
}

/* The first strip field in which a and b differ (the protocol and the solver may), or NULL. */
static const char *strip_differs(const rod_scene *a, const rod_scene *b)
{
#define SAME(f, name)                                                                                             \
    if (!(a->f == b->f || (isnan(a->f) && isnan(b->f)))) return name
    SAME(length, "ribbon.length");
    SAME(width, "ribbon.width");
    SAME(thickness, "ribbon.thickness");
    SAME(youngs_modulus, "ribbon.youngs_modulus");
    SAME(density, "ribbon.density");
    SAME(gravity[2], "ribbon.gravity");
    SAME(fold_angle_deg, "folds.angle_deg");
    SAME(fold_position, "folds.position");
    SAME(fold_angle_left_deg, "folds.angle_left_deg");
    SAME(fold_angle_right_deg, "folds.angle_right_deg");
    SAME(fold_position_left, "folds.position_left");
    SAME(fold_position_right, "folds.position_right");
    SAME(fold_hinge_stiffness, "folds.hinge_stiffness");
    SAME(fold_hinge_stiffness_left, "folds.hinge_stiffness_left");
    SAME(fold_hinge_stiffness_right, "folds.hinge_stiffness_right");
    SAME(fold_angle_rel, "imperfection.fold_angle_rel");
#undef SAME
    if (a->nodes != b->nodes) return "mesh.nodes";
    return NULL;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* The trial's observations appended to d->obs. */
static int trial_obs(store *st, const store_trial *t, const trial_pool_select *sel, trial_pool_trial *ct,
                     trial_pool *d, char *why, size_t why_len)
{
    store_sample *s = NULL;
    size_t n = 0;
    char w[512];
    if (store_samples_get(st, t->id, &s, &n, w, sizeof w) != STORE_OK) {
        snprintf(why, why_len, "trial %lld: %s", (long long)t->id, w);
        return -1;
    }
    double t_check, t_shear, t_return;
    store_events_state_times(st, t->id, &t_check, &t_shear, &t_return);
    (void)t_check;
    (void)t_shear;
    /* The frames measured before the return. */
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        const store_sample *x = &s[k];
        if (x->kind != STORE_SAMPLE_FRAME || !isfinite(x->dl) || !isfinite(x->dw) || !isfinite(x->dz) ||
            !isfinite(x->a) || (isfinite(t_return) && x->t_s >= t_return))
            continue;
        s[m++] = *x;
    }
    ct->frames = (long)m;
    double dl_hold = -INFINITY, dw_top = -INFINITY;
    for (size_t k = 0; k < m; k++) {
        dl_hold = fmax(dl_hold, s[k].dl);
        dw_top = fmax(dw_top, s[k].dw);
    }
    ct->dl_hold = m ? dl_hold : NAN;
    ct->dl_min = isnan(sel->dl_min) ? 0.8 * dl_hold : sel->dl_min;
    double snap = t->snapped == 1 ? t->snap_dw_measured : NAN;
    ct->dw_max = !isnan(sel->dw_max) ? sel->dw_max : isfinite(snap) ? 0.8 * snap : dw_top;
    /* Selected in time order. */
    size_t u = 0;
    for (size_t k = 0; k < m; k++)
        if (s[k].dl >= ct->dl_min && s[k].dw <= ct->dw_max && !(isfinite(snap) && s[k].dw >= snap)) s[u++] = s[k];
    if ((int)u < sel->min_samples) {
        snprintf(why, why_len,
                 "trial %lld: too few samples: %zu usable frame%s (Delta L >= %.4g, Delta W <= %.4g, before the snap and "
                 "the return; %ld frames measured in all), at least %d needed",
                 (long long)t->id, u, u == 1 ? "" : "s", ct->dl_min, ct->dw_max, ct->frames, sel->min_samples);
        free(s);
        return -1;
    }
    /* A strip in the lower state: the fit follows the upper one. */
    double *dz = malloc(sizeof(double) * u);
    if (!dz) {
        free(s);
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    for (size_t k = 0; k < u; k++) dz[k] = s[k].dz;
    qsort(dz, u, sizeof *dz, cmp_double);
    double med = dz[u / 2];
    free(dz);
    if (!(med > 0.0)) {
        snprintf(why, why_len,
                 "trial %lld: the strip was in the lower state (median Delta Z %.4g over %zu frames): the fit follows "
                 "the upper state; calibrate a trial of the strip mounted in the upper state",
                 (long long)t->id, med, u);
        free(s);
        return -1;
    }
    size_t take = u > (size_t)sel->max_samples ? (size_t)sel->max_samples : u;
    rod_fit_obs *g = realloc(d->obs, sizeof *g * ((size_t)d->nobs + take));
    if (!g) {
        free(s);
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    d->obs = g;
    for (size_t k = 0; k < take; k++) {
        size_t i = take > 1 ? (size_t)llround((double)k * (double)(u - 1) / (double)(take - 1)) : 0;
        d->obs[d->nobs++] = (rod_fit_obs){s[i].dl, s[i].dw, s[i].dz, s[i].a};
    }
    ct->used = (int)take;
    free(s);
    return 0;
}

int trial_pool_load(store *st, const int64_t *ids, int n, const trial_pool_select *sel, trial_pool *out,
                   char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    out->trials = calloc((size_t)n, sizeof *out->trials);
    if (!out->trials) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    for (int k = 0; k < n; k++) {
        store_trial t;
        char w[512];
        store_err e = store_trial_get(st, ids[k], &t, w, sizeof w);
        if (e != STORE_OK) {
            if (e == STORE_E_NOTFOUND)
                snprintf(why, why_len, "trial %lld: no such trial in this store", (long long)ids[k]);
            else
                snprintf(why, why_len, "trial %lld: %s", (long long)ids[k], w);
            goto fail;
        }
        for (int j = 0; j < k; j++)
            if (ids[j] == ids[k]) {
                snprintf(why, why_len, "trial %lld is named twice", (long long)ids[k]);
                goto fail;
            }
        if (t.status == STORE_STATUS_CREATED || t.status == STORE_STATUS_RUNNING) {
            snprintf(why, why_len, "trial %lld is unfinished (status %s): calibrate reads trials that have ended",
                     (long long)t.id, store_status_name(t.status));
            goto fail;
        }
        trial_pool_trial *ct = &out->trials[k];
        ct->id = t.id;
        snprintf(ct->mode, sizeof ct->mode, "%s", store_mode_name(t.mode));
        snprintf(ct->status, sizeof ct->status, "%s", store_status_name(t.status));
        ct->specimen_id = t.specimen_id;
        snprintf(ct->specimen, sizeof ct->specimen, "%s", t.specimen_name[0] ? t.specimen_name : "-");
        ct->snap_measured = t.snapped == 1 ? t.snap_dw_measured : NAN;
        ct->regime_measured = store_regime_name(t.regime_measured) ? store_regime_name(t.regime_measured) : "-";
        rod_scene sc;
        if (trial_scene(st, &t, sel, &sc, ct, why, why_len)) goto fail;
        if (k == 0) {
            out->scene = sc;
        } else {
            if (t.specimen_id != out->trials[0].specimen_id) {
                snprintf(why, why_len,
                         "trials %lld and %lld are of different specimens (%s, %s): calibrate fits one strip (with "
                         "--share-hinge, one per specimen sharing the hinge stiffness per unit width)",
                         (long long)ids[0], (long long)t.id, out->trials[0].specimen, ct->specimen);
                goto fail;
            }
            const char *f = strip_differs(&out->scene, &sc);
            if (f) {
                snprintf(why, why_len,
                         "trials %lld and %lld describe different strips (%s differs in their scenes or predictions): "
                         "calibrate fits one strip",
                         (long long)ids[0], (long long)t.id, f);
                goto fail;
            }
        }
        if (trial_obs(st, &t, sel, ct, out, why, why_len)) goto fail;
        out->ntrials = k + 1;
    }
    return 0;
fail:
    trial_pool_free(out);
    return -1;
}
