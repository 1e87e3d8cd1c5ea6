/* ctl_plan_bench.c: `ribbonctl plan-bench`, the simulated campaign (campaign_bench.h, issue 35
 * part D): the planner with calibration, then the same bench (same seed) with the offset fixed at
 * 0, against twins whose creases relaxed and soften; one machine-readable line. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "campaign.h"
#include "ctl.h"
#include "scene_file.h"
#include "store.h"

static void help(void)
{
    printf("usage: ribbonctl plan-bench --scene F [--phi LIST] [--max K] [--seed S] [--relax DEG] [--factor F]\n"
           "                            [--hinge K] [--spread S] [--dynamic] [--db FILE] [--verbose]\n"
           "\n"
           "The simulated campaign: the planner proposes one specimen at a time at the phi values of LIST\n"
           "(default 60,90,120); each is folded as a twin of the scene whose creases relaxed by --relax\n"
           "degrees (default 6) and are more compliant (rigid-crease stiffness factor --factor, default 3,\n"
           "or compliant hinges of --hinge K N m/rad),\n"
           "each crease off by up to --spread (default 0.01) at random, and its regime measured by the\n"
           "simulator's classification; until every phi's experimental boundary is at most 0.005 wide or\n"
           "--max specimens (default 15). Then the same bench without calibration. Truth: the twins' mean\n"
           "strip's boundary traced by rod_boundary. One line: bench-plan specimens=... max_error=...\n"
           "--dynamic measures each twin by its simulated snap (the fast prediction, the regime rule on\n"
           "peak |A|) and takes as truth the mean strip's dynamic switch bisected to 5e-4 (slow: about a\n"
           "second per specimen, ten per phi).\n"
           "--db writes the calibrated campaign's specimens (B-1, B-2, ...) and measured trials to a store\n"
           "(for ribbonctl phase).\n"
           "\n"
           "usage: ribbonctl plan-bench --camera --config RIG [--set K=V ...] [--dir D] [--name STEM] [--phi LIST]\n"
           "                            [--max K] [--seed S] [--relax DEG] [--hinge K] [--spread S]\n"
           "                            [--calibration both|on|off] [--no-dynamic-truth] [--timeout S] [--keep-videos]\n"
           "                            [--verbose]\n"
           "\n"
           "The same campaign through the camera (docs/campaign.md): each proposal is stored, approved\n"
           "(specimen C-k, an operator step, a trial in the queue), folded as a twin (creases relaxed by\n"
           "--relax, compliant hinges of --hinge K N m/rad, default 5e-3; each crease off by up to --spread,\n"
           "the same draws as above), the operator step confirmed with the angles measured at folding, and\n"
           "trialled by the queue as a real mock trial of the rig file RIG (mode mock; --set overrides it,\n"
           "e.g. twin.mesh.nodes=61): rendered, tracked, its regime read from the stored trial. Stores and\n"
           "videos go to --dir (default .) as STEM-cal.db, STEM-uncal.db (default STEM campaign). Scored\n"
           "against the twins' mean strip's static boundary and its dynamic switch (the fast predictor at\n"
           "the rig's shear speed; --no-dynamic-truth skips it). --timeout bounds one specimen (default 1200\n"
           "s). Each trial's video is removed once read unless --keep-videos. At phi 120 the twin cannot be\n"
           "mounted at mock.ini's Delta L 0.2 (nor at 0.3 from Gamma 0.206): add --set\n"
           "rail.compress.start_mm=130 (Delta L 0.4). Minutes per campaign (half a minute to a minute a\n"
           "trial). One line: bench-plan-camera specimens=...\n");
}

/* The calibrated campaign's specimens and their measured trials into a store (mock mode, done),
 * named B-1, B-2, ... in the order made: a store `ribbonctl phase` can draw. */
static int write_store(const char *db, const campaign_bench_result *r, const rod_scene *sc)
{
    char why[512];
    store *st;
    if (store_open(db, &st, why, sizeof why) != STORE_OK) {
        fprintf(stderr, "ribbonctl plan-bench: store %s: %s\n", db, why);
        return -1;
    }
    double t = store_wall_now();
    int used[64] = {0};
    for (int k = 0; k < r->specimens && k < 64; k++) {
        const campaign_obs *o = &r->obs[r->order[k]];
        int asym = used[r->order[k]] < o->n_asym;
        used[r->order[k]]++;
        store_specimen sp = store_specimen_default();
        snprintf(sp.name, sizeof sp.name, "B-%d", k + 1);
        sp.length_m = sc->length, sp.width_m = sc->width, sp.thickness_m = sc->thickness;
        sp.phi_deg = o->phi_deg;
        sp.fold_position = o->gamma;
        int64_t sid, tid;
        store_trial_def d = store_trial_def_default();
        d.created_wall_s = t;
        if (store_specimen_upsert(st, &sp, &sid, why, sizeof why) != STORE_OK ||
            (d.specimen_id = sid, store_trial_create(st, &d, &tid, why, sizeof why)) != STORE_OK ||
            store_trial_set_status(st, tid, STORE_STATUS_RUNNING, NULL, t, why, sizeof why) != STORE_OK ||
            store_trial_set_result(st, tid, true, 0.4, asym ? STORE_REGIME_ASYMMETRIC : STORE_REGIME_SYMMETRIC, why,
                                   sizeof why) != STORE_OK ||
            store_trial_set_status(st, tid, STORE_STATUS_DONE, "the simulated bench (ribbonctl plan-bench)", t, why,
                                   sizeof why) != STORE_OK) {
            fprintf(stderr, "ribbonctl plan-bench: store %s: %s\n", db, why);
            store_close(st);
            return -1;
        }
    }
    store_close(st);
    return 0;
}

