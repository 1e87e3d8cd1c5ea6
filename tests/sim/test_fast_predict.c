/* test_fast_predict: the fast prediction (quasi-static start, rod_quasi.h; longer post-snap
 * steps) against the fixed-step prediction of the same scene, on coarsened paper scenes of both
 * regimes: same regime, snap Delta W within 0.5% (the bench's target), and the dynamics started
 * on the static branch before the snap. Small enough for the sanitizer build. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>

#include "rod_protocol.h"

static rod_scene coarse_paper(double gamma)
{
    rod_scene s = rod_scene_default();
    s.fold_position = gamma;
    s.nodes = 41;
    s.dt = 5e-3;
    s.shear_max = 0.6;
    return s;
}

static void check(double gamma, int asymmetric)
{
    rod_scene s = coarse_paper(gamma);
    rod_predict_opts fixed = rod_predict_opts_default(), fast = rod_predict_opts_fast(&s);
    rod_prediction pf, pq;
    char err[256] = "";
    assert_int_equal(rod_predict(&s, &fixed, &pf, err, sizeof err), ROD_OK);
    assert_int_equal(rod_predict(&s, &fast, &pq, err, sizeof err), ROD_OK);
    assert_true(pf.snapped && pq.snapped);
    double rel = fabs(pq.snap_dw - pf.snap_dw) / pf.snap_dw;
    printf("Gamma %.2f: fixed %.5f fast %.5f (rel %.1e), dynamics from %.3f after %d static solves, "
           "steps %ld vs %ld\n", gamma, pf.snap_dw, pq.snap_dw, rel, pq.dw_switch, pq.quasi_solves, pf.steps, pq.steps);
    assert_true(rel < 5e-3);
    assert_int_equal(pf.asymmetric, asymmetric);
    assert_int_equal(pq.asymmetric, asymmetric);
    assert_true(pq.quasi_solves > 0 && pq.dw_switch > 0.0 && pq.dw_switch < pq.snap_dw - 0.01);
    assert_true(pq.steps < pf.steps / 2);
}

static void test_pitchfork_scene(void **st) { (void)st; check(0.13, 1); }
static void test_saddle_node_scene(void **st) { (void)st; check(0.21, 0); }

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pitchfork_scene),
        cmocka_unit_test(test_saddle_node_scene),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
