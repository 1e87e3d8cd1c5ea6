/* ctl_rails.c: `ribbonctl rails home|confirm-zero NAME --confirm`: a rail of the running ribbond
 * homed or its zero confirmed through the control API (POST /rails/NAME/home, /confirm-zero;
 * docs/api.md). ribbond holds the rails' device locks, so `ribbonctl rail` (which drives a rail
 * itself) cannot reach them while it runs; after a controller lost its position (issue 34 A,
 * docs/rails.md) this is how the lab clears it without stopping the daemon. The daemon refuses
 * it while a trial runs. One request; the daemon's reason on failure, exit 1. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "api.h"
#include "ctl.h"

static void help(void)
{
    printf("usage:\n"
           "  ribbonctl rails home NAME --confirm [--json]\n"
           "  ribbonctl rails confirm-zero NAME --confirm [--json]\n"
           "common: --url URL (default $RIBBON_URL or http://127.0.0.1:8377), --token T (default $RIBBON_TOKEN)\n"
           "\n"
           "Asks the running ribbond to home its rail NAME (the rig file's rail name: compress or shear),\n"
           "or to take the rail's controller count as right where it stands (confirm-zero: homing off, $22=0),\n"
           "after its G-code controller lost its position (a reset or an alarm: the rail refuses motion until\n"
           "then, also after a restart of ribbond). --confirm is required: homing drives the rail to its\n"
           "switch and a clamped specimen would be crushed. Refused while a trial runs. Homing answers once\n"
           "the cycle has started (the rail reads homing until it ends); `ribbonctl status` follows it.\n");
}

static int usage(const char *msg)
{
    fprintf(stderr, "ribbonctl rails: %s (see ribbonctl rails --help)\n", msg);
    return 2;
}

int ctl_rails_main(int argc, char **argv)
{
    const char *url = getenv("RIBBON_URL"), *token = getenv("RIBBON_TOKEN"), *words[2] = {NULL, NULL};
    if (!url || !*url) url = "http://127.0.0.1:8377";
    int n = 0, confirm = 0, json = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return 0;
        } else if (!strcmp(a, "--confirm")) {
            confirm = 1;
        } else if (!strcmp(a, "--json")) {
            json = 1;
        } else if (!strcmp(a, "--url") || !strcmp(a, "--token")) {
            if (i + 1 >= argc) return usage("missing value after option");
            if (!strcmp(a, "--url")) url = argv[++i];
            else token = argv[++i];
        } else if (a[0] == '-') {
            return usage("unknown option");
        } else if (n < 2) {
            words[n++] = a;
        } else {
            return usage("too many words");
        }
    }
    if (n != 2 || (strcmp(words[0], "home") != 0 && strcmp(words[0], "confirm-zero") != 0))
        return usage("ribbonctl rails home|confirm-zero NAME --confirm");
    if (strlen(words[1]) > 60 || strspn(words[1], "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-") !=
                                     strlen(words[1]))
        return usage("a rail name is letters, digits, '_', '.' and '-'");
    char path[128];
    snprintf(path, sizeof path, "/rails/%s/%s", words[1], words[0]);
    json_t *body = json_pack("{s:b}", "confirm", confirm), *out = NULL;
    api_client_config c = api_client_config_default();
    c.base_url = url;
    c.token = token;
    int status = 0;
    char why[512] = "";
    int rc = api_client_request(&c, "POST", path, body, &status, &out, NULL, NULL, why, sizeof why);
    json_decref(body);
    if (rc) {
        fprintf(stderr, "ribbonctl: %s\n", why);
        return 1;
    }
    if (status >= 400) {
        fprintf(stderr, "ribbonctl: POST %s: %d %s\n", path, status, why);
        json_decref(out);
        return 1;
    }
    if (json) {
        char *s = json_dumps(out, JSON_COMPACT);
        if (s) puts(s);
        free(s);
    } else {
        const char *st = json_string_value(json_object_get(out, "state"));
        const char *msg = json_string_value(json_object_get(out, "message"));
        json_t *pos = json_object_get(out, "position_mm");
        printf("rail %s: %s; %s", words[1], !strcmp(words[0], "home") ? "homing started" : "zero confirmed",
               st ? st : "?");
        if (json_is_number(pos)) printf(" at %.4f mm", json_number_value(pos));
        printf("%s%s\n", msg && *msg ? ": " : "", msg ? msg : "");
    }
    json_decref(out);
    return 0;
}