static void progress(void *u, const char *line)
{
    if (u) fprintf(stderr, "  %s\n", line);
}

int ctl_plan_bench_main(int argc, char **argv)
{
    const char *scene = NULL, *db = NULL;
    int verbose = 0;
    campaign_bench_opts o = campaign_bench_opts_default();
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--camera")) {
            for (int k = 1; k < argc; k++)
                if (!strcmp(argv[k], "--help") || !strcmp(argv[k], "-h")) {
                    help();
                    return 0;
                }
            return ctl_plan_bench_camera_main(argc, argv);
        }
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 0;
        }
        if (!strcmp(a, "--verbose")) {
            verbose = 1;
            continue;
        }
        if (!strcmp(a, "--dynamic")) {
            o.dynamic = 1;
            continue;
        }
        if (!v) {
            fprintf(stderr, "ribbonctl plan-bench: %s needs a value (see --help)\n", a);
            return 2;
        }
        char *end = NULL;
        i++;
        if (!strcmp(a, "--scene")) scene = v;
        else if (!strcmp(a, "--db")) db = v;
        else if (!strcmp(a, "--max")) o.max_specimens = (int)strtol(v, &end, 10);
        else if (!strcmp(a, "--seed")) o.seed = (unsigned)strtoul(v, &end, 10);
        else if (!strcmp(a, "--relax")) o.relax_deg = strtod(v, &end);
        else if (!strcmp(a, "--factor")) o.twin_stiffness_factor = strtod(v, &end);
        else if (!strcmp(a, "--hinge")) {
            o.twin_hinge = strtod(v, &end);
            if (!(o.twin_hinge > 0) || !isfinite(o.twin_hinge)) {
                fprintf(stderr, "ribbonctl plan-bench: --hinge takes a positive stiffness in N m/rad\n");
                return 2;
            }
        }
        else if (!strcmp(a, "--spread")) o.spread = strtod(v, &end);
        else if (!strcmp(a, "--phi")) {
            o.nphi = 0;
            const char *s = v;
            while (*s && o.nphi < CAMPAIGN_BENCH_MAX_PHI) {
                double x = strtod(s, &end);
                if (end == s || !(x > 0 && x < 180) || (*end && *end != ',')) {
                    fprintf(stderr, "ribbonctl plan-bench: --phi takes degrees, comma-separated\n");
                    return 2;
                }
                o.phi_deg[o.nphi++] = x;
                s = *end ? end + 1 : end;
            }
            end = NULL;
        } else {
            fprintf(stderr, "ribbonctl plan-bench: unknown argument %s (see --help)\n", a);
            return 2;
        }
        if (end && *end) {
            fprintf(stderr, "ribbonctl plan-bench: %s %s is not a number\n", a, v);
            return 2;
        }
    }
    if (!scene) {
        fprintf(stderr, "ribbonctl plan-bench: --scene F is required (the planner's model)\n");
        return 2;
    }
    rod_scene sc;
    cfg_error ce;
    char why[1024];
    if (cfg_scene_load(scene, NULL, 0, &sc, &ce) != CFG_OK) {
        cfg_error_format(&ce, why, sizeof why);
        fprintf(stderr, "ribbonctl plan-bench: %s\n", why);
        return 1;
    }
    campaign_bench_result r[2];
    for (int cal = 1; cal >= 0; cal--) {
        o.calibrate = cal;
        if (verbose) fprintf(stderr, "%s:\n", cal ? "calibrated" : "without calibration");
        if (campaign_bench_run(&sc, &o, &r[cal], progress, verbose ? &verbose : NULL, why, sizeof why)) {
            fprintf(stderr, "ribbonctl plan-bench: %s\n", why);
            return 1;
        }
    }
    if (db && write_store(db, &r[1], &sc)) return 1;
    printf("bench-plan nodes=%d phi=", sc.nodes);
    for (size_t j = 0; j < o.nphi; j++) printf("%s%g", j ? "," : "", o.phi_deg[j]);
    printf(" specimens=%d converged=%d max_error=%.5f offset=%.5f uncal_specimens=%d uncal_converged=%d "
           "uncal_max_error=%.5f truth=",
           r[1].specimens, r[1].converged, r[1].max_error, r[1].offset_mean, r[0].specimens, r[0].converged,
           r[0].max_error);
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[1].truth[j]);
    printf(" predicted=");
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[1].predicted[j]);
    printf(" located=");
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[1].located[j]);
    printf(" uncal_located=");
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[0].located[j]);
    printf(" grid_specimens=%d classify_s=%.2f wall_s=%.2f seed=%u\n",
           (int)lround(0.25 / 0.005) * (int)o.nphi, r[1].classify_s + r[0].classify_s, r[1].wall_s + r[0].wall_s,
           o.seed);
    return 0;
}
