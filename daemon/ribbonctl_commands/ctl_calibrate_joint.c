/* ctl_calibrate_joint.c: `ribbonctl calibrate ID [ID ...] --share-hinge` (issue 32 C): "separate
 * specimens can share the hinge stiffness per unit width".
 *
 * The trials are grouped by specimen (in the order the IDs first name each); each group is read
 * as `ribbonctl calibrate` reads one strip (trial_pool.h: the same cuts, overrides and
 * refusals, so a group must be one strip), and the groups are fitted together by
 * sim/rod_fit_joint.h: each specimen its own parameters (--fit's, or its trials' sim.fit_keys as
 * without --share-hinge: by default both crease angles), one k / b for all, each specimen's hinge
 * k_s = (k / b) b_s, set up as the in-trial fit is (trial_calibrate_setup: each group's
 * sim.fit_hinge on rigid creases, its keys, the priors, the tracker's common mode; the prior on ln k
 * is the one on ln(k / b)). The specimens must come to the same keys (one joint set). Printed: the shared k / b with its
 * standard error, each specimen's fit (keys "NAME:key", "not determined by these data" as
 * everywhere), the joint correlations, and per specimen the snap predicted with its fitted strip
 * (its block of the joint covariance makes the band) beside each of its trials' measured snap
 * and stored prediction. --write-scene FILE writes one scene per specimen, named FILE with
 * "-specimen<ID>" before its extension. Kept apart from ctl_calibrate.c, which only parses the
 * flag and hands over. */
#include "ctl_calibrate_joint.h"
#include "ctl_calibrate_out.h"

#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rod_fit_joint.h"
#include "rod_fit_snap.h"
#include "scene_write.h"

typedef struct jgroup {
    int64_t specimen_id;
    char name[80];
    int64_t ids[64];
    int n;
    trial_pool d;
    rod_fit_snap snap;
    int have_snap;
    char scene_path[1024];
} jgroup;

typedef struct jrun {
    const ctl_calib_joint_args *a;
    jgroup *g;
    int ng;
    rod_fit_joint_result r;
} jrun;

/* The trials grouped by specimen. 0, or -1 with the reason printed. */
static int group_trials(store *st, const ctl_calib_joint_args *a, jgroup *g, int *ng)
{
    *ng = 0;
    for (int k = 0; k < a->nids; k++) {
        store_trial t;
        char w[512];
        store_err e = store_trial_get(st, a->ids[k], &t, w, sizeof w);
        if (e != STORE_OK) {
            if (e == STORE_E_NOTFOUND)
                fprintf(stderr, "ribbonctl calibrate: trial %lld: no such trial in this store\n", (long long)a->ids[k]);
            else
                fprintf(stderr, "ribbonctl calibrate: trial %lld: %s\n", (long long)a->ids[k], w);
            return -1;
        }
        int j = 0;
        while (j < *ng && g[j].specimen_id != t.specimen_id) j++;
        if (j == *ng) {
            memset(&g[j], 0, sizeof g[j]);
            g[j].specimen_id = t.specimen_id;
            if (t.specimen_name[0]) snprintf(g[j].name, sizeof g[j].name, "%s", t.specimen_name);
            else if (t.specimen_id) snprintf(g[j].name, sizeof g[j].name, "specimen %lld", (long long)t.specimen_id);
            else snprintf(g[j].name, sizeof g[j].name, "no specimen");
            (*ng)++;
        }
        g[j].ids[g[j].n++] = a->ids[k];
    }
    return 0;
}

/* FILE with "-specimen<ID>" before the extension of its last path component. */
static void scene_name(const char *file, int64_t id, char *out, size_t len)
{
    const char *slash = strrchr(file, '/'), *dot = strrchr(file, '.');
    if (!dot || (slash && dot < slash) || dot == (slash ? slash + 1 : file))
        snprintf(out, len, "%s-specimen%lld", file, (long long)id);
    else
        snprintf(out, len, "%.*s-specimen%lld%s", (int)(dot - file), file, (long long)id, dot);
}

