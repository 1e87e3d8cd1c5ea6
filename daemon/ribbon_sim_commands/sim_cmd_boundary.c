/* sim_cmd_boundary.c: `ribbon-sim boundary`: the regime boundary Gamma*(phi) traced directly as
 * the codimension-2 point where the upper symmetric branch's pitchfork and saddle-node coincide
 * (sim/rod_boundary.h), continued in phi, at one or more Delta L; with --curves the fold and
 * pitchfork curves in (Gamma, Delta W) through it at the scene's phi and Delta L.
 *
 * Order of work: the start at the scene's (phi, Gamma, Delta L); --curves there; then for each
 * Delta L of --dl in turn, the current point is moved in Delta L, then in phi to A (not recorded)
 * and traced from A to B (recorded, A included). A phi range reaching 0 or 180 deg is traced to
 * 1 or 179 deg and stops there with a reason; every stop keeps the points before it and makes the
 * exit status 1 (3 when nothing at all was found). */
#include "rod_boundary.h"
#include "sim_cmd.h"
#include "sim_opts.h"
#include "sim_plot_boundary.h"
#include "sim_sweep_row.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_DL 16

static const char usage[] =
    "usage: ribbon-sim boundary --scene FILE [--set k=v ...] [--phi A:B] [--dl X,Y,...] [--curves]\n"
    "                           [--json] [--csv FILE] [--plot FILE.png] [--sweep-csv FILE]\n"
    "  Traces the regime boundary Gamma*(phi) directly: the point where the upper symmetric branch's\n"
    "  pitchfork and saddle-node coincide (both the even and the odd block of the Hessian singular),\n"
    "  found from the scene's Gamma and continued in phi from A to B (degrees, crease angle magnitude;\n"
    "  default: the scene's phi only) at each Delta L of --dl (default: the scene's). Prints phi,\n"
    "  Gamma*, Delta W and Delta Z there. --curves: the saddle-node and pitchfork curves in\n"
    "  (Gamma, Delta W) at the scene's phi and Delta L. --csv writes the points; --plot draws the\n"
    "  boundary over (phi, Gamma) (with --sweep-csv: over that sweep's classified points), or with\n"
    "  --curves the (Gamma, Delta W) diagram. Stops (Gamma out of range, phi at 0 or 180 deg, no\n"
    "  meeting point) are named and keep the points before them (exit 1).\n";

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct bopts {
    sim_opts so;
    double phi_a, phi_b;
    int has_phi;
    double dl[MAX_DL];
    int ndl;
    int curves;
    const char *csv, *plot, *sweep_csv;
} bopts;

static int parse(int argc, char **argv, bopts *o)
{
    memset(o, 0, sizeof *o);
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            fputs(usage, stdout);
            return 1;
        } else if (!strcmp(a, "--json")) {
            o->so.json = 1;
        } else if (!strcmp(a, "--curves")) {
            o->curves = 1;
        } else if (!v) {
            fprintf(stderr, "ribbon-sim boundary: %s needs a value\n%s", a, usage);
            return 2;
        } else if (!strcmp(a, "--scene")) {
            o->so.scene = v; i++;
        } else if (!strcmp(a, "--set")) {
            if (o->so.nsets >= SIM_OPTS_MAX_SETS) {
                fprintf(stderr, "ribbon-sim boundary: too many --set\n");
                return 2;
            }
            o->so.sets[o->so.nsets++] = v; i++;
        } else if (!strcmp(a, "--csv")) {
            o->csv = v; i++;
        } else if (!strcmp(a, "--plot")) {
            o->plot = v; i++;
        } else if (!strcmp(a, "--sweep-csv")) {
            o->sweep_csv = v; i++;
        } else if (!strcmp(a, "--phi")) {
            char extra;
            if (sscanf(v, "%lf:%lf%c", &o->phi_a, &o->phi_b, &extra) != 2 || !isfinite(o->phi_a) ||
                !isfinite(o->phi_b)) {
                fprintf(stderr, "ribbon-sim boundary: --phi needs A:B in degrees, got '%s'\n", v);
                return 2;
            }
            o->has_phi = 1; i++;
        } else if (!strcmp(a, "--dl")) {
            const char *p = v;
            while (*p) {
                char *end;
                double x = strtod(p, &end);
                if (end == p || !isfinite(x) || !(x > 0.0 && x < 1.0) || o->ndl >= MAX_DL) {
                    fprintf(stderr, "ribbon-sim boundary: --dl needs up to %d values in (0, 1), got '%s'\n", MAX_DL, v);
                    return 2;
                }
                o->dl[o->ndl++] = x;
                p = end;
                if (*p == ',') p++;
                else if (*p) {
                    fprintf(stderr, "ribbon-sim boundary: --dl: cannot read '%s'\n", v);
                    return 2;
                }
            }
            i++;
        } else {
            fprintf(stderr, "ribbon-sim boundary: unknown option %s\n%s", a, usage);
            return 2;
        }
    }
    if (!o->so.scene) {
        fprintf(stderr, "ribbon-sim boundary: --scene is required\n%s", usage);
        return 2;
    }
    return 0;
}

