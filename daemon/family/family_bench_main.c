/* family_bench_main.c: ribbon-fit-family, the calibration fit tested against a family of twins it
 * does not know (issue 32 D and E), as one machine-readable line on stdout (a benchmark, never a
 * timed test; its three-twin version is tests/daemon/family/test_family.c).
 *
 * Twins are independent, so they go to `--threads` workers (0: one per core) taking the next
 * index from a shared counter; the results do not depend on the count (each twin's draws and
 * camera noise come from (seed, index) alone). --verbose prints one line per twin on stderr.
 * The line (family.h for the meanings; errors relative to the twin's own snap):
 *   bench-fit-family twins= ran= seed= nodes= fit=KEYS scene_err_median= scene_err_max=
 *     before_err_median= before_err_max= before_in_2sd= before_z_median= before_regime=R/S
 *     at80_err_median= ... at80_regime=R/S tracker_dz_rms= tracker_a_rms=
 *     fit_before_cpu_s_median= fit_before_cpu_s_max= refresh_cpu_s_median= refresh_cpu_s_max=
 *     snap_band_cpu_s_median= snap_band_cpu_s_max= in_trial_cpu_s_median= in_trial_cpu_s_max=
 *     refresh_total_cpu_s_median= refresh_total_cpu_s_max=
 *     threads= wall_s= shapes= shape_source= sigma_shape= before_pos_undetermined=
 *     at80_pos_undetermined= shape_rms=
 * (the last six: the centrelines given to the fits, issue 32 A; shape_rms is the tracker's
 * centreline against the twin's over l, median over the family, -1 when none was kept)
 * CPU times are per thread (CLOCK_THREAD_CPUTIME_ID: one core's work, whatever the load):
 * fit_before_* the fit from compression and hold (issue 32 E: at most 2 s at N = 61), in_trial_*
 * that fit plus the calibrated prediction and its band (what must land before the shear starts),
 * refresh_* the fit with the shear to 80% started from the first fit, refresh_total_* with its
 * prediction and band (one refresh of the live prediction during the shear), snap_band_* the
 * calibrated prediction and its band alone (before the shear). --verbose's line per twin ends
 * with the four CPU times: fit + band before the shear, refresh + its band. */
#define _POSIX_C_SOURCE 200809L
#include "family.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "scene_file.h"

static const char usage[] =
    "usage: ribbon-fit-family --scene FILE [--set section.key=value ...] [--twins N] [--seed S]\n"
    "                         [--threads T] [--fit KEY,KEY,...] [--prior KEY=SIGMA ...]\n"
    "                         [--shear-frac F] [--sigma-dz X] [--sigma-a X] [--sigma-b-dz X]\n"
    "                         [--sigma-b-a X] [--held-at-truth]\n"
    "                         [--shapes N [--shape-source truth|tracker] [--sigma-shape X]\n"
    "                         [--shape-common-mode] [--refresh-shapes keep|drop]]\n"
    "                         [--verbose [--verbose]] [--json]\n"
    "  Draws N twins (20) of the scene's strip with seed S (1) across a hand-made strip's ranges\n"
    "  (crease angles 75-95 deg within 5% of each other, hinge bending length 1-20% of l, E -+ 20%,\n"
    "  crease positions -+ 1% of l), films each through the protocol with the rig's camera and\n"
    "  tracker, fits the scene from the compression and hold, and again with the shear up to F (0.8)\n"
    "  of the way to the twin's snap, and prints one line: the scene's and both calibrated\n"
    "  predictions' errors against each twin's own snap, the share inside the 2-sigma band, the\n"
    "  regime where the band does not reach the boundary, and the fit's CPU time. T workers (0:\n"
    "  one per core). --fit: the fitted parameters (ribbon-sim fit's keys; default all six, with\n"
    "  priors 7.6 deg on the angles, 1.41 on the hinge, 0.006 on the positions and 0.12 on E);\n"
    "  --prior as ribbon-sim fit's (relative for\n"
    "  the hinge and E); --fit clears the default priors.\n"
    "  The residuals are weighted by the scatter of the hold's frames unless --sigma-dz / --sigma-a\n"
    "  give the noise. --sigma-b-dz / --sigma-b-a: the tracker's error common to each phase\n"
    "  (compression, hold, shear) besides that noise, for the fit's covariance (a sandwich; below 0:\n"
    "  estimated from the phases' mean residuals; default 0 and 0.003 rad, the in-trial fit's). --held-at-truth (a diagnostic): the parameters not fitted are held at each\n"
    "  twin's own values instead of the scene's. --verbose: a line per twin on stderr (twice: the\n"
    "  fitted values against the twin's, with standard errors; ND: not determined by the data).\n"
    "  --shapes N: the strip's centreline at N compression frames (the last at the hold's Delta L)\n"
    "  is fitted too, 24 points each (docs/calibration.md): the twin's own with Gaussian noise of\n"
    "  --sigma-shape X per coordinate (over l; 0.001) with --shape-source truth (the default), or\n"
    "  the tracker's mapped to the plane with --shape-source tracker (weighted by X all the same).\n"
    "  --shape-common-mode: each centreline's error has a common mode too (its residual, in the\n"
    "  covariance); --refresh-shapes drop: the fit with the shear leaves the centrelines out, its\n"
    "  positions' prior the first fit's values and standard errors (at least 0.001 l), its other\n"
    "  priors on the scene's values (keep: the default, every prior on the first fit's values);\n"
    "  both together are the trial's fit with sim.fit_shape (docs/calibration.md).\n";

