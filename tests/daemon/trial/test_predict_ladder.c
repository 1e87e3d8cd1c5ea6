/* test_predict_ladder: error estimates of the resolution ladder against sequences whose limit is
 * known (s = s* + a h + b h^2, h = 1 / (N - 3): first order in dt, second in the mesh), the flag of
 * a ladder outside the asymptotic range, the choice of rung, the scene hash, and one real ladder on
 * a coarse scene (dt refined with the mesh); cancellation and the run-time estimate. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "trial.h"

/* Rungs with snap s* + a h + b h^2, h = 1 / (N - 3): the combined refinement's error (first
 * order in dt, second in the mesh, dt in proportion to h). */
static void fill(predict_ladder_rung *r, int n, const int *nodes, double s_star, double a, double b)
{
    for (int k = 0; k < n; k++) {
        memset(&r[k], 0, sizeof r[k]);
        r[k].nodes = nodes[k];
        double h = 1.0 / (double)(nodes[k] - 3);
        r[k].snap_dw = s_star + a * h + b * h * h;
        r[k].wall_s = 0.1 * pow(2.0, k);
    }
}

/* First order alone (the asymptotic order): Richardson at order 1 is exact, on every rung. */
static void richardson_exact_at_first_order(void **state)
{
    (void)state;
    int nodes[3] = {39, 75, 147};
    predict_ladder_rung r[3];
    rod_ladder_verdict v;
    fill(r, 3, nodes, 0.43, 0.5, 0.0);
    predict_ladder_estimate_errors(r, 3, &v);
    assert_true(v.asymptotic);
    assert_float_equal(v.order, 1.0, 1e-9);
    assert_float_equal(v.extrapolated, 0.43, 1e-12);
    for (int k = 0; k < 3; k++) {
        double exact = 0.5 / (nodes[k] - 3) / 0.43;
        assert_true(fabs(r[k].est_error - exact) < 1e-9 * exact);
    }
}

/* a h + b h^2 with a and b of one sign, from first order alone to second order alone: the observed
 * order lies in [1, 2], the ladder is in the asymptotic range, and every rung's estimate bounds its
 * true error from above by at most a factor of 3 (r + 1 at refinement ratio r = 2). The former
 * estimate (Richardson at the observed order) fails this: at b h = a on the finest rung it puts
 * the finest rung's error at 0.6 of the true one. */
static void mixed_orders_bounded_within_3(void **state)
{
    (void)state;
    int nodes[4] = {39, 75, 147, 291};
    double mix[] = {0.0, 0.1, 1.0, 10.0, 100.0, 1e4, 1e9}; /* b / a, with h ~ 1/36 .. 1/288 */
    for (size_t m = 0; m < sizeof mix / sizeof mix[0]; m++) {
        for (int sign = -1; sign <= 1; sign += 2) {
            double a = sign * 0.5 / (1.0 + mix[m]), b = sign * 0.5 * mix[m] / (1.0 + mix[m]) * 36.0;
            predict_ladder_rung r[4];
            rod_ladder_verdict v;
            fill(r, 4, nodes, 0.43, a, b);
            predict_ladder_estimate_errors(r, 4, &v);
            assert_true(v.asymptotic);
            assert_true(v.order >= 1.0 - 1e-9 && v.order <= 2.0 + 1e-9);
            assert_string_equal(v.note, "");
            for (int k = 0; k < 4; k++) {
                double h = 1.0 / (nodes[k] - 3), truth = fabs(a * h + b * h * h) / 0.43;
                /* relative to the estimated s*, not 0.43: the bound 3 holds to within that ratio */
                double den = 0.43 / fabs(v.extrapolated);
                if (!(r[k].est_error >= truth * den * (1 - 1e-9) && r[k].est_error <= 3.0 * truth * den * (1 + 1e-9)))
                    fail_msg("b/a = %g, sign %d, rung %d: estimate %.4g, true %.4g", mix[m], sign, k, r[k].est_error,
                             truth);
            }
        }
    }
}

/* Unequal refinement ratios (31, 61, 121: 28, 58, 118 edges): the observed order is still exact
 * for a pure power (rod_observed_order_ratios). */
static void unequal_ratios_observe_the_order(void **state)
{
    (void)state;
    int nodes[3] = {31, 61, 121};
    for (double p = 0.8; p < 2.3; p += 0.35) {
        predict_ladder_rung r[3];
        for (int k = 0; k < 3; k++) {
            memset(&r[k], 0, sizeof r[k]);
            r[k].nodes = nodes[k];
            r[k].snap_dw = 0.43 + 0.2 * pow(1.0 / (nodes[k] - 3), p);
        }
        rod_ladder_verdict v;
        predict_ladder_estimate_errors(r, 3, &v);
        assert_float_equal(v.order, p, 1e-9);
    }
}

