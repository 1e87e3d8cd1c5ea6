/* ctl_campaign.c: ribbonctl's campaign commands (issue 35): `specimen add|list|show|retire` and
 * `queue add|list|show|remove|move|start|stop|confirm`, each one request to ribbond's control API
 * (/specimens, /queue: docs/campaign.md), the same as a client would send. --json prints the
 * reply as it came; otherwise a short human form. Errors print the daemon's reason and exit 1. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "api.h"
#include "cfg_number.h"
#include "ctl.h"

#define MAX_WORDS 64

typedef struct campaign_opts {
    const char *url, *token;
    const char *words[MAX_WORDS]; /* positional words after the verb */
    int n_words;
    const char *set[MAX_WORDS], *fields[8];
    int n_set, n_fields;
    const char *specimen, *note, *prompt, *reason, *phi, *gamma, *material, *length, *width, *thickness, *angles,
        *positions, *folded_at, *orientation;
    int json, broken;
} campaign_opts;

static void help_specimen(void)
{
    printf("usage:\n"
           "  ribbonctl specimen add NAME --phi DEG --gamma G [--material M] [--length M] [--width M]\n"
           "      [--thickness M] [--angles LEFT,RIGHT] [--positions LEFT,RIGHT] [--folded-at ISO8601]\n"
           "      [--orientation up|down] [--json]\n"
           "  ribbonctl specimen list [--json]\n"
           "  ribbonctl specimen show NAME [--json]\n"
           "  ribbonctl specimen retire NAME --reason TEXT [--broken]\n"
           "common: --url URL (default $RIBBON_URL or http://127.0.0.1:8377), --token T (default $RIBBON_TOKEN)\n"
           "\n"
           "A specimen is the strip the lab made, known by the NAME written on it (letters, digits, . _ -):\n"
           "its design (--phi, the fold angle in degrees; --gamma, the fold position), its size and\n"
           "material (default: the rig file's scene), its measured creases (--angles in degrees, --positions\n"
           "as fractions of the free length, --folded-at with a zone) and its state: new, in use (after its\n"
           "first trial), retired or broken (retire --broken). `ribbonctl start --specimen NAME` runs a\n"
           "trial of it: its record sets the trial's specimen and scene keys, so the prediction uses it.\n"
           "A retired or broken specimen, or an unknown name, is refused and nothing starts.\n"
           "After each trial of it ribbond refits its strip from all its finished trials: `show` prints\n"
           "that calibration (the fitted values with their standard errors, what the data do not determine,\n"
           "the residual, the trials used, when) and the last refit's failure; its next trial predicts with it.\n");
}

static void help_queue(void)
{
    printf("usage:\n"
           "  ribbonctl queue add trial --specimen NAME [--set section.key=value ...] [--note TEXT]\n"
           "  ribbonctl queue add operator --prompt TEXT [--specimen NAME] [--field NAME ...]\n"
           "  ribbonctl queue add pause [--note TEXT]\n"
           "  ribbonctl queue list [--json]\n"
           "  ribbonctl queue show ID            (the item's whole status, JSON)\n"
           "  ribbonctl queue remove ID | move ID POSITION | start | stop\n"
           "  ribbonctl queue confirm ID [FIELD=VALUE ...]\n"
           "common: --url URL (default $RIBBON_URL or http://127.0.0.1:8377), --token T (default $RIBBON_TOKEN)\n"
           "\n"
           "The queue runs its items in order once started: a trial of a specimen; an operator step that\n"
           "waits until someone confirms it, with the values of its fields (crease_angle_left_deg,\n"
           "crease_angle_right_deg, crease_position_left, crease_position_right, folded_at), which become\n"
           "the specimen's record; a pause, which stops the queue. A trial that ends failed or aborted\n"
           "stops it too, and so does its end. stop starts no further item (abort stops a running trial).\n"
           "A running item can be neither removed nor moved. Each item ends done, failed, aborted, skipped\n"
           "(removed) or unknown (found running when ribbond restarted: the queue is then stopped, saying\n"
           "why, until someone starts it; a restart never resumes motion).\n");
}

static int usage(const char *cmd, const char *msg)
{
    fprintf(stderr, "ribbonctl %s: %s (see ribbonctl %s --help)\n", cmd, msg, cmd);
    return 2;
}

