/* sim_cmd_fit.c: `ribbon-sim fit`: a scene's strip fitted to a CSV of observed (Delta L,
 * Delta W, Delta Z, A) samples from any source (issue 32 C), printed with standard errors,
 * correlations, the directions the data do not determine, the residual in noise units and the
 * fitted strip's snap with its band (sim/rod_fit.h, sim/rod_fit_snap.h); --out-scene writes the
 * fitted strip as a scene file. */
#include "rod_fit.h"
#include "rod_fit_snap.h"
#include "sim_cmd.h"
#include "sim_opts.h"
#include "scene_write.h"

#include <ctype.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FIT_MAX_SAMPLES 100000
#define FIT_MAX_LINE 4096

static const char usage[] =
    "usage: ribbon-sim fit --scene FILE --csv SAMPLES.csv [--fit KEY,KEY,...] [--sigma-dz X]\n"
    "                      [--sigma-a X] [--bound KEY=LO:HI ...] [--prior KEY=SIGMA ...] [--paper]\n"
    "                      [--dw-max X] [--dl-min X] [--scale-covariance] [--no-snap]\n"
    "                      [--out-scene FILE] [--set section.key=value ...] [--json]\n"
    "  Fits the scene's strip to observed static states: a CSV with a header naming the columns\n"
    "  dl, dw, dz and a (Delta L, Delta W, Delta Z, A; other columns are ignored, so `ribbonctl\n"
    "  export ID --csv` reads as it is; rows with an empty or non-numeric value are skipped and\n"
    "  counted). The model follows the upper equilibrium through the samples' states and\n"
    "  compares its A_cam and projected Delta Z (--paper: the paper's A and Delta Z).\n"
    "  --fit      parameters to fit, the others held at the scene's values: folds.angle_left_deg,\n"
    "             folds.angle_right_deg, folds.position_left, folds.position_right,\n"
    "             folds.hinge_stiffness (compliant creases: one k for both, or one each with\n"
    "             folds.hinge_stiffness_left and _right), ribbon.youngs_modulus (G with it),\n"
    "             view.dz_offset (the camera's vertical offset, over l: not written to --out-scene);\n"
    "             default: both crease angles, and the hinge stiffness when the creases are compliant\n"
    "  --sigma-dz, --sigma-a   noise of Delta Z and of A (rad) that weights each residual\n"
    "             (defaults 0.002 and 0.015: the tracker's order, docs/vision.md)\n"
    "  --bound    KEY=LO:HI in the scene key's units (default: scene -+ 20 deg, -+ 0.05 l,\n"
    "             k / 100 .. x 100, E / 10 .. x 10, offset -+ 0.05)\n"
    "  --prior    KEY=SIGMA: a prior centred on the scene's value, SIGMA in the key's units\n"
    "             (relative for folds.hinge_stiffness and ribbon.youngs_modulus: 0.2 is 20%)\n"
    "  --dw-max   leave out samples beyond this Delta W (the fit's cut-off before the snap)\n"
    "  --dl-min   leave out samples below this Delta L (early compression, no upper state there)\n"
    "  --scale-covariance  standard errors scaled by the residual (chi2 / (n - p))\n"
    "  --no-snap  skip the fitted strip's snap prediction and its band\n"
    "  --out-scene  write the fitted strip as a scene file\n"
    "  Prints the fitted values with standard errors and correlations, names the parameters these\n"
    "  data do not determine (no number is given for them), the residual in noise units, and the\n"
    "  snap of the fitted strip (predict --fast) with a linearised 1-sigma band and the probability\n"
    "  of the other regime. Exit 1 when no parameter set fits (residual above 5 noise units RMS)\n"
    "  or the fit fails (the reason is printed), 2 on bad input. docs/calibration.md.\n";

#define FIT_MAX_SPECS 16

typedef struct fit_args {
    const char *csv, *fit, *out_scene;
    const char *bound[FIT_MAX_SPECS], *prior[FIT_MAX_SPECS];
    int nbound, nprior;
    double sigma_dz, sigma_a, dw_max, dl_min;
    int paper, scale_cov, no_snap;
} fit_args;

static int parse_num(const char *flag, const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v)) {
        fprintf(stderr, "ribbon-sim fit: %s %s: not a finite number\n", flag, s);
        return -1;
    }
    *out = v;
    return 0;
}

