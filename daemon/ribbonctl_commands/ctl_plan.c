/* ctl_plan.c: `ribbonctl plan`, the next specimens to make (issue 35 part D, docs/campaign.md
 * "The next specimen"). Proposing reads the store (--db, or the rig file's store.path) and the
 * predicted boundary (as `ribbonctl phase`: --boundary-csv, or traced from --config's scene and
 * cached), runs the planner (campaign_plan.h: the prediction shifted by the offset fitted from
 * the trials so far, the measured regimes with their noise) and stores the proposals as one
 * batch. --list shows them. --approve N asks ribbond (POST /plan/N/approve) to make proposal N a
 * specimen with an operator step and a trial in the queue. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "api.h"
#include "campaign.h"
#include "ctl.h"
#include "rig_config.h"
#include "store.h"

#define MAX_PHI 32

typedef struct plan_opts {
    const char *db, *config, *boundary_csv, *phi, *url, *token, *name;
    long count;
    long long approve;
    int json, list, no_calibration;
    double noise, tau, offset_sd;
} plan_opts;

static void help(void)
{
    printf("usage:\n"
           "  ribbonctl plan [--phi LIST] [--count K] [--db FILE] [--config RIG] [--boundary-csv FILE]\n"
           "      [--no-calibration] [--noise W] [--tau T] [--offset-sd S] [--json]\n"
           "  ribbonctl plan --list [--db FILE] [--config RIG] [--json]\n"
           "  ribbonctl plan --approve N [--name SPECIMEN] [--url URL] [--token T] [--json]\n"
           "\n"
           "Proposes the next K specimens (phi, Gamma) (default 3) that most reduce the uncertainty of the\n"
           "experimental boundary at the phi values of LIST (degrees, comma-separated; default: the phi\n"
           "values already trialled). The model: at each phi the true boundary is the predicted Gamma*(phi)\n"
           "(ribbon-sim boundary's: --boundary-csv, or traced from --config's scene and cached) plus one\n"
           "systematic offset shared by every phi, fitted from the trials so far (prior sd --offset-sd,\n"
           "default 0.03), plus a model error per phi (--tau, default 0.003); a trial near the boundary may\n"
           "go either way (probit width --noise, default 0.002). --no-calibration fixes the offset at 0.\n"
           "Each specimen goes to the widest belief, at its median (several at one phi: its quantiles).\n"
           "The proposals are stored (a new plan supersedes the ones not approved). A phi outside the\n"
           "model's range (where the predicted boundary was not traced) is refused, named.\n"
           "--approve N (through ribbond's API) adds specimen N's record (--name, default plan-N) and puts\n"
           "an operator step (fold and mount it, measured angles?) and a trial of it in the queue.\n");
}

static int usage(const char *msg)
{
    fprintf(stderr, "ribbonctl plan: %s (see ribbonctl plan --help)\n", msg);
    return 2;
}

static int parse(int argc, char **argv, plan_opts *o)
{
    memset(o, 0, sizeof *o);
    o->count = 3;
    o->noise = o->tau = o->offset_sd = NAN;
    o->url = getenv("RIBBON_URL");
    if (!o->url || !*o->url) o->url = "http://127.0.0.1:8377";
    o->token = getenv("RIBBON_TOKEN");
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        const char **dst = NULL;
        double *num = NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 1;
        } else if (!strcmp(a, "--json")) o->json = 1;
        else if (!strcmp(a, "--list")) o->list = 1;
        else if (!strcmp(a, "--no-calibration")) o->no_calibration = 1;
        else if (!strcmp(a, "--db")) dst = &o->db;
        else if (!strcmp(a, "--config")) dst = &o->config;
        else if (!strcmp(a, "--boundary-csv")) dst = &o->boundary_csv;
        else if (!strcmp(a, "--phi")) dst = &o->phi;
        else if (!strcmp(a, "--url")) dst = &o->url;
        else if (!strcmp(a, "--token")) dst = &o->token;
        else if (!strcmp(a, "--name")) dst = &o->name;
        else if (!strcmp(a, "--noise")) num = &o->noise;
        else if (!strcmp(a, "--tau")) num = &o->tau;
        else if (!strcmp(a, "--offset-sd")) num = &o->offset_sd;
        else if (!strcmp(a, "--count") || !strcmp(a, "--approve")) {
            char *end;
            errno = 0;
            long long n = v ? strtoll(v, &end, 10) : 0;
            if (!v || errno || *end || n < 1 || (a[2] == 'c' && n > 50))
                return usage(a[2] == 'c' ? "--count takes K in 1..50" : "--approve takes a proposal id >= 1");
            if (a[2] == 'c') o->count = (long)n;
            else o->approve = n;
            i++;
        } else {
            char m[160];
            snprintf(m, sizeof m, "unknown argument %s", a);
            return usage(m);
        }
        if (dst || num) {
            if (!v) return usage("missing value after option");
            if (dst) *dst = v;
            else {
                char *end;
                *num = strtod(v, &end);
                if (*end || !(*num > 0) || !isfinite(*num)) return usage("--noise, --tau and --offset-sd take a number > 0");
            }
            i++;
        }
    }
    if (!o->approve && !o->db && !o->config) return usage("which store? give --db FILE or --config RIG");
    return 0;
}

static void print_json(json_t *j)
{
    char *t = json_dumps(j, JSON_INDENT(2));
    if (t) puts(t);
    free(t);
}

static int approve(const plan_opts *o)
{
    char why[512];
    if (api_client_global_init(why, sizeof why)) {
        fprintf(stderr, "ribbonctl: %s\n", why);
        return 1;
    }
    api_client_config c = api_client_config_default();
    c.base_url = o->url;
    c.token = o->token;
    char path[64];
    snprintf(path, sizeof path, "/plan/%lld/approve", o->approve);
    json_t *body = o->name ? json_pack("{s:s}", "name", o->name) : json_object(), *out = NULL;
    int status = 0;
    int rc = api_client_request(&c, "POST", path, body, &status, &out, NULL, NULL, why, sizeof why);
    json_decref(body);
    api_client_global_cleanup();
    if (rc != 0) {
        fprintf(stderr, "ribbonctl: POST %s: %s\n", path, why);
        json_decref(out);
        return 1;
    }
    if (status >= 300) {
        json_t *e = json_object_get(out, "error");
        fprintf(stderr, "ribbonctl: POST %s: %d %s\n", path, status, json_is_string(e) ? json_string_value(e) : "");
        json_decref(out);
        return 1;
    }
    if (o->json) print_json(out);
    else {
        json_t *p = json_object_get(out, "proposal");
        printf("proposal %lld approved: specimen %s (phi %g, Gamma %.4f); queue items %lld (operator) and %lld (trial)\n",
               o->approve, json_string_value(json_object_get(p, "specimen")),
               json_real_value(json_object_get(p, "phi_deg")), json_real_value(json_object_get(p, "gamma")),
               (long long)json_integer_value(json_object_get(p, "operator_item")),
               (long long)json_integer_value(json_object_get(p, "trial_item")));
    }
    json_decref(out);
    return 0;
}

static int list(store *st, const plan_opts *o)
{
    store_plan_proposal *v = NULL;
    size_t n = 0;
    char why[512];
    if (store_plan_list(st, &v, &n, why, sizeof why) != STORE_OK) {
        fprintf(stderr, "ribbonctl plan: %s\n", why);
        return 1;
    }
    if (o->json) {
        json_t *a = json_array();
        for (size_t k = 0; k < n; k++) json_array_append_new(a, campaign_proposal_json(&v[k]));
        print_json(a);
        json_decref(a);
    } else {
        if (!n) printf("no proposals yet (ribbonctl plan --phi LIST --count K)\n");
        for (size_t k = 0; k < n; k++)
            printf("%4lld  batch %-3lld %-10s phi %-7g Gamma %.4f  (sd %.4f, predicted %.4f, offset %+.4f)%s%s\n",
                   (long long)v[k].id, (long long)v[k].batch, store_plan_status_name(v[k].status), v[k].phi_deg,
                   v[k].gamma, v[k].sd_before, v[k].predicted_gamma, v[k].offset_mean,
                   v[k].specimen_name[0] ? "  specimen " : "", v[k].specimen_name);
    }
    free(v);
    return 0;
}

int ctl_plan_main(int argc, char **argv)
{
    plan_opts o;
    int p = parse(argc, argv, &o);
    if (p) return p == 1 ? 0 : 2;
    if (o.approve) return approve(&o);
    char why[1024];
    static rig_config cfg;
    if (o.config) {
        cfg_error ce;
        if (rig_config_load(o.config, NULL, 0, &cfg, &ce) != CFG_OK) {
            cfg_error_format(&ce, why, sizeof why);
            fprintf(stderr, "ribbonctl plan: %s\n", why);
            return 1;
        }
    }
    const char *db = o.db ? o.db : cfg.store_path;
    store *st;
    store_open_params sp = store_open_params_default();
    sp.read_only = o.list;
    if (store_open_ex(db, &sp, &st, why, sizeof why) != STORE_OK) {
        fprintf(stderr, "ribbonctl plan: store %s: %s\n", db, why);
        return 1;
    }
    if (o.list) {
        int rc = list(st, &o);
        store_close(st);
        return rc;
    }
    campaign_phase ph;
    int rc = campaign_phase_collect(st, &ph, why, sizeof why);
    if (rc == -1) {
        fprintf(stderr, "ribbonctl plan: %s\n", why);
        store_close(st);
        return 1;
    }
    double phis[MAX_PHI];
    size_t nphi = 0;
    if (o.phi) {
        const char *s = o.phi;
        while (*s && nphi < MAX_PHI) {
            char *end;
            double v = strtod(s, &end);
            if (end == s || !(v > 0 && v < 180) || (*end && *end != ',')) {
                campaign_phase_free(&ph);
                store_close(st);
                return usage("--phi takes degrees in (0, 180), comma-separated");
            }
            phis[nphi++] = v;
            s = *end ? end + 1 : end;
        }
    } else if (rc == 0) {
        for (size_t k = 0; k < ph.n_edges && nphi < MAX_PHI; k++) phis[nphi++] = ph.edges[k].phi_deg;
    }
    if (!nphi) {
        fprintf(stderr, "ribbonctl plan: no phi to plan: %s; give --phi LIST\n", rc ? why : "no trialled phi");
        campaign_phase_free(&ph);
        store_close(st);
        return 2;
    }
    campaign_predicted pred = {0};
    int have = 0;
    if (ctl_campaign_predicted(o.config, o.boundary_csv, db, CAMPAIGN_PHI_TRACE_LO, CAMPAIGN_PHI_TRACE_HI, &pred, &cfg, &have) || !have) {
        if (!have) fprintf(stderr, "ribbonctl plan: the planner needs the predicted boundary: give --config RIG or --boundary-csv FILE\n");
        campaign_phase_free(&ph);
        store_close(st);
        return 1;
    }
    double predicted[MAX_PHI];
    for (size_t j = 0; j < nphi; j++)
        if (campaign_predicted_at(&pred, phis[j], &predicted[j], why, sizeof why)) {
            fprintf(stderr, "ribbonctl plan: %s\n", why);
            campaign_predicted_free(&pred);
            campaign_phase_free(&ph);
            store_close(st);
            return 1;
        }
    campaign_plan_opts po = campaign_plan_opts_default();
    if (isfinite(o.noise)) po.noise = o.noise;
    if (isfinite(o.tau)) po.tau = o.tau;
    if (isfinite(o.offset_sd)) po.offset_sd = o.offset_sd;
    po.calibrate = !o.no_calibration;
    campaign_belief beliefs[MAX_PHI];
    campaign_proposal props[50];
    campaign_plan_result res = {.beliefs = beliefs, .proposals = props};
    rc = campaign_plan_run(phis, predicted, nphi, ph.obs, ph.n_obs, &po, (size_t)o.count, &res, why, sizeof why);
    store_plan_proposal sp_rows[50];
    if (rc == 0) {
        for (size_t k = 0; k < res.k; k++) {
            double pg = 0;
            char w[8];
            campaign_predicted_at(&pred, props[k].phi_deg, &pg, w, sizeof w);
            sp_rows[k] = (store_plan_proposal){.phi_deg = props[k].phi_deg, .gamma = props[k].gamma,
                                               .sd_before = props[k].sd_before, .predicted_gamma = pg,
                                               .offset_mean = res.offset_mean, .offset_sd = res.offset_sd,
                                               .calibrated = po.calibrate};
        }
        if (store_plan_add_batch(st, sp_rows, res.k, store_wall_now(), why, sizeof why) != STORE_OK) rc = -1;
    }
    if (rc) {
        fprintf(stderr, "ribbonctl plan: %s\n", why);
    } else if (o.json) {
        json_t *b = json_array(), *a = json_array();
        for (size_t j = 0; j < nphi; j++)
            json_array_append_new(b, json_pack("{s:f,s:f,s:f,s:f,s:f,s:f,s:f}", "phi_deg", beliefs[j].phi_deg,
                                               "predicted_gamma", beliefs[j].predicted, "mean", beliefs[j].mean, "sd",
                                               beliefs[j].sd, "median", beliefs[j].median, "lo", beliefs[j].lo, "hi",
                                               beliefs[j].hi));
        for (size_t k = 0; k < res.k; k++) json_array_append_new(a, campaign_proposal_json(&sp_rows[k]));
        json_t *j = json_pack("{s:f,s:f,s:b,s:s,s:o,s:o}", "offset_mean", res.offset_mean, "offset_sd", res.offset_sd,
                              "calibrated", po.calibrate, "predicted_source", pred.source, "beliefs", b, "proposals", a);
        print_json(j);
        json_decref(j);
    } else {
        printf("offset %+.4f +- %.4f (%s), from %d measured trials\n", res.offset_mean, res.offset_sd,
               po.calibrate ? "fitted" : "fixed: no calibration", ph.n_trials);
        printf("phi_deg  predicted  belief mean +- sd    95%% interval\n");
        for (size_t j = 0; j < nphi; j++)
            printf("%-8g %-10.4f %.4f +- %.4f    [%.4f, %.4f]\n", beliefs[j].phi_deg, beliefs[j].predicted,
                   beliefs[j].mean, beliefs[j].sd, beliefs[j].lo, beliefs[j].hi);
        for (size_t k = 0; k < res.k; k++)
            printf("proposal %lld: phi %g deg, Gamma %.4f   (ribbonctl plan --approve %lld)\n", (long long)sp_rows[k].id,
                   sp_rows[k].phi_deg, sp_rows[k].gamma, (long long)sp_rows[k].id);
    }
    campaign_predicted_free(&pred);
    campaign_phase_free(&ph);
    store_close(st);
    return rc ? 1 : 0;
}
