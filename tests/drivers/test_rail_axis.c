/* test_rail_axis.c: the simulated axis follows a trapezoidal profile, ends exactly on its target,
 * jogs at constant velocity, and stops within v^2/(2a). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "rail_axis.h"

#define NEAR(a, b, tol) assert_true(fabs((a) - (b)) <= (tol))

static void test_trapezoid_reaches_target(void **s)
{
    (void)s;
    rail_axis a = rail_axis_make(0.0, 50.0, 100.0);
    rail_axis_move_to(&a, 10.0, 5.0);
    double vmax = 0.0, t = 0.0;
    /* Expected duration: d/v + v/a = 2 + 0.1 s. */
    for (int i = 0; i < 3000 && rail_axis_busy(&a); i++) {
        rail_axis_step(&a, 1e-3);
        t += 1e-3;
        vmax = fmax(vmax, a.vel_mm_s);
    }
    assert_false(rail_axis_busy(&a));
    assert_true(a.pos_mm == 10.0);
    NEAR(vmax, 5.0, 1e-9);
    NEAR(t, 2.1, 0.02); /* the last ms snaps onto the target */
}

static void test_triangle_short_move(void **s)
{
    (void)s;
    rail_axis a = rail_axis_make(5.0, 10.0, 100.0);
    rail_axis_move_to(&a, 4.0, 50.0); /* peak sqrt(a d) = sqrt(10) mm/s */
    double vmin = 0.0;
    for (int i = 0; i < 5000 && rail_axis_busy(&a); i++) {
        rail_axis_step(&a, 1e-3);
        vmin = fmin(vmin, a.vel_mm_s);
    }
    assert_true(a.pos_mm == 4.0);
    NEAR(vmin, -sqrt(10.0), 0.05);
}

static void test_jog_and_stop_distance(void **s)
{
    (void)s;
    rail_axis a = rail_axis_make(10.0, 20.0, 100.0);
    rail_axis_jog(&a, -4.0);
    rail_axis_step(&a, 1.0);
    NEAR(a.vel_mm_s, -4.0, 1e-9);
    double at_stop = a.pos_mm;
    rail_axis_stop(&a);
    rail_axis_step(&a, 1.0);
    assert_false(rail_axis_busy(&a));
    NEAR(at_stop - a.pos_mm, 16.0 / 40.0, 1e-3);
}

static void test_hard_limit_and_home(void **s)
{
    (void)s;
    rail_axis a = rail_axis_make(1.0, 100.0, 5.0);
    rail_axis_jog(&a, 10.0);
    rail_axis_step(&a, 2.0);
    assert_true(a.limit_hit);
    assert_true(a.pos_mm == 5.0);
    rail_axis_home(&a, 10.0);
    rail_axis_step(&a, 2.0);
    assert_true(a.homed);
    assert_false(a.limit_hit);
    assert_true(a.pos_mm == 0.0);
}

static void test_bad_dt_ignored(void **s)
{
    (void)s;
    rail_axis a = rail_axis_make(1.0, 100.0, 5.0);
    rail_axis_jog(&a, 1.0);
    rail_axis_step(&a, NAN);
    rail_axis_step(&a, -1.0);
    assert_true(a.pos_mm == 1.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_trapezoid_reaches_target), cmocka_unit_test(test_triangle_short_move),
        cmocka_unit_test(test_jog_and_stop_distance),    cmocka_unit_test(test_hard_limit_and_home),
        cmocka_unit_test(test_bad_dt_ignored),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
