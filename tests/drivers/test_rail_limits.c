/* test_rail_limits.c: the front end refuses, before anything is sent, every command outside the
 * soft limits, the speed limit or the minimum clamp gap, and homing without confirmation; jogs
 * end at the nearest limit. Runs on the mock with a virtual clock. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "rail_mock.h"

#define NEAR(a, b, tol) assert_true(fabs((a) - (b)) <= (tol))

typedef struct fixture {
    rail_vclock vc;
    rail *r;
} fixture;

/* Compression rail: soft [0, 50] mm, gap = 60 - position, minimum gap 20 mm -> position <= 40. */
static int setup(void **state)
{
    static fixture f;
    memset(&f, 0, sizeof f);
    rail_params p = rail_params_default();
    strcpy(p.name, "compress");
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 50.0;
    p.max_speed_mm_s = 10.0;
    p.accel_mm_s2 = 100.0;
    p.poll_hz = 50.0;
    p.min_gap_mm = 20.0;
    p.gap_at_zero_mm = 60.0;
    p.gap_per_mm = -1.0;
    rail_mock_params m = rail_mock_params_default();
    m.start_mm = 10.0;
    char why[256];
    assert_int_equal(rail_mock_open(&f.r, &p, &m, rail_clock_virtual(&f.vc), why, sizeof why), RAIL_OK);
    *state = &f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    rail_close(f->r);
    return 0;
}

static void assert_still_at(rail *r, double mm)
{
    rail_status st;
    rail_clock_sleep(rail_get_clock(r), 1.0);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_IDLE);
    assert_true(st.position_mm == mm);
}

static void test_soft_limits_refuse(void **state)
{
    fixture *f = *state;
    assert_int_equal(rail_move_abs(f->r, 51.0, 1.0), RAIL_E_LIMIT);
    assert_non_null(strstr(rail_last_error(f->r), "soft limits"));
    assert_int_equal(rail_move_abs(f->r, -0.001, 1.0), RAIL_E_LIMIT);
    assert_int_equal(rail_move_rel(f->r, -10.5, 1.0), RAIL_E_LIMIT);
    assert_int_equal(rail_move_abs(f->r, NAN, 1.0), RAIL_E_INVALID);
    assert_int_equal(rail_move_rel(f->r, INFINITY, 1.0), RAIL_E_INVALID);
    assert_still_at(f->r, 10.0);
}

static void test_speed_limit_refuses(void **state)
{
    fixture *f = *state;
    assert_int_equal(rail_move_abs(f->r, 20.0, 10.5), RAIL_E_SPEED);
    assert_non_null(strstr(rail_last_error(f->r), "above the limit"));
    assert_int_equal(rail_move_abs(f->r, 20.0, 0.0), RAIL_E_SPEED);
    assert_int_equal(rail_move_abs(f->r, 20.0, -1.0), RAIL_E_SPEED);
    assert_int_equal(rail_jog(f->r, -11.0), RAIL_E_SPEED);
    assert_int_equal(rail_jog(f->r, 0.0), RAIL_E_SPEED);
    assert_still_at(f->r, 10.0);
}

static void test_min_gap_refuses(void **state)
{
    fixture *f = *state;
    assert_int_equal(rail_move_abs(f->r, 45.0, 5.0), RAIL_E_GAP);
    assert_non_null(strstr(rail_last_error(f->r), "minimum"));
    assert_int_equal(rail_move_abs(f->r, 40.0, 10.0), RAIL_OK); /* exactly the minimum gap */
    rail_status st;
    assert_int_equal(rail_wait_idle(f->r, 10.0, &st), RAIL_OK);
    assert_true(st.position_mm == 40.0);
    assert_int_equal(rail_move_rel(f->r, 0.01, 1.0), RAIL_E_GAP);
    assert_int_equal(rail_jog(f->r, 1.0), RAIL_E_LIMIT); /* already on the gap edge */
}

static void test_jog_ends_at_limit(void **state)
{
    fixture *f = *state;
    rail_status st;
    assert_int_equal(rail_jog(f->r, 10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(f->r, 20.0, &st), RAIL_OK);
    assert_true(st.position_mm == 40.0); /* gap edge, not soft max 50 */
    assert_int_equal(rail_jog(f->r, -10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(f->r, 20.0, &st), RAIL_OK);
    assert_true(st.position_mm == 0.0);
}

static void test_home_needs_confirmation(void **state)
{
    fixture *f = *state;
    assert_int_equal(rail_home(f->r, false), RAIL_E_CONFIRM);
    assert_non_null(strstr(rail_last_error(f->r), "specimen"));
    assert_still_at(f->r, 10.0);
    assert_int_equal(rail_home(f->r, true), RAIL_OK);
    rail_status st;
    assert_int_equal(rail_wait_idle(f->r, 10.0, &st), RAIL_OK);
    assert_true(st.position_mm == 0.0);
}

static void test_params_check_names_field(void **state)
{
    (void)state;
    char why[256];
    rail_params p = rail_params_default();
    p.soft_max_mm = p.soft_min_mm;
    assert_int_equal(rail_params_check(&p, why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "soft_min_mm"));
    p = rail_params_default();
    p.max_speed_mm_s = NAN;
    assert_int_equal(rail_params_check(&p, why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "max_speed_mm_s"));
    p = rail_params_default();
    p.gap_per_mm = 2.0;
    assert_int_equal(rail_params_check(&p, why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "gap_per_mm"));
    assert_string_equal(rail_err_message(RAIL_E_GAP), "closer than the minimum clamp gap");
    assert_string_equal(rail_err_message((rail_err)999), "unknown error");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_soft_limits_refuse, setup, teardown),
        cmocka_unit_test_setup_teardown(test_speed_limit_refuses, setup, teardown),
        cmocka_unit_test_setup_teardown(test_min_gap_refuses, setup, teardown),
        cmocka_unit_test_setup_teardown(test_jog_ends_at_limit, setup, teardown),
        cmocka_unit_test_setup_teardown(test_home_needs_confirmation, setup, teardown),
        cmocka_unit_test(test_params_check_names_field),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
