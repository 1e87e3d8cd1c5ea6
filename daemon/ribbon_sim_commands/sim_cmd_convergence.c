/* sim_cmd_convergence.c: `ribbon-sim convergence`: error against run time. Runs the prediction
 * (fast mode) over a ladder that halves the edge length and the time step together, and
 * estimates each rung's error in the snap Delta W against the Richardson extrapolation of the
 * three finest rungs (the observed order is printed, not assumed). */
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
    "  the scene's dt (fast mode), and prints for each rung the snap Delta W, its\n"
    "  relative error against the Richardson-extrapolated value, and the wall time.\n";

#define RUNGS 4

int sim_cmd_convergence(int argc, char **argv)
{
    sim_opts o;
    int rc = sim_opts_parse(argc, argv, "json", usage, &o);
    if (rc) return rc == 1 ? 0 : 2;
    rod_scene base;
    if (!sim_opts_load_scene(&o, &base)) return 2;
    double snap[RUNGS], wall[RUNGS];
    int nodes[RUNGS];
    double dts[RUNGS];
    for (int k = 0; k < RUNGS; k++) {
        rod_scene s = base;
        s.nodes = 36 * (1 << k) + 3;
        s.dt = base.dt * (double)(1 << (RUNGS - 1 - k));
        if (s.shear_max < 0.8) s.shear_max = 0.8; /* coarse rungs snap later */
        nodes[k] = s.nodes;
        dts[k] = s.dt;
        rod_predict_opts po = rod_predict_opts_default();
        po.adaptive = 1;
        rod_prediction p;
        char err[512] = "";
        if (!o.json) fprintf(stderr, "  rung %d/%d: N = %d, dt = %g s ...\n", k + 1, RUNGS, s.nodes, s.dt);
        rod_status st = rod_predict(&s, &po, &p, err, sizeof err);
        if (st != ROD_OK) {
            fprintf(stderr, "ribbon-sim convergence: rung N = %d, dt = %g: %s\n", s.nodes, s.dt,
                    err[0] ? err : rod_status_message(st));
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
    double order = rod_observed_order(snap[RUNGS - 3], snap[RUNGS - 2], snap[RUNGS - 1], 2.0);
    double extrap = snap[RUNGS - 1];
    if (isfinite(order)) extrap = rod_richardson(snap[RUNGS - 2], snap[RUNGS - 1], 2.0, order);
    if (o.json) {
        json_t *j = json_object(), *arr = json_array();
        for (int k = 0; k < RUNGS; k++)
            json_array_append_new(arr, json_pack("{s:i,s:f,s:f,s:f,s:f}", "nodes", nodes[k], "dt", dts[k], "snap_dw",
                                                 snap[k], "rel_error", fabs(snap[k] - extrap) / fabs(extrap),
                                                 "wall_s", wall[k]));
        json_object_set_new(j, "rungs", arr);
        json_object_set_new(j, "extrapolated_snap_dw", json_real(extrap));
        json_object_set_new(j, "observed_order", isfinite(order) ? json_real(order) : json_null());
        char *txt = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(10));
        puts(txt);
        free(txt);
        json_decref(j);
        return 0;
    }
    printf("%6s %10s %12s %12s %9s\n", "N", "dt (s)", "snap dW", "rel. error", "wall (s)");
    for (int k = 0; k < RUNGS; k++)
        printf("%6d %10.4g %12.6f %12.2e %9.2f\n", nodes[k], dts[k], snap[k], fabs(snap[k] - extrap) / fabs(extrap),
               wall[k]);
    if (isfinite(order))
        printf("observed order %.2f; Richardson-extrapolated snap Delta W %.6f\n", order, extrap);
    else
        printf("the three finest rungs do not converge monotonically; errors are against the finest rung\n");
    return 0;
}
