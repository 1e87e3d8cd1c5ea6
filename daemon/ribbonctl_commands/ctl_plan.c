/* ctl_plan.c: `ribbonctl plan`, the next specimens to make (issue 35 part D, docs/campaign.md
 * "The next specimen"). Proposing reads the store (--db, or the rig file's store.path) and the
 * predicted boundary (as `ribbonctl phase`: --boundary-csv, or traced from --config's scene and
 * cached), pools the trials' calibrations into the lab strip (campaign_strip.h) and traces its
 * boundary (cached on the strip), runs the planner (campaign_plan.h: that boundary shifted by the
 * offset fitted from the trials so far, the measured regimes with their noise) and stores the
 * proposals as one batch. --list shows them. --approve N asks ribbond (POST /plan/N/approve) to make proposal N a
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
    int json, list, no_calibration, no_strip;
    double noise, tau, offset_sd, spread_max, undecided;
} plan_opts;

static void help(void)
{
    printf("usage:\n"
           "  ribbonctl plan [--phi LIST] [--count K] [--db FILE] [--config RIG] [--boundary-csv FILE]\n"
           "      [--no-strip] [--no-calibration] [--noise W] [--undecided H] [--tau T] [--offset-sd S]\n"
           "      [--spread-max S] [--json]\n"
           "  ribbonctl plan --list [--db FILE] [--config RIG] [--json]\n"
           "  ribbonctl plan --approve N [--name SPECIMEN] [--url URL] [--token T] [--json]\n"
           "\n"
           "Proposes the next K specimens (phi, Gamma) (default 3) that most reduce the uncertainty of the\n"
           "experimental boundary at the phi values of LIST (degrees, comma-separated; default: the phi\n"
           "values already trialled). The model: at each phi the true boundary is the lab strip's Gamma*\n"
           "plus a systematic offset of that phi: a common offset (prior sd --offset-sd, default 0.03) plus\n"
           "that phi's deviation from it, of sd s, itself fitted (prior log-uniform from --tau, default\n"
           "0.003, to --spread-max, default 0.02; --spread-max equal to --tau: one offset for every phi).\n"
           "All fitted from the trials so far, so the per-phi offsets are pooled toward the common one as\n"
           "much as the trials say they agree; each is printed with its error. A trial near the\n"
           "boundary may go either way (probit width --noise, default 0.002), or read undecided (the\n"
           "camera could not tell): an undecided trial says the boundary lies within about --undecided\n"
           "(default 0.002; 0: undecided trials are ignored) of its Gamma. The lab strip is the scene\n"
           "with what the trials' calibrations (each trial's fitted strip) share: the creases' mean\n"
           "relaxation, the hinge stiffness and E, each pooled by its standard errors where a fit\n"
           "determined it; its boundary is traced from --config's scene with them (cached beside the store)\n"
           "and read at phi - relaxation. Without calibrations it is the predicted Gamma*(phi) (ribbon-sim\n"
           "boundary's: --boundary-csv, or traced from --config's scene and cached); with --boundary-csv\n"
           "alone only the relaxation is used. The first line says which strip. --no-strip plans from the\n"
           "predicted boundary and the offset alone; --no-calibration also fixes the offset at 0.\n"
           "Each specimen goes to the widest belief, at its median (several at one phi: its quantiles).\n"
           "The proposals are stored (a new plan supersedes the ones not approved). A phi outside the\n"
           "model's range (where the boundary was not traced) is refused, named.\n"
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
    o->noise = o->tau = o->offset_sd = o->spread_max = o->undecided = NAN;
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
        else if (!strcmp(a, "--no-strip")) o->no_strip = 1;
        else if (!strcmp(a, "--db")) dst = &o->db;
        else if (!strcmp(a, "--config")) dst = &o->config;
        else if (!strcmp(a, "--boundary-csv")) dst = &o->boundary_csv;
        else if (!strcmp(a, "--phi")) dst = &o->phi;
        else if (!strcmp(a, "--url")) dst = &o->url;
        else if (!strcmp(a, "--token")) dst = &o->token;
        else if (!strcmp(a, "--name")) dst = &o->name;
        else if (!strcmp(a, "--noise")) num = &o->noise;
        else if (!strcmp(a, "--undecided")) num = &o->undecided;
        else if (!strcmp(a, "--tau")) num = &o->tau;
        else if (!strcmp(a, "--offset-sd")) num = &o->offset_sd;
        else if (!strcmp(a, "--spread-max")) num = &o->spread_max;
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
                if (*end || !isfinite(*num) || !(*num > 0 || (num == &o->undecided && *num == 0)))
                    return usage("--noise, --tau, --offset-sd and --spread-max take a number > 0, --undecided >= 0");
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

static json_t *num_or_null(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

static json_t *strip_json(const campaign_lab_strip *ls, const char *note)
{
    char d[400];
    campaign_strip_describe(ls, d, sizeof d);
    return json_pack("{s:s,s:s,s:i,s:i,s:i,s:o,s:o,s:i,s:o,s:o,s:i,s:o,s:o}", "description", d, "note", note, "fits",
                     ls->n_fits, "calibrations", ls->n_calibrations, "relax_fits", ls->n_relax, "relax_deg", num_or_null(ls->n_relax ? ls->relax_deg : NAN),
                     "relax_se", num_or_null(ls->relax_se), "hinge_fits", ls->n_hinge, "hinge", num_or_null(ls->hinge),
                     "hinge_se_rel", num_or_null(ls->hinge_se_rel), "youngs_fits", ls->n_youngs, "youngs",
                     num_or_null(ls->youngs), "youngs_se_rel", num_or_null(ls->youngs_se_rel));
}

/* The lab strip from the store's calibrations (zeroed with --no-strip or --no-calibration) and,
 * when it changes the scene's hinge or E, its boundary traced from --config's scene and cached
 * beside the store (DB.labstrip.boundary.csv, keyed on the rig, the scene and the strip; *labpred,
 * n 0 when the scene's curve serves). A trace that does not cover the planned phi, or no scene to
 * trace, falls back to the relaxation alone, said in note. -1 only when the store cannot be
 * read. */