/* 0, 1 (help printed) or 2 (usage error printed). */
static int parse(const char *cmd, int argc, char **argv, campaign_opts *o)
{
    memset(o, 0, sizeof *o);
    o->url = getenv("RIBBON_URL");
    if (!o->url || !*o->url) o->url = "http://127.0.0.1:8377";
    o->token = getenv("RIBBON_TOKEN");
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            if (!strcmp(cmd, "specimen")) help_specimen();
            else help_queue();
            return 1;
        }
        struct { const char *name; const char **dst; } takes[] = {
            {"--url", &o->url}, {"--token", &o->token}, {"--specimen", &o->specimen}, {"--note", &o->note},
            {"--prompt", &o->prompt}, {"--reason", &o->reason}, {"--phi", &o->phi}, {"--gamma", &o->gamma},
            {"--material", &o->material}, {"--length", &o->length}, {"--width", &o->width},
            {"--thickness", &o->thickness}, {"--angles", &o->angles}, {"--positions", &o->positions},
            {"--folded-at", &o->folded_at}, {"--orientation", &o->orientation}};
        int took = 0;
        for (size_t k = 0; k < sizeof takes / sizeof takes[0]; k++)
            if (!strcmp(a, takes[k].name)) {
                if (!v) return usage(cmd, "missing value after option");
                *takes[k].dst = v;
                i++;
                took = 1;
            }
        if (took) continue;
        if (!strcmp(a, "--set") || !strcmp(a, "--field")) {
            int set = !strcmp(a, "--set");
            if (!v || (set ? o->n_set >= MAX_WORDS : o->n_fields >= 8)) return usage(cmd, "too many or missing values");
            if (set) o->set[o->n_set++] = v;
            else o->fields[o->n_fields++] = v;
            i++;
        } else if (!strcmp(a, "--json")) o->json = 1;
        else if (!strcmp(a, "--broken")) o->broken = 1;
        else if (a[0] == '-' && a[1] == '-') {
            char msg[128];
            snprintf(msg, sizeof msg, "unknown option %.64s", a);
            return usage(cmd, msg);
        } else if (o->n_words < MAX_WORDS) o->words[o->n_words++] = a;
        else return usage(cmd, "too many arguments");
    }
    return 0;
}

/* One request; 0 with *out, or 1 with the reason printed. */
static int call(const campaign_opts *o, const char *method, const char *path, const json_t *body, json_t **out)
{
    api_client_config c = api_client_config_default();
    c.base_url = o->url;
    c.token = o->token;
    int status = 0;
    char why[600] = "";
    *out = NULL;
    if (api_client_request(&c, method, path, body, &status, out, NULL, NULL, why, sizeof why)) {
        fprintf(stderr, "ribbonctl: %s\n", why);
        return 1;
    }
    if (status >= 400) {
        fprintf(stderr, "ribbonctl: %s %s: %s\n", method, path, why);
        json_decref(*out);
        *out = NULL;
        return 1;
    }
    return 0;
}