#define MAX_SETS 32
#define MAX_TWINS 1000

typedef struct job {
    const rod_scene *sc;
    family_ranges rg;
    uint64_t seed;
    family_case_opts o;
    family_case *cases;
    int n, verbose;
    atomic_int next;
    pthread_mutex_t print;
} job;

static void print_case(job *j, const family_case *c)
{
    pthread_mutex_lock(&j->print);
    if (!c->ok) {
        fprintf(stderr, "twin %2d: angles %.2f %.2f pos %.4f %.4f k %.3g E %.3g: %s\n", c->index,
                c->twin.fold_angle_left_deg, c->twin.fold_angle_right_deg, c->twin.fold_position_left,
                c->twin.fold_position_right, c->twin.fold_hinge_stiffness, c->twin.youngs_modulus, c->why);
    } else {
        const rod_scene *t = &c->twin;
        fprintf(stderr,
                "twin %2d: angles %.2f %.2f pos %.4f %.4f k %.3g E %.3g | truth %.5f %s (peak %.3f) scene %+.2f%% | "
                "before ",
                c->index, t->fold_angle_left_deg, t->fold_angle_right_deg, t->fold_position_left,
                t->fold_position_right, t->fold_hinge_stiffness, t->youngs_modulus, c->truth_dw,
                c->truth_asym ? "asym" : "sym", c->truth_peak_a, 100 * (c->scene_dw - c->truth_dw) / c->truth_dw);
        const family_fit *f[2] = {&c->before, &c->at};
        for (int k = 0; k < 2; k++) {
            if (f[k]->ok)
                fprintf(stderr, "%+.2f%% sd %.2f%% rms %.2f %s (peak %.3f sd %.3f) p %.2g dir %d out %d%s",
                        100 * (f[k]->snap.snap_dw - c->truth_dw) / c->truth_dw, 100 * f[k]->snap.snap_sd / c->truth_dw,
                        f[k]->fit.rms, f[k]->snap.asymmetric ? "asym" : "sym", f[k]->snap.peak_abs_a, f[k]->snap.peak_sd, f[k]->snap.p_other,
                        f[k]->snap.directions, f[k]->snap.left_out, k == 0 ? " | at80 " : "");
            else
                fprintf(stderr, "failed (%s)%s", f[k]->why, k == 0 ? " | at80 " : "");
        }
        fprintf(stderr, " | track dz %.2g a %.2g sigma %.2g %.2g | cpu fit %.3f + band %.3f, refresh %.3f + %.3f s | %.0f s\n",
                c->film_stats.dz_rms, c->film_stats.a_rms, c->sigma_dz, c->sigma_a, c->before.fit_cpu_s,
                c->before.snap_cpu_s, c->at.fit_cpu_s, c->at.snap_cpu_s, c->wall_s);
        if (c->nshapes > 0)
            fprintf(stderr, "   shapes %d: tracker off the twin by %.2g l RMS (mean x %+.2g, z %+.2g); "
                    "the fits' shape residual before / at80 %.2f / %.2f noise units\n", c->nshapes,
                    c->film_stats.shape_rms, c->film_stats.shape_mean_x, c->film_stats.shape_mean_z,
                    c->before.fit.shape_rms, c->at.fit.shape_rms);
        if (j->verbose > 1)
            for (int k = 0; k < 2; k++) {
                const rod_fit_result *r = &f[k]->fit;
                double tu[ROD_FIT_NKEYS];
                rod_fit_scene_values(&c->twin, tu);
                fprintf(stderr, "   %s sv %.3g..%.3g:", k ? "at80  " : "before", r->sv_min, r->sv_max);
                for (int q = 0; q < ROD_FIT_NKEYS; q++)
                    if (r->fitted[q])
                        fprintf(stderr, " %s %.4g (truth %.4g, se %.3g%s)", rod_fit_key_name((rod_fit_key)q), r->u[q], tu[q],
                                r->se[q], r->determined[q] ? "" : " ND");
                fprintf(stderr, "\n   %s corr:", k ? "at80  " : "before");
                for (int q = 0; q < ROD_FIT_NKEYS; q++)
                    for (int w = q + 1; w < ROD_FIT_NKEYS; w++)
                        if (r->fitted[q] && r->fitted[w] && r->determined[q] && r->determined[w])
                            fprintf(stderr, " %d-%d %+.2f", q, w, r->corr[q][w]);
                fprintf(stderr, "\n");
            }
    }
    pthread_mutex_unlock(&j->print);
}

