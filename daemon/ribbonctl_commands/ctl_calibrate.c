/* ctl_calibrate.c: `ribbonctl calibrate ID [ID ...]`: one strip fitted to what the camera saw
 * in one or several stored trials (issue 32 C), offline, from the store.
 *
 * The trials' strip and observations come from the trial room's pool (daemon/trial/trial_pool.h,
 * shared with ribbond's refit of a specimen); the fit and the snap
 * predicted with the fitted strip are the simulator's (sim/rod_fit.h, sim/rod_fit_snap.h, as
 * `ribbon-sim fit` uses them, with the same keys and the same words for what the data do not
 * determine). Printed beside each trial's measured snap and its stored prediction, so the
 * calibration's gain (or loss) is read off directly. The fit is set up by the function ribbond's
 * in-trial fit and its specimen refit use (trial_calibrate_setup, with the trial's sim.fit_hinge
 * and sim.fit_keys read back from its stored rig file), so a trial's frames refit offline give
 * its in-trial values (test_ctl_calibrate_trial). --write-scene writes the fitted strip as a
 * scene file (config/scene_write.h) that ribbon-sim reads. Replays are trials like any other
 * (their creases come from the recorded trial's prediction). Exit 0 with the fit; 1 when a
 * trial is refused (the reason names it), the fit fails or no parameter set fits; 2 on usage. */
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api.h"
#include "ctl.h"
#include "ctl_calibrate_joint.h"
#include "ctl_calibrate_out.h"
#include "rod_fit.h"
#include "rod_fit_snap.h"
#include "scene_write.h"
#include "store.h"
#include "trial.h"

#define MAX_IDS 64
#define MAX_SETS 64

static const char usage[] =
    "usage: ribbonctl calibrate ID [ID ...] [--db FILE] [--fit KEY,KEY,...] [--json] [--write-scene FILE]\n"
    "                           [--set section.key=value ...] [--dw-max X] [--dl-min X] [--max-samples N]\n"
    "                           [--sigma-dz X] [--sigma-a X] [--scale-covariance] [--no-snap] [--share-hinge]\n"
    "  Fits one strip to the camera's Delta Z and A in stored trials (replays too): the trial's\n"
    "  scene with the creases its prediction used, followed through the compression near the hold\n"
    "  and the shear up to a cut-off. Several trials must be of one specimen (or --share-hinge);\n"
    "  they share its parameters. Prints each fitted value with its standard error (\"not\n"
    "  determined by these data\" when the data cannot fix it), their correlations, the residual in\n"
    "  noise units, and the fitted strip's snap with a 1-sigma band and its 2-sigma interval, its\n"
    "  regime and the probability of the other one, beside each trial's measured and predicted snap.\n"
    "  Set up as the trial's own in-trial fit was (ribbond's trial_calibrate_setup): the trial's\n"
    "  sim.fit_hinge makes rigid creases hinges of that stiffness (the start and the prior's centre),\n"
    "  its sim.fit_keys are the default keys, weak priors around the strip's values (10 deg on an\n"
    "  angle, 0.88 in ln k, 0.005 on view.dz_offset) and the tracker's common mode on A (0.003 rad)\n"
    "  in the standard errors; with --share-hinge too (each specimen's trial's sim.fit_hinge).\n"
    "  --db         the store (default: ask ribbond where its store is, --url / $RIBBON_URL)\n"
    "  --fit        parameters fitted, the others held: folds.angle_left_deg, folds.angle_right_deg,\n"
    "               folds.position_left, folds.position_right, folds.hinge_stiffness (one k for\n"
    "               both creases, compliant creases) or folds.hinge_stiffness_left and _right (one\n"
    "               each), ribbon.youngs_modulus, view.dz_offset (the\n"
    "               camera's vertical offset, over l); default: both crease angles, and the hinge\n"
    "               stiffness when the creases are compliant (or the trial's sim.fit_keys)\n"
    "  --set        scene overrides on the trials' strip (mesh.nodes=61 for speed; a compliant\n"
    "               folds.hinge_stiffness as the start, in place of the trial's sim.fit_hinge)\n"
    "  --dw-max     last Delta W used (default 0.8 of the measured snap; the whole shear without one)\n"
    "  --dl-min     first Delta L used (default 0.8 of the trial's hold)\n"
    "  --max-samples  frames per trial, thinned evenly beyond it (default 200)\n"
    "  --sigma-dz, --sigma-a  the tracker's noise of Delta Z and A (defaults 0.002, 0.015 rad)\n"
    "  --scale-covariance  standard errors scaled by the residual; --no-snap  no snap prediction\n"
    "  --write-scene  the fitted strip as a scene file for ribbon-sim\n"
    "  --share-hinge  trials of several specimens: grouped per specimen, each group one strip with its\n"
    "               own parameters (--fit or, as without it, the trials' sim.fit_keys: the same for\n"
    "               every specimen), one hinge stiffness per unit width k / b\n"
    "               (folds.hinge_stiffness_per_width, N/rad) shared by all, k = (k / b) width;\n"
    "               prints k / b with its standard error and each specimen's fit and snap;\n"
    "               --write-scene FILE writes one scene per specimen, FILE-specimen<ID>.ini\n"
    "  Exit 1 when a trial is refused (no such trial, unfinished, too few samples, lower state,\n"
    "  different specimens) or no parameter set fits; 2 on usage (an unknown key). docs/calibration.md.\n";

