/* sim_cmd_trajectory.c: `ribbon-sim trajectory`: the simulated trial step by step as CSV.
 * Written to FILE.tmp and renamed on success, so a failed run never leaves a half-written file
 * under the requested name. */
#include "rod_protocol.h"
#include "sim_cmd.h"
#include "sim_opts.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

static const char usage[] =
    "usage: ribbon-sim trajectory --scene FILE --out FILE.csv [--set section.key=value ...] [--fast]\n"
    "  Writes one row per time step of the shear: t (s), dw, dz, a, a_cam, energy (J, elastic +\n"
    "  kinetic), then the snap summary on stderr.\n";

static int on_sample(void *user, const rod_sample *s, const rod *r)
{
    (void)r;
    FILE *f = user;
    fprintf(f, "%.6f,%.8f,%.8f,%.8e,%.8e,%.10e\n", s->t, s->dw, s->dz, s->a, s->a_cam, s->elastic + s->kinetic);
    return ferror(f) ? 1 : 0;
}

int sim_cmd_trajectory(int argc, char **argv)
{
    sim_opts o;
    int rc = sim_opts_parse(argc, argv, "out fast", usage, &o);
    if (rc) return rc == 1 ? 0 : 2;
    if (!o.out) {
        fprintf(stderr, "ribbon-sim trajectory: --out FILE.csv is required\n");
        return 2;
    }
    rod_scene sc;
    if (!sim_opts_load_scene(&o, &sc)) return 2;
    char tmp[4096];
    if (snprintf(tmp, sizeof tmp, "%s.tmp", o.out) >= (int)sizeof tmp) {
        fprintf(stderr, "ribbon-sim trajectory: --out path too long\n");
        return 2;
    }
    FILE *f = fopen(tmp, "w");
    if (!f) {
        fprintf(stderr, "ribbon-sim trajectory: cannot write %s: %s\n", tmp, strerror(errno));
        return 1;
    }
    fprintf(f, "t,dw,dz,a,a_cam,energy\n");
    rod_predict_opts po = rod_predict_opts_default();
    po.adaptive = o.fast;
    po.on_sample = on_sample;
    po.user = f;
    rod_prediction p;
    char err[512] = "";
    rod_status st = rod_predict(&sc, &po, &p, err, sizeof err);
    int werr = ferror(f);
    if (fclose(f) != 0) werr = 1;
    if (st != ROD_OK || werr) {
        remove(tmp);
        fprintf(stderr, "ribbon-sim trajectory: %s\n", werr ? "write error" : (err[0] ? err : rod_status_message(st)));
        return 1;
    }
    if (rename(tmp, o.out) != 0) {
        fprintf(stderr, "ribbon-sim trajectory: cannot rename %s to %s: %s\n", tmp, o.out, strerror(errno));
        return 1;
    }
    if (p.snapped)
        fprintf(stderr, "%ld steps written to %s; snap at Delta W = %.4f (%s)\n", p.steps, o.out, p.snap_dw,
                p.asymmetric ? "asymmetric" : "symmetric");
    else
        fprintf(stderr, "%ld steps written to %s; no snap up to Delta W = %g\n", p.steps, o.out, sc.shear_max);
    return 0;
}
