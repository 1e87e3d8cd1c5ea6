/* test_hinge_convergence: with compliant creases (sim/rod_hinge.c) the static first instability
 * and the dynamic snap converge as N grows, to a limit that does not depend on N; with rigid
 * creases the limit is a rigid crease (issue 31 A, "Convergence"). Orders and limits printed.
 *
 * Scene: the mock rig's PET strip (mock-gamma013.ini: 200 x 5 x 0.25 mm, phi 90 deg, Delta L 0.5)
 * with the creases at Gamma = 0.125 so that N - 3 = 40, 80, 160, 320 edges nest with nodes on the
 * creases (as test_convergence_orders). Compliant: k = 1e-3 N m/rad, L* = E I1 / k = 26 mm, so
 * every rung's Voronoi length (5 .. 0.6 mm) is below L*.
 *
 * What the numbers say (Release, this machine), and what is asserted:
 *   static first pitchfork (ribbon-sim continue's first instability, the perfect scene):
 *     compliant 0.29285, 0.29433, 0.29505, 0.29542: observed orders 1.04, 0.96 (first order),
 *     limit 0.2958 (Richardson with p = 1). Asserted: every rung a pitchfork, differences of one
 *     sign shrinking, the finest order in [0.7, 2.7], and the rungs within 1.5% of the limit (N = 43
 *     is 1.0% off).
 *     The first-order term is the strip's own in-plane and twist compliance over the crease node's
 *     Voronoi cell: the discrete rod measures both in the node's averaged frame, but across a
 *     90 deg crease each half-cell bends and twists about its own edge's axes (E I2 >> G J for a
 *     ribbon, so the split matters): making the crease node's twist stiff instead moves the same
 *     ladder to 0.30476, 0.29920, 0.29726, 0.29647, first order from above, the same limit. The
 *     closed forms of test_hinge (planar, where those terms vanish) converge at second order.
 *     rigid 0.37005, 0.38704, 0.39142, 0.39277: orders 1.95, 1.70, limit about 0.3933; the rigid
 *     crease's penalty, stiffness_factor E I1 / dl_hat, grows as N grows, so the limit is a
 *     perfectly rigid crease (printed, not asserted beyond convergence).
 *   dynamic snap (predict --fast, dt 2 ms): compliant 0.3599, 0.3603, 0.3606, 0.3609 (within 0.3%
 *     over the ladder; the differences, 1e-4 Delta W a rung, sit at the onset's resolution of one
 *     step, 1e-4 here, so no order is read from them); rigid 0.3835, 0.3994, 0.4036, 0.4049.
 *     Asserted: every rung snaps asymmetrically, the compliant rungs from N = 83 on within 0.5% of
 *     the finest.
 * HEAVY: eight analyses and eight predictions, about 20 s in Release. */
#include "rod_bifurcation.h"
#include "rod_protocol.h"
#include "scene_file.h"

#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#define SCENE RIBBON_SOURCE_DIR "/config/scenes/mock-gamma013.ini"
#define RUNGS 4
static const int NODES[RUNGS] = {43, 83, 163, 323};

static rod_scene load(int nodes, const char *hinge)
{
    char n[32], k[64];
    snprintf(n, sizeof n, "mesh.nodes=%d", nodes);
    snprintf(k, sizeof k, "folds.hinge_stiffness=%s", hinge);
    const char *ovr[] = {"folds.position=0.125", n, k};
    rod_scene s;
    cfg_error err;
    char msg[1024];
    if (cfg_scene_load(SCENE, ovr, 3, &s, &err) != CFG_OK) {
        cfg_error_format(&err, msg, sizeof msg);
        fail_msg("%s", msg);
    }
    return s;
}

static double first_pitchfork(const rod_scene *s)
{
    rod_analysis_opts o = rod_analysis_opts_classify();
    rod_analysis a;
    char why[512] = "";
    rod_status st = rod_bifurcation_analyse(s, &o, &a, why, sizeof why);
    if (st != ROD_OK) fail_msg("analysis: %s", why);
    assert_true(a.first >= 0);
    assert_int_equal(a.events[a.first].kind, ROD_EVENT_PITCHFORK);
    double dw = a.events[a.first].at.dw;
    rod_analysis_free(&a);
    return dw;
}

static double snap(const rod_scene *s)
{
    rod_predict_opts o = rod_predict_opts_fast(s);
    rod_prediction p;
    char why[512] = "";
    if (rod_predict(s, &o, &p, why, sizeof why) != ROD_OK) fail_msg("predict: %s", why);
    assert_true(p.snapped && p.asymmetric);
    return p.snap_dw;
}

static double order3(const double *v, int i) { return log2((v[i - 1] - v[i - 2]) / (v[i] - v[i - 1])); }

static void ladder(const char *hinge, double *stat, double *dyn)
{
    for (int r = 0; r < RUNGS; r++) {
        rod_scene s = load(NODES[r], hinge);
        stat[r] = first_pitchfork(&s);
        dyn[r] = snap(&s);
        print_message("%-7s N = %3d: first pitchfork Delta W %.5f, snap Delta W %.5f\n", hinge, NODES[r], stat[r],
                      dyn[r]);
    }
    for (int r = 2; r < RUNGS; r++)
        print_message("%-7s orders (N %d, %d, %d): pitchfork %.2f, snap %.2f\n", hinge, NODES[r - 2], NODES[r - 1],
                      NODES[r], order3(stat, r), order3(dyn, r));
}

static void test_compliant_converges(void **state)
{
    (void)state;
    double st[RUNGS], dy[RUNGS];
    ladder("1e-3", st, dy);
    for (int r = 2; r < RUNGS; r++) {
        double d0 = st[r - 1] - st[r - 2], d1 = st[r] - st[r - 1];
        assert_true(d0 * d1 > 0.0 && fabs(d1) < fabs(d0));
    }
    double p = order3(st, RUNGS - 1);
    assert_true(p >= 0.7 && p <= 2.7);
    double d = st[RUNGS - 1] - st[RUNGS - 2], limit = st[RUNGS - 1] + d / (pow(2.0, p) - 1.0);
    print_message("compliant pitchfork limit %.5f (Richardson, p = %.2f)\n", limit, p);
    for (int r = 0; r < RUNGS; r++) assert_true(fabs(st[r] / limit - 1.0) < 0.015);
    for (int r = 1; r < RUNGS; r++) assert_true(fabs(dy[r] / dy[RUNGS - 1] - 1.0) < 0.005);
}

static void test_rigid_limit(void **state)
{
    (void)state;
    double st[RUNGS], dy[RUNGS];
    ladder("rigid", st, dy);
    for (int r = 2; r < RUNGS; r++) {
        double d0 = st[r - 1] - st[r - 2], d1 = st[r] - st[r - 1];
        assert_true(d0 * d1 > 0.0 && fabs(d1) < fabs(d0));
    }
    double p = order3(st, RUNGS - 1), d = st[RUNGS - 1] - st[RUNGS - 2];
    print_message("rigid pitchfork limit %.5f (Richardson, p = %.2f): a rigid crease\n",
                  st[RUNGS - 1] + d / (pow(2.0, p) - 1.0), p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_compliant_converges),
        cmocka_unit_test(test_rigid_limit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
