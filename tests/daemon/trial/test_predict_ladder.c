/* test_predict_ladder: error estimates of the resolution ladder against sequences whose limit is
 * known (s(N) = s* + C / (N - 1)^p), the choice of rung, the scene hash, and one real ladder on a
 * coarse scene; cancellation and the run-time estimate. */
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

static void fill(predict_ladder_rung *r, int n, const int *nodes, double s_star, double C, double p)
{
    for (int k = 0; k < n; k++) {
        memset(&r[k], 0, sizeof r[k]);
        r[k].nodes = nodes[k];
        r[k].snap_dw = s_star + C / pow(nodes[k] - 1, p);
        r[k].wall_s = 0.1 * pow(2.0, k);
    }
}

static void richardson_exact(void **state)
{
    (void)state;
    int nodes[3] = {31, 61, 121};
    for (int p = 1; p <= 2; p++) {
        predict_ladder_rung r[3];
        fill(r, 3, nodes, 0.43, 0.5, p);
        predict_ladder_estimate_errors(r, 3);
        for (int k = 0; k < 3; k++) {
            double exact = 0.5 / pow(nodes[k] - 1, p) / 0.43;
            assert_true(fabs(r[k].est_error - exact) < 1e-9 * exact + 1e-14);
        }
    }
}

static void non_monotone_falls_back_to_first_order(void **state)
{
    (void)state;
    int nodes[3] = {31, 61, 121};
    predict_ladder_rung r[3];
    fill(r, 3, nodes, 0.43, 0.5, 1);
    r[0].snap_dw = 0.40; /* the coarsest rung on the other side */
    predict_ladder_estimate_errors(r, 3);
    /* First order from the two finest is still exact for them. */
    assert_true(fabs(r[2].est_error - 0.5 / 120.0 / 0.43) < 1e-12);
    assert_true(r[0].est_error > 0.05);
}

static void choose_cheapest_meeting_target(void **state)
{
    (void)state;
    int nodes[3] = {31, 61, 121};
    predict_ladder_rung r[3];
    fill(r, 3, nodes, 0.43, 0.5, 1);
    predict_ladder_estimate_errors(r, 3); /* errors 3.9e-2, 1.9e-2, 9.7e-3 */
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
    char why[256] = "";
    assert_int_equal(predict_ladder_compute(&s, nodes, 2, 1, r, NULL, NULL, NULL, why, sizeof why), 0);
    printf("ladder: N=21 %.5f (err %.3g, %.2f s), N=41 %.5f (err %.3g, %.2f s)\n", r[0].snap_dw, r[0].est_error,
           r[0].wall_s, r[1].snap_dw, r[1].est_error, r[1].wall_s);
    assert_true(r[0].snapped && r[1].snapped);
    assert_true(r[0].est_error > r[1].est_error);
    int bad[2] = {41, 21};
    assert_int_equal(predict_ladder_compute(&s, bad, 2, 1, r, NULL, NULL, NULL, why, sizeof why), -1);
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
    assert_int_equal(predict_ladder_compute(&s, nodes, 2, 0, r, NULL, NULL, &flag, why, sizeof why), -1);
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
    assert_float_equal(predict_ladder_estimate_s(&s, nodes, 2, 0), e1 * 302.0 / 101.0, 1e-9);
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
        cmocka_unit_test(richardson_exact),
        cmocka_unit_test(non_monotone_falls_back_to_first_order),
        cmocka_unit_test(choose_cheapest_meeting_target),
        cmocka_unit_test(hash_ignores_mesh_only),
        cmocka_unit_test(real_ladder),
        cmocka_unit_test(ladder_cancels),
        cmocka_unit_test(estimate_scales),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
