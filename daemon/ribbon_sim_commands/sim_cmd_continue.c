/* sim_cmd_continue.c: `ribbon-sim continue`: the bifurcation analysis of a scene
 * (sim/rod_bifurcation.h): branches, located events and the predicted regime, for a person, as
 * one JSON object, as CSV rows, and as a PNG diagram.
 *
 * The options shared with the other subcommands go through sim_opts; the ones only this command
 * takes (--csv, --plot, --keep-imperfection, --no-switch, --nodes) are taken out of argv first. */
#include "rod_bifurcation.h"
#include "sim_cmd.h"
#include "sim_opts.h"
#include "sim_plot_continue.h"

#include <errno.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char usage[] =
    "usage: ribbon-sim continue --scene FILE [--set section.key=value ...] [--json] [--csv FILE]\n"
    "                           [--plot FILE.png] [--keep-imperfection] [--no-switch]\n"
    "  Bifurcation analysis at protocol.compression: reaches the upper state, follows the\n"
    "  equilibrium branch in Delta W by pseudo-arclength continuation (through folds, along\n"
    "  unstable segments), counts negative Hessian eigenvalues at every point, locates each change\n"
    "  (to 1e-5 in Delta W), classifies it by the symmetry of the critical mode (antisymmetric:\n"
    "  pitchfork; symmetric at a fold of the load path: saddle-node), and follows the asymmetric\n"
    "  branch from the first pitchfork. The first instability predicts the regime: pitchfork first\n"
    "  is an asymmetric snap, saddle-node first a symmetric one.\n"
    "  The primary branch is traced on the perfect (C2-symmetric) scene; --keep-imperfection keeps\n"
    "  imperfection.fold_angle_rel. --no-switch skips the asymmetric branch.\n"
    "  --json prints one object (first_instability, regime, events, branches); --csv writes one row\n"
    "  per branch point; --plot draws Delta Z and A against Delta W (PNG, PLplot).\n";

typedef struct extra {
    const char *csv, *plot;
    int keep_imperfection, no_switch;
} extra;

/* Takes this command's own options out of argv (in place); returns the new argc, -1 on error. */
static int take_extra(int argc, char **argv, extra *x)
{
    int out = 1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char **dst = !strcmp(a, "--csv") ? &x->csv : !strcmp(a, "--plot") ? &x->plot : NULL;
        if (dst) {
            if (i + 1 >= argc) {
                fprintf(stderr, "ribbon-sim continue: %s needs a file name\n", a);
                return -1;
            }
            *dst = argv[++i];
        } else if (!strcmp(a, "--keep-imperfection")) {
            x->keep_imperfection = 1;
        } else if (!strcmp(a, "--no-switch")) {
            x->no_switch = 1;
        } else {
            argv[out++] = argv[i];
        }
    }
    return out;
}

static json_t *point_json(const rod_cont_point *p)
{
    json_t *j = json_object();
    json_object_set_new(j, "dw", json_real(p->dw));
    json_object_set_new(j, "dz", json_real(p->dz));
    json_object_set_new(j, "a", json_real(p->a));
    json_object_set_new(j, "energy", json_real(p->energy));
    json_object_set_new(j, "n_negative", json_integer(p->n_negative));
    json_object_set_new(j, "stable", json_boolean(p->stable));
    return j;
}

static json_t *event_json(const rod_event *e)
{
    json_t *j = json_object();
    json_object_set_new(j, "type", json_string(rod_event_name(e->kind)));
    json_object_set_new(j, "branch", json_integer(e->branch));
    json_object_set_new(j, "dw", json_real(e->at.dw));
    json_object_set_new(j, "dz", json_real(e->at.dz));
    json_object_set_new(j, "a", json_real(e->at.a));
    json_object_set_new(j, "dw_bracket", json_real(e->lambda_width));
    json_object_set_new(j, "located", json_boolean(e->located));
    json_object_set_new(j, "fold", json_boolean(e->fold));
    json_object_set_new(j, "mode_parity", json_real(e->parity));
    json_object_set_new(j, "load_projection", json_real(e->load_projection));
    json_object_set_new(j, "eig_before", json_real(e->eig_before));
    json_object_set_new(j, "eig_after", json_real(e->eig_after));
    json_object_set_new(j, "n_negative_before", json_integer(e->n_negative_before));
    json_object_set_new(j, "n_negative_after", json_integer(e->n_negative_after));
    return j;
}