/* Takes this command's own flags out of argv (the rest go to sim_opts_parse). */
static int take_flags(int *argc, char **argv, fit_args *a)
{
    int out = 1;
    for (int i = 1; i < *argc; i++) {
        const char *f = argv[i];
        const char **str = !strcmp(f, "--csv") ? &a->csv : !strcmp(f, "--fit") ? &a->fit
                         : !strcmp(f, "--out-scene") ? &a->out_scene : NULL;
        double *num = !strcmp(f, "--sigma-dz") ? &a->sigma_dz : !strcmp(f, "--sigma-a") ? &a->sigma_a
                    : !strcmp(f, "--dw-max") ? &a->dw_max : !strcmp(f, "--dl-min") ? &a->dl_min : NULL;
        if (str || num) {
            if (i + 1 >= *argc) {
                fprintf(stderr, "ribbon-sim fit: %s needs a value (see --help)\n", f);
                return -1;
            }
            if (str) *str = argv[++i];
            else if (parse_num(f, argv[++i], num)) return -1;
            continue;
        }
        if (!strcmp(f, "--bound") || !strcmp(f, "--prior")) {
            int bound = !strcmp(f, "--bound");
            int *cnt = bound ? &a->nbound : &a->nprior;
            if (i + 1 >= *argc || *cnt >= FIT_MAX_SPECS) {
                fprintf(stderr, "ribbon-sim fit: %s needs a value (at most %d of them; see --help)\n", f, FIT_MAX_SPECS);
                return -1;
            }
            (bound ? a->bound : a->prior)[(*cnt)++] = argv[++i];
            continue;
        }
        if (!strcmp(f, "--paper")) a->paper = 1;
        else if (!strcmp(f, "--scale-covariance")) a->scale_cov = 1;
        else if (!strcmp(f, "--no-snap")) a->no_snap = 1;
        else argv[out++] = argv[i];
    }
    *argc = out;
    return 0;
}

static int column(char *const *cols, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(cols[i], name)) return i;
    return -1;
}

/* Splits line at commas in place (trailing CR/LF and surrounding spaces removed). */
static int split(char *line, char **cols, int max)
{
    int n = 0;
    line[strcspn(line, "\r\n")] = '\0';
    char *p = line;
    while (n < max) {
        char *e = strchr(p, ',');
        if (e) *e = '\0';
        while (isspace((unsigned char)*p)) p++;
        char *t = p + strlen(p);
        while (t > p && isspace((unsigned char)t[-1])) *--t = '\0';
        cols[n++] = p;
        if (!e) break;
        p = e + 1;
    }
    return n;
}

static int read_csv(const char *path, double dw_max, double dl_min, rod_fit_obs **out, int *n_out, int *skipped)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "ribbon-sim fit: --csv %s: %s\n", path, strerror(errno));
        return -1;
    }
    char line[FIT_MAX_LINE];
    char *cols[64];
    int idx[4] = {-1, -1, -1, -1};
    static const char *const names[4] = {"dl", "dw", "dz", "a"};
    rod_fit_obs *obs = NULL;
    int n = 0, cap = 0, lineno = 0, rc = -1;
    *skipped = 0;
    if (!fgets(line, sizeof line, f)) {
        fprintf(stderr, "ribbon-sim fit: --csv %s: empty file (a header naming dl, dw, dz, a is needed)\n", path);
        goto done;
    }
    lineno = 1;
    int nc = split(line, cols, 64);
    for (int k = 0; k < 4; k++)
        if ((idx[k] = column(cols, nc, names[k])) < 0) {
            fprintf(stderr, "ribbon-sim fit: --csv %s: the header has no column \"%s\" (needed: dl, dw, dz, a)\n",
                    path, names[k]);
            goto done;
        }
    while (fgets(line, sizeof line, f)) {
        lineno++;
        if (!strchr(line, '\n') && !feof(f)) {
            fprintf(stderr, "ribbon-sim fit: --csv %s:%d: line longer than %d bytes\n", path, lineno, FIT_MAX_LINE - 1);
            goto done;
        }
        nc = split(line, cols, 64);
        if (nc == 1 && cols[0][0] == '\0') continue;
        double v[4];
        int ok = 1;
        for (int k = 0; k < 4 && ok; k++) {
            if (idx[k] >= nc || !cols[idx[k]][0]) {
                ok = 0;
                break;
            }
            char *end;
            v[k] = strtod(cols[idx[k]], &end);
            ok = *end == '\0' && isfinite(v[k]);
        }
        if (!ok) {
            (*skipped)++;
            continue;
        }
        if (dw_max > 0.0 && v[1] > dw_max) continue;
        if (dl_min > 0.0 && v[0] < dl_min) continue;
        if (n >= FIT_MAX_SAMPLES) {
            fprintf(stderr, "ribbon-sim fit: --csv %s: more than %d samples\n", path, FIT_MAX_SAMPLES);
            goto done;
        }
        if (n == cap) {
            cap = cap ? 2 * cap : 256;
            rod_fit_obs *g = realloc(obs, sizeof *obs * (size_t)cap);
            if (!g) {
                fprintf(stderr, "ribbon-sim fit: out of memory\n");
                goto done;
            }
            obs = g;
        }
        obs[n++] = (rod_fit_obs){v[0], v[1], v[2], v[3]};
    }
    rc = 0;
