/* ctl_trials.c: ribbonctl's trial commands: start, abort, status, list, show, export, report,
 * phase-report and replay.
 *
 * Online, they ask ribbond's control API (--url, default http://127.0.0.1:8377 or $RIBBON_URL;
 * --token or $RIBBON_TOKEN). With --db FILE, list, show, export, report, phase-report and replay
 * read (and replay writes) the SQLite store directly: offline analysis, no daemon needed.
 * phase-report and replay without --db ask the daemon where its store is. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <jansson.h>

#include "api.h"
#include "cfg_number.h"
#include "ctl.h"
#include "scene_file.h"
#include "store.h"
#include "rig_config.h"
#include "trial.h"
#include "trial_report.h"
#include "twin.h"

#define MAX_SET 64

typedef struct ctl_opts {
    const char *url, *token, *db, *out, *note, *video, *scene, *config, *specimen;
    const char *set[MAX_SET];
    int n_set;
    int json, wait, csv, all;
    int64_t id;
    const char *phi, *gamma;
} ctl_opts;

static int usage_error(const char *cmd, const char *msg)
{
    fprintf(stderr, "ribbonctl %s: %s (see ribbonctl %s --help)\n", cmd, msg, cmd);
    return 2;
}

static void help(const char *cmd)
{
    printf("usage:\n"
           "  ribbonctl start [--specimen NAME] [--set section.key=value ...] [--note TEXT] [--wait [--out REPORT.png]]\n"
           "      [--json]\n"
           "  ribbonctl abort\n"
           "  ribbonctl status [--json]\n"
           "  ribbonctl list [--json] [--db FILE]\n"
           "  ribbonctl show ID [--json] [--db FILE]\n"
           "  ribbonctl export ID --csv [--out FILE] [--db FILE]   (samples of one trial; stdout by default)\n"
           "  ribbonctl export --all --out DIR [--db FILE]        (trials.csv + one samples CSV per trial)\n"
           "  ribbonctl report ID --out FILE.png [--db FILE]\n"
           "  ribbonctl phase-report --out FILE.png [--db FILE] [--scene F] [--phi A:B:n] [--gamma C:D:m]\n"
           "  ribbonctl replay ID [--video FILE] [--db FILE] [--json]\n"
           "  ribbonctl replay --config REPLAY.ini [--set section.key=value ...] [--db FILE] [--json]\n"
           "common: --url URL (default $RIBBON_URL or http://127.0.0.1:8377), --token T (default $RIBBON_TOKEN)\n"
           "\n"
           "start asks ribbond to run one trial of its rig file (with --set overrides of the keys a trial\n"
           "may change: its scene, the specimen, the trial's timing; docs/api.md); --specimen names a specimen\n"
           "of the store (ribbonctl specimen add): its record sets the trial's specimen and scene keys before\n"
           "--set, and an unknown, retired or broken specimen is refused with nothing started;\n"
           "--wait follows it on stderr and prints the measured and predicted snap when it ends (with --out,\n"
           "also its report) and the store's path on a line `database: PATH`.\n"
           "report draws Delta Z and A against Delta W, measured and predicted, snaps marked.\n"
           "phase-report draws every trial's measured regime over the predicted (Gamma, phi) phase diagram,\n"
           "computed for the scene (--scene, default the paper scene at N = 41, dt = 10 ms, fast mode)\n"
           "on the grid --phi (default 30:150:5, degrees) x --gamma (default 0.08:0.28:6).\n"
           "replay runs a recorded trial's video and rail positions through the tracker and snap detection\n"
           "again and stores the result as a new trial linked to its source. With --config, a replay-mode\n"
           "rig file names what to replay: [replay] source_trial (or ID), or an outside recording\n"
           "(replay.video, replay.rails as t_s,compress_mm,shear_mm, camera.calibration); the store is the\n"
           "rig file's store.path unless --db is given (cmd: %s).\n",
           cmd);
}

static int parse(const char *cmd, int argc, char **argv, ctl_opts *o, int want_id)
{
    memset(o, 0, sizeof *o);
    o->url = getenv("RIBBON_URL");
    if (!o->url || !*o->url) o->url = "http://127.0.0.1:8377";
    o->token = getenv("RIBBON_TOKEN");
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help(cmd);
            return 1;
        }
#define TAKE(field)                                                                                               \
    do {                                                                                                          \
        if (!v) return (usage_error(cmd, "missing value after option"), -1);                                        \
        o->field = v;                                                                                             \
        i++;                                                                                                      \
    } while (0)
        if (!strcmp(a, "--url")) TAKE(url);
        else if (!strcmp(a, "--token")) TAKE(token);
        else if (!strcmp(a, "--db")) TAKE(db);
        else if (!strcmp(a, "--out")) TAKE(out);
        else if (!strcmp(a, "--note")) TAKE(note);
        else if (!strcmp(a, "--video")) TAKE(video);
        else if (!strcmp(a, "--scene")) TAKE(scene);
        else if (!strcmp(a, "--config")) TAKE(config);
        else if (!strcmp(a, "--specimen")) TAKE(specimen);
        else if (!strcmp(a, "--phi")) TAKE(phi);
        else if (!strcmp(a, "--gamma")) TAKE(gamma);
        else if (!strcmp(a, "--set")) {
            if (!v || o->n_set >= MAX_SET) return (usage_error(cmd, "--set needs section.key=value (at most 64)"), -1);
            o->set[o->n_set++] = v;
            i++;
        } else if (!strcmp(a, "--json")) o->json = 1;
        else if (!strcmp(a, "--wait")) o->wait = 1;
        else if (!strcmp(a, "--csv")) o->csv = 1;
        else if (!strcmp(a, "--all")) o->all = 1;
        else if (want_id && !o->id && a[0] != '-') {
            char *end;
            errno = 0;
            long long id = strtoll(a, &end, 10);
            if (errno || *end || id < 1) return (usage_error(cmd, "ID must be a positive integer"), -1);
            o->id = id;
        } else {
            char msg[128];
            snprintf(msg, sizeof msg, "unknown argument %s", a);
            return (usage_error(cmd, msg), -1);
        }
#undef TAKE
    }
    return 0;
}

/* One API request; prints the reason on failure. Returns the HTTP status, or -1. */
static int request(const ctl_opts *o, const char *method, const char *path, const json_t *body, json_t **out,
                   unsigned char **bytes, size_t *len)
{
    api_client_config c = api_client_config_default();
    c.base_url = o->url;
    c.token = o->token;
    int status = 0;
    char why[512] = "";
    if (out) *out = NULL;
    if (api_client_request(&c, method, path, body, &status, out, bytes, len, why, sizeof why)) {
        fprintf(stderr, "ribbonctl: %s\n", why);
        return -1;
    }
    if (status >= 400) {
        fprintf(stderr, "ribbonctl: %s %s: %d %s\n", method, path, status, why);
        if (out && *out) {
            json_decref(*out);
            *out = NULL;
        }
        return -1;
    }
    return status;
}