typedef struct calib_args {
    int64_t ids[MAX_IDS];
    int nids;
    const char *db, *fit, *write_scene, *url, *token;
    const char *sets[MAX_SETS];
    int nsets, json, scale_cov, no_snap, share_hinge;
    double sigma_dz, sigma_a, dw_max, dl_min;
    long max_samples;
} calib_args;

static int bad(const char *msg, const char *arg)
{
    fprintf(stderr, "ribbonctl calibrate: %s%s%s (see ribbonctl calibrate --help)\n", msg, arg ? " " : "", arg ? arg : "");
    return 2;
}

static int num(const char *flag, const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v)) {
        fprintf(stderr, "ribbonctl calibrate: %s %s: not a finite number\n", flag, s);
        return 2;
    }
    *out = v;
    return 0;
}

/* 0, 1 (help printed) or 2 (usage error, printed). */
static int parse(int argc, char **argv, calib_args *a)
{
    for (int i = 1; i < argc; i++) {
        const char *f = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(f, "--help") || !strcmp(f, "-h")) {
            fputs(usage, stdout);
            return 1;
        }
        const char **str = !strcmp(f, "--db") ? &a->db : !strcmp(f, "--fit") ? &a->fit
                         : !strcmp(f, "--write-scene") ? &a->write_scene : !strcmp(f, "--url") ? &a->url
                         : !strcmp(f, "--token") ? &a->token : NULL;
        double *d = !strcmp(f, "--sigma-dz") ? &a->sigma_dz : !strcmp(f, "--sigma-a") ? &a->sigma_a
                  : !strcmp(f, "--dw-max") ? &a->dw_max : !strcmp(f, "--dl-min") ? &a->dl_min : NULL;
        int is_set = !strcmp(f, "--set"), is_max = !strcmp(f, "--max-samples");
        if (str || d || is_set || is_max) {
            if (!v) return bad("missing value after", f);
            i++;
            if (str) *str = v;
            else if (d && num(f, v, d)) return 2;
            else if (is_set) {
                if (a->nsets >= MAX_SETS) return bad("too many --set (at most 64)", NULL);
                a->sets[a->nsets++] = v;
            } else if (is_max) {
                char *end;
                errno = 0;
                a->max_samples = strtol(v, &end, 10);
                if (errno || *end || end == v || a->max_samples < 4 || a->max_samples > 100000)
                    return bad("--max-samples takes a count from 4 to 100000, not", v);
            }
            continue;
        }
        if (!strcmp(f, "--json")) a->json = 1;
        else if (!strcmp(f, "--scale-covariance")) a->scale_cov = 1;
        else if (!strcmp(f, "--no-snap")) a->no_snap = 1;
        else if (!strcmp(f, "--share-hinge")) a->share_hinge = 1;
        else if (f[0] != '-') {
            char *end;
            errno = 0;
            long long id = strtoll(f, &end, 10);
            if (errno || *end || id < 1) return bad("a trial ID is a positive integer, not", f);
            if (a->nids >= MAX_IDS) return bad("too many trials (at most 64)", NULL);
            a->ids[a->nids++] = id;
        } else
            return bad("unknown argument", f);
    }
    if (!a->nids) return bad("which trials? ribbonctl calibrate ID [ID ...]", NULL);
    if (!(a->sigma_dz > 0.0) || !(a->sigma_a > 0.0)) return bad("--sigma-dz and --sigma-a must be positive", NULL);
    return 0;
}