static int lab_strip(const plan_opts *o, const rig_config *cfg, const char *db, store *st,
                     const campaign_predicted *pred, const campaign_phase *ph, const double *phis, size_t nphi,
                     campaign_lab_strip *ls, campaign_predicted *labpred, char *note, size_t note_len)
{
    campaign_strip_fit *fits = NULL;
    size_t n = 0;
    int failed = 0;
    char why[1024];
    memset(labpred, 0, sizeof *labpred);
    if (o->no_strip || o->no_calibration) {
        campaign_strip_pool(NULL, 0, ls);
        snprintf(note, note_len, "%s", o->no_calibration ? "--no-calibration" : "--no-strip");
        return 0;
    }
    if (campaign_strip_collect(st, &fits, &n, &failed, why, sizeof why)) {
        fprintf(stderr, "ribbonctl plan: the calibrations: %s\n", why);
        return -1;
    }
    campaign_strip_pool(fits, n, ls);
    size_t ncal = 0;
    for (size_t k = 0; k < n; k++) ncal += fits[k].from_calibration != 0;
    free(fits);
    /* Which records: the specimens' calibrations first, their trials' own fits only for
     * specimens without one (campaign_strip_collect). */
    if (ncal && ncal < n)
        snprintf(note, note_len, "from %zu specimen calibration%s and %zu trial fit%s (of specimens without one)",
                 ncal, ncal == 1 ? "" : "s", n - ncal, n - ncal == 1 ? "" : "s");
    else if (ncal)
        snprintf(note, note_len, "from %zu specimen calibration%s", ncal, ncal == 1 ? "" : "s");
    else
        snprintf(note, note_len, "from %zu trial fit%s (no specimen calibration)", n, n == 1 ? "" : "s");
    if (failed) {
        size_t len = strlen(note);
        snprintf(note + len, note_len - len, " (%d more trial%s whose fit failed or determined nothing)", failed,
                 failed == 1 ? "" : "s");
    }
    if (!campaign_strip_needs_trace(ls)) return 0;
    char key[96];
    campaign_strip_key(ls, key, sizeof key);
    if (!o->config) {
        size_t len = strlen(note);
        snprintf(note + len, note_len - len, "; its %s not used: no scene to trace it from (give --config RIG)", key);
        ls->hinge = ls->youngs = NAN;
        ls->n_hinge = ls->n_youngs = 0;
        return 0;
    }
    rod_scene lab;
    campaign_strip_apply(&cfg->scene, ls, &lab);
    char *base = campaign_predicted_key_text(cfg->path, cfg->scene_path);
    size_t tl = (base ? strlen(base) : 0) + sizeof key + 32;
    char *text = malloc(tl), cache[1100];
    if (!text) {
        free(base);
        fprintf(stderr, "ribbonctl plan: out of memory\n");
        return -1;
    }
    snprintf(text, tl, "%s\nlab strip %s", base ? base : "", key);
    free(base);
    unsigned long long hash = (unsigned long long)campaign_predicted_key(text);
    free(text);
    snprintf(cache, sizeof cache, "%s.labstrip.boundary.csv", db);
    size_t len = strlen(note);
    /* The cache: this strip's curve when it covers the planned phi. */
    FILE *f = fopen(cache, "r");
    if (f) {
        unsigned long long k = 0;
        int ok = fscanf(f, "# campaign-boundary key=%llx", &k) == 1 && k == hash;
        fclose(f);
        double gg;
        size_t j = 0;
        if (ok && campaign_predicted_load_csv(cache, labpred, why, sizeof why) == 0) {
            while (j < nphi && campaign_strip_at(labpred, ls, phis[j], &gg, why, sizeof why) == 0) j++;
            if (j == nphi) {
                snprintf(labpred->source, sizeof labpred->source, "cache %.580s", cache);
                snprintf(note + len, note_len - len, "; its boundary from the %s", labpred->source);
                return 0;
            }
            campaign_predicted_free(labpred);
        }
    }
    /* Traced from the strip's codim-2 point near the planned phi nearest the scene's angle, at
     * the predicted boundary there plus the offset the trials give it (where the strip's boundary
     * should be), then around it (campaign_strip_trace). */
    size_t near = 0;
    double phi_s = fabs(cfg->scene.fold_angle_deg);
    for (size_t j = 1; j < nphi; j++)
        if (fabs(phis[j] - phi_s) < fabs(phis[near] - phi_s)) near = j;
    double g0 = NAN;
    if (campaign_predicted_at(pred, phis[near], &g0, why, sizeof why) == 0 && ph && ph->n_obs) {
        campaign_plan_opts po = campaign_plan_opts_default();
        campaign_belief b;
        campaign_plan_result res = {.beliefs = &b, .proposals = NULL};
        if (campaign_plan_run(&phis[near], &g0, 1, ph->obs, ph->n_obs, &po, 0, &res, why, sizeof why) == 0)
            g0 = b.median; /* phi's own belief: the scene's boundary moved by its trials */
    }
    if (!isfinite(g0)) g0 = cfg->scene.fold_position;
    double starts[] = {g0, g0 + 0.005, g0 - 0.005, g0 + 0.01, g0 - 0.01};
    fprintf(stderr, "lab strip boundary: %s, traced over phi %g .. %g deg\n", key, CAMPAIGN_PHI_TRACE_LO,
            CAMPAIGN_PHI_TRACE_HI);
    if (campaign_strip_trace(&lab, ls, phis[near] - (ls->n_relax ? ls->relax_deg : 0), starts, 5, CAMPAIGN_PHI_TRACE_LO,
                             CAMPAIGN_PHI_TRACE_HI, phis, nphi, labpred, why, sizeof why)) {
        snprintf(note + len, note_len - len, "; its boundary could not be traced over the planned phi (%.700s): "
                 "planning from the predicted boundary with the relaxation alone", why);
        ls->hinge = ls->youngs = NAN;
        ls->n_hinge = ls->n_youngs = 0;
        memset(labpred, 0, sizeof *labpred);
        return 0;
    }
    char line[128], w[300];
    snprintf(line, sizeof line, "# campaign-boundary key=%016llx phi=%.17g:%.17g", hash, CAMPAIGN_PHI_TRACE_LO,
             CAMPAIGN_PHI_TRACE_HI);
    int saved = campaign_predicted_save_csv(labpred, cache, line, w, sizeof w) == 0;
    snprintf(note + len, note_len - len, "; its boundary %.400s%s%.300s%s%.200s", labpred->source,
             saved ? ", cached in " : " (not cached: ", saved ? cache : w, saved ? "" : ")", "");
    if (labpred->stop[0]) {
        len = strlen(note);
        snprintf(note + len, note_len - len, "; stopped %.300s", labpred->stop);
    }
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
    campaign_lab_strip ls;
    campaign_predicted labpred = {0};
    char strip_note[1400] = "";
    if (lab_strip(&o, &cfg, db, st, &pred, rc == 0 ? &ph : NULL, phis, nphi, &ls, &labpred, strip_note,
                  sizeof strip_note)) {
        campaign_predicted_free(&pred);
        campaign_phase_free(&ph);
        store_close(st);
        return 1;
    }
    const campaign_predicted *model = labpred.n ? &labpred : &pred;
    double predicted[MAX_PHI], scene_gamma[MAX_PHI];
    for (size_t j = 0; j < nphi; j++)
        if (campaign_strip_at(model, &ls, phis[j], &predicted[j], why, sizeof why) ||
            campaign_predicted_at(&pred, phis[j], &scene_gamma[j], why, sizeof why)) {
            fprintf(stderr, "ribbonctl plan: %s\n", why);
            campaign_predicted_free(&labpred);
            campaign_predicted_free(&pred);
            campaign_phase_free(&ph);
            store_close(st);
            return 1;
        }
    campaign_plan_opts po = campaign_plan_opts_default();
    if (isfinite(o.noise)) po.noise = o.noise;
    if (isfinite(o.undecided)) po.undecided = o.undecided;
    if (isfinite(o.tau)) po.tau = o.tau;
    if (isfinite(o.offset_sd)) po.offset_sd = o.offset_sd;
    if (isfinite(o.spread_max)) po.spread_max = o.spread_max;
    else if (po.spread_max < po.tau) po.spread_max = po.tau; /* --tau above the default spread: one offset */
    po.calibrate = !o.no_calibration;
    campaign_belief beliefs[MAX_PHI];
    campaign_proposal props[50];
    campaign_plan_result res = {.beliefs = beliefs, .proposals = props};
    rc = campaign_plan_run(phis, predicted, nphi, ph.obs, ph.n_obs, &po, (size_t)o.count, &res, why, sizeof why);
    store_plan_proposal sp_rows[50];
    if (rc == 0) {
        for (size_t k = 0; k < res.k; k++) {
            double pg = 0; /* the model's boundary there: the lab strip's */
            for (size_t j = 0; j < nphi; j++)
                if (phis[j] == props[k].phi_deg) pg = predicted[j];
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
            json_array_append_new(b, json_pack("{s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f}", "phi_deg",
                                               beliefs[j].phi_deg, "predicted_gamma", beliefs[j].predicted, "scene_gamma", scene_gamma[j],
                                               "offset_mean", beliefs[j].offset_mean, "offset_sd", beliefs[j].sd,
                                               "mean", beliefs[j].mean, "sd", beliefs[j].sd, "median",
                                               beliefs[j].median, "lo", beliefs[j].lo, "hi", beliefs[j].hi));
        for (size_t k = 0; k < res.k; k++) json_array_append_new(a, campaign_proposal_json(&sp_rows[k]));
        json_t *j = json_pack("{s:f,s:f,s:f,s:f,s:b,s:s,s:o,s:o,s:o}", "offset_mean", res.offset_mean, "offset_sd",
                              res.offset_sd, "spread_mean", res.spread_mean, "spread_max", po.spread_max, "calibrated",
                              po.calibrate, "predicted_source", model->source, "strip",
                              strip_json(&ls, strip_note), "beliefs", b, "proposals", a);
        print_json(j);
        json_decref(j);
    } else {
        char d[400];
        campaign_strip_describe(&ls, d, sizeof d);
        printf("strip: %s%s%s\n", d, strip_note[0] ? "; " : "", strip_note);
        if (po.calibrate)
            printf("offset %+.4f +- %.4f (fitted, common), the per-phi offsets' spread %.4f (fitted, %.4f .. %.4f), "
                   "from %d measured trials\n", res.offset_mean, res.offset_sd, res.spread_mean, po.tau, po.spread_max,
                   ph.n_trials);
        else
            printf("offset %+.4f +- %.4f (fixed: no calibration), from %d measured trials\n", res.offset_mean,
                   res.offset_sd, ph.n_trials);
        printf("phi_deg  predicted  lab strip  offset +- sd         belief mean +- sd    95%% interval\n");
        for (size_t j = 0; j < nphi; j++)
            printf("%-8g %-10.4f %-10.4f %+.4f +- %.4f    %.4f +- %.4f    [%.4f, %.4f]\n", beliefs[j].phi_deg,
                   scene_gamma[j], beliefs[j].predicted, beliefs[j].offset_mean, beliefs[j].sd, beliefs[j].mean,
                   beliefs[j].sd, beliefs[j].lo, beliefs[j].hi);
        for (size_t k = 0; k < res.k; k++)
            printf("proposal %lld: phi %g deg, Gamma %.4f   (ribbonctl plan --approve %lld)\n", (long long)sp_rows[k].id,
                   sp_rows[k].phi_deg, sp_rows[k].gamma, (long long)sp_rows[k].id);
    }
    campaign_predicted_free(&labpred);
    campaign_predicted_free(&pred);
    campaign_phase_free(&ph);
    store_close(st);
    return rc ? 1 : 0;
}
