/* ctl_check.c: `ribbonctl check`: is the rig a rig file describes ready? One line per check, ok /
 * warn / fail with what to do (daemon/check/check.h lists them); exit 0 when nothing fails, 1 on
 * any fail, 2 on a usage error or a rig file that does not load.
 *
 *   ribbonctl check --config RIG.ini [--set SECTION.KEY=VALUE ...] [--user NAME] [--json]
 *
 * Access is judged for the service user ribbond runs as (ribbon, config/ribbond.service), so
 * that root running the check does not pass a port only root may open; --user names another,
 * and when the service user does not exist yet (not installed) the calling user is judged, with
 * a warning. Nothing moves a rail; a rail a running ribbond holds is reported, not opened. */
#include <pwd.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "ctl.h"
#include "rig_config.h"

#define CHECK_SERVICE_USER "ribbon"
#define CHECK_MAX_SET 32

static void usage(FILE *f)
{
    fprintf(f, "usage: ribbonctl check --config RIG.ini [--set SECTION.KEY=VALUE ...] [--user NAME] [--json]\n"
               "  opens every part the rig file names (rails, camera, store) without moving anything and\n"
               "  prints one line per check: ok | warn | fail, what was found and what to do.\n"
               "  --user NAME  judge port, store and video access for NAME (default: the service user\n"
               "               " CHECK_SERVICE_USER ", or this user when " CHECK_SERVICE_USER " does not exist)\n"
               "  exit status: 0 ready (warnings allowed), 1 a check failed, 2 usage or rig file error\n");
}

int ctl_check_main(int argc, char **argv)
{
    const char *config = NULL, *user = NULL, *set[CHECK_MAX_SET];
    int n_set = 0, json = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--json")) {
            json = 1;
        } else if ((!strcmp(a, "--config") || !strcmp(a, "--user") || !strcmp(a, "--set")) && !v) {
            fprintf(stderr, "ribbonctl check: %s needs a value\n", a);
            return 2;
        } else if (!strcmp(a, "--config")) {
            config = argv[++i];
        } else if (!strcmp(a, "--user")) {
            user = argv[++i];
        } else if (!strcmp(a, "--set")) {
            if (n_set == CHECK_MAX_SET) {
                fprintf(stderr, "ribbonctl check: at most %d --set\n", CHECK_MAX_SET);
                return 2;
            }
            set[n_set++] = argv[++i];
        } else {
            fprintf(stderr, "ribbonctl check: unexpected argument '%s'\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (!config) {
        usage(stderr);
        return 2;
    }
    rig_config *cfg = malloc(sizeof *cfg);
    check_report *rep = malloc(sizeof *rep);
    if (!cfg || !rep) {
        fprintf(stderr, "ribbonctl check: out of memory\n");
        free(cfg);
        free(rep);
        return 1;
    }
    cfg_error ce;
    if (rig_config_load(config, set, n_set, cfg, &ce) != CFG_OK) {
        char msg[700];
        fprintf(stderr, "ribbonctl check: %s\n", cfg_error_format(&ce, msg, sizeof msg));
        free(cfg);
        free(rep);
        return 2;
    }
    check_env env = check_env_default();
    int fallback = 0;
    if (user) {
        env.service_user = user;
    } else if (getpwnam(CHECK_SERVICE_USER)) {
        env.service_user = CHECK_SERVICE_USER;
    } else {
        fallback = 1; /* judged as the calling user, said below */
    }
    check_report_init(rep);
    if (fallback) {
        struct passwd *pw = getpwuid(getuid());
        check_add(rep, CHECK_WARN, "service", "user", "no user '" CHECK_SERVICE_USER "' (ribbond.service's; docs/install.md): "
                  "access judged for %s instead", pw ? pw->pw_name : "this user");
    }
    check_rig_run(cfg, &env, rep);
    if (json) {
        json_t *o = check_report_json(rep);
        json_object_set_new(o, "config", json_string(cfg->path));
        char *s = json_dumps(o, JSON_COMPACT);
        printf("%s\n", s ? s : "{}");
        free(s);
        json_decref(o);
    } else {
        check_report_print(rep, stdout);
    }
    int rc = rep->fails ? 1 : 0;
    free(cfg);
    free(rep);
    return rc;
}
