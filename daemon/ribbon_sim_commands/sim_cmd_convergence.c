/* sim_cmd_convergence.c: `ribbon-sim convergence`: error against run time. Runs the prediction
 * (fast mode) over a ladder that halves the edge length, the time step and the fast mode's step
 * control targets together, and estimates each rung's error in the snap Delta W with
 * rod_ladder_estimate (sim/rod_richardson.h, the estimate the daemon's ladder uses): Richardson
 * at the combined refinement's asymptotic order 1 when the observed order of the three finest
 * rungs lies in [0.7, 2.3], otherwise "not in the asymptotic range" with a safety factor of 3.
 * The finest rung's own error is estimated too (never 0 against itself). */
#include "rod_protocol.h"
#include "rod_richardson.h"
#include "sim_cmd.h"
#include "sim_opts.h"

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static const char usage[] =
    "usage: ribbon-sim convergence --scene FILE [--set section.key=value ...] [--json]\n"
    "  Predicts the snap on the ladder N - 3 = 36, 72, 144, 288 edges with dt = 8, 4, 2, 1 times\n"
    "  the scene's dt and the fast mode's step targets scaled with dt, and prints for each rung\n"
    "  the snap Delta W, its estimated relative error (Richardson at order 1 when the observed\n"
    "  order lies in [0.7, 2.3], else flagged not in the asymptotic range) and the wall time.\n";

#define RUNGS 4

/* Prints the table or the JSON of the ladder. */
static void report(int json, const int *nodes, const double *dts, const double *scale, const double *snap,
                   const double *err, const double *wall, const rod_ladder_verdict *v)
{
    if (json) {
        json_t *j = json_object(), *arr = json_array();
        for (int k = 0; k < RUNGS; k++)
            json_array_append_new(arr, json_pack("{s:i,s:f,s:f,s:o,s:f,s:f}", "nodes", nodes[k], "dt", dts[k],
                                                 "snap_dw", snap[k], "rel_error",
                                                 err[k] >= 0 ? json_real(err[k]) : json_null(), "wall_s", wall[k],
                                                 "adapt_scale", scale[k]));
        json_object_set_new(j, "rungs", arr);
        json_object_set_new(j, "extrapolated_snap_dw",
                            isfinite(v->extrapolated) ? json_real(v->extrapolated) : json_null());
        json_object_set_new(j, "observed_order", isfinite(v->order) ? json_real(v->order) : json_null());
        json_object_set_new(j, "expected_order", json_pack("[f,f]", ROD_LADDER_ORDER_LO, ROD_LADDER_ORDER_HI));
        json_object_set_new(j, "estimate_order", json_real(ROD_LADDER_ORDER_FORMAL));
        json_object_set_new(j, "asymptotic", json_boolean(v->asymptotic));
        json_object_set_new(j, "safety_factor", json_real(v->safety));
        json_object_set_new(j, "note", json_string(v->note));
        char *txt = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(10));
        puts(txt);
        free(txt);
        json_decref(j);
        return;
    }
    printf("%6s %10s %12s %12s %9s\n", "N", "dt (s)", "snap dW", "est. error", "wall (s)");
    for (int k = 0; k < RUNGS; k++) {
        if (err[k] >= 0)
            printf("%6d %10.4g %12.6f %12.2e %9.2f\n", nodes[k], dts[k], snap[k], err[k], wall[k]);
        else
            printf("%6d %10.4g %12.6f %12s %9.2f\n", nodes[k], dts[k], snap[k], "-", wall[k]);
    }
    if (isfinite(v->order)) printf("observed order %.2f (expected %.1f to %.1f)", v->order, ROD_LADDER_ORDER_LO,
                                   ROD_LADDER_ORDER_HI);
    else printf("no observed order");
    if (v->asymptotic)
        printf("; in the asymptotic range: errors against Richardson at order %g, snap Delta W -> %.6f\n",
               ROD_LADDER_ORDER_FORMAL, v->extrapolated);
    else printf("\n%s\n", v->note);
}

int sim_cmd_convergence(int argc, char **argv)
{
    sim_opts o;
    int rc = sim_opts_parse(argc, argv, "json", usage, &o);
    if (rc) return rc == 1 ? 0 : 2;
    rod_scene base;
    if (!sim_opts_load_scene(&o, &base)) return 2;
    double snap[RUNGS], wall[RUNGS], h[RUNGS], err[RUNGS], dts[RUNGS], scale[RUNGS];
    int nodes[RUNGS];
    for (int k = 0; k < RUNGS; k++) {
        rod_scene s = base;
        s.nodes = 36 * (1 << k) + 3;
        s.dt = base.dt * (double)(1 << (RUNGS - 1 - k));
        if (s.shear_max < 0.8) s.shear_max = 0.8; /* coarse rungs snap later */
        nodes[k] = s.nodes;
        dts[k] = s.dt;
        h[k] = 1.0 / (double)(s.nodes - 3);
        rod_predict_opts po = rod_predict_opts_default();
        po.adaptive = 1;
        po.adapt_scale = scale[k] = s.dt / base.dt;
        rod_prediction p;
        char msg[512] = "";
        if (!o.json) fprintf(stderr, "  rung %d/%d: N = %d, dt = %g s ...\n", k + 1, RUNGS, s.nodes, s.dt);
        rod_status st = rod_predict(&s, &po, &p, msg, sizeof msg);
        if (st != ROD_OK) {
            fprintf(stderr, "ribbon-sim convergence: rung N = %d, dt = %g: %s\n", s.nodes, s.dt,
                    msg[0] ? msg : rod_status_message(st));
            return 1;
        }
        if (!p.snapped) {
            fprintf(stderr, "ribbon-sim convergence: rung N = %d, dt = %g: no snap up to Delta W = %g\n", s.nodes,
                    s.dt, s.shear_max);
            return 1;
        }
        snap[k] = p.snap_dw;
        wall[k] = p.wall_s;
    }
    rod_ladder_verdict v;
    rod_ladder_estimate(h, snap, RUNGS, err, &v);
    report(o.json, nodes, dts, scale, snap, err, wall, &v);
    return 0;
}
