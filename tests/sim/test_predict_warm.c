/* test_predict_warm: the fast prediction started warm (rod_predict_warm: a nearby strip's upper
 * state and a static state on its quasi-static branch, as the band's probes start from the
 * fitted strip's, sim/rod_fit_snap.c) against the same strip's cold start (the route, the
 * quasi-static steps from Delta W = 0): the same snap, peak |A| and regime with fewer static
 * solves and no route; and each case where a warm start would not give the cold answer falls
 * back to the cold start by itself (rod_prediction.warm 0, the cold answer): a start at or after
 * the strip's own switch to the dynamics, a state on the other (lower) branch, a state of another
 * mesh. On the PET strip at N = 31 (the fit tests' kit). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>

#include "fit_scene_kit.h"
#include "rod_protocol.h"
#include "rod_quasi.h"
#include "rod_route.h"
#include "rod_solver.h"

/* The strip's own states: its upper state (branch +1) or lower (-1) at Delta W 0, and its static
   branch followed to Delta W dw. */
static void states_of(const rod_scene *sc, int branch, double dw, rod_snapshot *upper, rod_snapshot *at)
{
    char why[160];
    rod *r = NULL;
    assert_int_equal(rod_alloc(sc, &r, why, sizeof why), ROD_OK);
    rod_solver *s = rod_solver_alloc(r);
    assert_non_null(s);
    assert_true(rod_snapshot_alloc(r, upper));
    assert_true(rod_snapshot_alloc(r, at));
    rod_route_report rep = {0};
    assert_int_equal(rod_route_to_state(r, s, sc, branch, &rep), ROD_OK);
    rod_snapshot_save(r, upper);
    double reached = 0.0;
    if (dw > 0.0) assert_int_equal(rod_follow_shear(r, s, sc, sc->compression, 0.0, dw, rod_quasi_step(sc), &reached, NULL), ROD_OK);
    rod_snapshot_save(r, at);
    rod_solver_free(s);
    rod_free(r);
}

static rod_prediction predict(const rod_scene *sc, const rod_predict_warm *warm)
{
    rod_predict_opts o = rod_predict_opts_fast(sc);
    o.warm = warm;
    rod_prediction p;
    char why[256] = "";
    rod_status st = rod_predict(sc, &o, &p, why, sizeof why);
    if (st != ROD_OK) printf("predict: %s\n", why);
    assert_int_equal(st, ROD_OK);
    assert_true(p.snapped);
    return p;
}

/* A strip 1.5 standard deviations or so from the kit's, as the band's probes are. */
static rod_scene probe_strip(void)
{
    rod_scene p = fit_kit_pet(31);
    p.fold_angle_left_deg = -88.0;
    p.fold_angle_right_deg = -90.5;
    p.fold_position_left = 0.205;
    p.fold_hinge_stiffness = 3.0e-3;
    return p;
}

static void same_answer(const rod_prediction *w, const rod_prediction *c)
{
    printf("  snap %.9f (cold %.9f), peak |A| %.6f (cold %.6f), %d quasi-static solves (cold %d)\n", w->snap_dw,
           c->snap_dw, w->peak_abs_a, c->peak_abs_a, w->quasi_solves, c->quasi_solves);
    assert_true(fabs(w->snap_dw - c->snap_dw) <= 1e-9);
    assert_true(fabs(w->peak_abs_a - c->peak_abs_a) <= 1e-6);
    assert_int_equal(w->asymmetric, c->asymmetric);
    assert_true(fabs(w->dz_upper - c->dz_upper) <= 1e-9);
}

static void test_a_warm_start_gives_the_cold_answer_for_less(void **st)
{
    (void)st;
    rod_scene centre = fit_kit_pet(31), probe = probe_strip();
    rod_prediction pc = predict(&centre, NULL), cold = predict(&probe, NULL);
    assert_int_equal(cold.warm, 0);
    assert_true(cold.stage_route);
    double step = rod_quasi_step(&centre);
    rod_snapshot up, at;
    rod_predict_warm w = {&up, &at, floor(0.7 * pc.dw_switch / step) * step};
    states_of(&centre, +1, w.dw, &up, &at);
    rod_prediction warm = predict(&probe, &w);
    assert_int_equal(warm.warm, 1);
    assert_false(warm.stage_route);
    same_answer(&warm, &cold);
    assert_true(warm.quasi_solves < cold.quasi_solves);
    rod_snapshot_free(&up);
    rod_snapshot_free(&at);
}

static void test_a_start_at_the_switch_falls_back(void **st)
{
    (void)st;
    rod_scene centre = fit_kit_pet(31), probe = probe_strip();
    rod_prediction cold = predict(&probe, NULL);
    double step = rod_quasi_step(&centre);
    rod_snapshot up, at;
    /* on the grid two steps before the probe's own switch: inside the margin */
    rod_predict_warm w = {&up, &at, round(cold.dw_switch / step) * step - 2.0 * step};
    states_of(&centre, +1, w.dw, &up, &at);
    rod_prediction warm = predict(&probe, &w);
    assert_int_equal(warm.warm, 0);
    same_answer(&warm, &cold);
    rod_snapshot_free(&up);
    rod_snapshot_free(&at);
}

static void test_a_lower_state_falls_back(void **st)
{
    (void)st;
    rod_scene centre = fit_kit_pet(31), probe = probe_strip();
    rod_prediction cold = predict(&probe, NULL);
    rod_snapshot up, at;
    rod_predict_warm w = {&up, &at, 0.0};
    states_of(&centre, -1, 0.0, &up, &at);
    rod_prediction warm = predict(&probe, &w);
    assert_int_equal(warm.warm, 0);
    same_answer(&warm, &cold);
    rod_snapshot_free(&up);
    rod_snapshot_free(&at);
}

static void test_another_mesh_falls_back(void **st)
{
    (void)st;
    rod_scene other = fit_kit_pet(41), probe = probe_strip();
    rod_prediction cold = predict(&probe, NULL);
    rod_snapshot up, at;
    rod_predict_warm w = {&up, &at, 0.0};
    states_of(&other, +1, 0.0, &up, &at);
    rod_prediction warm = predict(&probe, &w);
    assert_int_equal(warm.warm, 0);
    same_answer(&warm, &cold);
    rod_snapshot_free(&up);
    rod_snapshot_free(&at);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_warm_start_gives_the_cold_answer_for_less),
        cmocka_unit_test(test_a_start_at_the_switch_falls_back),
        cmocka_unit_test(test_a_lower_state_falls_back),
        cmocka_unit_test(test_another_mesh_falls_back),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