static int write_scenes(jrun *j)
{
    for (int s = 0; s < j->ng; s++) {
        jgroup *g = &j->g[s];
        scene_name(j->a->write_scene, g->specimen_id, g->scene_path, sizeof g->scene_path);
        rod_scene fitted = g->d.scene;
        rod_fit_scene_apply(&fitted, j->r.spec[s].u);
        char head[768];
        int len = snprintf(head, sizeof head, "written by ribbonctl calibrate --share-hinge: specimen %s fitted to trial",
                           g->name);
        for (int k = 0; k < g->d.ntrials && len < (int)sizeof head - 160; k++)
            len += snprintf(head + len, sizeof head - (size_t)len, "%s %lld", k ? "," : (g->d.ntrials > 1 ? "s" : ""),
                            (long long)g->d.trials[k].id);
        snprintf(head + len, sizeof head - (size_t)len,
                 "\nwith a hinge stiffness per unit width of %.6g N/rad shared with %d other specimen%s (residual %.3g "
                 "noise units RMS)", exp(j->r.kb), j->ng - 1, j->ng == 2 ? "" : "s", j->r.spec[s].rms);
        FILE *f = fopen(g->scene_path, "w");
        if (!f || cfg_scene_write(f, &fitted, head) || fclose(f)) {
            fprintf(stderr, "ribbonctl calibrate: --write-scene %s: %s\n", g->scene_path, strerror(errno));
            return -1;
        }
    }
    return 0;
}

static json_t *spec_params_json(const jrun *j, int s)
{
    const rod_fit_result *r = &j->r.spec[s];
    json_t *ps = json_array();
    int keys[ROD_FIT_NKEYS], m = 0;
    keys[m++] = ROD_FIT_HINGE;
    for (int i = 0; i < j->r.nown; i++) keys[m++] = j->r.own[i];
    for (int i = 0; i < m; i++) {
        int k = keys[i];
        char key[ROD_FIT_JOINT_KEY_LEN + 8];
        snprintf(key, sizeof key, "%s:%s", j->g[s].name, rod_fit_key_name((rod_fit_key)k));
        json_array_append_new(ps, json_pack("{s:s, s:f, s:f, s:o, s:b, s:s, s:b, s:b}", "key", key, "scene",
                                            ctl_calib_natural(k, r->u0[k]), "fitted", ctl_calib_natural(k, r->u[k]), "se",
                                            ctl_calib_num_or_null(r->se[k]), "determined", r->determined[k], "se_kind",
                                            rod_fit_key_log(k) ? "relative" : "absolute", "at_bound",
                                            r->at_bound[k] != 0, "shared", k == ROD_FIT_HINGE));
    }
    return ps;
}