/* The --fit list into o->fit (the default when NULL). 0, or 2 with the key named. */
static int parse_keys(const char *list, const rod_scene *sc, rod_fit_opts *o)
{
    if (!list) {
        o->fit[ROD_FIT_ANGLE_LEFT] = o->fit[ROD_FIT_ANGLE_RIGHT] = 1;
        o->fit[ROD_FIT_HINGE] = !rod_scene_hinge_rigid(sc);
        return 0;
    }
    char buf[512];
    snprintf(buf, sizeof buf, "%s", list);
    for (char *save = NULL, *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        int k = rod_fit_key_parse(t);
        if (k < 0) {
            fprintf(stderr, "ribbonctl calibrate: --fit %s: not a fit parameter (", t);
            for (int j = 0; j < ROD_FIT_NKEYS; j++) fprintf(stderr, "%s%s", j ? ", " : "", rod_fit_key_name(j));
            fprintf(stderr, ")\n");
            return 2;
        }
        o->fit[k] = 1;
    }
    return 0;
}

static int open_store(const calib_args *a, store **st)
{
    char why[512], path[1024];
    const char *db = a->db;
    if (!db) {
        api_client_config c = api_client_config_default();
        c.base_url = a->url ? a->url : getenv("RIBBON_URL") && *getenv("RIBBON_URL") ? getenv("RIBBON_URL")
                                                                                      : "http://127.0.0.1:8377";
        c.token = a->token ? a->token : getenv("RIBBON_TOKEN");
        json_t *s = NULL;
        int status = 0;
        if (api_client_global_init(why, sizeof why) ||
            api_client_request(&c, "GET", "/status", NULL, &status, &s, NULL, NULL, why, sizeof why) || status >= 400) {
            fprintf(stderr, "ribbonctl calibrate: no --db, and ribbond could not say where its store is: %s\n", why);
            json_decref(s);
            api_client_global_cleanup();
            return -1;
        }
        const char *p = json_string_value(json_object_get(s, "store"));
        snprintf(path, sizeof path, "%s", p ? p : "");
        json_decref(s);
        api_client_global_cleanup();
        db = path;
    }
    store_open_params p = store_open_params_default();
    p.read_only = true;
    if (store_open_ex(db, &p, st, why, sizeof why) != STORE_OK) {
        fprintf(stderr, "ribbonctl calibrate: store %s: %s\n", db, why);
        return -1;
    }
    return 0;
}

typedef struct calib_out {
    const calib_args *a;
    const trial_pool *d;
    const rod_fit_result *r;
    const rod_fit_snap *snap; /* NULL: none */
    int keys[ROD_FIT_NKEYS], m;
} calib_out;

static json_t *to_json(const calib_out *c)
{
    const rod_fit_result *r = c->r;
    json_t *j = json_object(), *tr = json_array(), *ps = json_array(), *cm = json_array();
    for (int k = 0; k < c->d->ntrials; k++) {
        const trial_pool_trial *t = &c->d->trials[k];
        json_array_append_new(tr, ctl_calib_trial_json(t));
    }
    json_object_set_new(j, "trials", tr);
    json_object_set_new(j, "samples", json_integer(r->nobs));
    json_object_set_new(j, "nodes", json_integer(c->d->scene.nodes));
    json_object_set_new(j, "rms", json_real(r->rms));
    json_object_set_new(j, "rms_start", json_real(r->rms_start));
    json_object_set_new(j, "misfit", json_boolean(r->misfit));
    json_object_set_new(j, "iterations", json_integer(r->iterations));
    json_object_set_new(j, "iterations_capped", json_boolean(r->capped));
    json_object_set_new(j, "fit_wall_s", json_real(r->wall_s));
    for (int i = 0; i < c->m; i++) {
        int k = c->keys[i];
        json_t *row = json_array();
        for (int jj = 0; jj < c->m; jj++)
            json_array_append_new(row, (r->determined[k] && r->determined[c->keys[jj]]) ? json_real(r->corr[k][c->keys[jj]])
                                                                                       : json_null());
        json_array_append_new(cm, row);
        json_array_append_new(ps, json_pack("{s:s, s:f, s:f, s:o, s:b, s:s, s:b}", "key", rod_fit_key_name(k), "scene",
            ctl_calib_natural(k, r->u0[k]), "fitted", ctl_calib_natural(k, r->u[k]), "se", ctl_calib_num_or_null(r->se[k]), "determined",
            r->determined[k], "se_kind", rod_fit_key_log(k) ? "relative" : "absolute", "at_bound", r->at_bound[k] != 0));
    }
    json_object_set_new(j, "parameters", ps);
    json_object_set_new(j, "correlation", cm);
    const rod_fit_snap *s = c->snap;
    if (s) json_object_set_new(j, "snap", ctl_calib_snap_json(s));
    json_object_set_new(j, "scene_written", c->a->write_scene ? json_string(c->a->write_scene) : json_null());
    return j;
}