done:
    fclose(f);
    if (rc) {
        free(obs);
        obs = NULL;
        n = 0;
    }
    *out = obs;
    *n_out = n;
    return rc;
}

static int parse_keys(const char *list, const rod_scene *sc, rod_fit_opts *o)
{
    if (!list) {
        o->fit[ROD_FIT_ANGLE_LEFT] = o->fit[ROD_FIT_ANGLE_RIGHT] = 1;
        o->fit[ROD_FIT_HINGE] = !rod_scene_hinge_rigid(sc);
        return 0;
    }
    char buf[512];
    snprintf(buf, sizeof buf, "%s", list);
    for (char *t = strtok(buf, ","); t; t = strtok(NULL, ",")) {
        int k = rod_fit_key_parse(t);
        if (k < 0) {
            fprintf(stderr, "ribbon-sim fit: --fit %s: not a fit parameter (", t);
            for (int j = 0; j < ROD_FIT_NKEYS; j++) fprintf(stderr, "%s%s", j ? ", " : "", rod_fit_key_name(j));
            fprintf(stderr, ")\n");
            return -1;
        }
        o->fit[k] = 1;
    }
    return 0;
}

/* --bound KEY=LO:HI and --prior KEY=SIGMA into the options (fit units). */
static int parse_specs(const fit_args *a, rod_fit_opts *o)
{
    for (int b = 0; b < 2; b++) {
        int n = b ? a->nprior : a->nbound;
        for (int i = 0; i < n; i++) {
            const char *spec = b ? a->prior[i] : a->bound[i];
            const char *flag = b ? "--prior" : "--bound";
            char buf[256];
            snprintf(buf, sizeof buf, "%s", spec);
            char *eq = strchr(buf, '=');
            if (!eq) {
                fprintf(stderr, "ribbon-sim fit: %s %s: expected %s\n", flag, spec, b ? "KEY=SIGMA" : "KEY=LO:HI");
                return -1;
            }
            *eq = '\0';
            int k = rod_fit_key_parse(buf);
            if (k < 0) {
                fprintf(stderr, "ribbon-sim fit: %s %s: %s is not a fit parameter\n", flag, spec, buf);
                return -1;
            }
            int lg = rod_fit_key_log(k);
            if (b) {
                double sg;
                if (parse_num(flag, eq + 1, &sg)) return -1;
                if (!(sg > 0.0)) {
                    fprintf(stderr, "ribbon-sim fit: %s %s: the width must be positive\n", flag, spec);
                    return -1;
                }
                o->prior_sigma[k] = lg ? log1p(sg) : sg;
            } else {
                char *colon = strchr(eq + 1, ':');
                double lo, hi;
                if (!colon) {
                    fprintf(stderr, "ribbon-sim fit: %s %s: expected KEY=LO:HI\n", flag, spec);
                    return -1;
                }
                *colon = '\0';
                if (parse_num(flag, eq + 1, &lo) || parse_num(flag, colon + 1, &hi)) return -1;
                if (lg && !(lo > 0.0 && hi > 0.0)) {
                    fprintf(stderr, "ribbon-sim fit: %s %s: the bounds of %s must be positive\n", flag, spec, buf);
                    return -1;
                }
                o->lo[k] = lg ? log(lo) : lo;
                o->hi[k] = lg ? log(hi) : hi;
            }
        }
    }
    return 0;
}

/* A value in the units the scene file uses. */
static double natural(int k, double u)
{
    return rod_fit_key_log(k) ? exp(u) : u;
}