static void *worker(void *p)
{
    job *j = p;
    for (;;) {
        int i = atomic_fetch_add(&j->next, 1);
        if (i >= j->n) break;
        family_case_run(j->sc, &j->rg, j->seed, i, &j->o, &j->cases[i]);
        if (j->verbose) print_case(j, &j->cases[i]);
    }
    return NULL;
}

static int cmpd(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median and max of one timing over the family's successful calibrations. */
static void timing(const family_case *c, int n, int which, double *med, double *mx)
{
    double v[MAX_TWINS];
    int m = 0;
    for (int k = 0; k < n; k++) {
        if (!c[k].ok) continue;
        const family_fit *b = &c[k].before, *a = &c[k].at;
        double x = which == 0 ? b->fit_cpu_s
                 : which == 1 ? a->fit_cpu_s
                 : which == 2 ? b->snap_cpu_s
                 : which == 3 ? (b->ok ? b->fit_cpu_s + b->snap_cpu_s : 0)
                              : (a->ok ? a->fit_cpu_s + a->snap_cpu_s : 0);
        if (x > 0) v[m++] = x;
    }
    qsort(v, (size_t)m, sizeof *v, cmpd);
    *med = m ? (m % 2 ? v[m / 2] : 0.5 * (v[m / 2 - 1] + v[m / 2])) : NAN;
    *mx = m ? v[m - 1] : NAN;
}

static int parse_fit(const char *s, rod_fit_opts *o)
{
    char buf[512];
    snprintf(buf, sizeof buf, "%s", s);
    for (int k = 0; k < ROD_FIT_NKEYS; k++) o->fit[k] = 0;
    for (char *save = NULL, *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        int k = rod_fit_key_parse(t);
        if (k < 0) {
            fprintf(stderr, "ribbon-fit-family: --fit: %s is not a parameter\n", t);
            return -1;
        }
        o->fit[k] = 1;
    }
    return 0;
}

static int parse_prior(const char *s, rod_fit_opts *o)
{
    char key[128];
    const char *eq = strchr(s, '=');
    if (!eq || (size_t)(eq - s) >= sizeof key) goto bad;
    memcpy(key, s, (size_t)(eq - s));
    key[eq - s] = 0;
    int k = rod_fit_key_parse(key);
    char *end;
    double v = strtod(eq + 1, &end);
    if (k < 0 || *end || !(v > 0) || !isfinite(v)) goto bad;
    o->prior_sigma[k] = rod_fit_key_log(k) ? log1p(v) : v;
    return 0;
bad:
    fprintf(stderr, "ribbon-fit-family: --prior %s: want KEY=SIGMA with a parameter and SIGMA > 0\n", s);
    return -1;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off(); /* GSL's failures come back as codes, never as an abort */
    const char *scene = NULL, *sets[MAX_SETS], *fitkeys = NULL, *priors[ROD_FIT_NKEYS];
    int nsets = 0, npriors = 0, twins = 20, threads = 0, verbose = 0, json = 0;
    unsigned long long seed = 1;
    /* sigma_b_a: the in-trial fit's TRIAL_CALIBRATE_BIAS_A (daemon/trial/trial_calibrate.h, 0.003 rad:
     * the tracker's per-phase bias on A measured on these films); --sigma-b-a 0 turns it off */
    double frac = 0.8, sigma_dz = 0, sigma_a = 0, sigma_b_dz = 0, sigma_b_a = 0.003;
    int held_truth = 0, nshapes = 0, shape_source = FAMILY_SHAPES_TRUTH;
    double sigma_shape = 0.001;
    int shape_cm = 0, refresh_shapes = 1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int more = i + 1 < argc;
        char *end = NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            fputs(usage, stdout);
            return 0;
        } else if (!strcmp(a, "--verbose")) verbose++;
        else if (!strcmp(a, "--json")) json = 1;
        else if (!strcmp(a, "--held-at-truth")) held_truth = 1;
        else if (!strcmp(a, "--sigma-dz") && more && (sigma_dz = strtod(argv[++i], &end), !*end) && sigma_dz > 0) continue;
        else if (!strcmp(a, "--sigma-a") && more && (sigma_a = strtod(argv[++i], &end), !*end) && sigma_a > 0) continue;
        else if (!strcmp(a, "--sigma-b-dz") && more && (sigma_b_dz = strtod(argv[++i], &end), !*end) &&
                 isfinite(sigma_b_dz)) continue;
        else if (!strcmp(a, "--sigma-b-a") && more && (sigma_b_a = strtod(argv[++i], &end), !*end) && isfinite(sigma_b_a))
            continue;
        else if (!strcmp(a, "--shapes") && more && (nshapes = (int)strtol(argv[++i], &end, 10), !*end) && nshapes >= 0 &&
                 nshapes <= 20) continue;
        else if (!strcmp(a, "--shape-common-mode")) shape_cm = 1;
        else if (!strcmp(a, "--refresh-shapes") && more && (!strcmp(argv[i + 1], "keep") || !strcmp(argv[i + 1], "drop"))) {
            refresh_shapes = !strcmp(argv[++i], "keep");
            continue;
        }
        else if (!strcmp(a, "--sigma-shape") && more && (sigma_shape = strtod(argv[++i], &end), !*end) &&
                 sigma_shape > 0 && isfinite(sigma_shape)) continue;
        else if (!strcmp(a, "--shape-source") && more && (!strcmp(argv[i + 1], "truth") || !strcmp(argv[i + 1], "tracker"))) {
            shape_source = !strcmp(argv[++i], "truth") ? FAMILY_SHAPES_TRUTH : FAMILY_SHAPES_TRACKER;
            continue;
        }
        else if (!strcmp(a, "--scene") && more) scene = argv[++i];
        else if (!strcmp(a, "--set") && more && nsets < MAX_SETS) sets[nsets++] = argv[++i];
        else if (!strcmp(a, "--fit") && more) fitkeys = argv[++i];
        else if (!strcmp(a, "--prior") && more && npriors < ROD_FIT_NKEYS) priors[npriors++] = argv[++i];
        else if (!strcmp(a, "--twins") && more && (twins = (int)strtol(argv[++i], &end, 10), !*end) && twins >= 1 &&
                 twins <= MAX_TWINS) continue;
        else if (!strcmp(a, "--threads") && more && (threads = (int)strtol(argv[++i], &end, 10), !*end) &&
                 threads >= 0 && threads <= 256) continue;
        else if (!strcmp(a, "--seed") && more && (seed = strtoull(argv[++i], &end, 10), !*end)) continue;
        else if (!strcmp(a, "--shear-frac") && more && (frac = strtod(argv[++i], &end), !*end) && frac > 0 &&
                 frac < 1) continue;
        else {
            fprintf(stderr, "ribbon-fit-family: bad or incomplete argument %s\n%s", a, usage);
            return 2;
        }
    }
    if (!scene) {
        fprintf(stderr, "ribbon-fit-family: --scene is required\n%s", usage);
        return 2;
    }
    rod_scene sc;
    cfg_error ce;
    if (cfg_scene_load(scene, sets, nsets, &sc, &ce) != CFG_OK) {
        char buf[1024];
        fprintf(stderr, "ribbon-fit-family: %s\n", cfg_error_format(&ce, buf, sizeof buf));
        return 2;
    }
    job j = {.sc = &sc, .rg = family_ranges_default(), .seed = seed, .n = twins, .verbose = verbose};
    j.o = family_case_opts_default(&sc);
    j.o.shear_frac = frac;
    j.o.held_at_truth = held_truth;
    j.o.film.n_shapes = nshapes;
    j.o.shape_source = nshapes > 0 ? shape_source : FAMILY_SHAPES_NONE;
    j.o.shape_noise = sigma_shape;
    j.o.fit.sigma_shape = sigma_shape;
    j.o.fit.shape_common_mode = shape_cm;
    j.o.refresh_shapes = refresh_shapes;
    if (sigma_dz > 0 || sigma_a > 0) {
        j.o.noise_from_hold = 0;
        if (sigma_dz > 0) j.o.fit.sigma_dz = sigma_dz;
        if (sigma_a > 0) j.o.fit.sigma_a = sigma_a;
    }
    j.o.fit.sigma_b_dz = sigma_b_dz;
    j.o.fit.sigma_b_a = sigma_b_a;
    if (fitkeys) {
        for (int k = 0; k < ROD_FIT_NKEYS; k++) j.o.fit.prior_sigma[k] = INFINITY;
        if (parse_fit(fitkeys, &j.o.fit) != 0) return 2;
    }
    for (int k = 0; k < npriors; k++)
        if (parse_prior(priors[k], &j.o.fit) != 0) return 2;
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        char why[256];
        if (j.o.fit.fit[k] && rod_fit_key_usable(&sc, (rod_fit_key)k, why, sizeof why) != 0) {
            fprintf(stderr, "ribbon-fit-family: --fit: %s\n", why);
            return 2;
        }
    }
    char why[256];
    rod_scene probe;
    if (family_draw(&sc, &j.rg, seed, 0, &probe, why, sizeof why) != 0) {
        fprintf(stderr, "ribbon-fit-family: %s\n", why);
        return 2;
    }
    j.cases = calloc((size_t)twins, sizeof *j.cases);
    if (!j.cases) return 1;
    atomic_init(&j.next, 0);
    pthread_mutex_init(&j.print, NULL);
    if (threads == 0) {
        long c = sysconf(_SC_NPROCESSORS_ONLN);
        threads = c > 0 ? (int)c : 1;
    }
    if (threads > twins) threads = twins;
    double t0 = now_s();
    pthread_t th[256];
    int started = 0;
    for (; started < threads; started++)
        if (pthread_create(&th[started], NULL, worker, &j) != 0) break;
    if (started == 0) worker(&j);
    for (int k = 0; k < started; k++) pthread_join(th[k], NULL);
    double wall = now_s() - t0;

    family_summary s;
    family_summarise(j.cases, twins, &s);
    double fb_med, fb_max, rf_med, rf_max, sn_med, sn_max;
    timing(j.cases, twins, 0, &fb_med, &fb_max);
    timing(j.cases, twins, 1, &rf_med, &rf_max);
    timing(j.cases, twins, 2, &sn_med, &sn_max);
    double it_med, it_max, ir_med, ir_max;
    timing(j.cases, twins, 3, &it_med, &it_max);
    timing(j.cases, twins, 4, &ir_med, &ir_max);
    /* A figure with nothing to take it over (no twin ran, no fit landed) prints as -1, never NaN. */
    double *figs[] = {&s.scene_median, &s.scene_max, &s.before_median, &s.before_max, &s.before_in2sd,
                      &s.before_z_median, &s.at_median, &s.at_max, &s.at_in2sd, &s.at_z_median, &s.tracker_dz_rms,
                      &s.tracker_a_rms, &fb_med, &fb_max, &rf_med, &rf_max, &sn_med, &sn_max, &it_med, &it_max,
                      &ir_med, &ir_max};
    for (size_t k = 0; k < sizeof figs / sizeof figs[0]; k++)
        if (!isfinite(*figs[k])) *figs[k] = -1.0;
    char keys[256] = "";
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (j.o.fit.fit[k])
            snprintf(keys + strlen(keys), sizeof keys - strlen(keys), "%s%s", keys[0] ? "," : "",
                     rod_fit_key_name((rod_fit_key)k));
    const char *fmt = json
        ? "{\"twins\":%d,\"ran\":%d,\"seed\":%llu,\"nodes\":%d,\"fit\":\"%s\",\"scene_err_median\":%.6g,"
          "\"scene_err_max\":%.6g,\"before_fits\":%d,\"before_err_median\":%.6g,\"before_err_max\":%.6g,"
          "\"before_in_2sd\":%.6g,\"before_z_median\":%.6g,\"before_regime_right\":%d,\"before_regime_scored\":%d,"
          "\"at_fits\":%d,\"at_err_median\":%.6g,\"at_err_max\":%.6g,\"at_in_2sd\":%.6g,\"at_z_median\":%.6g,"
          "\"at_regime_right\":%d,\"at_regime_scored\":%d,\"shear_frac\":%.6g,\"tracker_dz_rms\":%.6g,"
          "\"tracker_a_rms\":%.6g,\"fit_before_cpu_s_median\":%.6g,\"fit_before_cpu_s_max\":%.6g,"
          "\"refresh_cpu_s_median\":%.6g,\"refresh_cpu_s_max\":%.6g,\"snap_band_cpu_s_median\":%.6g,"
          "\"snap_band_cpu_s_max\":%.6g,\"in_trial_cpu_s_median\":%.6g,"
          "\"in_trial_cpu_s_max\":%.6g,\"refresh_total_cpu_s_median\":%.6g,\"refresh_total_cpu_s_max\":%.6g,"
          "\"threads\":%d,\"wall_s\":%.6g,\"shapes\":%d,\"shape_source\":\"%s\",\"sigma_shape\":%.6g,"
          "\"before_pos_undetermined\":%d,\"at_pos_undetermined\":%d,\"shape_rms\":%.6g,"
          "\"shape_common_mode\":%d,\"refresh_shapes\":\"%s\"}\n"
        : "bench-fit-family twins=%d ran=%d seed=%llu nodes=%d fit=%s scene_err_median=%.5f scene_err_max=%.5f "
          "before_fits=%d before_err_median=%.5f before_err_max=%.5f before_in_2sd=%.3f before_z_median=%.2f "
          "before_regime=%d/%d at_fits=%d at_err_median=%.5f at_err_max=%.5f at_in_2sd=%.3f at_z_median=%.2f "
          "at_regime=%d/%d shear_frac=%.2f tracker_dz_rms=%.5f tracker_a_rms=%.4f fit_before_cpu_s_median=%.3f "
          "fit_before_cpu_s_max=%.3f refresh_cpu_s_median=%.3f refresh_cpu_s_max=%.3f snap_band_cpu_s_median=%.3f "
          "snap_band_cpu_s_max=%.3f "
          "in_trial_cpu_s_median=%.3f in_trial_cpu_s_max=%.3f refresh_total_cpu_s_median=%.3f "
          "refresh_total_cpu_s_max=%.3f threads=%d wall_s=%.1f shapes=%d shape_source=%s sigma_shape=%.5f "
          "before_pos_undetermined=%d at80_pos_undetermined=%d shape_rms=%.6f shape_common_mode=%d "
          "refresh_shapes=%s\n";
    printf(fmt, s.twins, s.ran, seed, sc.nodes, keys, s.scene_median, s.scene_max, s.fits_before, s.before_median,
           s.before_max, s.before_in2sd, s.before_z_median, s.regime_right_before, s.regime_scored_before, s.fits_at,
           s.at_median, s.at_max, s.at_in2sd, s.at_z_median, s.regime_right_at, s.regime_scored_at, frac,
           s.tracker_dz_rms, s.tracker_a_rms, fb_med, fb_max, rf_med, rf_max, sn_med, sn_max, it_med, it_max, ir_med,
           ir_max, threads,
           wall, nshapes, j.o.shape_source == FAMILY_SHAPES_TRACKER ? "tracker" : nshapes > 0 ? "truth" : "none",
           sigma_shape, s.before_pos_undetermined, s.at_pos_undetermined, s.shape_rms, shape_cm,
           refresh_shapes ? "keep" : "drop");
    for (int k = 0; k < twins; k++)
        if (!j.cases[k].ok) fprintf(stderr, "ribbon-fit-family: %s\n", j.cases[k].why);
    free(j.cases);
    pthread_mutex_destroy(&j.print);
    return s.ran == twins ? 0 : 1;
}
