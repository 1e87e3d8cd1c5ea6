/* test_predict_ladder: error estimates of the resolution ladder against sequences whose limit is
 * known (s(N) = s* + C / (N - 1)^p), the choice of rung, the scene hash, and one real ladder on a
 * coarse scene. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "predict_ladder.h"

static void fill(ladder_rung *r, int n, const int *nodes, double s_star, double C, double p)
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
        ladder_rung r[3];
        fill(r, 3, nodes, 0.43, 0.5, p);
        ladder_estimate_errors(r, 3);
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
    ladder_rung r[3];
    fill(r, 3, nodes, 0.43, 0.5, 1);
    r[0].snap_dw = 0.40; /* the coarsest rung on the other side */
    ladder_estimate_errors(r, 3);
    /* First order from the two finest is still exact for them. */
    assert_true(fabs(r[2].est_error - 0.5 / 120.0 / 0.43) < 1e-12);
    assert_true(r[0].est_error > 0.05);
}

static void choose_cheapest_meeting_target(void **state)
{
    (void)state;
    int nodes[3] = {31, 61, 121};
    ladder_rung r[3];
    fill(r, 3, nodes, 0.43, 0.5, 1);
    ladder_estimate_errors(r, 3); /* errors 3.9e-2, 1.9e-2, 9.7e-3 */
    assert_int_equal(ladder_choose(r, 3, 0.05), 0);
    assert_int_equal(ladder_choose(r, 3, 0.02), 1);
    assert_int_equal(ladder_choose(r, 3, 0.01), 2);
    assert_int_equal(ladder_choose(r, 3, 1e-6), 2); /* none meets it: the finest */
}

static void hash_ignores_mesh_only(void **state)
{
    (void)state;
    rod_scene a = rod_scene_default(), b = a;
    char ha[17], hb[17];
    b.nodes = 61;
    scene_hash(&a, ha);
    scene_hash(&b, hb);
    assert_string_equal(ha, hb);
    b.fold_position = 0.21;
    scene_hash(&b, hb);
    assert_string_not_equal(ha, hb);
    assert_int_equal(strlen(ha), 16);
}

static void real_ladder(void **state)
{
    (void)state;
    rod_scene s = rod_scene_default();
    s.dt = 0.01;
    int nodes[2] = {21, 41};
    ladder_rung r[2];
    char why[256] = "";
    assert_int_equal(ladder_compute(&s, nodes, 2, 1, r, NULL, NULL, why, sizeof why), 0);
    printf("ladder: N=21 %.5f (err %.3g, %.2f s), N=41 %.5f (err %.3g, %.2f s)\n", r[0].snap_dw, r[0].est_error,
           r[0].wall_s, r[1].snap_dw, r[1].est_error, r[1].wall_s);
    assert_true(r[0].snapped && r[1].snapped);
    assert_true(r[0].est_error > r[1].est_error);
    int bad[2] = {41, 21};
    assert_int_equal(ladder_compute(&s, bad, 2, 1, r, NULL, NULL, why, sizeof why), -1);
    assert_non_null(strstr(why, "increasing"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(richardson_exact),
        cmocka_unit_test(non_monotone_falls_back_to_first_order),
        cmocka_unit_test(choose_cheapest_meeting_target),
        cmocka_unit_test(hash_ignores_mesh_only),
        cmocka_unit_test(real_ladder),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