static void print_text(const calib_out *c)
{
    const rod_fit_result *r = c->r;
    const trial_pool *d = c->d;
    printf("calibrate    %d trial%s of specimen %s: %d samples, %d parameter%s, N = %d, %d iterations, %.2f s\n",
           d->ntrials, d->ntrials == 1 ? "" : "s", d->trials[0].specimen, r->nobs, c->m, c->m == 1 ? "" : "s",
           d->scene.nodes, r->iterations, r->wall_s);
    for (int k = 0; k < d->ntrials; k++) {
        const trial_pool_trial *t = &d->trials[k];
        printf("  trial %-5lld %s, %s: %d of %ld frames, Delta L %.4g .. %.4g, Delta W up to %.4g\n", (long long)t->id,
               t->mode, t->status, t->used, t->frames, t->dl_min, t->dl_hold, t->dw_max);
    }
    printf("residual     %.3g noise units RMS over %d residuals (at the trials' strip: %.3g)\n", r->rms, r->nres,
           r->rms_start);
    printf("%-27s %14s %14s   %s\n", "parameter", "trial's strip", "fitted", "standard error");
    for (int i = 0; i < c->m; i++) {
        int k = c->keys[i];
        char se[96];
        ctl_calib_se_text(k, r, se, sizeof se);
        printf("%-27s %14.6g %14.6g   %s%s\n", rod_fit_key_name(k), ctl_calib_natural(k, r->u0[k]), ctl_calib_natural(k, r->u[k]), se,
               r->at_bound[k] ? (r->at_bound[k] > 0 ? "  AT ITS UPPER BOUND" : "  AT ITS LOWER BOUND") : "");
    }
    if (c->m > 1) {
        printf("correlation ");
        for (int i = 0; i < c->m; i++) {
            printf("%s", i ? "            " : "");
            for (int jj = 0; jj < c->m; jj++) {
                if (r->determined[c->keys[i]] && r->determined[c->keys[jj]]) printf(" %+6.3f", r->corr[c->keys[i]][c->keys[jj]]);
                else printf("      -");
            }
            printf("\n");
        }
    }
    if (c->snap) ctl_calib_print_snap(c->snap, d, "");
}

