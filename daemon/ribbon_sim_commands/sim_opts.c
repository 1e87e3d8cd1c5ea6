/* sim_opts.c: shared option parsing for ribbon-sim subcommands (see sim_opts.h). */
#include "sim_opts.h"
#include "cfg_number.h"
#include "scene_file.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int allowed_flag(const char *allowed, const char *name)
{
    size_t n = strlen(name);
    for (const char *p = allowed; p && (p = strstr(p, name)); p += n)
        if ((p == allowed || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return 1;
    return 0;
}

static int parse_double(const char *flag, const char *v, double *out)
{
    char *end;
    errno = 0;
    double x = cfg_number_strtod(v, &end);
    if (errno || end == v || *end != '\0' || !isfinite(x)) {
        fprintf(stderr, "ribbon-sim: %s needs a finite number, got '%s'\n", flag, v);
        return 0;
    }
    *out = x;
    return 1;
}

int sim_opts_parse(int argc, char **argv, const char *allowed, const char *usage, sim_opts *o)
{
    memset(o, 0, sizeof *o);
    o->branch = 1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            fputs(usage, stdout);
            return 1;
        }
        if (strncmp(a, "--", 2) != 0) {
            fprintf(stderr, "ribbon-sim %s: unexpected argument '%s' (see --help)\n", argv[0], a);
            return 2;
        }
        const char *name = a + 2;
        char key[32];
        const char *val = NULL;
        const char *eq = strchr(name, '=');
        size_t kl = eq ? (size_t)(eq - name) : strlen(name);
        if (kl >= sizeof key) kl = sizeof key - 1;
        memcpy(key, name, kl);
        key[kl] = '\0';
        int takes_value = strcmp(key, "json") && strcmp(key, "fast");
        if (takes_value) {
            if (eq) val = eq + 1;
            else if (i + 1 < argc) val = argv[++i];
            else {
                fprintf(stderr, "ribbon-sim %s: --%s needs a value\n", argv[0], key);
                return 2;
            }
        } else if (eq) {
            fprintf(stderr, "ribbon-sim %s: --%s takes no value\n", argv[0], key);
            return 2;
        }
        if (!strcmp(key, "scene")) o->scene = val;
        else if (!strcmp(key, "set")) {
            if (o->nsets >= SIM_OPTS_MAX_SETS) {
                fprintf(stderr, "ribbon-sim %s: at most %d --set options\n", argv[0], SIM_OPTS_MAX_SETS);
                return 2;
            }
            o->sets[o->nsets++] = val;
        } else if (!allowed_flag(allowed, key)) {
            fprintf(stderr, "ribbon-sim %s: unknown option --%s (see --help)\n", argv[0], key);
            return 2;
        } else if (!strcmp(key, "json")) o->json = 1;
        else if (!strcmp(key, "fast")) o->fast = 1;
        else if (!strcmp(key, "out")) o->out = val;
        else if (!strcmp(key, "dl")) {
            if (!parse_double("--dl", val, &o->dl)) return 2;
            o->has_dl = 1;
        } else if (!strcmp(key, "dw")) {
            if (!parse_double("--dw", val, &o->dw)) return 2;
            o->has_dw = 1;
        } else if (!strcmp(key, "branch")) {
            if (!strcmp(val, "upper")) o->branch = 1;
            else if (!strcmp(val, "lower")) o->branch = -1;
            else {
                fprintf(stderr, "ribbon-sim %s: --branch is upper or lower, got '%s'\n", argv[0], val);
                return 2;
            }
        }
    }
    if (!o->scene) {
        fprintf(stderr, "ribbon-sim %s: --scene FILE is required (see --help)\n", argv[0]);
        return 2;
    }
    return 0;
}

int sim_opts_load_scene(const sim_opts *o, rod_scene *s)
{
    cfg_error err;
    if (cfg_scene_load(o->scene, o->sets, o->nsets, s, &err) != CFG_OK) {
        char buf[1024];
        fprintf(stderr, "ribbon-sim: %s\n", cfg_error_format(&err, buf, sizeof buf));
        return 0;
    }
    return 1;
}
