/* ctl_plan_bench_camera.c: `ribbonctl plan-bench --camera`, the simulated campaign through the
 * camera (campaign_camera_bench.h, issue 35 part D): the truths once, then the calibrated and the
 * uncalibrated campaign of mock trials, each in its own store; one machine-readable line. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "campaign.h"
#include "ctl.h"

static void progress(void *u, const char *line)
{
    if (u) fprintf(stderr, "  %s\n", line);
}

/* "a,b,c" of n numbers, "-" for one not known. */
static void print_list(const char *key, const double *v, size_t n)
{
    printf(" %s=", key);
    for (size_t j = 0; j < n; j++) {
        if (j) putchar(',');
        if (isfinite(v[j])) printf("%.5f", v[j]);
        else putchar('-');
    }
}

static void print_num(const char *key, double v)
{
    if (isfinite(v)) printf(" %s=%.5f", key, v);
    else printf(" %s=-", key);
}

/* Per phi of the campaign: " PREFIXspecimens_phi=a,b,c PREFIXagree_phi=x/a,y/b,z/c" (the trials
 * whose measured regime is the twin's own, of the specimens at that phi). */
static void print_per_phi(const char *p, const campaign_camera_result *c, const double *phi, size_t n)
{
    int used[CAMPAIGN_BENCH_MAX_PHI], agree[CAMPAIGN_BENCH_MAX_PHI];
    campaign_camera_per_phi(c, phi, n, used, agree);
    printf(" %sspecimens_phi=", p);
    for (size_t j = 0; j < n; j++) printf("%s%d", j ? "," : "", used[j]);
    printf(" %sagree_phi=", p);
    for (size_t j = 0; j < n; j++) printf("%s%d/%d", j ? "," : "", agree[j], used[j]);
}