static json_t *point_json(const rod_codim2_point *p)
{
    return json_pack("{s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:i}", "phi_deg", p->phi_deg, "dl", p->dl, "gamma",
                     p->gamma, "dw", p->dw, "dz", p->dz, "eig_even", p->eig_even, "eig_odd", p->eig_odd, "eig_scale",
                     p->eig_scale, "parity_even", p->parity_even, "parity_odd", p->parity_odd, "outer_edges",
                     p->outer_edges);
}

static json_t *crit_json(const rod_crit_curve *c)
{
    json_t *a = json_array();
    for (size_t k = 0; k < c->n; k++)
        json_array_append_new(a, json_pack("{s:f,s:f,s:f,s:f}", "gamma", c->pts[k].gamma, "dw", c->pts[k].dw, "dz",
                                           c->pts[k].dz, "g_other", c->pts[k].g_other));
    return json_pack("{s:o,s:s}", "points", a, "end", c->end_reason);
}

static int push(rod_boundary_curve *rec, const rod_codim2_point *p)
{
    if (rec->n == rec->cap) {
        size_t cap = rec->cap ? 2 * rec->cap : 64;
        rod_codim2_point *np = realloc(rec->pts, cap * sizeof *np);
        if (!np) return 0;
        rec->pts = np;
        rec->cap = cap;
    }
    rec->pts[rec->n++] = *p;
    return 1;
}

/* Traces the boundary at one Delta L into rec, in increasing phi. From the start point (the
 * mark), moved in Delta L at the scene's phi; then, when the scene's phi lies inside [A, B],
 * down to A and (from the same point again) up to B, else to A unrecorded and on to B. The ends
 * are kept inside [1, 179] deg. */
static void trace_one(rod_boundary *b, const bopts *o, double dl, double phi_scene, rod_boundary_curve *rec)
{
    rod_boundary_curve part = {0};
    double a = o->has_phi ? fmin(o->phi_a, o->phi_b) : phi_scene, bb = o->has_phi ? fmax(o->phi_a, o->phi_b) : phi_scene;
    double a1 = fmin(fmax(a, 1.0), 179.0), b1 = fmin(fmax(bb, 1.0), 179.0);
    rod_boundary_return(b);
    rod_codim2_point cur;
    rod_boundary_current(b, &cur);
    rec->end_status = ROD_OK;
    rec->end_reason[0] = '\0';
    if (fabs(cur.dl - dl) > 1e-12 && rod_boundary_move(b, ROD_PAR_DL, dl, &part) != ROD_OK) {
        rec->end_status = part.end_status;
        snprintf(rec->end_reason, sizeof rec->end_reason, "moving to Delta L = %g: %.200s", dl, part.end_reason);
        rod_boundary_curve_free(&part);
        return;
    }
    rod_boundary_curve_free(&part);
    rod_boundary_current(b, &cur);
    char reason[2][256] = {"", ""};
    if (a1 < cur.phi_deg && cur.phi_deg < b1) {
        rod_codim2_point mid = cur;
        rod_boundary_mark(b);
        rod_status s1 = rod_boundary_move(b, ROD_PAR_PHI, a1, &part);
        for (size_t k = part.n; k-- > 0;) push(rec, &part.pts[k]);
        if (s1 != ROD_OK) {
            rec->end_status = s1;
            snprintf(reason[0], sizeof reason[0], "toward %g deg: %.200s", a1, part.end_reason);
        }
        rod_boundary_curve_free(&part);
        push(rec, &mid);
        rod_boundary_return(b);
        rod_status s2 = rod_boundary_move(b, ROD_PAR_PHI, b1, &part);
        for (size_t k = 0; k < part.n; k++) push(rec, &part.pts[k]);
        if (s2 != ROD_OK) {
            rec->end_status = s2;
            snprintf(reason[1], sizeof reason[1], "toward %g deg: %.200s", b1, part.end_reason);
        }
        rod_boundary_curve_free(&part);
    } else {
        if (fabs(cur.phi_deg - a1) > 1e-12 && rod_boundary_move(b, ROD_PAR_PHI, a1, &part) != ROD_OK) {
            rec->end_status = part.end_status;
            snprintf(rec->end_reason, sizeof rec->end_reason, "moving to phi = %g deg: %.200s", a1, part.end_reason);
            rod_boundary_curve_free(&part);
            return;
        }
        rod_boundary_curve_free(&part);
        rod_boundary_current(b, &cur);
        push(rec, &cur);
        if (fabs(b1 - a1) > 1e-12) {
            rod_status s2 = rod_boundary_move(b, ROD_PAR_PHI, b1, &part);
            for (size_t k = 0; k < part.n; k++) push(rec, &part.pts[k]);
            if (s2 != ROD_OK) {
                rec->end_status = s2;
                snprintf(reason[1], sizeof reason[1], "%.250s", part.end_reason);
            }
            rod_boundary_curve_free(&part);
        }
    }
    if (rec->end_status != ROD_OK)
        snprintf(rec->end_reason, sizeof rec->end_reason, "%.120s%s%.120s", reason[0], reason[0][0] && reason[1][0] ? "; " : "",
                 reason[1]);
    else if (a != a1 || bb != b1) {
        rec->end_status = ROD_ERR_SCENE;
        snprintf(rec->end_reason, sizeof rec->end_reason,
                 "the phi range %g:%g crosses %s deg (the creases vanish or close there): traced to %g deg", a, bb,
                 a <= 0.0 ? "0" : "180", a != a1 ? a1 : b1);
    } else {
        snprintf(rec->end_reason, sizeof rec->end_reason, "covered phi %g .. %g", a1, b1);
    }
}