static void print_json(const char *scene, const rod_scene *sc, const rod_analysis *a)
{
    json_t *j = json_object();
    json_object_set_new(j, "scene", json_string(scene));
    json_object_set_new(j, "nodes", json_integer(sc->nodes));
    json_object_set_new(j, "compression", json_real(sc->compression));
    json_object_set_new(j, "fold_angle_rel", json_real(a->fold_angle_rel));
    json_object_set_new(j, "dz_upper", json_real(a->dz_upper));
    json_object_set_new(j, "regime", json_string(a->regime));
    if (a->first >= 0) {
        const rod_event *e = &a->events[a->first];
        json_t *f = json_object();
        json_object_set_new(f, "type", json_string(rod_event_name(e->kind)));
        json_object_set_new(f, "dw", json_real(e->at.dw));
        json_object_set_new(f, "dz", json_real(e->at.dz));
        json_object_set_new(j, "first_instability", f);
    } else {
        json_object_set_new(j, "first_instability", json_null());
    }
    json_t *ev = json_array();
    for (int e = 0; e < a->nevents; e++) json_array_append_new(ev, event_json(&a->events[e]));
    json_object_set_new(j, "events", ev);
    json_t *brs = json_array();
    for (int b = 0; b < a->nbranches; b++) {
        const rod_branch *br = &a->branches[b];
        json_t *jb = json_object();
        json_object_set_new(jb, "id", json_integer(br->id));
        json_object_set_new(jb, "parent_event", br->parent_event >= 0 ? json_integer(br->parent_event) : json_null());
        json_object_set_new(jb, "end_status", json_string(rod_status_message(br->end_status)));
        json_object_set_new(jb, "end_reason", json_string(br->end_reason));
        json_t *pts = json_array();
        for (size_t i = 0; i < br->n; i++) json_array_append_new(pts, point_json(&br->points[i]));
        json_object_set_new(jb, "points", pts);
        json_array_append_new(brs, jb);
    }
    json_object_set_new(j, "branches", brs);
    json_object_set_new(j, "newton_iterations", json_integer((json_int_t)a->count.newton_iterations));
    json_object_set_new(j, "factorisations", json_integer((json_int_t)a->count.factorisations));
    json_object_set_new(j, "worst_residual_rel", json_real(a->worst_residual));
    json_object_set_new(j, "route_wall_s", json_real(a->route_wall_s));
    json_object_set_new(j, "wall_s", json_real(a->wall_s));
    json_object_set_new(j, "version", json_string(RIBBON_VERSION));
    char *s = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(10));
    if (s) puts(s);
    free(s);
    json_decref(j);
}

static int write_csv(const char *path, const rod_analysis *a)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        fprintf(stderr, "ribbon-sim continue: cannot write %s: %s\n", path, strerror(errno));
        return 0;
    }
    fprintf(f, "branch,dw,dz,a,energy,n_negative,stable,arclength\n");
    for (int b = 0; b < a->nbranches; b++)
        for (size_t i = 0; i < a->branches[b].n; i++) {
            const rod_cont_point *p = &a->branches[b].points[i];
            fprintf(f, "%d,%.10g,%.10g,%.10g,%.10g,%d,%d,%.8g\n", a->branches[b].id, p->dw, p->dz, p->a, p->energy,
                    p->n_negative, p->stable, p->s);
        }
    int ok = !ferror(f);
    if (fclose(f) != 0) ok = 0;
    if (!ok) fprintf(stderr, "ribbon-sim continue: error writing %s\n", path);
    return ok;
}

