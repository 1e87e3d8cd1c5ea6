/* sim_opts.h: the options every ribbon-sim scene subcommand shares (--scene, --set, --json,
 * --help) plus the few that some take, parsed one way so every subcommand behaves the same. */
#ifndef RIBBON_DAEMON_SIM_OPTS_H
#define RIBBON_DAEMON_SIM_OPTS_H

#include "scene.h"

#define SIM_OPTS_MAX_SETS 64

typedef struct sim_opts {
    const char *scene;                     /* --scene FILE (required) */
    const char *sets[SIM_OPTS_MAX_SETS];   /* --set section.key=value, in order */
    int nsets;
    int json;                              /* --json */
    int fast;                              /* --fast: adaptive time stepping */
    const char *out;                       /* --out FILE */
    double dl, dw;                         /* --dl, --dw */
    int has_dl, has_dw;
    int branch;                            /* --branch upper (+1) | lower (-1) */
} sim_opts;

/* Parses argv[1..]; `allowed` lists the optional flags this subcommand accepts, e.g.
 * "json fast out dl dw branch". Returns 0 to go on, 1 when --help was printed (exit 0),
 * 2 on a usage error (message printed). */
int sim_opts_parse(int argc, char **argv, const char *allowed, const char *usage, sim_opts *o);

/* Loads the scene with its overrides; prints "ribbon-sim: FILE:LINE: key: message" on error. */
int sim_opts_load_scene(const sim_opts *o, rod_scene *s);

#endif