static json_t *to_json(const jrun *j)
{
    const rod_fit_joint_result *r = &j->r;
    json_t *o = json_object(), *sp = json_array(), *keys = json_array(), *cm = json_array();
    json_object_set_new(o, "share_hinge", json_true());
    json_object_set_new(o, "hinge_per_width",
                        json_pack("{s:s, s:s, s:f, s:f, s:o, s:s, s:b, s:b}", "key", ROD_FIT_JOINT_SHARED_KEY, "unit",
                                  "N/rad", "start", exp(r->kb0), "fitted", exp(r->kb), "se", ctl_calib_num_or_null(r->kb_se),
                                  "se_kind", "relative", "determined", r->kb_determined, "at_bound", r->kb_at_bound != 0));
    for (int s = 0; s < j->ng; s++) {
        const jgroup *g = &j->g[s];
        json_t *tr = json_array();
        for (int k = 0; k < g->d.ntrials; k++) json_array_append_new(tr, ctl_calib_trial_json(&g->d.trials[k]));
        json_t *e = json_pack("{s:s, s:I, s:f, s:I, s:i, s:f, s:f, s:o, s:o}", "specimen", g->name, "specimen_id",
                              (json_int_t)g->specimen_id, "width", g->d.scene.width, "nodes",
                              (json_int_t)g->d.scene.nodes, "samples", r->spec[s].nobs, "rms", r->spec[s].rms,
                              "rms_start", r->spec[s].rms_start, "trials", tr, "parameters", spec_params_json(j, s));
        json_object_set_new(e, "scene_written", g->scene_path[0] ? json_string(g->scene_path) : json_null());
        if (g->have_snap) json_object_set_new(e, "snap", ctl_calib_snap_json(&g->snap));
        json_array_append_new(sp, e);
    }
    json_object_set_new(o, "specimens", sp);
    for (int a = 0; a < r->np; a++) {
        json_array_append_new(keys, json_string(r->key[a]));
        json_t *row = json_array();
        for (int b = 0; b < r->np; b++)
            json_array_append_new(row, r->determined[a] && r->determined[b] ? json_real(r->corr[a * r->np + b])
                                                                            : json_null());
        json_array_append_new(cm, row);
    }
    json_object_set_new(o, "keys", keys);
    json_object_set_new(o, "correlation", cm);
    json_object_set_new(o, "samples", json_integer(r->nobs));
    json_object_set_new(o, "rms", json_real(r->rms));
    json_object_set_new(o, "rms_start", json_real(r->rms_start));
    json_object_set_new(o, "misfit", json_boolean(r->misfit));
    json_object_set_new(o, "iterations", json_integer(r->iterations));
    json_object_set_new(o, "iterations_capped", json_boolean(r->capped));
    json_object_set_new(o, "fit_wall_s", json_real(r->wall_s));
    return o;
}

static void print_snap(const jgroup *g)
{
    if (g->have_snap) ctl_calib_print_snap(&g->snap, &g->d, "  ");
}

static void print_text(const jrun *j)
{
    const rod_fit_joint_result *r = &j->r;
    int ntr = 0;
    for (int s = 0; s < j->ng; s++) ntr += j->g[s].d.ntrials;
    printf("calibrate    %d trial%s of %d specimen%s, the hinge stiffness per unit width shared: %d samples, %d "
           "parameter%s, %d iterations, %.2f s\n", ntr, ntr == 1 ? "" : "s", j->ng, j->ng == 1 ? "" : "s", r->nobs,
           r->np, r->np == 1 ? "" : "s", r->iterations, r->wall_s);
    printf("residual     %.3g noise units RMS over %d residuals (at the start: %.3g)\n", r->rms, r->nres, r->rms_start);
    char se[96];
    if (!isfinite(r->kb_se)) snprintf(se, sizeof se, "not determined by these data");
    else snprintf(se, sizeof se, "%.3g%% (relative)%s", 100.0 * r->kb_se, r->kb_determined ? "" : " (prior only)");
    printf("shared       %s %.6g N/rad (start %.6g): %s%s\n", ROD_FIT_JOINT_SHARED_KEY, exp(r->kb), exp(r->kb0), se,
           r->kb_at_bound ? (r->kb_at_bound > 0 ? "  AT ITS UPPER BOUND" : "  AT ITS LOWER BOUND") : "");
    for (int s = 0; s < j->ng; s++) {
        const jgroup *g = &j->g[s];
        const rod_fit_result *q = &r->spec[s];
        printf("specimen     %s: width %.4g mm, N = %d, %d trial%s, %d samples, residual %.3g noise units RMS (at the "
               "start: %.3g)\n", g->name, 1e3 * g->d.scene.width, g->d.scene.nodes, g->d.ntrials,
               g->d.ntrials == 1 ? "" : "s", q->nobs, q->rms, q->rms_start);
        for (int k = 0; k < g->d.ntrials; k++) {
            const trial_pool_trial *t = &g->d.trials[k];
            printf("  trial %-5lld %s, %s: %d of %ld frames, Delta L %.4g .. %.4g, Delta W up to %.4g\n",
                   (long long)t->id, t->mode, t->status, t->used, t->frames, t->dl_min, t->dl_hold, t->dw_max);
        }
        printf("  %-40s %14s %14s   %s\n", "parameter", "trial's strip", "fitted", "standard error");
        int keys[ROD_FIT_NKEYS], m = 0;
        for (int i = 0; i < r->nown; i++) keys[m++] = r->own[i];
        keys[m++] = ROD_FIT_HINGE;
        for (int i = 0; i < m; i++) {
            int k = keys[i];
            char key[ROD_FIT_JOINT_KEY_LEN + 8];
            snprintf(key, sizeof key, "%s:%s", g->name, rod_fit_key_name((rod_fit_key)k));
            ctl_calib_se_text(k, q, se, sizeof se);
            printf("  %-40s %14.6g %14.6g   %s%s%s\n", key, ctl_calib_natural(k, q->u0[k]), ctl_calib_natural(k, q->u[k]), se,
                   k == ROD_FIT_HINGE ? " (k / b times the width)" : "",
                   q->at_bound[k] ? (q->at_bound[k] > 0 ? "  AT ITS UPPER BOUND" : "  AT ITS LOWER BOUND") : "");
        }
        print_snap(g);
    }
    if (r->np > 1) {
        printf("correlation  (%s", r->key[0]);
        for (int a = 1; a < r->np; a++) printf(", %s", r->key[a]);
        printf(")\n");
        for (int a = 0; a < r->np; a++) {
            printf("            ");
            for (int b = 0; b < r->np; b++) {
                if (r->determined[a] && r->determined[b]) printf(" %+6.3f", r->corr[a * r->np + b]);
                else printf("      -");
            }
            printf("\n");
        }
    }
}

