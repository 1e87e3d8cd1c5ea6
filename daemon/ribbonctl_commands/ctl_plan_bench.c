/* ctl_plan_bench.c: `ribbonctl plan-bench`, the simulated campaign (campaign_bench.h, issue 35
 * part D): the planner calibrated by the twins' fits (the lab strip and the offset), with the offset
 * alone, and with the offset fixed at 0, on the same bench (same seed), against twins whose
 * creases relaxed and soften; one machine-readable line. */
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
           "                            [--hinge K] [--spread S] [--dynamic] [--truth static|dynamic]\n"
           "                            [--fit-hinge K] [--db FILE] [--verbose]\n"
           "\n"
           "The simulated campaign: the planner proposes one specimen at a time at the phi values of LIST\n"
           "(default 60,90,120); each is folded as a twin of the scene whose creases relaxed by --relax\n"
           "degrees (default 6) and are more compliant (rigid-crease stiffness factor --factor, default 3,\n"
           "or compliant hinges of --hinge K N m/rad),\n"
           "each crease off by up to --spread (default 0.01) at random, and its regime measured by the\n"
           "simulator's classification; until every phi's experimental boundary is at most 0.005 wide or\n"
           "--max specimens (default 15). Three campaigns on the same twins: calibrated (each twin's strip\n"
           "fitted from its noisy static observables before the snap, as a trial's calibration; the fits\n"
           "pooled into the lab strip whose boundary the planner traces, plus the fitted offset), offset\n"
           "only (the scene's boundary plus the offset), and without calibration. The fits start from the\n"
           "design's scene: both crease angles, and the hinge from --fit-hinge K when the scene's creases\n"
           "are rigid (default 3e-3 with --hinge, none without; 0: never). Truth: the twins' mean strip's\n"
           "boundary traced by rod_boundary. One line: bench-plan specimens=... max_error=...\n"
           "--dynamic measures each twin by its simulated snap (the fast prediction, the regime rule on\n"
           "peak |A|) and takes as truth the mean strip's dynamic switch bisected to 5e-4 (slow: about a\n"
           "second per specimen, ten per phi). --truth chooses what the campaigns are scored against,\n"
           "whatever measured the twins (default: the measurement's kind).\n"
           "--db writes the calibrated campaign's specimens (B-1, B-2, ...) and measured trials to a store\n"
           "(for ribbonctl phase).\n"
           "\n"
           "usage: ribbonctl plan-bench --camera --config RIG [--set K=V ...] [--dir D] [--name STEM] [--phi LIST]\n"
           "                            [--max K] [--seed S] [--relax DEG] [--hinge K] [--spread S]\n"
           "                            [--calibration both|on|off] [--no-strip] [--no-dynamic-truth] [--timeout S]\n"
           "                            [--keep-videos] [--verbose]\n"
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
           "s). The calibrated campaign plans as ribbonctl plan does: from the lab strip (the specimens'\n"
           "calibrations, else their trials' fits) and the per-phi offsets pooled toward a common one;\n"
           "--no-strip plans from the scene's boundary and the offsets instead (--strip, the default, is\n"
           "accepted).\n"
           "Each trial's video is removed once read unless --keep-videos. At phi 120 the twin cannot be\n"
           "mounted at mock.ini's Delta L 0.2 (nor at 0.3 from Gamma 0.206): add --set\n"
           "rail.compress.start_mm=130 (Delta L 0.4). Minutes per campaign (half a minute to a minute a\n"
           "trial). One line: bench-plan-camera specimens=...\n");
}

/* Specimen k's calibration as a trial's fit record (trial_calibrated_json's form) with the
 * values the lab strip pools: both creases at the fit's mean magnitude with its standard error
 * (the pooling takes their mean), the hinge where it was fitted. */
static void fit_json(const campaign_strip_fit *f, const rod_scene *sc, double phi, char *out, size_t len)
{
    double sg = sc->fold_angle_deg < 0 ? -1 : 1;
    int n = snprintf(out, len, "{\"ok\":true,\"source\":\"ribbonctl plan-bench (the snap not predicted: the "
                               "bench's placeholder 0.4 and the measured regime)\",\"parameters\":[");
    for (int side = 0; side < 2; side++)
        n += snprintf(out + n, len - (size_t)n,
                      "%s{\"key\":\"folds.angle_%s_deg\",\"scene\":%.10g,\"fitted\":%.10g,\"se\":%.10g,"
                      "\"se_kind\":\"absolute\",\"determined\":true,\"at_bound\":0}",
                      side ? "," : "", side ? "right" : "left", sg * phi, sg * f->angle_mean_deg, f->angle_se_deg);
    if (isfinite(f->ln_hinge))
        n += snprintf(out + n, len - (size_t)n,
                      ",{\"key\":\"folds.hinge_stiffness\",\"scene\":%.10g,\"fitted\":%.10g,\"se\":%.10g,"
                      "\"se_kind\":\"relative\",\"determined\":true,\"at_bound\":0}",
                      f->hinge_scene, exp(f->ln_hinge), f->ln_hinge_se);
    snprintf(out + n, len - (size_t)n, "]}");
}