static json_t *num_or_null(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

int sim_cmd_fit(int argc, char **argv)
{
    fit_args a = {0};
    rod_fit_opts o = rod_fit_opts_default();
    a.sigma_dz = o.sigma_dz;
    a.sigma_a = o.sigma_a;
    if (take_flags(&argc, argv, &a)) return 2;
    sim_opts so;
    int rc = sim_opts_parse(argc, argv, "json", usage, &so);
    if (rc) return rc == 1 ? 0 : 2;
    if (!a.csv) {
        fprintf(stderr, "ribbon-sim fit: --csv is required (see --help)\n");
        return 2;
    }
    rod_scene sc;
    if (!sim_opts_load_scene(&so, &sc)) return 2;
    if (parse_keys(a.fit, &sc, &o) || parse_specs(&a, &o)) return 2;
    o.sigma_dz = a.sigma_dz;
    o.sigma_a = a.sigma_a;
    o.paper = a.paper;
    o.scale_covariance = a.scale_cov;
    rod_fit_obs *obs = NULL;
    int n = 0, skipped = 0;
    if (read_csv(a.csv, a.dw_max, a.dl_min, &obs, &n, &skipped)) return 2;
    rod_fit_result r;
    char why[512];
    rod_status st = rod_fit_run(&sc, obs, n, &o, &r, why, sizeof why);
    free(obs);
    if (st != ROD_OK) {
        fprintf(stderr, "ribbon-sim fit: %s\n", why);
        return st == ROD_ERR_SCENE ? 2 : 1;
    }
    rod_fit_snap snap;
    memset(&snap, 0, sizeof snap);
    int have_snap = 0;
    if (!a.no_snap && !r.misfit) {
        if (rod_fit_snap_predict(&sc, &r, &snap, why, sizeof why) == ROD_OK) have_snap = 1;
        else fprintf(stderr, "ribbon-sim fit: the fitted strip's prediction failed: %s\n", why);
    }
    int keys[ROD_FIT_NKEYS], m = 0;
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (r.fitted[k]) keys[m++] = k;
    if (so.json) {
        json_t *j = json_object(), *ps = json_array(), *cm = json_array();
        json_object_set_new(j, "csv", json_string(a.csv));
        json_object_set_new(j, "samples", json_integer(r.nobs));
        json_object_set_new(j, "skipped", json_integer(skipped));
        json_object_set_new(j, "observables", json_string(a.paper ? "paper" : "camera"));
        json_object_set_new(j, "rms", json_real(r.rms));
        json_object_set_new(j, "rms_start", json_real(r.rms_start));
        json_object_set_new(j, "misfit", json_boolean(r.misfit));
        json_object_set_new(j, "iterations", json_integer(r.iterations));
        json_object_set_new(j, "iterations_capped", json_boolean(r.capped));
        json_object_set_new(j, "evaluations", json_integer(r.evaluations));
        json_object_set_new(j, "fit_wall_s", json_real(r.wall_s));
        for (int i = 0; i < m; i++) {
            int k = keys[i];
            json_t *row = json_array();
            for (int jj = 0; jj < m; jj++)
                json_array_append_new(row, (r.determined[k] && r.determined[keys[jj]]) ? json_real(r.corr[k][keys[jj]])
                                                                                       : json_null());
            json_array_append_new(cm, row);
            json_array_append_new(ps, json_pack("{s:s, s:f, s:f, s:o, s:b, s:s, s:b}", "key", rod_fit_key_name(k),
                "scene", natural(k, r.u0[k]), "fitted", natural(k, r.u[k]),
                "se", num_or_null(r.se[k]), "determined", r.determined[k],
                "se_kind", rod_fit_key_log(k) ? "relative" : "absolute", "at_bound", r.at_bound[k] != 0));
        }
        json_object_set_new(j, "parameters", ps);
        json_object_set_new(j, "correlation", cm);
        if (have_snap) {
            json_t *s = json_object();
            json_object_set_new(s, "snapped", json_boolean(snap.snapped));
            if (snap.snapped) {
                json_object_set_new(s, "snap_dw", json_real(snap.snap_dw));
                json_object_set_new(s, "regime", json_string(snap.asymmetric ? "asymmetric" : "symmetric"));
                json_object_set_new(s, "peak_abs_a", json_real(snap.peak_abs_a));
            }
            json_object_set_new(s, "band", json_boolean(snap.band_ok));
            if (snap.band_ok) {
                json_object_set_new(s, "snap_sd", json_real(snap.snap_sd));
                json_object_set_new(s, "p_other_regime", json_real(snap.p_other));
                json_object_set_new(s, "directions", json_integer(snap.directions));
                json_object_set_new(s, "method", json_string("linearised: central differences along the covariance's principal directions"));
            }
            if (snap.note[0]) json_object_set_new(s, "note", json_string(snap.note));
            json_object_set_new(s, "wall_s", json_real(snap.wall_s));
            json_object_set_new(j, "snap", s);
        }
        char *txt = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(10));
        puts(txt);
        free(txt);
        json_decref(j);
    } else {
        printf("fit          %s: %d samples (%d skipped), %d parameter%s, %d iterations, %.2f s\n", a.csv, r.nobs,
               skipped, m, m == 1 ? "" : "s", r.iterations, r.wall_s);
        printf("residual     %.3g noise units RMS over %d residuals (at the scene's values: %.3g)\n", r.rms, r.nres,
               r.rms_start);
        printf("%-24s %14s %14s   %s\n", "parameter", "scene", "fitted", "standard error");
        for (int i = 0; i < m; i++) {
            int k = keys[i];
            char se[96];
            if (!isfinite(r.se[k])) snprintf(se, sizeof se, "not determined by these data");
            else if (rod_fit_key_log(k)) snprintf(se, sizeof se, "%.3g%% (relative)", 100.0 * r.se[k]);
            else snprintf(se, sizeof se, "%.3g%s", r.se[k], r.determined[k] ? "" : " (prior only: not determined by these data)");
            printf("%-24s %14.6g %14.6g   %s%s\n", rod_fit_key_name(k), natural(k, r.u0[k]), natural(k, r.u[k]), se,
                   r.at_bound[k] ? (r.at_bound[k] > 0 ? "  AT ITS UPPER BOUND" : "  AT ITS LOWER BOUND") : "");
        }
        if (m > 1) {
            printf("correlation ");
            for (int i = 0; i < m; i++) {
                printf("%s", i ? "            " : "");
                for (int jj = 0; jj < m; jj++) {
                    if (r.determined[keys[i]] && r.determined[keys[jj]]) printf(" %+6.3f", r.corr[keys[i]][keys[jj]]);
                    else printf("      -");
                }
                printf("\n");
            }
        }
        if (have_snap) {
            if (!snap.snapped) printf("snap         none before protocol.shear_max (%s)\n", snap.note);
            else if (snap.band_ok)
                printf("snap         Delta W %.5f +- %.5f (1 sigma, linearised over %d principal directions), %s; "
                       "P(%s) = %.3g%s%s\n", snap.snap_dw, snap.snap_sd, snap.directions,
                       snap.asymmetric ? "asymmetric" : "symmetric", snap.asymmetric ? "symmetric" : "asymmetric",
                       snap.p_other, snap.note[0] ? "; " : "", snap.note);
            else
                printf("snap         Delta W %.5f, %s (%s)\n", snap.snap_dw, snap.asymmetric ? "asymmetric" : "symmetric",
                       snap.note);
        }
    }
    if (r.capped)
        fprintf(stderr, "ribbon-sim fit: Levenberg-Marquardt stopped at its cap of %d iterations before converging: "
                        "the values printed are the best found\n", o.max_iterations);
    for (int i = 0; i < m; i++)
        if (r.at_bound[keys[i]])
            fprintf(stderr, "ribbon-sim fit: %s ran to its %s bound %g: the data ask for a value outside the bounds\n",
                    rod_fit_key_name(keys[i]), r.at_bound[keys[i]] > 0 ? "upper" : "lower",
                    natural(keys[i], r.at_bound[keys[i]] > 0 ? r.hi[keys[i]] : r.lo[keys[i]]));
    if (r.misfit) {
        fprintf(stderr, "ribbon-sim fit: no parameter set fits these data: the residual is %.3g noise units RMS "
                        "(above %g); check the noise levels, the samples' columns and the scene\n", r.rms, o.misfit);
        return 1;
    }
    if (a.out_scene) {
        rod_scene fitted = sc;
        rod_fit_scene_apply(&fitted, r.u);
        FILE *f = fopen(a.out_scene, "w");
        char head[256];
        snprintf(head, sizeof head, "written by ribbon-sim fit: the scene fitted to %s\n(residual %.3g noise units RMS)",
                 a.csv, r.rms);
        if (!f || cfg_scene_write(f, &fitted, head) || fclose(f)) {
            fprintf(stderr, "ribbon-sim fit: --out-scene %s: %s\n", a.out_scene, strerror(errno));
            return 1;
        }
        if (!so.json) printf("scene        %s\n", a.out_scene);
    }
    return 0;
}
