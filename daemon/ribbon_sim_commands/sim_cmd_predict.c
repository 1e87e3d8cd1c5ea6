/* sim_cmd_predict.c: `ribbon-sim predict`: the simulated trial (route, shear, snap), printed
 * for a person or as one JSON object. */
#include "rod_protocol.h"
#include "sim_cmd.h"
#include "sim_opts.h"

#include <jansson.h>
#include <stdio.h>
#include <unistd.h>

static const char usage[] =
    "usage: ribbon-sim predict --scene FILE [--set section.key=value ...] [--fast] [--json]\n"
    "  Simulates the protocol: reach the upper state at protocol.compression, then shear at\n"
    "  protocol.shear_rate until the ribbon snaps or protocol.shear_max is reached.\n"
    "  Prints the snap Delta W, the regime (symmetric / asymmetric), the peak |A| during the snap,\n"
    "  the steps and the wall time. --fast uses adaptive time stepping (README \"Speed\").\n"
    "  --json prints one object: snap_dw (null without a snap), regime (symmetric, asymmetric or\n"
    "  none), peak_abs_a, steps, wall_s, and what ran (terms: stretch, bend, twist, fold (rigid\n"
    "  creases), hinge (compliant creases), gravity, damping; stages).\n";

typedef struct progress {
    int tty;
    long n;
} progress;

static int on_sample(void *user, const rod_sample *s, const rod *r)
{
    (void)r;
    progress *p = user;
    if (p->tty && (p->n++ % 200) == 0) fprintf(stderr, "\r  shearing: Delta W %.4f  Delta Z %+.4f  A %+.2e ", s->dw, s->dz, s->a);
    return 0;
}

int sim_cmd_predict(int argc, char **argv)
{
    sim_opts o;
    int rc = sim_opts_parse(argc, argv, "json fast", usage, &o);
    if (rc) return rc == 1 ? 0 : 2;
    rod_scene sc;
    if (!sim_opts_load_scene(&o, &sc)) return 2;
    rod_predict_opts po = o.fast ? rod_predict_opts_fast(&sc) : rod_predict_opts_default();
    progress pr = {isatty(2) && !o.json, 0};
    po.on_sample = on_sample;
    po.user = &pr;
    rod_prediction p;
    char err[512] = "";
    rod_status st = rod_predict(&sc, &po, &p, err, sizeof err);
    if (pr.tty) fputs("\r\033[K", stderr);
    if (st != ROD_OK) {
        fprintf(stderr, "ribbon-sim predict: %s: %s\n", o.scene, err[0] ? err : rod_status_message(st));
        return 1;
    }
    const char *regime = !p.snapped ? "none" : p.asymmetric ? "asymmetric" : "symmetric";
    if (o.json) {
        json_t *j = json_object();
        json_object_set_new(j, "scene", json_string(o.scene));
        json_object_set_new(j, "snapped", json_boolean(p.snapped));
        json_object_set_new(j, "snap_dw", p.snapped ? json_real(p.snap_dw) : json_null());
        json_object_set_new(j, "regime", json_string(regime));
        json_object_set_new(j, "peak_abs_a", json_real(p.peak_abs_a));
        json_object_set_new(j, "dz_upper", json_real(p.dz_upper));
        json_object_set_new(j, "dz_final", json_real(p.dz_final));
        json_object_set_new(j, "steps", json_integer(p.steps));
        json_object_set_new(j, "rejected_steps", json_integer(p.rejected));
        json_object_set_new(j, "sim_time_s", json_real(p.sim_time));
        json_object_set_new(j, "wall_s", json_real(p.wall_s));
        json_object_set_new(j, "fast", json_boolean(o.fast));
        json_object_set_new(j, "nodes", json_integer(sc.nodes));
        json_object_set_new(j, "dt", json_real(sc.dt));
        json_object_set_new(j, "fold_angle_rel", json_real(sc.fold_angle_rel));
        json_object_set_new(j, "version", json_string(RIBBON_VERSION));
        json_t *terms = json_object();
        json_object_set_new(terms, "stretch", json_integer((json_int_t)p.count.stretch_evals));
        json_object_set_new(terms, "bend", json_integer((json_int_t)p.count.bend_evals));
        json_object_set_new(terms, "twist", json_integer((json_int_t)p.count.twist_evals));
        json_object_set_new(terms, "fold", json_integer((json_int_t)p.count.fold_evals));
        json_object_set_new(terms, "hinge", json_integer((json_int_t)p.count.hinge_evals));
        json_object_set_new(terms, "gravity", json_integer((json_int_t)p.count.gravity_evals));
        json_object_set_new(terms, "damping", json_integer((json_int_t)p.count.damping_evals));
        json_object_set_new(j, "term_evaluations", terms);
        json_t *stages = json_object();
        json_object_set_new(stages, "route", json_boolean(p.stage_route));
        json_object_set_new(stages, "shear", json_boolean(p.stage_shear));
        json_object_set_new(stages, "damping", json_boolean(p.stage_damping));
        json_object_set_new(j, "stages", stages);
        json_object_set_new(j, "newton_iterations", json_integer((json_int_t)p.count.newton_iterations));
        json_object_set_new(j, "factorisations", json_integer((json_int_t)p.count.factorisations));
        char *s = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(10));
        puts(s);
        free(s);
        json_decref(j);
        return 0;
    }
    printf("scene        %s (N = %d, dt = %g s%s)\n", o.scene, sc.nodes, sc.dt, o.fast ? ", adaptive" : "");
    printf("upper state  Delta Z = %.4f at Delta L = %g\n", p.dz_upper, sc.compression);
    if (p.snapped)
        printf("snap         Delta W = %.4f, %s (peak |A| = %.3g rad)\n", p.snap_dw, regime, p.peak_abs_a);
    else
        printf("snap         none up to Delta W = %g (shear limit reached, no snap)\n", sc.shear_max);
    printf("run          %ld steps (%ld rejected), %.1f s simulated, %.2f s wall\n", p.steps, p.rejected,
           p.sim_time, p.wall_s);
    printf("evaluated    stretch, bend, twist%s%s%s%s\n", p.count.fold_evals ? ", folds" : "",
           p.count.hinge_evals ? ", hinges" : "", p.count.gravity_evals ? ", gravity" : "", p.count.damping_evals && sc.damping > 0 ? ", damping" : "");
    return 0;
}
