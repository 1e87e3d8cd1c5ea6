/* ctl_phase.c: `ribbonctl phase`, the lab's own phase diagram (issue 35 part C,
 * docs/campaign.md "The lab's phase diagram"): every specimen's measured regimes at its design
 * (phi, Gamma) with counts, the boundary the experiments support per phi with its interval, over
 * the predicted boundary Gamma*(phi) (ribbon-sim boundary's, from --boundary-csv or traced from
 * the rig file's scene and cached beside the store) and, with --map, the predicted regime map.
 * Offline: it reads the store file (--db, or the rig file's store.path) read-only. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "campaign.h"
#include "cfg_number.h"
#include "ctl.h"
#include "rig_config.h"
#include "store.h"
#include "trial_report.h"

typedef struct phase_opts {
    const char *db, *config, *boundary_csv, *out, *csv;
    int json, map;
} phase_opts;

static void help(void)
{
    printf("usage:\n"
           "  ribbonctl phase [--db FILE] [--config RIG] [--boundary-csv FILE] [--out FIG.png] [--csv FILE]\n"
           "      [--map] [--json]\n"
           "\n"
           "The lab's phase diagram: every specimen's measured regimes at its design (phi, Gamma),\n"
           "repeated trials as counts; per phi the boundary the experiments support (where the measured\n"
           "regimes switch: the bracket between the highest asymmetric and lowest symmetric Gamma, or a\n"
           "probit fit with a noise width and a 95%% interval where they overlap); and the predicted\n"
           "boundary Gamma*(phi). The predicted boundary is ribbon-sim boundary's CSV (--boundary-csv), or\n"
           "traced from the rig file's scene (--config; about half a second at N = 61) and cached in\n"
           "DB.boundary.csv beside the store. --map also draws the predicted regime map (N = 41, about\n"
           "0.5 s a point, 30 points). The store is --db, else the rig file's store.path.\n"
           "--out writes the figure (PNG), --csv its data (kind,phi_deg,gamma,...: docs/campaign.md),\n"
           "--json the same data as one JSON object; otherwise a table per phi.\n"
           "Errors: no specimens in the store, no measured trials of any specimen.\n");
}

static int usage(const char *msg)
{
    fprintf(stderr, "ribbonctl phase: %s (see ribbonctl phase --help)\n", msg);
    return 2;
}

static int parse(int argc, char **argv, phase_opts *o)
{
    memset(o, 0, sizeof *o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        const char **dst = NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 1;
        } else if (!strcmp(a, "--json")) o->json = 1;
        else if (!strcmp(a, "--map")) o->map = 1;
        else if (!strcmp(a, "--db")) dst = &o->db;
        else if (!strcmp(a, "--config")) dst = &o->config;
        else if (!strcmp(a, "--boundary-csv")) dst = &o->boundary_csv;
        else if (!strcmp(a, "--out")) dst = &o->out;
        else if (!strcmp(a, "--csv")) dst = &o->csv;
        else {
            char m[160];
            snprintf(m, sizeof m, "unknown argument %s", a);
            return usage(m);
        }
        if (dst) {
            if (!v) return usage("missing value after option");
            *dst = v;
            i++;
        }
    }
    if (!o->db && !o->config) return usage("which store? give --db FILE or --config RIG");
    if (o->map && !o->config) return usage("--map needs --config (the scene to predict)");
    return 0;
}

int ctl_campaign_predicted(const char *config, const char *boundary_csv, const char *db, double phi_lo, double phi_hi,
                           campaign_predicted *pred, rig_config *cfg_out, int *have)
{
    char why[1024];
    *have = 0;
    if (boundary_csv) {
        if (campaign_predicted_load_csv(boundary_csv, pred, why, sizeof why)) {
            fprintf(stderr, "ribbonctl: %s\n", why);
            return -1;
        }
        *have = 1;
        return 0;
    }
    if (!config) return 0;
    char *key = campaign_predicted_key_text(cfg_out->path, cfg_out->scene_path);
    char cache[1100];
    snprintf(cache, sizeof cache, "%s.boundary.csv", db);
    fprintf(stderr, "predicted boundary: phi %g .. %g deg from %s\n", phi_lo, phi_hi, cfg_out->scene_path);
    int rc = campaign_predicted_cached(&cfg_out->scene, key ? key : "", phi_lo, phi_hi, cache, pred, why, sizeof why);
    free(key);
    if (rc) {
        fprintf(stderr, "ribbonctl: the predicted boundary: %s\n", why);
        return -1;
    }
    fprintf(stderr, "predicted boundary: %s%s%s\n", pred->source, pred->stop[0] ? "; stopped " : "", pred->stop);
    *have = 1;
    return 0;
}

int ctl_phase_main(int argc, char **argv)
{
    phase_opts o;
    int p = parse(argc, argv, &o);
    if (p) return p == 1 ? 0 : 2;
    char why[1024];
    static rig_config cfg;
    if (o.config) {
        cfg_error ce;
        if (rig_config_load(o.config, NULL, 0, &cfg, &ce) != CFG_OK) {
            cfg_error_format(&ce, why, sizeof why);
            fprintf(stderr, "ribbonctl phase: %s\n", why);
            return 1;
        }
    }
    const char *db = o.db ? o.db : cfg.store_path;
    store *st;
    store_open_params sp = store_open_params_default();
    sp.read_only = 1;
    if (store_open_ex(db, &sp, &st, why, sizeof why) != STORE_OK) {
        fprintf(stderr, "ribbonctl phase: store %s: %s\n", db, why);
        return 1;
    }
    campaign_phase ph;
    int rc = campaign_phase_collect(st, &ph, why, sizeof why);
    store_close(st);
    if (rc) {
        fprintf(stderr, "ribbonctl phase: %s\n", why);
        return 1;
    }
    double lo = ph.obs[0].phi_deg, hi = ph.obs[ph.n_obs - 1].phi_deg;
    campaign_predicted pred = {0};
    int have = 0;
    if (ctl_campaign_predicted(o.config, o.boundary_csv, db, CAMPAIGN_PHI_TRACE_LO, CAMPAIGN_PHI_TRACE_HI, &pred, &cfg,
                               &have)) {
        campaign_phase_free(&ph);
        return 1;
    }
    if (!have) fprintf(stderr, "ribbonctl phase: no predicted boundary (give --config RIG or --boundary-csv FILE)\n");
    const campaign_predicted *pp = have ? &pred : NULL;
    rc = 0;
    if (o.csv && campaign_phase_write_csv(&ph, pp, o.csv, why, sizeof why)) {
        fprintf(stderr, "ribbonctl phase: %s\n", why);
        rc = 1;
    }
    if (!rc && o.out) {
        plot_phase_data base;
        plot_phase_data_default(&base);
        phase_grid g = {0};
        plot_regime *codes = NULL;
        if (o.map) {
            rod_scene sc = cfg.scene;
            sc.nodes = 41;
            sc.dt = 0.01;
            double p0 = fmax(1, lo - 5), p1 = fmin(179, hi + 5);
            fprintf(stderr, "predicting the regime map (5 x 6 points, N = 41)\n");
            if (phase_grid_compute(&sc, p0, p1, p0 < p1 ? 5 : 1, 0.08, 0.28, 6, &g, NULL, NULL, NULL, why, sizeof why)) {
                fprintf(stderr, "ribbonctl phase: the predicted map: %s\n", why);
                rc = 1;
            } else if ((codes = calloc(g.n_phi * g.n_gamma, sizeof *codes))) {
                for (size_t k = 0; k < g.n_phi * g.n_gamma; k++) codes[k] = (plot_regime)g.regime[k];
                base.gamma = g.gamma, base.n_gamma = g.n_gamma, base.phi_deg = g.phi_deg, base.n_phi = g.n_phi;
                base.grid = codes;
            }
        }
        if (!rc && campaign_phase_png(&ph, pp, &base, o.out, why, sizeof why)) {
            fprintf(stderr, "ribbonctl phase: %s\n", why);
            rc = 1;
        }
        free(codes);
        if (o.map) phase_grid_free(&g);
    }
    if (!rc && o.json) {
        json_t *j = campaign_phase_json(&ph, pp);
        char *txt = json_dumps(j, JSON_INDENT(2));
        if (txt) puts(txt);
        free(txt);
        json_decref(j);
    } else if (!rc && !o.out && !o.csv) {
        printf("%d specimens, %d measured trials\n", ph.n_specimens, ph.n_trials);
        printf("phi_deg   method   Gamma_exp  interval              asym sym  predicted\n");
        for (size_t k = 0; k < ph.n_edges; k++) {
            const campaign_edge *e = &ph.edges[k];
            double g = NAN;
            char w[8];
            if (pp) campaign_predicted_at(pp, e->phi_deg, &g, w, sizeof w);
            printf("%-9g %-8s %-10.5g [%.5g, %.5g]  %4d %4d  %.5g\n", e->phi_deg, campaign_edge_method_name(e->method),
                   e->gamma, e->lo, e->hi, e->n_asym, e->n_sym, g);
        }
    }
    if (!rc && o.out) printf("phase figure: %s\n", o.out);
    if (!rc && o.csv) printf("phase data: %s\n", o.csv);
    campaign_predicted_free(&pred);
    campaign_phase_free(&ph);
    return rc;
}