int ctl_calibrate_joint(store *st, const ctl_calib_joint_args *a)
{
    jrun j;
    memset(&j, 0, sizeof j);
    j.a = a;
    j.g = calloc((size_t)a->nids, sizeof *j.g);
    rod_fit_joint_spec *specs = calloc((size_t)a->nids, sizeof *specs);
    int rc = 1;
    char why[1024];
    if (!j.g || !specs) {
        fprintf(stderr, "ribbonctl calibrate: out of memory\n");
        goto done;
    }
    rod_fit_opts set = rod_fit_opts_default();
    const char *set_keys = "";
    if (group_trials(st, a, j.g, &j.ng)) goto done;
    for (int s = 0; s < j.ng; s++) {
        jgroup *g = &j.g[s];
        if (trial_pool_load(st, g->ids, g->n, a->sel, &g->d, why, sizeof why)) {
            fprintf(stderr, "ribbonctl calibrate: specimen %s: %s\n", g->name, why);
            j.ng = s; /* the groups read so far are freed below (this one freed itself) */
            goto done;
        }
        /* The in-trial fit's setup, as without --share-hinge (trial_calibrate_setup): the group's
           first trial's sim.fit_hinge on rigid creases, its sim.fit_keys unless --fit names keys;
           its priors and common mode below. The hinge stiffness is the shared one (fitted anyway),
           so not each specimen's own. */
        const trial_pool_trial *t0 = &g->d.trials[0];
        const char *keys = a->fit_keys ? a->fit_keys : t0->fit_keys;
        char rk[24], rw[320];
        if (t0->fit_unread[0])
            fprintf(stderr, "ribbonctl calibrate: trial %lld: %s: fitted without the hinge guess, with the default keys\n",
                    (long long)t0->id, t0->fit_unread);
        rod_fit_opts gs;
        if (trial_calibrate_setup(&g->d.scene, t0->fit_hinge, keys, &gs, rk, rw, sizeof rw) < 0) {
            fprintf(stderr, "ribbonctl calibrate: specimen %s: %s%s\n", g->name, rw,
                    a->fit_keys ? "" : " (its trials' sim.fit_keys)");
            j.ng = s + 1;
            goto done;
        }
        gs.fit[ROD_FIT_HINGE] = 0;
        if (s == 0) {
            set = gs;
            set_keys = keys;
        } else if (memcmp(gs.fit, set.fit, sizeof set.fit)) {
            fprintf(stderr, "ribbonctl calibrate: specimen %s's trials fit other keys (sim.fit_keys \"%s\") than specimen "
                            "%s's (\"%s\"): a joint fit has one set; name it with --fit\n",
                    g->name, keys, j.g[0].name, set_keys);
            j.ng = s + 1;
            goto done;
        }
        specs[s] = (rod_fit_joint_spec){g->name, &g->d.scene, g->d.obs, g->d.nobs};
    }
    rod_fit_joint_opts o = rod_fit_joint_opts_default();
    o.each = a->fit;
    memcpy(o.each.fit, set.fit, sizeof o.each.fit); /* the keys every specimen came to, the hinge shared */
    memcpy(o.each.prior_sigma, set.prior_sigma, sizeof o.each.prior_sigma);
    o.each.sigma_b_dz = set.sigma_b_dz;
    o.each.sigma_b_a = set.sigma_b_a;
    o.kb_prior_sigma = set.prior_sigma[ROD_FIT_HINGE]; /* ln k_s = ln(k / b) + ln b_s: the same width */
    rod_status fs = rod_fit_joint_run(specs, j.ng, &o, &j.r, why, sizeof why);
    if (fs != ROD_OK) {
        fprintf(stderr, "ribbonctl calibrate: the joint fit failed: %s\n", why);
        goto done;
    }
    rc = 0;
    if (j.r.misfit) {
        fprintf(stderr, "ribbonctl calibrate: no parameter set fits these data: the residual is %.3g noise units RMS "
                        "(above %g); check the noise levels (--sigma-dz, --sigma-a), the cut-offs and the strips\n",
                j.r.rms, o.each.misfit);
        rc = 1;
    }
    if (!rc && !a->no_snap)
        for (int s = 0; s < j.ng; s++) {
            jgroup *g = &j.g[s];
            if (rod_fit_snap_predict(&g->d.scene, &j.r.spec[s], &g->snap, why, sizeof why) == ROD_OK) g->have_snap = 1;
            else fprintf(stderr, "ribbonctl calibrate: specimen %s: the fitted strip's prediction failed: %s\n", g->name,
                         why);
        }
    if (!rc && a->write_scene && write_scenes(&j)) rc = 1;
    if (a->json) {
        json_t *o2 = to_json(&j);
        char *txt = json_dumps(o2, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
        if (txt) puts(txt);
        free(txt);
        json_decref(o2);
    } else {
        print_text(&j);
        for (int s = 0; !rc && a->write_scene && s < j.ng; s++)
            printf("scene        %s: %s\n", j.g[s].name, j.g[s].scene_path);
    }
    if (j.r.capped)
        fprintf(stderr, "ribbonctl calibrate: Levenberg-Marquardt stopped at its cap of %d iterations before converging: "
                        "the values printed are the best found\n", o.each.max_iterations);
    if (j.r.kb_at_bound)
        fprintf(stderr, "ribbonctl calibrate: %s ran to its %s bound %g N/rad: the data ask for a value outside the "
                        "bounds\n", ROD_FIT_JOINT_SHARED_KEY, j.r.kb_at_bound > 0 ? "upper" : "lower",
                exp(j.r.kb_at_bound > 0 ? j.r.kb_hi : j.r.kb_lo));
    for (int s = 0; s < j.ng; s++)
        for (int i = 0; i < j.r.nown; i++) {
            int k = j.r.own[i];
            const rod_fit_result *q = &j.r.spec[s];
            if (q->at_bound[k])
                fprintf(stderr, "ribbonctl calibrate: %s:%s ran to its %s bound %g: the data ask for a value outside the "
                                "bounds\n", j.g[s].name, rod_fit_key_name((rod_fit_key)k),
                        q->at_bound[k] > 0 ? "upper" : "lower", ctl_calib_natural(k, q->at_bound[k] > 0 ? q->hi[k] : q->lo[k]));
        }
done:
    rod_fit_joint_result_free(&j.r);
    if (j.g)
        for (int s = 0; s < j.ng; s++) trial_pool_free(&j.g[s].d);
    free(j.g);
    free(specs);
    return rc;
}
