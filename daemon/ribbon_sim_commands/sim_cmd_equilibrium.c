/* sim_cmd_equilibrium.c: `ribbon-sim equilibrium`: one static equilibrium at (Delta L, Delta W)
 * on the upper or lower branch, reached by the documented route and then by following the
 * branch in Delta W. */
#include "rod_observe.h"
#include "rod_route.h"
#include "rod_solver.h"
#include "sim_cmd.h"
#include "sim_opts.h"

#include <gsl/gsl_errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static const char usage[] =
    "usage: ribbon-sim equilibrium --scene FILE --dl X --dw Y [--branch upper|lower]\n"
    "                              [--set section.key=value ...] [--json]\n"
    "  Static equilibrium at Delta L = X, Delta W = Y on the chosen branch (default upper).\n"
    "  Prints Delta Z, A, A_cam, the energy (J), the force the moving clamp exerts on the ribbon\n"
    "  (N, x y z) and the final residual relative to E I1 / l^2. Fails with the reason when the\n"
    "  branch ends before Delta W = Y.\n";

int sim_cmd_equilibrium(int argc, char **argv)
{
    sim_opts o;
    int rc = sim_opts_parse(argc, argv, "json dl dw branch", usage, &o);
    if (rc) return rc == 1 ? 0 : 2;
    if (!o.has_dl || !o.has_dw) {
        fprintf(stderr, "ribbon-sim equilibrium: --dl and --dw are required (see --help)\n");
        return 2;
    }
    rod_scene sc;
    if (!sim_opts_load_scene(&o, &sc)) return 2;
    sc.compression = o.dl;
    char err[512];
    rod *r = NULL;
    if (rod_alloc(&sc, &r, err, sizeof err) != ROD_OK) {
        fprintf(stderr, "ribbon-sim equilibrium: --dl %g: %s\n", o.dl, err);
        return 2;
    }
    rod_solver *s = rod_solver_alloc(r);
    double *k1 = malloc(sizeof(double) * (size_t)r->n);
    int status = 1;
    if (!s || !k1) {
        fprintf(stderr, "ribbon-sim equilibrium: out of memory\n");
        goto done;
    }
    rod_route_report rep = {0};
    rod_status st = rod_route_to_state(r, s, &sc, o.branch, &rep);
    if (st != ROD_OK) {
        fprintf(stderr, "ribbon-sim equilibrium: could not reach the %s state at Delta L = %g: %s\n",
                o.branch > 0 ? "upper" : "lower", o.dl, rod_status_message(st));
        goto done;
    }
    double reached = 0.0;
    st = rod_follow_shear(r, s, &sc, o.dl, 0.0, o.dw, 0.01, &reached, &rep);
    if (st != ROD_OK) {
        fprintf(stderr, "ribbon-sim equilibrium: the %s branch ends before Delta W = %g (followed to %.5f): %s\n",
                o.branch > 0 ? "upper" : "lower", o.dw, reached, rod_status_message(st));
        goto done;
    }
    rod_obs ob;
    rod_observe(r, k1, &ob);
    double energy = rod_energy(r);
    const double *g = rod_solver_gradient(s);
    double f[3] = {0, 0, 0};
    for (int node = r->n - 2; node < r->n; node++)
        for (int k = 0; k < 3; k++) f[k] += g[4 * node + k];
    /* Every number printed is finite: json_real(NaN) is NULL and the key would silently vanish
       from the JSON (a residual omitted with exit 0, issue 17 item 12). */
    const double shown[] = {ob.dz, ob.a, ob.a_cam, energy, rep.residual_rel, f[0], f[1], f[2]};
    for (size_t k = 0; k < sizeof shown / sizeof shown[0]; k++)
        if (!isfinite(shown[k])) {
            fprintf(stderr, "ribbon-sim equilibrium: the equilibrium has non-finite values (residual %g): the "
                            "scene is out of the solver's numeric range\n", rep.residual_rel);
            goto done;
        }
    if (o.json) {
        json_t *j = json_object();
        json_object_set_new(j, "dl", json_real(o.dl));
        json_object_set_new(j, "dw", json_real(o.dw));
        json_object_set_new(j, "branch", json_string(o.branch > 0 ? "upper" : "lower"));
        json_object_set_new(j, "dz", json_real(ob.dz));
        json_object_set_new(j, "a", json_real(ob.a));
        json_object_set_new(j, "a_cam", json_real(ob.a_cam));
        json_object_set_new(j, "energy", json_real(energy));
        json_object_set_new(j, "residual", json_real(rep.residual_rel));
        json_object_set_new(j, "reaction", json_pack("[fff]", f[0], f[1], f[2]));
        char *txt = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(10));
        puts(txt);
        free(txt);
        json_decref(j);
    } else {
        printf("Delta Z %.6f  A %.3e  A_cam %.3e  energy %.6g J\n", ob.dz, ob.a, ob.a_cam, energy);
        printf("clamp force on ribbon (N): %.6g %.6g %.6g   residual %.2e (relative)\n", f[0], f[1], f[2],
               rep.residual_rel);
    }
    status = 0;
done:
    free(k1);
    rod_solver_free(s);
    rod_free(r);
    return status;
}