static void print_json(const json_t *j)
{
    char *t = json_dumps(j, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
    if (t) printf("%s\n", t);
    free(t);
}

static const char *js(const json_t *o, const char *k)
{
    const char *s = json_string_value(json_object_get(o, k));
    return s ? s : "-";
}

static void num(char *buf, size_t n, const json_t *v)
{
    if (json_is_number(v)) snprintf(buf, n, "%g", json_number_value(v));
    else snprintf(buf, n, "-");
}

static void print_specimen(const json_t *s)
{
    char phi[32], g[32], l[32], r[32];
    num(phi, sizeof phi, json_object_get(s, "phi_deg"));
    num(g, sizeof g, json_object_get(s, "gamma"));
    num(l, sizeof l, json_object_get(s, "crease_angle_left_deg"));
    num(r, sizeof r, json_object_get(s, "crease_angle_right_deg"));
    printf("%-16s %-8s phi %-6s Gamma %-6s creases %s, %s deg  trials %lld%s%s\n", js(s, "name"), js(s, "state"), phi,
           g, l, r, (long long)json_integer_value(json_object_get(s, "trials_count")),
           json_is_string(json_object_get(s, "state_reason")) ? "  " : "",
           json_is_string(json_object_get(s, "state_reason")) ? js(s, "state_reason") : "");
}

/* The specimen's calibration (its strip fitted to its trials) and its last refit's failure. */
static void print_calibration(const json_t *s)
{
    const json_t *c = json_object_get(s, "calibration"), *f = json_object_get(s, "calibration_failure");
    if (!json_is_object(c)) {
        printf("  calibration  none yet\n");
    } else {
        printf("  calibration  trials");
        const json_t *tr = json_object_get(c, "trials");
        for (size_t k = 0; k < json_array_size(tr); k++)
            printf("%s %lld", k ? "," : "", (long long)json_integer_value(json_array_get(tr, k)));
        printf(" (%lld frames, N = %lld), %s: residual %.3g noise units RMS (%.3g at the measured strip)\n",
               (long long)json_integer_value(json_object_get(c, "frames")),
               (long long)json_integer_value(json_object_get(c, "nodes")), js(c, "at"),
               json_number_value(json_object_get(c, "rms")), json_number_value(json_object_get(c, "rms_start")));
        const json_t *ps = json_object_get(c, "parameters");
        for (size_t k = 0; k < json_array_size(ps); k++) {
            const json_t *p = json_array_get(ps, k), *se = json_object_get(p, "se");
            printf("    %-27s %12.6g  (measured %.6g)  ", js(p, "key"), json_number_value(json_object_get(p, "value")),
                   json_number_value(json_object_get(p, "start")));
            if (!json_is_true(json_object_get(p, "determined")) || !json_is_number(se))
                printf("not determined by these data: its trials predict with the measured value\n");
            else if (!strcmp(js(p, "se_kind"), "relative"))
                printf("+- %.3g%%\n", 100.0 * json_number_value(se));
            else
                printf("+- %.3g\n", json_number_value(se));
        }
        const json_t *sk = json_object_get(c, "skipped");
        for (size_t k = 0; k < json_array_size(sk); k++)
            printf("    skipped trial %lld: %s\n", (long long)json_integer_value(json_object_get(json_array_get(sk, k), "trial")),
                   js(json_array_get(sk, k), "why"));
    }
    if (json_is_object(f))
        printf("  last refit   after trial %lld failed: %s: %s%s\n",
               (long long)json_integer_value(json_object_get(f, "after_trial")), js(f, "reason_key"), js(f, "reason"),
               json_is_object(c) ? " (the calibration above stands)" : "");
}

/* "A,B" into two numbers in the body. */
static int pair(const char *cmd, json_t *body, const char *text, const char *k1, const char *k2)
{
    char a[64], *comma;
    snprintf(a, sizeof a, "%s", text);
    if (!(comma = strchr(a, ','))) return usage(cmd, "--angles and --positions take LEFT,RIGHT");
    *comma = '\0';
    double x, y;
    if (cfg_number_parse(a, &x) || cfg_number_parse(comma + 1, &y)) return usage(cmd, "LEFT,RIGHT must be numbers");
    json_object_set_new(body, k1, json_real(x));
    json_object_set_new(body, k2, json_real(y));
    return 0;
}

static int number_field(const char *cmd, json_t *body, const char *key, const char *text)
{
    double x;
    if (!text) return 0;
    if (cfg_number_parse(text, &x)) {
        char msg[96];
        snprintf(msg, sizeof msg, "%s must be a number", key);
        return usage(cmd, msg);
    }
    json_object_set_new(body, key, json_real(x));
    return 0;
}

static int specimen_main(const campaign_opts *o)
{
    const char *verb = o->n_words ? o->words[0] : "";
    json_t *out = NULL, *body = NULL;
    char path[160];
    int rc = 0;
    if (!strcmp(verb, "list") && o->n_words == 1) {
        if ((rc = call(o, "GET", "/specimens", NULL, &out))) return rc;
        if (o->json) print_json(out);
        for (size_t k = 0; !o->json && k < json_array_size(out); k++) print_specimen(json_array_get(out, k));
    } else if (!strcmp(verb, "show") && o->n_words == 2) {
        snprintf(path, sizeof path, "/specimens/%.100s", o->words[1]);
        if ((rc = call(o, "GET", path, NULL, &out))) return rc;
        if (o->json) print_json(out);
        else {
            print_specimen(out);
            print_calibration(out);
            json_t *t = json_object_get(out, "trials");
            for (size_t k = 0; k < json_array_size(t); k++) {
                json_t *e = json_array_get(t, k);
                printf("  trial %lld  %-11s %s\n", (long long)json_integer_value(json_object_get(e, "id")), js(e, "status"),
                       js(e, "regime_measured"));
            }
        }
    } else if (!strcmp(verb, "add") && o->n_words == 2) {
        if (!o->phi || !o->gamma) return usage("specimen", "add needs --phi and --gamma (the design)");
        body = json_pack("{s:s}", "name", o->words[1]);
        if (number_field("specimen", body, "phi_deg", o->phi) || number_field("specimen", body, "gamma", o->gamma) ||
            number_field("specimen", body, "length_m", o->length) || number_field("specimen", body, "width_m", o->width) ||
            number_field("specimen", body, "thickness_m", o->thickness) ||
            (o->angles && pair("specimen", body, o->angles, "crease_angle_left_deg", "crease_angle_right_deg")) ||
            (o->positions && pair("specimen", body, o->positions, "crease_position_left", "crease_position_right"))) {
            json_decref(body);
            return 2;
        }
        if (o->material) json_object_set_new(body, "material", json_string(o->material));
        if (o->folded_at) json_object_set_new(body, "folded_at", json_string(o->folded_at));
        if (o->orientation) json_object_set_new(body, "crease_orientation", json_string(o->orientation));
        rc = call(o, "POST", "/specimens", body, &out);
        if (!rc) {
            if (o->json) print_json(out);
            else print_specimen(out);
        }
    } else if (!strcmp(verb, "retire") && o->n_words == 2) {
        if (!o->reason) return usage("specimen", "retire needs --reason TEXT");
        body = json_pack("{s:s, s:b}", "reason", o->reason, "broken", o->broken);
        snprintf(path, sizeof path, "/specimens/%.100s/retire", o->words[1]);
        rc = call(o, "POST", path, body, &out);
        if (!rc) {
            if (o->json) print_json(out);
            else print_specimen(out);
        }
    } else {
        return usage("specimen", "add NAME ..., list, show NAME or retire NAME --reason TEXT");
    }
    json_decref(body);
    json_decref(out);
    return rc;
}

static void print_item(const json_t *it)
{
    const char *kind = js(it, "kind");
    printf("%4lld  %-9s %-8s", (long long)json_integer_value(json_object_get(it, "id")), js(it, "status"), kind);
    if (!strcmp(kind, "trial")) printf(" %s", js(it, "specimen"));
    if (!strcmp(kind, "operator")) printf(" \"%s\"", js(it, "prompt"));
    if (json_is_string(json_object_get(it, "note"))) printf("  (%s)", js(it, "note"));
    if (json_is_integer(json_object_get(it, "trial_id")))
        printf("  trial %lld", (long long)json_integer_value(json_object_get(it, "trial_id")));
    if (json_is_string(json_object_get(it, "reason"))) printf("  %s", js(it, "reason"));
    printf("\n");
}

static int parse_id(const char *s, long long *id)
{
    char *end;
    errno = 0;
    *id = strtoll(s, &end, 10);
    return !(errno || *end || *id < 1);
}

static int queue_main(const campaign_opts *o)
{
    const char *verb = o->n_words ? o->words[0] : "";
    json_t *out = NULL, *body = NULL;
    char path[96];
    long long id = 0;
    int rc;
    if (!strcmp(verb, "list") && o->n_words == 1) {
        if ((rc = call(o, "GET", "/queue", NULL, &out))) return rc;
        if (o->json) print_json(out);
        else {
            int running = json_is_true(json_object_get(out, "running"));
            printf("queue %s%s%s\n", running ? "running" : "stopped", running ? "" : ": ", running ? "" : js(out, "reason"));
            if (json_is_object(json_object_get(out, "current"))) print_item(json_object_get(out, "current"));
            static const char *const parts[] = {"queued", "history"};
            for (int p = 0; p < 2; p++)
                for (size_t k = 0; k < json_array_size(json_object_get(out, parts[p])); k++)
                    print_item(json_array_get(json_object_get(out, parts[p]), k));
        }
        json_decref(out);
        return 0;
    }
    if ((!strcmp(verb, "start") || !strcmp(verb, "stop")) && o->n_words == 1) {
        snprintf(path, sizeof path, "/queue/%s", verb);
        body = json_object();
    } else if (!strcmp(verb, "add") && o->n_words == 2) {
        const char *kind = o->words[1];
        if (strcmp(kind, "trial") && strcmp(kind, "operator") && strcmp(kind, "pause"))
            return usage("queue", "add trial, add operator or add pause");
        body = json_pack("{s:s}", "kind", kind);
        if (o->specimen) json_object_set_new(body, "specimen", json_string(o->specimen));
        if (o->note) json_object_set_new(body, "note", json_string(o->note));
        if (o->prompt) json_object_set_new(body, "prompt", json_string(o->prompt));
        if (o->n_set) {
            json_t *a = json_array();
            for (int k = 0; k < o->n_set; k++) json_array_append_new(a, json_string(o->set[k]));
            json_object_set_new(body, "set", a);
        }
        if (o->n_fields) {
            json_t *a = json_array();
            for (int k = 0; k < o->n_fields; k++) json_array_append_new(a, json_string(o->fields[k]));
            json_object_set_new(body, "fields", a);
        }
        snprintf(path, sizeof path, "/queue");
    } else if (o->n_words >= 2 && parse_id(o->words[1], &id) &&
               ((!strcmp(verb, "show") && o->n_words == 2) || (!strcmp(verb, "remove") && o->n_words == 2) ||
                (!strcmp(verb, "move") && o->n_words == 3) || !strcmp(verb, "confirm"))) {
        if (!strcmp(verb, "show")) {
            snprintf(path, sizeof path, "/queue/%lld", id);
            if ((rc = call(o, "GET", path, NULL, &out))) return rc;
            print_json(out);
            json_decref(out);
            return 0;
        }
        snprintf(path, sizeof path, "/queue/%lld/%s", id, verb);
        body = json_object();
        if (!strcmp(verb, "move")) {
            long long pos;
            if (!parse_id(o->words[2], &pos)) {
                json_decref(body);
                return usage("queue", "move ID POSITION: POSITION is 1 (next) or more");
            }
            json_object_set_new(body, "position", json_integer(pos));
        }
        if (!strcmp(verb, "confirm")) {
            json_t *values = json_object();
            for (int k = 2; k < o->n_words; k++) {
                const char *eq = strchr(o->words[k], '=');
                char key[64];
                double x;
                if (!eq || eq == o->words[k] || (size_t)(eq - o->words[k]) >= sizeof key) {
                    json_decref(values);
                    json_decref(body);
                    return usage("queue", "confirm ID FIELD=VALUE ...");
                }
                snprintf(key, sizeof key, "%.*s", (int)(eq - o->words[k]), o->words[k]);
                /* numbers as numbers, anything else (folded_at) as text */
                json_object_set_new(values, key, cfg_number_parse(eq + 1, &x) ? json_string(eq + 1) : json_real(x));
            }
            json_object_set_new(body, "values", values);
        }
    } else {
        return usage("queue", "add, list, show ID, remove ID, move ID POSITION, start, stop or confirm ID");
    }
    rc = call(o, "POST", path, body, &out);
    json_decref(body);
    if (!rc) {
        if (o->json || !json_is_integer(json_object_get(out, "id"))) print_json(out);
        else print_item(out);
    }
    json_decref(out);
    return rc;
}

int ctl_campaign_main(int argc, char **argv)
{
    const char *cmd = argv[0];
    campaign_opts o;
    int p = parse(cmd, argc, argv, &o);
    if (p == 1) return 0;
    if (p) return 2;
    char why[256];
    if (api_client_global_init(why, sizeof why)) {
        fprintf(stderr, "ribbonctl: %s\n", why);
        return 1;
    }
    int rc = !strcmp(cmd, "specimen") ? specimen_main(&o) : queue_main(&o);
    api_client_global_cleanup();
    return rc;
}