static void print_text(const char *scene, const rod_scene *sc, const rod_analysis *a)
{
    printf("scene        %s (N = %d, Delta L = %g, imperfection %g%s)\n", scene, sc->nodes, sc->compression,
           a->fold_angle_rel, a->fold_angle_rel == 0.0 ? ": perfect scene" : "");
    printf("upper state  Delta Z = %.4f at Delta W = 0\n", a->dz_upper);
    for (int b = 0; b < a->nbranches; b++) {
        const rod_branch *br = &a->branches[b];
        printf("\nbranch %d (%s): %zu points; ended: %s\n", br->id,
               br->parent_event < 0 ? "primary" : "switched at a pitchfork", br->n, br->end_reason);
        printf("  %-6s %10s %10s %11s  %s\n", "branch", "Delta W", "Delta Z", "A", "stability");
        for (size_t i = 0; i < br->n; i++) {
            const rod_cont_point *p = &br->points[i];
            printf("  %-6d %10.5f %10.5f %11.4e  %s", br->id, p->dw, p->dz, p->a, p->stable ? "stable" : "unstable");
            if (!p->stable) printf(" (%d negative)", p->n_negative);
            putchar('\n');
        }
    }
    printf("\nevents\n");
    if (a->nevents == 0) printf("  none\n");
    for (int e = 0; e < a->nevents; e++) {
        const rod_event *ev = &a->events[e];
        printf("  %-12s branch %d  Delta W %.5f  Delta Z %.5f  (mode parity %+.3f, load projection %.2e%s)\n",
               rod_event_name(ev->kind), ev->branch, ev->at.dw, ev->at.dz, ev->parity, ev->load_projection,
               ev->located ? "" : ", NOT fully located");
    }
    if (a->first >= 0) {
        const rod_event *f = &a->events[a->first];
        printf("\nfirst instability  %s at Delta W = %.5f (Delta Z = %.5f)\n", rod_event_name(f->kind), f->at.dw,
               f->at.dz);
    } else {
        printf("\nfirst instability  none on the traced branch\n");
    }
    printf("predicted regime   %s\n", !strcmp(a->regime, "asymmetric") ? "asymmetric snap (pitchfork first)"
                                      : !strcmp(a->regime, "symmetric") ? "symmetric snap (saddle-node first)"
                                                                          : "none");
    printf("run                %llu Newton iterations, %llu factorisations, %.2f s wall (route to the upper state %.2f s)\n",
           (unsigned long long)a->count.newton_iterations, (unsigned long long)a->count.factorisations, a->wall_s,
           a->route_wall_s);
    if (a->worst_residual > 0.0)
        printf("note               some points next to critical points were accepted with a stalled corrector\n"
               "                   (residual up to %.2g of EI1 / l^2; tolerance %g)\n", a->worst_residual, sc->tolerance);
}

int sim_cmd_continue(int argc, char **argv)
{
    extra x = {0};
    argc = take_extra(argc, argv, &x);
    if (argc < 0) return 2;
    sim_opts o;
    int rc = sim_opts_parse(argc, argv, "json", usage, &o);
    if (rc) return rc == 1 ? 0 : 2;
    rod_scene sc;
    if (!sim_opts_load_scene(&o, &sc)) return 2;
    rod_analysis_opts ao = rod_analysis_opts_default();
    ao.keep_imperfection = x.keep_imperfection;
    ao.switch_branches = !x.no_switch;
    rod_analysis a;
    char err[512] = "";
    rod_status st = rod_bifurcation_analyse(&sc, &ao, &a, err, sizeof err);
    if (st != ROD_OK) {
        fprintf(stderr, "ribbon-sim continue: %s: %s\n", o.scene, err[0] ? err : rod_status_message(st));
        return 1;
    }
    int status = 0;
    if (x.csv && !write_csv(x.csv, &a)) status = 1;
    if (x.plot) {
        char title[256], perr[256];
        snprintf(title, sizeof title, "#gG %.3g, #gf %.3g#uo#d, #gDL %.3g, N %d", sc.fold_position, sc.fold_angle_deg,
                 sc.compression, sc.nodes);
        if (sim_plot_continue(x.plot, &a, title, perr, sizeof perr) != 0) {
            fprintf(stderr, "ribbon-sim continue: %s\n", perr);
            status = 1;
        }
    }
    if (o.json) print_json(o.scene, &sc, &a);
    else print_text(o.scene, &sc, &a);
    rod_analysis_free(&a);
    return status;
}