static void print_json(const json_t *j)
{
    char *s = json_dumps(j, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
    if (s) puts(s);
    free(s);
}

static const char *jstr(const json_t *o, const char *k)
{
    const char *s = json_string_value(json_object_get(o, k));
    return s ? s : "-";
}

static void fmt_num(char *buf, size_t n, const json_t *v)
{
    if (json_is_number(v))
        snprintf(buf, n, "%.5f", json_number_value(v));
    else
        snprintf(buf, n, "-");
}

/* The reason of a trial's failed prediction, or NULL when it has none or it did not fail. */
static const char *prediction_failure(const json_t *t)
{
    const json_t *pr = json_object_get(t, "prediction");
    const char *st = json_string_value(json_object_get(pr, "status"));
    if (!st || strcmp(st, "failed")) return NULL;
    const char *why = json_string_value(json_object_get(pr, "failure"));
    return why ? why : "no reason stored";
}

/* The calibrated snap and its band as "0.40522+-0.00230" (or its failure's key, or "-"). */
static void fmt_calibrated(char *buf, size_t n, const json_t *t)
{
    const json_t *v = json_object_get(t, "snap_dw_calibrated"), *sd = json_object_get(t, "snap_sd_calibrated");
    const char *f = json_string_value(json_object_get(t, "fit_failure"));
    if (json_is_number(v) && json_is_number(sd))
        snprintf(buf, n, "%.5f+-%.5f", json_number_value(v), json_number_value(sd));
    else if (json_is_number(v))
        snprintf(buf, n, "%.5f", json_number_value(v));
    else if (f)
        snprintf(buf, n, "failed");
    else if (json_is_string(json_object_get(t, "regime_calibrated")))
        snprintf(buf, n, "no snap");
    else
        snprintf(buf, n, "-");
}

static void print_trial_row(const json_t *t)
{
    char m[32], p[32], c[48];
    fmt_num(m, sizeof m, json_object_get(t, "snap_dw_measured"));
    fmt_num(p, sizeof p, json_object_get(t, "snap_dw_predicted"));
    fmt_calibrated(c, sizeof c, t);
    printf("%5lld  %-6s  %-11s  %9s  %-10s  %9s  %-10s  %17s  %-10s  %8lld\n",
           (long long)json_integer_value(json_object_get(t, "id")), jstr(t, "mode"), jstr(t, "status"), m,
           jstr(t, "regime_measured"), p, prediction_failure(t) ? "failed" : jstr(t, "regime_predicted"), c,
           jstr(t, "regime_calibrated"), (long long)json_integer_value(json_object_get(t, "samples")));
}

/* What the prediction used of the specimen: each crease's angle and position and where each came
 * from (scene or specimen), the crease model (rigid or the hinge's stiffness), the values the
 * specimen's calibration put in their place, and the creases' age at the trial. */
static void print_creases(const json_t *t)
{
    const json_t *c = json_object_get(json_object_get(t, "prediction"), "creases");
    if (json_is_number(json_object_get(c, "angle_left_deg")))
        printf("  prediction's creases: left %g deg (%s) at %g (%s), right %g deg (%s) at %g (%s)\n",
               json_number_value(json_object_get(c, "angle_left_deg")), jstr(c, "angle_left_from"),
               json_number_value(json_object_get(c, "position_left")), jstr(c, "position_left_from"),
               json_number_value(json_object_get(c, "angle_right_deg")), jstr(c, "angle_right_from"),
               json_number_value(json_object_get(c, "position_right")), jstr(c, "position_right_from"));
    const json_t *k = json_object_get(c, "hinge_stiffness");
    if (json_is_number(k))
        printf("  prediction's crease hinges: %g N m/rad\n", json_number_value(k));
    else if (json_is_string(k))
        printf("  prediction's crease hinges: %s\n", json_string_value(k));
    const json_t *cal = json_object_get(json_object_get(t, "prediction"), "calibration");
    if (json_is_object(cal)) {
        printf("  prediction's strip calibrated (the specimen's trials");
        const json_t *tr = json_object_get(cal, "trials"), *ap = json_object_get(cal, "applied");
        for (size_t i = 0; i < json_array_size(tr); i++)
            printf("%s %lld", i ? "," : "", (long long)json_integer_value(json_array_get(tr, i)));
        printf("):");
        for (size_t i = 0; i < json_array_size(ap); i++) {
            const json_t *a = json_array_get(ap, i);
            printf("%s %s %.6g (was %.6g, %s)", i ? "," : "", jstr(a, "key"), json_number_value(json_object_get(a, "value")),
                   json_number_value(json_object_get(a, "replaced")), jstr(a, "replaced_from"));
        }
        printf("\n");
    }
    const json_t *age = json_object_get(t, "crease_age_s");
    if (json_is_number(age))
        printf("  creases folded %.2f days before the trial\n", json_number_value(age) / 86400.0);
}

static void print_header(void)
{
    printf("%5s  %-6s  %-11s  %9s  %-10s  %9s  %-10s  %17s  %-10s  %8s\n", "id", "mode", "status", "snap_meas",
           "regime", "snap_pred", "predicted", "snap_cal (1 sigma)", "calibrated", "samples");
}

/* Mock mode: the twin's own snap (its "twin truth" event) and what it is (its "twin" event),
 * with the measurement's and the prediction's differences from it. Nothing for other trials. */
static void print_twin_truth(const json_t *t, const json_t *m, const json_t *p, const json_t *c)
{
    json_t *evs = json_object_get(t, "events");
    const char *params = NULL, *truth = NULL;
    for (size_t k = 0; k < json_array_size(evs); k++) {
        const char *msg = json_string_value(json_object_get(json_array_get(evs, k), "message"));
        if (!msg) continue;
        if (!strncmp(msg, TWIN_TRUTH_PREFIX, strlen(TWIN_TRUTH_PREFIX))) truth = msg;
        else if (!strncmp(msg, TWIN_PARAMS_PREFIX, strlen(TWIN_PARAMS_PREFIX))) params = msg;
    }
    if (!truth) return;
    double dw = NAN;
    char regime[16] = "-";
    if (!twin_truth_parse(truth, &dw, regime, sizeof regime)) {
        printf("  twin truth %s\n", truth + strlen(TWIN_TRUTH_PREFIX));
        return;
    }
    printf("  twin truth snap Delta W = %.5f  regime %s", dw, regime);
    if (params) {
        /* "twin: N = 121, dt = 0.001 s; ...": the resolution, as the prediction's is shown. */
        int n = 0;
        double dt = NAN;
        if (sscanf(params, TWIN_PARAMS_PREFIX "N = %d, dt = %lf", &n, &dt) == 2) printf("  (N = %d, dt = %g s)", n, dt);
    }
    printf("\n");
    if (params) {
        const char *semi = strchr(params, ';');
        if (semi) printf("  twin       %s\n", semi + 2);
    }
    if (json_is_number(m))
        printf("  measured - twin truth   %+.5f (%+.2f%%)\n", json_number_value(m) - dw,
               100.0 * (json_number_value(m) - dw) / dw);
    if (json_is_number(p))
        printf("  predicted - twin truth  %+.5f (%+.2f%%)\n", json_number_value(p) - dw,
               100.0 * (json_number_value(p) - dw) / dw);
    if (json_is_number(c))
        printf("  calibrated - twin truth %+.5f (%+.2f%%)\n", json_number_value(c) - dw,
               100.0 * (json_number_value(c) - dw) / dw);
}

/* The calibrated prediction (issue 32 B): the snap of the strip fitted to the trial's own frames,
 * its 1-sigma band, its regime and the other one's probability, which fit it is, and its
 * difference from the measurement; or the fit's named failure. Nothing for trials without a fit. */
static void print_calibrated(const json_t *t, const json_t *m)
{
    const json_t *c = json_object_get(t, "snap_dw_calibrated"), *sd = json_object_get(t, "snap_sd_calibrated");
    const json_t *fit = json_object_get(t, "fit");
    const char *f = json_string_value(json_object_get(t, "fit_failure"));
    if (f) {
        printf("  calibrated failed: %s (the scene's prediction stands)\n", f);
        return;
    }
    if (!json_is_string(json_object_get(t, "regime_calibrated"))) return;
    if (!json_is_number(c)) {
        printf("  calibrated no snap before protocol.shear_max\n");
        return;
    }
    printf("  calibrated snap Delta W = %.5f", json_number_value(c));
    if (json_is_number(sd)) printf(" +- %.5f (1 sigma)", json_number_value(sd));
    printf("  regime %s", jstr(t, "regime_calibrated"));
    const json_t *po = json_object_get(t, "p_other_regime_calibrated");
    if (json_is_number(po)) printf(", P(other) %.3g", json_number_value(po));
    json_int_t k = json_integer_value(json_object_get(fit, "refresh"));
    if (json_is_object(fit))
        printf("  (%s, %lld + %lld frames)", k ? "refreshed in the shear" : "from the compression and hold",
               (long long)json_integer_value(json_object_get(fit, "frames_before")),
               (long long)json_integer_value(json_object_get(fit, "frames_shear")));
    printf("\n");
    const json_t *ps = json_object_get(fit, "parameters");
    for (size_t i = 0; i < json_array_size(ps); i++) {
        const json_t *q = json_array_get(ps, i);
        const json_t *se = json_object_get(q, "se");
        printf("    %-24s %12.6g -> %12.6g  ", jstr(q, "key"), json_number_value(json_object_get(q, "scene")),
               json_number_value(json_object_get(q, "fitted")));
        if (!json_is_number(se)) printf("not determined by these data\n");
        else if (!strcmp(jstr(q, "se_kind"), "relative")) printf("+- %.3g%%\n", 100.0 * json_number_value(se));
        else printf("+- %.3g\n", json_number_value(se));
    }
    if (json_is_number(m) && json_number_value(m) != 0.0) {
        double d = json_number_value(c) - json_number_value(m);
        printf("  calibrated - measured %+.5f (%+.2f%%", d, 100.0 * d / json_number_value(m));
        if (json_is_number(sd) && json_number_value(sd) > 0.0) printf(", %.2f sigma", d / json_number_value(sd));
        printf(")\n");
    }
}

/* Measured against predicted, the line make demo shows. */
static void print_comparison(const json_t *t)
{
    json_t *m = json_object_get(t, "snap_dw_measured"), *p = json_object_get(t, "snap_dw_predicted");
    printf("trial %lld: %s%s%s\n", (long long)json_integer_value(json_object_get(t, "id")), jstr(t, "status"),
           json_is_string(json_object_get(t, "reason")) && *jstr(t, "reason") ? " - " : "",
           json_is_string(json_object_get(t, "reason")) ? jstr(t, "reason") : "");
    char ms[32], ps[32];
    fmt_num(ms, sizeof ms, m);
    fmt_num(ps, sizeof ps, p);
    printf("  measured   snap Delta W = %s  regime %s\n", ms, jstr(t, "regime_measured"));
    json_t *pr = json_object_get(t, "prediction");
    if (prediction_failure(t)) /* the trial ran; its prediction did not */
        printf("  predicted  failed: %s", prediction_failure(t));
    else
        printf("  predicted  snap Delta W = %s  regime %s", ps, jstr(t, "regime_predicted"));
    if (json_is_object(pr) && !prediction_failure(t))
        printf("  (N = %lld, dt = %g s, %.2f s wall)", (long long)json_integer_value(json_object_get(pr, "nodes")),
               json_number_value(json_object_get(pr, "dt")), json_number_value(json_object_get(pr, "wall_s")));
    printf("\n");
    if (json_is_number(m) && json_is_number(p) && json_number_value(m) != 0.0) {
        double d = json_number_value(p) - json_number_value(m);
        printf("  predicted - measured  %+.5f (%+.2f%%)\n", d, 100.0 * d / json_number_value(m));
    }
    print_calibrated(t, m);
    print_twin_truth(t, m, p, json_object_get(t, "snap_dw_calibrated"));
    json_t *lc = json_object_get(t, "stop_cmd_latency_s"), *ls = json_object_get(t, "stop_stand_latency_s");
    if (json_is_number(lc)) {
        printf("  snap-to-stop latency %.1f ms to the stop command", 1e3 * json_number_value(lc));
        if (json_is_number(ls))
            printf(", %.1f ms to the shear rail standing\n", 1e3 * json_number_value(ls));
        else
            printf(" (the rail was not read standing before the return)\n");
    }
}

static int open_db(const ctl_opts *o, store **st, int read_only)
{
    char why[512];
    store_open_params p = store_open_params_default();
    p.read_only = read_only;
    char path[1024];
    const char *db = o->db;
    if (!db) {
        /* Ask the daemon where its store is. */
        json_t *s = NULL;
        if (request(o, "GET", "/status", NULL, &s, NULL, NULL) < 0) return -1;
        snprintf(path, sizeof path, "%s", jstr(s, "store"));
        json_decref(s);
        db = path;
    }
    if (store_open_ex(db, &p, st, why, sizeof why) != STORE_OK) {
        fprintf(stderr, "ribbonctl: store %s: %s\n", db, why);
        return -1;
    }
    return 0;
}

/* GET /trials/{id}/report.png into path. Returns 0, or 1 with the reason printed. */
static int fetch_report(const ctl_opts *o, int64_t id, const char *out)
{
    char path[64];
    snprintf(path, sizeof path, "/trials/%lld/report.png", (long long)id);
    unsigned char *png = NULL;
    size_t len = 0;
    if (request(o, "GET", path, NULL, NULL, &png, &len) < 0) return 1;
    FILE *f = fopen(out, "wb");
    int ok = f && fwrite(png, 1, len, f) == len;
    if (f && fclose(f) != 0) ok = 0;
    free(png);
    if (!ok) {
        fprintf(stderr, "ribbonctl: %s: %s\n", out, strerror(errno));
        return 1;
    }
    printf("report: %s\n", out);
    return 0;
}

/* ---- commands ------------------------------------------------------------------------------------ */

static int wait_for(const ctl_opts *o, int64_t id)
{
    char last[128] = ""; /* a state, or "done, refitting specimen NAME" */
    for (int polls = 0; polls < 24 * 3600 * 4; polls++) {
        json_t *s = NULL;
        if (request(o, "GET", "/status", NULL, &s, NULL, NULL) < 0) return 1;
        json_t *t = json_object_get(s, "trial");
        int running = json_is_object(t) && json_integer_value(json_object_get(t, "id")) == id;
        if (running) {
            const char *state = jstr(t, "state");
            char dw[32], dz[32];
            fmt_num(dw, sizeof dw, json_object_get(t, "dw"));
            fmt_num(dz, sizeof dz, json_object_get(t, "dz"));
            if (isatty(2))
                fprintf(stderr, "\r  %-12s frame %5lld  Delta W %s  Delta Z %s   ", state,
                        (long long)json_integer_value(json_object_get(t, "frames")), dw, dz);
            else if (strcmp(state, last))
                fprintf(stderr, "  %s\n", state);
            snprintf(last, sizeof last, "%s", state);
        }
        json_decref(s);
        if (!running) break;
        struct timespec ts = {0, 250000000};
        nanosleep(&ts, NULL);
    }
    if (isatty(2)) fprintf(stderr, "\n");
    /* The session joins its prediction before it ends, so the stored trial is complete now. */
    json_t *t = NULL;
    char path[64];
    snprintf(path, sizeof path, "/trials/%lld", (long long)id);
    if (request(o, "GET", path, NULL, &t, NULL, NULL) < 0) return 1;
    if (o->json)
        print_json(t);
    else
        print_comparison(t);
    int ok = !strcmp(jstr(t, "status"), "done");
    json_decref(t);
    if (o->out && fetch_report(o, id, o->out)) return 1; /* start --wait --out FILE.png */
    json_t *s = NULL;
    if (!o->json && request(o, "GET", "/status", NULL, &s, NULL, NULL) > 0) printf("database: %s\n", jstr(s, "store"));
    json_decref(s);
    return ok ? 0 : 1;
}

static int cmd_start(const ctl_opts *o)
{
    json_t *body = json_object();
    if (o->n_set) {
        json_t *a = json_array();
        for (int k = 0; k < o->n_set; k++) json_array_append_new(a, json_string(o->set[k]));
        json_object_set_new(body, "set", a);
    }
    if (o->note) json_object_set_new(body, "note", json_string(o->note));
    if (o->specimen) json_object_set_new(body, "specimen", json_string(o->specimen));
    json_t *t = NULL;
    int st = request(o, "POST", "/trials", body, &t, NULL, NULL);
    json_decref(body);
    if (st < 0) return 1;
    int64_t id = json_integer_value(json_object_get(t, "id"));
    if (!o->wait) {
        if (o->json)
            print_json(t);
        else
            printf("trial %lld started\n", (long long)id);
        json_decref(t);
        return 0;
    }
    json_decref(t);
    fprintf(stderr, "trial %lld started; following it\n", (long long)id);
    return wait_for(o, id);
}

static int cmd_simple(const ctl_opts *o, const char *method, const char *path)
{
    json_t *t = NULL;
    if (request(o, method, path, NULL, &t, NULL, NULL) < 0) return 1;
    print_json(t);
    json_decref(t);
    return 0;
}

static int cmd_list(const ctl_opts *o)
{
    json_t *arr = NULL;
    if (o->db) {
        store *st;
        char why[512];
        if (open_db(o, &st, 1)) return 1;
        store_err e = store_trials_json(st, &arr, why, sizeof why);
        store_close(st);
        if (e != STORE_OK) {
            fprintf(stderr, "ribbonctl: %s\n", why);
            return 1;
        }
    } else if (request(o, "GET", "/trials", NULL, &arr, NULL, NULL) < 0) {
        return 1;
    }
    if (o->json) {
        print_json(arr);
    } else {
        print_header();
        for (size_t k = 0; k < json_array_size(arr); k++) print_trial_row(json_array_get(arr, k));
    }
    json_decref(arr);
    return 0;
}

/* "  overrides (in order): a=1, b=2": what the trial's files were run with changed. */
static void print_overrides(const json_t *t)
{
    const json_t *ov = json_object_get(t, "overrides");
    if (!json_is_array(ov)) {
        printf("  overrides: not recorded (a trial stored before they were)\n");
        return;
    }
    if (json_array_size(ov) == 0) {
        printf("  overrides: none (the rig and scene files as stored)\n");
        return;
    }
    printf("  overrides (in order, after the files):");
    for (size_t k = 0; k < json_array_size(ov); k++)
        printf("%s %s", k ? "," : "", json_string_value(json_array_get(ov, k)));
    printf("\n");
}

static int cmd_show(const ctl_opts *o)
{
    if (!o->id) return usage_error("show", "which trial? ribbonctl show ID");
    json_t *t = NULL;
    if (o->db) {
        store *st;
        char why[512];
        if (open_db(o, &st, 1)) return 1;
        store_err e = store_trial_json(st, o->id, &t, why, sizeof why);
        if (e == STORE_OK) trial_config_text_add_overrides(st, o->id, t);
        store_close(st);
        if (e != STORE_OK) {
            fprintf(stderr, "ribbonctl: %s\n", why);
            return 1;
        }
    } else {
        char path[64];
        snprintf(path, sizeof path, "/trials/%lld", (long long)o->id);
        if (request(o, "GET", path, NULL, &t, NULL, NULL) < 0) return 1;
    }
    if (o->json)
        print_json(t);
    else {
        print_comparison(t);
        printf("  mode %s, samples %lld, video %s, specimen %s\n", jstr(t, "mode"),
               (long long)json_integer_value(json_object_get(t, "samples")), jstr(t, "video_path"), jstr(t, "specimen"));
        print_creases(t);
        print_overrides(t);
        json_t *ev = json_object_get(t, "events");
        for (size_t k = 0; k < json_array_size(ev); k++) {
            json_t *e = json_array_get(ev, k);
            char ts[32];
            fmt_num(ts, sizeof ts, json_object_get(e, "t_s"));
            printf("  %10s s  %-8s %s\n", ts, jstr(e, "kind"), jstr(e, "message"));
        }
    }
    json_decref(t);
    return 0;
}

static int cmd_export(const ctl_opts *o)
{
    if (!o->all && !o->id) return usage_error("export", "export ID --csv, or export --all --out DIR");
    if (!o->all && !o->csv) return usage_error("export", "the format is CSV: add --csv");
    if (o->all && !o->out) return usage_error("export", "--all needs --out DIR");
    store *st;
    char why[512];
    if (open_db(o, &st, 1)) return 1;
    store_err e;
    if (o->all) {
        e = store_export_all(st, o->out, why, sizeof why);
        if (e == STORE_OK) fprintf(stderr, "exported every trial into %s\n", o->out);
    } else {
        FILE *f = o->out ? fopen(o->out, "w") : stdout;
        if (!f) {
            fprintf(stderr, "ribbonctl: %s: %s\n", o->out, strerror(errno));
            store_close(st);
            return 1;
        }
        e = store_export_trial_csv(st, o->id, f, why, sizeof why);
        if (o->out && fclose(f) != 0 && e == STORE_OK) {
            snprintf(why, sizeof why, "%s: %s", o->out, strerror(errno));
            e = STORE_E_IO;
        }
    }
    store_close(st);
    if (e != STORE_OK) {
        fprintf(stderr, "ribbonctl: %s\n", why);
        return 1;
    }
    return 0;
}

static int cmd_report(const ctl_opts *o)
{
    if (!o->id || !o->out) return usage_error("report", "ribbonctl report ID --out FILE.png");
    char why[512];
    if (o->db) {
        store *st;
        if (open_db(o, &st, 1)) return 1;
        trial_err rc = trial_report_png(st, o->id, o->out, why, sizeof why);
        store_close(st);
        if (rc != TRIAL_OK) {
            fprintf(stderr, "ribbonctl: report: %s\n", why);
            return 1;
        }
        printf("report: %s\n", o->out);
        return 0;
    }
    return fetch_report(o, o->id, o->out);
}

static int parse_range(const char *s, double *a, double *b, size_t *n)
{
    double x, y;
    int k;
    if (!s) return 0;
    if (cfg_number_range(s, &x, &y, &k, 64) != 0) return -1;
    *a = x;
    *b = y;
    *n = (size_t)k;
    return 0;
}

static void grid_progress(void *u, size_t done, size_t total)
{
    (void)u;
    fprintf(stderr, "\r  phase diagram: %zu / %zu points", done, total);
    if (done == total) fprintf(stderr, "\n");
}

static int cmd_phase_report(const ctl_opts *o)
{
    if (!o->out) return usage_error("phase-report", "ribbonctl phase-report --out FILE.png");
    double p0 = 30, p1 = 150, g0 = 0.08, g1 = 0.28;
    size_t np = 5, ng = 6;
    if (parse_range(o->phi, &p0, &p1, &np) || parse_range(o->gamma, &g0, &g1, &ng))
        return usage_error("phase-report", "--phi and --gamma take FROM:TO:COUNT (FROM <= TO, count 1..64)");
    rod_scene sc;
    cfg_error ce;
    char why[512];
    if (o->scene) {
        if (cfg_scene_load(o->scene, NULL, 0, &sc, &ce) != CFG_OK) {
            cfg_error_format(&ce, why, sizeof why);
            fprintf(stderr, "ribbonctl: %s\n", why);
            return 1;
        }
    } else {
        sc = rod_scene_default();
        sc.nodes = 41;
        sc.dt = 0.01;
    }
    store *st;
    if (open_db(o, &st, 1)) return 1;
    phase_grid g;
    fprintf(stderr, "predicting the phase diagram (%zu x %zu points, N = %d)\n", np, ng, sc.nodes);
    int rc = phase_grid_compute(&sc, p0, p1, np, g0, g1, ng, &g, grid_progress, NULL, NULL, why, sizeof why);
    if (rc == 0) rc = trial_phase_report_png(st, &g, o->out, why, sizeof why);
    phase_grid_free(&g);
    store_close(st);
    if (rc) {
        fprintf(stderr, "ribbonctl: phase-report: %s\n", why);
        return 1;
    }
    printf("phase report: %s\n", o->out);
    return 0;
}

static void replay_progress(void *u, long f, long total)
{
    (void)u;
    if (total > 0)
        fprintf(stderr, "\r  replay: frame %ld / %ld", f, total);
    else
        fprintf(stderr, "\r  replay: frame %ld", f);
}

static int cmd_replay(const ctl_opts *o)
{
    rig_config cfg;
    int have_cfg = 0;
    if (o->config) {
        cfg_error ce;
        if (rig_config_load(o->config, o->set, o->n_set, &cfg, &ce) != CFG_OK) {
            char msg[600];
            cfg_error_format(&ce, msg, sizeof msg);
            fprintf(stderr, "ribbonctl replay: %s\n", msg);
            return 1;
        }
        if (cfg.mode != RIG_MODE_REPLAY) {
            fprintf(stderr, "ribbonctl replay: %s is a %s-mode rig file; replay needs rig.mode = replay\n", o->config,
                    rig_mode_name(cfg.mode));
            return 2;
        }
        have_cfg = 1;
    } else if (o->n_set) {
        return usage_error("replay", "--set needs --config");
    }
    int64_t source = o->id ? o->id : have_cfg ? cfg.replay.source_trial : 0;
    int files = !source && have_cfg && cfg.replay.video[0];
    if (!source && !files)
        return usage_error("replay", "ribbonctl replay ID (the recorded trial), or --config with a replay rig file");
    ctl_opts oo = *o;
    if (!oo.db && have_cfg) oo.db = cfg.store_path;
    store *st;
    if (open_db(&oo, &st, 0)) return 1;
    char why[512];
    trial_replay *r = NULL;
    int64_t nid = 0;
    trial_result res;
    memset(&res, 0, sizeof res);
    int rc = trial_replay_prepare(st, have_cfg ? &cfg : NULL, o->id, o->video, &r, why, sizeof why);
    if (rc == 0) rc = trial_replay_run(r, st, o->note, replay_progress, NULL, &nid, &res, why, sizeof why);
    trial_replay_free(r);
    fprintf(stderr, "\n");
    if (rc) {
        if (files)
            fprintf(stderr, "ribbonctl: replay of %s: %s\n", cfg.replay.video, why);
        else
            fprintf(stderr, "ribbonctl: replay of trial %lld: %s\n", (long long)source, why);
        store_close(st);
        return 1;
    }
    json_t *t = NULL;
    if (store_trial_json(st, nid, &t, why, sizeof why) == STORE_OK) {
        if (o->json)
            print_json(t);
        else if (files)
            printf("replay of %s is trial %lld: %s at Delta W = %.5f (%ld frames)\n", cfg.replay.video,
                   (long long)nid, res.regime, res.snap_dw, res.frames);
        else
            printf("replay of trial %lld is trial %lld: %s at Delta W = %.5f (%ld frames)\n", (long long)source,
                   (long long)nid, res.regime, res.snap_dw, res.frames);
        json_decref(t);
    }
    store_close(st);
    return 0;
}

int ctl_trials_main(int argc, char **argv)
{
    const char *cmd = argv[0];
    ctl_opts o;
    int want_id = !strcmp(cmd, "show") || !strcmp(cmd, "export") || !strcmp(cmd, "report") || !strcmp(cmd, "replay");
    int p = parse(cmd, argc, argv, &o, want_id);
    if (p == 1) return 0;
    if (p < 0) return 2;
    char why[256];
    if (api_client_global_init(why, sizeof why)) {
        fprintf(stderr, "ribbonctl: %s\n", why);
        return 1;
    }
    int rc;
    if (!strcmp(cmd, "start")) rc = cmd_start(&o);
    else if (!strcmp(cmd, "abort")) rc = cmd_simple(&o, "POST", "/trials/current/abort");
    else if (!strcmp(cmd, "status")) rc = cmd_simple(&o, "GET", "/status");
    else if (!strcmp(cmd, "list")) rc = cmd_list(&o);
    else if (!strcmp(cmd, "show")) rc = cmd_show(&o);
    else if (!strcmp(cmd, "export")) rc = cmd_export(&o);
    else if (!strcmp(cmd, "report")) rc = cmd_report(&o);
    else if (!strcmp(cmd, "phase-report")) rc = cmd_phase_report(&o);
    else if (!strcmp(cmd, "replay")) rc = cmd_replay(&o);
    else rc = usage_error(cmd, "unknown trial command");
    api_client_global_cleanup();
    return rc;
}