/* The mock scene's former N-only ladder (issue 31: 0.4105, 0.4224, 0.4238 at N = 31, 61, 121)
 * observes an order near 3, outside the expected range: flagged, the order not used, the errors
 * carrying the safety factor 3 (the finest: 3 |d| / (r - 1)). Differences that change sign are
 * flagged too; so is a ladder of two rungs (no order observed). The finest rung's estimate is
 * never 0 while the two finest rungs differ. */
static void out_of_range_flagged(void **state)
{
    (void)state;
    int nodes[3] = {31, 61, 121};
    predict_ladder_rung r[3];
    fill(r, 3, nodes, 0, 0, 0);
    r[0].snap_dw = 0.4105;
    r[1].snap_dw = 0.4224;
    r[2].snap_dw = 0.4238;
    rod_ladder_verdict v;
    predict_ladder_estimate_errors(r, 3, &v);
    printf("issue 31's ladder: order %.2f, %s; errors %.3g %.3g %.3g\n", v.order, v.note, r[0].est_error,
           r[1].est_error, r[2].est_error);
    assert_false(v.asymptotic);
    assert_true(v.order > ROD_LADDER_ORDER_HI);
    assert_non_null(strstr(v.note, "not in the asymptotic range"));
    assert_float_equal(v.safety, 3.0, 0);
    double ratio = 118.0 / 58.0, tail = 0.0014 / (ratio - 1.0);
    assert_float_equal(r[2].est_error, 3.0 * tail / (0.4238 + tail), 1e-9);
    assert_true(r[1].est_error > r[2].est_error && r[0].est_error > r[1].est_error);

    r[0].snap_dw = 0.4300; /* the coarsest on the other side */
    predict_ladder_estimate_errors(r, 3, &v);
    assert_false(v.asymptotic);
    assert_true(isnan(v.order));
    assert_non_null(strstr(v.note, "do not shrink with one sign"));
    assert_true(r[2].est_error > 0.0);

    predict_ladder_estimate_errors(r + 1, 2, &v); /* two rungs */
    assert_false(v.asymptotic);
    assert_non_null(strstr(v.note, "two rungs"));
    assert_true(r[2].est_error > 0.0);

    r[1].snap_dw = r[2].snap_dw; /* equal: nothing to estimate, and no 0 either */
    predict_ladder_estimate_errors(r, 3, &v);
    for (int k = 0; k < 3; k++) assert_true(r[k].est_error < 0.0);
    assert_non_null(strstr(v.note, "agree exactly"));
}

static void choose_cheapest_meeting_target(void **state)
{
    (void)state;
    int nodes[3] = {39, 75, 147};
    predict_ladder_rung r[3];
    fill(r, 3, nodes, 0.43, 0.5, 0.0);
    predict_ladder_estimate_errors(r, 3, NULL); /* errors 3.2e-2, 1.6e-2, 8.1e-3 */
    assert_int_equal(predict_ladder_choose(r, 3, 0.05), 0);
    assert_int_equal(predict_ladder_choose(r, 3, 0.02), 1);
    assert_int_equal(predict_ladder_choose(r, 3, 0.01), 2);
    assert_int_equal(predict_ladder_choose(r, 3, 1e-6), 2); /* none meets it: the finest */
}

static void hash_ignores_mesh_only(void **state)
{
    (void)state;
    rod_scene a = rod_scene_default(), b = a;
    char ha[17], hb[17];
    b.nodes = 61;
    predict_scene_hash(&a, ha);
    predict_scene_hash(&b, hb);
    assert_string_equal(ha, hb);
    b.fold_position = 0.21;
    predict_scene_hash(&b, hb);
    assert_string_not_equal(ha, hb);
    assert_int_equal(strlen(ha), 16);
    /* A compliant hinge or a crease's own angle is another scene (issue 31). */
    b = a;
    b.fold_hinge_stiffness = 2.5e-3;
    predict_scene_hash(&b, hb);
    assert_string_not_equal(ha, hb);
    b = a;
    b.fold_angle_right_deg = -91.0;
    predict_scene_hash(&b, hb);
    assert_string_not_equal(ha, hb);
}