int ctl_calibrate_main(int argc, char **argv)
{
    calib_args a;
    memset(&a, 0, sizeof a);
    rod_fit_opts o = rod_fit_opts_default();
    trial_pool_select sel = trial_pool_select_default();
    a.sigma_dz = o.sigma_dz;
    a.sigma_a = o.sigma_a;
    a.dw_max = sel.dw_max;
    a.dl_min = sel.dl_min;
    a.max_samples = sel.max_samples;
    int rc = parse(argc, argv, &a);
    if (rc) return rc == 1 ? 0 : 2;
    /* An unknown key is a usage error before anything is read (the scene only decides the default). */
    if (a.fit) {
        rod_scene any = rod_scene_default();
        rod_fit_opts probe = o;
        if (parse_keys(a.fit, &any, &probe)) return 2;
    }
    sel.dw_max = a.dw_max;
    sel.dl_min = a.dl_min;
    sel.max_samples = (int)a.max_samples;
    sel.sets = a.sets;
    sel.n_sets = a.nsets;
    store *st;
    if (open_store(&a, &st)) return 1;
    if (a.share_hinge) {
        ctl_calib_joint_args ja = {.ids = a.ids, .nids = a.nids, .sel = &sel, .fit_keys = a.fit, .fit = o,
                                   .json = a.json, .no_snap = a.no_snap, .write_scene = a.write_scene};
        ja.fit.sigma_dz = a.sigma_dz;
        ja.fit.sigma_a = a.sigma_a;
        ja.fit.scale_covariance = a.scale_cov;
        rc = ctl_calibrate_joint(st, &ja);
        store_close(st);
        return rc;
    }
    trial_pool d;
    char why[1024];
    if (trial_pool_load(st, a.ids, a.nids, &sel, &d, why, sizeof why)) {
        store_close(st);
        fprintf(stderr, "ribbonctl calibrate: %s\n", why);
        return 1;
    }
    store_close(st);
    /* The in-trial fit's setup, by the function ribbond's fit and its specimen refit use: the
       trial's sim.fit_hinge on rigid creases, its sim.fit_keys unless --fit names keys, the
       priors around the strip's values and the tracker's common mode in the covariance. */
    const trial_pool_trial *t0 = &d.trials[0];
    if (t0->fit_unread[0])
        fprintf(stderr, "ribbonctl calibrate: trial %lld: %s: fitted without the hinge guess, with the default keys\n",
                (long long)t0->id, t0->fit_unread);
    char rk[24], rw[320];
    int rigid = rod_scene_hinge_rigid(&d.scene);
    if (trial_calibrate_setup(&d.scene, t0->fit_hinge, a.fit ? a.fit : t0->fit_keys, &o, rk, rw, sizeof rw) < 0) {
        fprintf(stderr, "ribbonctl calibrate: %s%s\n", rw, a.fit ? "" : " (the trial's sim.fit_keys)");
        trial_pool_free(&d);
        return 1;
    }
    if (rigid && !rod_scene_hinge_rigid(&d.scene))
        fprintf(stderr, "ribbonctl calibrate: the trials' creases are rigid; fitted as hinges of %g N m/rad (the trial's "
                        "sim.fit_hinge: the start and the prior's centre), as its in-trial fit was\n", t0->fit_hinge);
    o.sigma_dz = a.sigma_dz;
    o.sigma_a = a.sigma_a;
    o.scale_covariance = a.scale_cov;
    rod_fit_result r;
    rod_status fs = rod_fit_run(&d.scene, d.obs, d.nobs, &o, &r, why, sizeof why);
    if (fs != ROD_OK) {
        fprintf(stderr, "ribbonctl calibrate: the fit failed: %s\n", why);
        trial_pool_free(&d);
        return 1;
    }
    rod_fit_snap snap;
    int have_snap = 0;
    if (!a.no_snap && !r.misfit) {
        if (rod_fit_snap_predict(&d.scene, &r, &snap, why, sizeof why) == ROD_OK) have_snap = 1;
        else fprintf(stderr, "ribbonctl calibrate: the fitted strip's prediction failed: %s\n", why);
    }
    calib_out c = {.a = &a, .d = &d, .r = &r, .snap = have_snap ? &snap : NULL};
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (r.fitted[k]) c.keys[c.m++] = k;
    rc = 0;
    if (r.misfit) {
        fprintf(stderr, "ribbonctl calibrate: no parameter set fits these data: the residual is %.3g noise units RMS "
                        "(above %g); check the noise levels (--sigma-dz, --sigma-a), the cut-offs and the strip\n",
                r.rms, o.misfit);
        rc = 1;
    }
    if (!rc && a.write_scene) {
        rod_scene fitted = d.scene;
        rod_fit_scene_apply(&fitted, r.u);
        char head[512];
        int len = snprintf(head, sizeof head, "written by ribbonctl calibrate: the strip fitted to trial");
        for (int k = 0; k < d.ntrials && len < (int)sizeof head - 32; k++)
            len += snprintf(head + len, sizeof head - (size_t)len, "%s %lld", k ? "," : (d.ntrials > 1 ? "s" : ""),
                            (long long)d.trials[k].id);
        snprintf(head + len, sizeof head - (size_t)len, "\n(residual %.3g noise units RMS)", r.rms);
        FILE *f = fopen(a.write_scene, "w");
        if (!f || cfg_scene_write(f, &fitted, head) || fclose(f)) {
            fprintf(stderr, "ribbonctl calibrate: --write-scene %s: %s\n", a.write_scene, strerror(errno));
            rc = 1;
        }
    }
    if (!rc || r.misfit) {
        if (a.json) {
            json_t *j = to_json(&c);
            char *txt = json_dumps(j, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
            if (txt) puts(txt);
            free(txt);
            json_decref(j);
        } else {
            print_text(&c);
            if (!rc && a.write_scene) printf("scene        %s\n", a.write_scene);
        }
    }
    if (r.capped)
        fprintf(stderr, "ribbonctl calibrate: Levenberg-Marquardt stopped at its cap of %d iterations before converging: "
                        "the values printed are the best found\n", o.max_iterations);
    for (int i = 0; i < c.m; i++)
        if (r.at_bound[c.keys[i]])
            fprintf(stderr, "ribbonctl calibrate: %s ran to its %s bound %g: the data ask for a value outside the bounds\n",
                    rod_fit_key_name(c.keys[i]), r.at_bound[c.keys[i]] > 0 ? "upper" : "lower",
                    ctl_calib_natural(c.keys[i], r.at_bound[c.keys[i]] > 0 ? r.hi[c.keys[i]] : r.lo[c.keys[i]]));
    trial_pool_free(&d);
    return rc;
}