/* The calibrated campaign's specimens and their measured trials into a store (mock mode, done),
 * named B-1, B-2, ... in the order made, each trial with its twin's calibration: a store
 * `ribbonctl phase` can draw and `ribbonctl plan` plans from. */
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
        char fj[1024];
        store_trial_def d = store_trial_def_default();
        d.created_wall_s = t;
        if (store_specimen_upsert(st, &sp, &sid, why, sizeof why) != STORE_OK ||
            (d.specimen_id = sid, store_trial_create(st, &d, &tid, why, sizeof why)) != STORE_OK ||
            store_trial_set_status(st, tid, STORE_STATUS_RUNNING, NULL, t, why, sizeof why) != STORE_OK ||
            store_trial_set_result(st, tid, true, 0.4, asym ? STORE_REGIME_ASYMMETRIC : STORE_REGIME_SYMMETRIC, why,
                                   sizeof why) != STORE_OK ||
            (r->has_fit[k] && (fit_json(&r->fit[k], sc, o->phi_deg, fj, sizeof fj),
                               store_trial_set_calibrated(st, tid,
                                                          &(store_calibrated){.snap_dw = 0.4, .snap_sd = NAN,
                                                                              .p_other = NAN,
                                                                              .regime = asym ? "asymmetric" : "symmetric",
                                                                              .fit_json = fj},
                                                          why, sizeof why) != STORE_OK)) ||
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
        if (!strcmp(a, "--truth")) {
            if (strcmp(v, "static") && strcmp(v, "dynamic")) {
                fprintf(stderr, "ribbonctl plan-bench: --truth takes static or dynamic\n");
                return 2;
            }
            o.truth = strcmp(v, "static") ? 2 : 1;
            continue;
        }
        if (!strcmp(a, "--fit-hinge")) {
            o.fit_hinge_start = strtod(v, &end);
            if (*end || !(o.fit_hinge_start >= 0) || !isfinite(o.fit_hinge_start)) {
                fprintf(stderr, "ribbonctl plan-bench: --fit-hinge takes a stiffness >= 0 in N m/rad (0: no hinge)\n");
                return 2;
            }
            continue;
        }
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
    /* r[2]: calibrated with the lab strip; r[1]: the offset alone; r[0]: without calibration. */
    static campaign_bench_result r[3];
    for (int m = 2; m >= 0; m--) {
        o.calibrate = m > 0;
        o.lab_strip = m == 2;
        if (verbose) fprintf(stderr, "%s:\n", m == 2 ? "calibrated (lab strip + offset)" : m ? "offset only" : "without calibration");
        if (campaign_bench_run(&sc, &o, &r[m], progress, verbose ? &verbose : NULL, why, sizeof why)) {
            fprintf(stderr, "ribbonctl plan-bench: %s\n", why);
            return 1;
        }
    }
    if (db && write_store(db, &r[2], &sc)) return 1;
    printf("bench-plan nodes=%d phi=", sc.nodes);
    for (size_t j = 0; j < o.nphi; j++) printf("%s%g", j ? "," : "", o.phi_deg[j]);
    int dyn = o.truth == 2 || (o.truth == 0 && o.dynamic);
    printf(" measured=%s truth_kind=%s", o.dynamic ? "dynamic" : "static", dyn ? "dynamic" : "static");
    const char *pre[3] = {"uncal_", "offset_", ""};
    for (int m = 2; m >= 0; m--) {
        printf(" %sspecimens=%d %sconverged=%d %smax_error=%.5f %serrors=", pre[m], r[m].specimens, pre[m],
               r[m].converged, pre[m], r[m].max_error, pre[m]);
        for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[m].located[j] - r[m].truth[j]);
        if (m) printf(" %soffset=%.5f", pre[m], r[m].offset_mean);
    }
    printf(" truth=");
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[2].truth[j]);
    if (dyn) {
        printf(" truth_static=");
        for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[2].truth_static[j]);
    }
    printf(" predicted=");
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[2].predicted[j]);
    printf(" lab_model=");
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[2].model[j]);
    printf(" located=");
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[2].located[j]);
    printf(" offset_located=");
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[1].located[j]);
    printf(" uncal_located=");
    for (size_t j = 0; j < o.nphi; j++) printf("%s%.5f", j ? "," : "", r[0].located[j]);
    const campaign_lab_strip *ls = &r[2].strip;
    printf(" calibrations=%d fit_failures=%d strip_relax_deg=%.3f strip_relax_se=%.3f strip_hinge=%.3g "
           "strip_hinge_se_rel=%.3f traces=%d fit_s=%.2f trace_s=%.2f",
           r[2].calibrations, r[2].calibration_failures, ls->relax_deg, ls->relax_se, ls->hinge, ls->hinge_se_rel,
           r[2].traces, r[2].fit_s, r[2].trace_s);
    printf(" grid_specimens=%d classify_s=%.2f wall_s=%.2f seed=%u\n",
           (int)lround(0.25 / 0.005) * (int)o.nphi, r[2].classify_s + r[1].classify_s + r[0].classify_s,
           r[2].wall_s + r[1].wall_s + r[0].wall_s, o.seed);
    return 0;
}