int sim_cmd_boundary(int argc, char **argv)
{
    bopts o;
    int rc = parse(argc, argv, &o);
    if (rc) return rc == 1 ? 0 : 2;
    rod_scene sc;
    if (!sim_opts_load_scene(&o.so, &sc)) return 2;
    if (o.ndl == 0) o.dl[o.ndl++] = sc.compression;
    sweep_table sweep = {0};
    if (o.sweep_csv) {
        char err[256];
        FILE *f = fopen(o.sweep_csv, "r");
        if (!f) {
            fprintf(stderr, "ribbon-sim boundary: cannot read %s\n", o.sweep_csv);
            return 2;
        }
        fclose(f);
        if (sweep_table_load(o.sweep_csv, &sweep, err, sizeof err) != 0) {
            fprintf(stderr, "ribbon-sim boundary: %s\n", err);
            return 2;
        }
    }
    double t0 = now();
    rod_boundary_opts bo = rod_boundary_opts_default();
    rod_boundary *b = NULL;
    rod_codim2_point start;
    char why[512] = "";
    rod_status st = rod_boundary_start(&sc, &bo, &b, &start, why, sizeof why);
    if (st != ROD_OK) {
        fprintf(stderr, "ribbon-sim boundary: %s\n", why);
        if (o.so.json) {
            json_t *j = json_pack("{s:s,s:s}", "status", "not found", "reason", why);
            char *txt = json_dumps(j, JSON_COMPACT);
            puts(txt);
            free(txt);
            json_decref(j);
        }
        rod_boundary_free(b);
        sweep_table_free(&sweep);
        return 3;
    }
    rod_boundary_mark(b);
    rod_crit_curve fold = {0}, pf = {0};
    if (o.curves) {
        double lo = fmax(bo.gamma_min, start.gamma - 0.05), hi = fmin(bo.gamma_max, start.gamma + 0.05);
        rod_boundary_crit_curve(b, ROD_CRIT_FOLD, lo, hi, 0.005, &fold);
        rod_boundary_crit_curve(b, ROD_CRIT_PITCHFORK, lo, hi, 0.005, &pf);
    }
    rod_boundary_curve curves[MAX_DL];
    memset(curves, 0, sizeof curves);
    int stopped = 0;
    double phi_scene = fabs(sc.fold_angle_deg);
    for (int k = 0; k < o.ndl; k++) {
        trace_one(b, &o, o.dl[k], phi_scene, &curves[k]);
        stopped |= curves[k].end_status != ROD_OK;
    }
    double wall = now() - t0;
    stopped |= o.curves && (fold.end_status != ROD_OK || pf.end_status != ROD_OK);

    if (o.csv) {
        FILE *f = fopen(o.csv, "w");
        if (!f) {
            fprintf(stderr, "ribbon-sim boundary: cannot write %s\n", o.csv);
            stopped = 1;
        } else {
            fprintf(f, "kind,dl,phi_deg,gamma,dw,dz,eig_even,eig_odd,parity_even,parity_odd\n");
            for (int k = 0; k < o.ndl; k++)
                for (size_t i = 0; i < curves[k].n; i++) {
                    const rod_codim2_point *p = &curves[k].pts[i];
                    fprintf(f, "boundary,%.17g,%.17g,%.17g,%.17g,%.17g,%.6g,%.6g,%.6f,%.6f\n", p->dl, p->phi_deg,
                            p->gamma, p->dw, p->dz, p->eig_even, p->eig_odd, p->parity_even, p->parity_odd);
                }
            const rod_crit_curve *cc[2] = {&fold, &pf};
            const char *nm[2] = {"saddle-node", "pitchfork"};
            for (int c = 0; c < 2; c++)
                for (size_t i = 0; i < cc[c]->n; i++)
                    fprintf(f, "%s,%.17g,%.17g,%.17g,%.17g,%.17g,,,,\n", nm[c], start.dl, start.phi_deg,
                            cc[c]->pts[i].gamma, cc[c]->pts[i].dw, cc[c]->pts[i].dz);
            fclose(f);
        }
    }
    if (o.plot) {
        char err[256];
        int pr = o.curves ? sim_plot_boundary_curves(o.plot, &fold, &pf, &start, err, sizeof err)
                          : sim_plot_boundary(o.plot, curves, o.dl, o.ndl, o.sweep_csv ? &sweep : NULL, err, sizeof err);
        if (pr != 0) {
            fprintf(stderr, "ribbon-sim boundary: %s\n", err);
            stopped = 1;
        }
    }
    if (o.so.json) {
        json_t *bs = json_array();
        for (int k = 0; k < o.ndl; k++) {
            json_t *pts = json_array();
            for (size_t i = 0; i < curves[k].n; i++) json_array_append_new(pts, point_json(&curves[k].pts[i]));
            json_array_append_new(bs, json_pack("{s:f,s:o,s:s,s:b}", "dl", o.dl[k], "points", pts, "end",
                                                curves[k].end_reason, "complete", curves[k].end_status == ROD_OK));
        }
        json_t *j = json_pack("{s:s,s:o,s:o,s:f}", "status", stopped ? "stopped" : "ok", "start", point_json(&start),
                              "boundaries", bs, "wall_s", wall);
        if (o.curves) {
            json_object_set_new(j, "saddle_node", crit_json(&fold));
            json_object_set_new(j, "pitchfork", crit_json(&pf));
        }
        char *txt = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(10));
        puts(txt);
        free(txt);
        json_decref(j);
    } else {
        printf("start        phi %.2f deg, Delta L %g: Gamma* = %.6f, Delta W = %.6f, Delta Z = %.4f "
               "(critical eigenvalues %.2g, %.2g of max K_ii %.2g; parities %+.3f, %+.3f)\n",
               start.phi_deg, start.dl, start.gamma, start.dw, start.dz, start.eig_even, start.eig_odd, start.eig_scale,
               start.parity_even, start.parity_odd);
        if (o.curves) {
            const rod_crit_curve *cc[2] = {&fold, &pf};
            const char *nm[2] = {"saddle-node", "pitchfork"};
            for (int c = 0; c < 2; c++) {
                printf("%-12s %zu points (%s)\n", nm[c], cc[c]->n, cc[c]->end_reason);
                for (size_t i = 0; i < cc[c]->n; i++)
                    printf("  Gamma %.4f  Delta W %.6f  Delta Z %.4f\n", cc[c]->pts[i].gamma, cc[c]->pts[i].dw,
                           cc[c]->pts[i].dz);
            }
        }
        for (int k = 0; k < o.ndl; k++) {
            printf("boundary     Delta L %g: %zu points (%s)\n", o.dl[k], curves[k].n,
                   curves[k].end_reason[0] ? curves[k].end_reason : "done");
            for (size_t i = 0; i < curves[k].n; i++)
                printf("  phi %7.3f deg  Gamma* %.6f  Delta W %.6f  Delta Z %.4f\n", curves[k].pts[i].phi_deg,
                       curves[k].pts[i].gamma, curves[k].pts[i].dw, curves[k].pts[i].dz);
        }
        printf("wall         %.2f s\n", wall);
    }
    for (int k = 0; k < o.ndl; k++) rod_boundary_curve_free(&curves[k]);
    rod_crit_curve_free(&fold);
    rod_crit_curve_free(&pf);
    rod_boundary_free(b);
    sweep_table_free(&sweep);
    return stopped ? 1 : 0;
}
