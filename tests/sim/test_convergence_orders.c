/* test_convergence_orders: the snap Delta W of the full protocol (rod_predict) converges as the
 * mesh and the time step are refined, each separately, and the observed orders are printed
 * (issue 2 C, last item).
 *
 * Scene: the mock rig's PET strip (config/scenes/mock-gamma013.ini: 200 x 5 x 0.25 mm, phi 90 deg,
 * Delta L 0.5, 10 mm/s, asymmetric snap) with the creases at Gamma = 0.125 instead of 0.13, so
 * that every rung's mesh (N - 3 = 40, 80, 160, 320 edges) is uniform with nodes exactly on the
 * creases: then refining halves every edge and the error is a clean power of h. (At 0.13 the
 * edges next to the creases change irregularly from rung to rung.)
 *
 *   space  N - 3 = 40, 80, 160, 320 at dt = 2 ms, fast mode (its steps return to dt whenever the
 *          ribbon moves, so the snap is resolved with dt on every rung).
 *   time   dt = 8, 4, 2, 1, 0.5 ms at N - 3 = 40, fixed steps.
 * Orders p = log2((s1 - s0) / (s2 - s1)) from successive triples (rod_observed_order, the code
 * `ribbon-sim convergence` and the daemon's ladder use).
 *
 * Asserted, and why:
 *   - every rung snaps asymmetrically (the regime does not depend on the resolution);
 *   - the differences between successive rungs keep one sign and shrink strictly (monotone
 *     convergence; otherwise no order is observed at all);
 *   - space: the finest order within [1.3, 2.7] (the discrete rod's curvatures are centred
 *     differences and its masses lumped, both O(h^2)), every order >= 1;
 *   - time: the finest order within [0.6, 1.5] (implicit Euler is first order, and so is the
 *     snap onset's resolution of one step, shear_rate dt / l), every order >= 0.5.
 * The time ladder's values are multiples of shear_rate dt / l (the onset is a step), so its
 * orders scatter about 1 by a few tenths; the bounds allow that and no more.
 * HEAVY: nine protocol runs, about 25 s in Release. */
#include "rod_protocol.h"
#include "rod_richardson.h"
#include "scene_file.h"

#include <gsl/gsl_errno.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <cmocka.h>

#define SCENE RIBBON_SOURCE_DIR "/config/scenes/mock-gamma013.ini"
#define MAX_RUNGS 5

static rod_scene load_scene(void)
{
    const char *ovr[] = {"folds.position=0.125"};
    rod_scene s;
    cfg_error err;
    char msg[1024];
    if (cfg_scene_load(SCENE, ovr, 1, &s, &err) != CFG_OK) {
        cfg_error_format(&err, msg, sizeof msg);
        fail_msg("%s", msg);
    }
    return s;
}

static double predict_snap(const rod_scene *s, int adaptive, double *wall)
{
    rod_predict_opts o = rod_predict_opts_default();
    o.adaptive = adaptive;
    rod_prediction p;
    char err[512] = "";
    rod_status st = rod_predict(s, &o, &p, err, sizeof err);
    if (st != ROD_OK) fail_msg("N = %d, dt = %g: %s", s->nodes, s->dt, err);
    if (!p.snapped) fail_msg("N = %d, dt = %g: no snap up to Delta W = %g", s->nodes, s->dt, s->shear_max);
    assert_true(p.asymmetric);
    *wall = p.wall_s;
    return p.snap_dw;
}

/* Prints the ladder, its orders and the Richardson-extrapolated value; checks monotone
 * convergence and the order bounds. */
static void check_ladder(const char *what, const char *unit, const double *res, const double *snap,
                         const double *wall, int n, double p_lo, double p_hi, double p_min)
{
    double order[MAX_RUNGS];
    for (int k = 0; k + 2 < n; k++) order[k] = rod_observed_order(snap[k], snap[k + 1], snap[k + 2], 2.0);
    double p_fin = order[n - 3];
    double ref = isfinite(p_fin) ? rod_richardson(snap[n - 2], snap[n - 1], 2.0, p_fin) : snap[n - 1];
    print_message("%s ladder:\n  %10s %12s %12s %12s %8s %9s\n", what, unit, "snap dW", "difference", "|s - s*|", "order",
                  "wall (s)");
    for (int k = 0; k < n; k++) {
        char diff[32] = "", ord[32] = "";
        if (k > 0) snprintf(diff, sizeof diff, "%+.3e", snap[k] - snap[k - 1]);
        if (k >= 2 && isfinite(order[k - 2])) snprintf(ord, sizeof ord, "%.2f", order[k - 2]);
        else if (k >= 2) snprintf(ord, sizeof ord, "none");
        print_message("  %10g %12.6f %12s %12.2e %8s %9.2f\n", res[k], snap[k], diff,
                      isfinite(ref) ? fabs(snap[k] - ref) : -1.0, ord, wall[k]);
    }
    if (isfinite(p_fin))
        print_message("  observed order (finest triple) %.2f; Richardson-extrapolated snap Delta W %.6f\n", p_fin, ref);
    for (int k = 0; k + 2 < n; k++) {
        /* rod_observed_order is NAN unless the differences keep their sign and shrink. */
        if (!isfinite(order[k]))
            fail_msg("%s: differences %.3e then %.3e do not shrink monotonically", what, snap[k + 1] - snap[k],
                     snap[k + 2] - snap[k + 1]);
        if (order[k] < p_min) fail_msg("%s: order %.2f from rung %d is below %.2f", what, order[k], k + 1, p_min);
    }
    if (!(p_fin >= p_lo && p_fin <= p_hi))
        fail_msg("%s: finest observed order %.2f outside [%.2f, %.2f]", what, p_fin, p_lo, p_hi);
}

static void test_space(void **state)
{
    (void)state;
    rod_scene base = load_scene();
    base.dt = 2e-3;
    double res[MAX_RUNGS], snap[MAX_RUNGS], wall[MAX_RUNGS];
    int n = 4;
    for (int k = 0; k < n; k++) {
        rod_scene s = base;
        s.nodes = 40 * (1 << k) + 3;
        res[k] = s.nodes;
        snap[k] = predict_snap(&s, 1, &wall[k]);
    }
    check_ladder("space (dt = 2 ms, fast mode)", "N", res, snap, wall, n, 1.3, 2.7, 1.0);
}

static void test_time(void **state)
{
    (void)state;
    rod_scene base = load_scene();
    base.nodes = 43;
    double res[MAX_RUNGS], snap[MAX_RUNGS], wall[MAX_RUNGS];
    int n = 5;
    for (int k = 0; k < n; k++) {
        rod_scene s = base;
        s.dt = 8e-3 / (double)(1 << k);
        res[k] = s.dt;
        snap[k] = predict_snap(&s, 0, &wall[k]);
    }
    check_ladder("time (N = 43, fixed steps)", "dt (s)", res, snap, wall, n, 0.6, 1.5, 0.5);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_space),
        cmocka_unit_test(test_time),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
