/* test_rod_seed_fold: where a followed upper state ends (sim/rod_seed_fold.c), against
 * independent computations at the README diagram's last cross (Gamma 0.244, phi near 135 deg,
 * N = 61, Delta L 0.5):
 * - the fold in phi located at Delta W = 0 equals the phi where the upper state's saddle-node in
 *   Delta W (rod_bifurcation_analyse, the sweep's classification) reaches Delta W = 0,
 *   extrapolated from two phi by the square-root law of a fold (Delta W_fold^2 linear in phi);
 * - the fold in Gamma at phi 135 deg is a fold: the state exists just before it (continuation to
 *   Gamma_f - 4e-6 succeeds) and not after (to Gamma_f + 1e-4 it is lost), and the even
 *   eigenvalue goes to zero as the square root of the distance (ratio 2 for distances 1.6e-5 and
 *   4e-6; measured 2.007; the law holds within about 2e-5 of this sharp fold, beyond it another
 *   even mode is the nearest to zero);
 * - at low Gamma (phi 95 deg) the state ends at a pitchfork instead (odd mode), whose eigenvalue
 *   is zero there.
 * About 2 s. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>

#include "cfg_error.h"
#include "rod_bifurcation.h"
#include "rod_critical.h"
#include "rod_route.h"
#include "rod_seed.h"
#include "rod_seed_fold.h"
#include "rod_solver.h"
#include "scene_file.h"

#include "seed_scene_kit.h"

/* Continues from (phi0, g0) toward (phi1, g1), expecting the path to end; locates its end. */
static rod_seed_fold_report end_of_path(double phi0, double g0, double phi1, double g1)
{
    rod_scene a = scene(phi0, g0), b = scene(phi1, g1), lsc;
    rod_solver *s = NULL;
    rod *r = routed(&a, &s), *out = NULL, *last = NULL;
    rod_seed_report rep;
    assert_int_equal(rod_seed_continue_keep(r, &a, &b, s, &out, &rep, &last, &lsc), ROD_ERR_BRANCH_LOST);
    assert_null(out);
    assert_non_null(last);
    rod_seed_fold_report fr;
    assert_int_equal(rod_seed_fold_locate(last, &lsc, &b, &fr), ROD_OK);
    rod_free(last);
    rod_free(r);
    rod_solver_free(s);
    return fr;
}

/* The saddle-node's Delta W on the upper branch at (phi, gamma), by the sweep's classification. */
static double saddle_node_dw(double phi, double gamma)
{
    rod_scene sc = scene(phi, gamma);
    rod_analysis_opts o = rod_analysis_opts_classify();
    rod_analysis a;
    char why[200];
    assert_int_equal(rod_bifurcation_analyse(&sc, &o, &a, why, sizeof why), ROD_OK);
    assert_true(a.first >= 0);
    assert_int_equal(a.events[a.first].kind, ROD_EVENT_SADDLE_NODE);
    double dw = a.events[a.first].at.dw;
    rod_analysis_free(&a);
    return dw;
}

static void test_fold_in_phi_is_where_the_saddle_node_reaches_zero(void **state)
{
    (void)state;
    rod_seed_fold_report fr = end_of_path(125.0, 0.244, 135.0, 0.244);
    assert_true(fr.located);
    assert_false(fr.pitchfork);
    assert_int_equal(fr.par, ROD_PAR_PHI);
    assert_true(fr.parity > 0.99);
    assert_true(fr.eig_rel < 1e-12);
    assert_int_equal(fr.n_negative, 0);
    /* Independent: Delta W_fold(phi)^2 is linear near the fold; its zero. */
    double p0 = 133.75, p1 = 133.80, w0 = saddle_node_dw(p0, 0.244), w1 = saddle_node_dw(p1, 0.244);
    assert_true(w0 > w1 && w1 > 0.0);
    double extrap = p1 + w1 * w1 / (w0 * w0 - w1 * w1) * (p1 - p0);
    print_message("fold in phi located at %.5f deg; saddle-node extrapolated to Delta W = 0 at %.5f deg (Delta W %.5f, %.5f)\n",
                  fr.at, extrap, w0, w1);
    assert_true(fabs(fr.at - extrap) < 3e-3);
    assert_true(fr.at > p1 && fr.at < 135.0);
}

static void test_fold_in_gamma_is_a_fold(void **state)
{
    (void)state;
    rod_seed_fold_report fr = end_of_path(135.0, 0.2167, 135.0, 0.2444);
    assert_true(fr.located);
    assert_false(fr.pitchfork);
    assert_int_equal(fr.par, ROD_PAR_GAMMA);
    assert_true(fr.at > 0.2167 && fr.at < 0.2444);
    assert_true(fr.eig_rel < 1e-12);
    /* The state exists 4e-6 before the fold, not 1e-4 after; its even eigenvalue at distances
     * 1.6e-5 and 4e-6 has the ratio 2 of the square-root law. */
    rod_scene a = scene(135.0, 0.2167);
    rod_solver *s = NULL;
    rod *r = routed(&a, &s);
    double eig[2];
    const double dist[2] = {1.6e-5, 4e-6};
    for (int k = 0; k < 2; k++) {
        rod_scene b = scene(135.0, fr.at - dist[k]);
        rod *out = NULL;
        rod_seed_report rep;
        assert_int_equal(rod_seed_continue(r, &a, &b, s, &out, &rep), ROD_OK);
        rod_crit *c = rod_crit_alloc(out, NULL);
        assert_non_null(c);
        double p[ROD_NPAR] = {0.0, b.fold_position, b.fold_angle_deg * M_PI / 180.0, b.compression};
        rod_crit_report cr;
        assert_int_equal(rod_crit_modes(c, p, &cr, NULL, 0), ROD_OK);
        eig[k] = cr.eig_even;
        rod_crit_free(c);
        rod_free(out);
    }
    print_message("fold in Gamma at %.6f; even eigenvalue %.4g at -1.6e-5, %.4g at -4e-6 (ratio %.3f)\n", fr.at, eig[0],
                  eig[1], eig[0] / eig[1]);
    assert_true(eig[0] > 0.0 && eig[1] > 0.0);
    assert_true(fabs(eig[0] / eig[1] - 2.0) < 0.2);
    rod_scene past = scene(135.0, fr.at + 1e-4);
    rod *out = NULL;
    rod_seed_report rep;
    assert_int_equal(rod_seed_continue(r, &a, &past, s, &out, &rep), ROD_ERR_BRANCH_LOST);
    assert_true(rep.gamma_reached < fr.at + 1e-6);
    rod_free(r);
    rod_solver_free(s);
}

static void test_low_gamma_end_is_a_pitchfork(void **state)
{
    (void)state;
    rod_seed_fold_report fr = end_of_path(95.0, 0.0778, 95.0, 0.05);
    assert_true(fr.located);
    assert_true(fr.pitchfork);
    assert_true(fr.parity < -0.99);
    assert_true(fr.at > 0.05 && fr.at < 0.0778);
    assert_true(fr.eig_rel < 1e-12);
    print_message("pitchfork in Gamma at %.6f (odd eigenvalue %.3g at the last state)\n", fr.at, fr.eig_from);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fold_in_phi_is_where_the_saddle_node_reaches_zero),
        cmocka_unit_test(test_fold_in_gamma_is_a_fold),
        cmocka_unit_test(test_low_gamma_end_is_a_pitchfork),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