static void real_ladder(void **state)
{
    (void)state;
    rod_scene s = rod_scene_default();
    s.dt = 0.01;
    int nodes[2] = {21, 41};
    predict_ladder_rung r[2];
    rod_ladder_verdict v;
    char why[256] = "";
    assert_int_equal(predict_ladder_compute(&s, nodes, 2, 1, r, &v, NULL, NULL, NULL, why, sizeof why), 0);
    printf("ladder: N=21 %.5f (dt %g, err %.3g, %.2f s), N=41 %.5f (dt %g, err %.3g, %.2f s); %s\n", r[0].snap_dw,
           r[0].dt, r[0].est_error, r[0].wall_s, r[1].snap_dw, r[1].dt, r[1].est_error, r[1].wall_s, v.note);
    assert_true(r[0].snapped && r[1].snapped);
    assert_true(r[0].est_error > r[1].est_error && r[1].est_error > 0.0);
    /* dt refined with the mesh (finest at the scene's), the step control's targets with dt */
    assert_float_equal(r[1].dt, 0.01, 0);
    assert_float_equal(r[0].dt, 0.01 * 38.0 / 18.0, 1e-15);
    assert_float_equal(r[0].adapt_scale, 38.0 / 18.0, 1e-12);
    assert_float_equal(r[1].adapt_scale, 1.0, 0);
    assert_non_null(strstr(v.note, "two rungs"));
    int bad[2] = {41, 21};
    assert_int_equal(predict_ladder_compute(&s, bad, 2, 1, r, NULL, NULL, NULL, NULL, why, sizeof why), -1);
    assert_non_null(strstr(why, "increasing"));
}

/* Cancellation (issue 17, defect 4): a ladder that would run for minutes (dt = 1e-5 s) stops
 * within a few seconds of its flag being set from another thread, and says so. */
typedef struct cancel_after {
    atomic_int *flag;
    double seconds;
} cancel_after;

static void *set_flag_later(void *arg)
{
    cancel_after *c = arg;
    struct timespec ts = {(time_t)c->seconds, (long)((c->seconds - (double)(time_t)c->seconds) * 1e9)};
    nanosleep(&ts, NULL);
    atomic_store(c->flag, 1);
    return NULL;
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void ladder_cancels(void **state)
{
    (void)state;
    rod_scene s = rod_scene_default();
    s.dt = 1e-5;
    int nodes[2] = {21, 41};
    predict_ladder_rung r[2];
    char why[256] = "";
    atomic_int flag = 0;
    cancel_after c = {&flag, 0.3};
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, set_flag_later, &c), 0);
    double t0 = now_s();
    assert_int_equal(predict_ladder_compute(&s, nodes, 2, 0, r, NULL, NULL, NULL, &flag, why, sizeof why), -1);
    double took = now_s() - t0;
    pthread_join(th, NULL);
    printf("cancelled after %.2f s: %s\n", took, why);
    assert_non_null(strstr(why, "cancelled"));
    assert_true(took < 10.0); /* uncancelled, this ladder takes minutes */
}

/* The estimate scales as nodes / dt, and fast mode takes a twentieth of the steps; the paper's
 * scene (l = 1 m, Delta W to 0.6 at 0.01 m/s, dt = 1 ms, N = 201) gives 60,000 steps. */
static void estimate_scales(void **state)
{
    (void)state;
    rod_scene s = rod_scene_default();
    s.dt = 1e-3;
    s.nodes = 101;
    double e1 = predict_estimate_s(&s, 0);
    assert_true(e1 > 0 && isfinite(e1));
    s.dt = 1e-6;
    assert_float_equal(predict_estimate_s(&s, 0) / e1, 1000.0, 1e-6);
    assert_float_equal(predict_estimate_s(&s, 1) / e1, 1000.0 / PREDICT_FAST_STEP_RATIO, 1e-6);
    s.nodes = 201;
    assert_float_equal(predict_estimate_s(&s, 0) / e1, 1000.0 * 201.0 / 101.0, 1e-6);
    int nodes[2] = {101, 201};
    s.dt = 1e-3;
    /* the coarse rung at dt times 198 / 98 */
    assert_float_equal(predict_ladder_estimate_s(&s, nodes, 2, 0), e1 * (98.0 / 198.0 + 201.0 / 101.0), 1e-9);
    s.dt = 0;
    assert_true(isinf(predict_estimate_s(&s, 0)));
    rod_scene paper = rod_scene_default();
    paper.length = 1.0;
    paper.shear_max = 0.6;
    paper.shear_rate = 0.01;
    paper.dt = 1e-3;
    paper.nodes = 201;
    assert_float_equal(predict_estimate_s(&paper, 0), 60000.0 * 201.0 * PREDICT_STEP_NODE_S, 1e-9);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(richardson_exact_at_first_order),
        cmocka_unit_test(mixed_orders_bounded_within_3),
        cmocka_unit_test(unequal_ratios_observe_the_order),
        cmocka_unit_test(out_of_range_flagged),
        cmocka_unit_test(choose_cheapest_meeting_target),
        cmocka_unit_test(hash_ignores_mesh_only),
        cmocka_unit_test(real_ladder),
        cmocka_unit_test(ladder_cancels),
        cmocka_unit_test(estimate_scales),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