int ctl_plan_bench_camera_main(int argc, char **argv)
{
    campaign_camera_opts o = campaign_camera_opts_default();
    int verbose = 0, dynamic = 1, which = 3; /* bit 1 calibrated, bit 0 uncalibrated */
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--camera")) continue;
        if (!strcmp(a, "--verbose")) {
            verbose = 1;
            continue;
        }
        if (!strcmp(a, "--keep-videos")) {
            o.keep_videos = 1;
            continue;
        }
        if (!strcmp(a, "--strip") || !strcmp(a, "--no-strip")) {
            o.strip = a[2] == 's';
            continue;
        }
        if (!strcmp(a, "--no-dynamic-truth")) {
            dynamic = 0;
            continue;
        }
        if (!v) {
            fprintf(stderr, "ribbonctl plan-bench --camera: %s needs a value (see --help)\n", a);
            return 2;
        }
        char *end = NULL;
        i++;
        if (!strcmp(a, "--config")) o.rig_path = v;
        else if (!strcmp(a, "--dir")) o.dir = v;
        else if (!strcmp(a, "--name")) o.name = v;
        else if (!strcmp(a, "--set")) {
            if (o.n_sets == CAMPAIGN_CAMERA_MAX_SETS || !strchr(v, '=')) {
                fprintf(stderr, "ribbonctl plan-bench --camera: --set takes section.key=value, at most %d\n",
                        CAMPAIGN_CAMERA_MAX_SETS);
                return 2;
            }
            o.sets[o.n_sets++] = v;
        } else if (!strcmp(a, "--max")) o.bench.max_specimens = (int)strtol(v, &end, 10);
        else if (!strcmp(a, "--seed")) o.bench.seed = (unsigned)strtoul(v, &end, 10);
        else if (!strcmp(a, "--relax")) o.bench.relax_deg = strtod(v, &end);
        else if (!strcmp(a, "--spread")) o.bench.spread = strtod(v, &end);
        else if (!strcmp(a, "--timeout")) o.trial_timeout_s = strtod(v, &end);
        else if (!strcmp(a, "--hinge")) {
            o.bench.twin_hinge = strtod(v, &end);
            if (!(o.bench.twin_hinge >= 0) || !isfinite(o.bench.twin_hinge)) {
                fprintf(stderr, "ribbonctl plan-bench --camera: --hinge takes a stiffness in N m/rad (0: the rig "
                                "file's twin)\n");
                return 2;
            }
        } else if (!strcmp(a, "--calibration")) {
            which = !strcmp(v, "both") ? 3 : !strcmp(v, "on") ? 2 : !strcmp(v, "off") ? 1 : 0;
            if (!which) {
                fprintf(stderr, "ribbonctl plan-bench --camera: --calibration takes both, on or off\n");
                return 2;
            }
        } else if (!strcmp(a, "--phi")) {
            o.bench.nphi = 0;
            const char *s = v;
            while (*s && o.bench.nphi < CAMPAIGN_BENCH_MAX_PHI) {
                double x = strtod(s, &end);
                if (end == s || !(x > 0 && x < 180) || (*end && *end != ',')) {
                    fprintf(stderr, "ribbonctl plan-bench --camera: --phi takes degrees, comma-separated\n");
                    return 2;
                }
                o.bench.phi_deg[o.bench.nphi++] = x;
                s = *end ? end + 1 : end;
            }
            end = NULL;
        } else {
            fprintf(stderr, "ribbonctl plan-bench --camera: unknown argument %s (see --help)\n", a);
            return 2;
        }
        if (end && *end) {
            fprintf(stderr, "ribbonctl plan-bench --camera: %s %s is not a number\n", a, v);
            return 2;
        }
    }
    if (!o.rig_path) {
        fprintf(stderr, "ribbonctl plan-bench --camera: --config F is required (a mock-mode rig file: the planner's "
                        "model is its scene, the twins its [twin])\n");
        return 2;
    }
    if (o.bench.max_specimens < 1 || o.bench.max_specimens > CAMPAIGN_CAMERA_MAX_SPECIMENS) {
        fprintf(stderr, "ribbonctl plan-bench --camera: --max takes 1..%d\n", CAMPAIGN_CAMERA_MAX_SPECIMENS);
        return 2;
    }
    char why[1024];
    campaign_camera_truth truth;
    if (verbose) fprintf(stderr, "truths (the model, the twins' mean strip%s):\n", dynamic ? ", its dynamic switch" : "");
    if (campaign_camera_truth_trace(&o, dynamic, &truth, why, sizeof why)) {
        fprintf(stderr, "ribbonctl plan-bench --camera: %s\n", why);
        return 1;
    }
    if (verbose) fprintf(stderr, "  %.1f s\n", truth.wall_s);
    campaign_camera_result *r = calloc(2, sizeof *r);
    if (!r) {
        fprintf(stderr, "ribbonctl plan-bench --camera: out of memory\n");
        return 1;
    }
    for (int cal = 1; cal >= 0; cal--) {
        if (!(which & (1 << cal))) continue;
        o.bench.calibrate = cal;
        if (campaign_camera_run(&o, &truth, &r[cal], progress, verbose ? &verbose : NULL, why, sizeof why)) {
            fprintf(stderr, "ribbonctl plan-bench --camera: %s campaign: %s\n", cal ? "calibrated" : "uncalibrated",
                    why);
            free(r);
            return 1;
        }
    }
    size_t n = o.bench.nphi;
    printf("bench-plan-camera twin_nodes=%d phi=", truth.nodes);
    for (size_t j = 0; j < n; j++) printf("%s%g", j ? "," : "", o.bench.phi_deg[j]);
    double trials = 0, trial_s = 0;
    for (int cal = 1; cal >= 0; cal--) {
        const campaign_camera_result *c = &r[cal];
        const char *p = cal ? "" : "uncal_";
        if (!(which & (1 << cal))) {
            printf(" %sspecimens=-", p);
            continue;
        }
        printf(" %sspecimens=%d %sconverged=%d", p, c->specimens, p, c->converged);
        char k[40];
        snprintf(k, sizeof k, "%smax_error_static", p);
        print_num(k, c->err_static);
        snprintf(k, sizeof k, "%smax_error_dynamic", p);
        print_num(k, c->err_dynamic);
        printf(" %sagree=%d/%d %sclear_agree=%d/%d %sundecided=%d", p, c->agree, c->specimens, p, c->clear_agree, c->clear,
               p, c->undecided);
        print_per_phi(p, c, o.bench.phi_deg, n);
        if (cal) {
            print_num("offset", c->offset_mean);
            print_list("offsets", c->offsets, n);
            print_num("spread", c->spread_mean);
        }
        if (cal && o.strip) {
            printf(" strip_fits=%d strip_calibrations=%d", c->strip.n_fits, c->strip.n_calibrations);
            print_num("strip_relax_deg", c->strip.n_relax ? c->strip.relax_deg : NAN);
            printf(" strip_hinge=%.3g strip_traces=%d strip_failures=%d", c->strip.hinge, c->strip_traces,
                   c->strip_failures);
            print_list("lab_model", c->model, n);
        }
        trials += c->specimens;
        trial_s += c->trials_s;
    }
    print_list("truth_static", truth.statik, n);
    print_list("truth_dynamic", truth.dynamic, n);
    print_list("predicted", truth.predicted, n);
    if (which & 2) print_list("located", r[1].located, n);
    if (which & 1) print_list("uncal_located", r[0].located, n);
    printf(" grid_specimens=%d", (int)lround(0.25 / 0.005) * (int)n);
    print_num("trial_s", trials > 0 ? trial_s / trials : NAN);
    printf(" truth_s=%.1f wall_s=%.1f seed=%u\n", truth.wall_s, truth.wall_s + r[0].wall_s + r[1].wall_s,
           o.bench.seed);
    free(r);
    return 0;
}
