/* test_rail_mock.c: the mock rail runs the compress-hold-shear-stop sequence on a virtual clock,
 * stops within the deceleration distance, extrapolates between polls, and reports injected
 * faults (stall, communication loss, alarm) as the right state with a reason. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "rail_mock.h"

#define NEAR(a, b, tol) assert_true(fabs((a) - (b)) <= (tol))

static rail *open_mock(rail_vclock *vc, const char *name, rail_mock_params m)
{
    rail_params p = rail_params_default();
    strcpy(p.name, name);
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 100.0;
    p.max_speed_mm_s = 20.0;
    p.accel_mm_s2 = 100.0;
    p.poll_hz = 10.0;
    rail *r = NULL;
    char why[256];
    assert_int_equal(rail_mock_open(&r, &p, &m, rail_clock_virtual(vc), why, sizeof why), RAIL_OK);
    return r;
}

static void test_compress_hold_shear_stop(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail_mock_params m = rail_mock_params_default();
    rail *comp = open_mock(&vc, "compress", m);
    rail *shear = open_mock(&vc, "shear", m);
    rail_status st;
    assert_int_equal(rail_move_abs(comp, 25.0, 10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(comp, 10.0, &st), RAIL_OK);
    assert_true(st.position_mm == 25.0);
    rail_clock_sleep(rail_clock_virtual(&vc), 2.0); /* hold */
    assert_int_equal(rail_jog(shear, 0.5), RAIL_OK);   /* slow shear ramp */
    for (int i = 0; i < 40; i++) {
        rail_clock_sleep(rail_clock_virtual(&vc), 0.1);
        assert_int_equal(rail_status_get(shear, &st), RAIL_OK);
    }
    assert_int_equal(st.state, RAIL_STATE_MOVING);
    NEAR(st.velocity_mm_s, 0.5, 1e-9);
    NEAR(st.position_mm, 0.5 * 4.0 - 0.5 * 0.5 / 100.0 / 2.0, 1e-3); /* minus the ramp-up lag */
    assert_int_equal(rail_stop(shear), RAIL_OK);
    assert_int_equal(rail_wait_idle(shear, 5.0, &st), RAIL_OK);
    NEAR(st.position_mm, 2.0, 0.01);
    assert_int_equal(rail_status_poll(comp, &st), RAIL_OK);
    assert_true(st.position_mm == 25.0);
    rail_close(comp);
    rail_close(shear);
}

static void test_stop_within_decel_distance(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail *r = open_mock(&vc, "shear", rail_mock_params_default());
    rail_status st;
    assert_int_equal(rail_move_abs(r, 90.0, 20.0), RAIL_OK);
    rail_clock_sleep(rail_clock_virtual(&vc), 1.0);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    double at = st.position_mm, v = st.velocity_mm_s;
    NEAR(v, 20.0, 1e-9);
    assert_int_equal(rail_stop(r), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 5.0, &st), RAIL_OK);
    double d = st.position_mm - at;
    assert_true(d > 0.0);
    assert_true(d <= rail_stop_distance_mm(r, v) + 1e-6);
    NEAR(d, rail_stop_distance_mm(r, v), 0.05);
    rail_close(r);
}

static void test_poll_rate_and_extrapolation(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail *r = open_mock(&vc, "shear", rail_mock_params_default());
    rail_status st;
    assert_int_equal(rail_jog(r, 5.0), RAIL_OK);
    rail_clock_sleep(rail_clock_virtual(&vc), 1.0);
    assert_int_equal(rail_status_get(r, &st), RAIL_OK);
    assert_false(st.extrapolated);
    double t0 = st.t_s, p0 = st.position_mm;
    rail_clock_sleep(rail_clock_virtual(&vc), 0.05); /* under the 0.1 s poll period */
    assert_int_equal(rail_status_get(r, &st), RAIL_OK);
    assert_true(st.extrapolated);
    assert_true(st.t_s == t0);
    NEAR(st.position_mm, p0 + 0.25, 1e-9);
    rail_clock_sleep(rail_clock_virtual(&vc), 0.06);
    assert_int_equal(rail_status_get(r, &st), RAIL_OK);
    assert_false(st.extrapolated);
    rail_close(r);
}

static void test_stall_is_a_fault(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail_mock_params m = rail_mock_params_default();
    m.stall_at_mm = 12.5;
    rail *r = open_mock(&vc, "compress", m);
    rail_status st;
    assert_int_equal(rail_move_abs(r, 30.0, 10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 10.0, &st), RAIL_E_STATE);
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    assert_true(st.position_mm == 12.5);
    assert_non_null(strstr(st.message, "stall"));
    assert_int_equal(rail_move_abs(r, 20.0, 1.0), RAIL_E_STATE); /* refused until reset */
    assert_int_equal(rail_reset(r), RAIL_OK);
    assert_int_equal(rail_move_abs(r, 20.0, 10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 10.0, &st), RAIL_OK);
    assert_true(st.position_mm == 20.0);
    rail_close(r);
}

static void test_comm_loss_detected(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail_mock_params m = rail_mock_params_default();
    m.comm_loss_after_s = 1.0;
    rail *r = open_mock(&vc, "shear", m);
    rail_status st;
    assert_int_equal(rail_jog(r, 2.0), RAIL_OK);
    double t_lost = -1.0;
    for (int i = 0; i < 100; i++) {
        rail_clock_sleep(rail_clock_virtual(&vc), 0.1);
        if (rail_status_get(r, &st) != RAIL_OK) {
            t_lost = vc.t_s;
            break;
        }
    }
    assert_true(t_lost >= 1.0 && t_lost - 1.0 <= 0.5);
    assert_int_equal(st.state, RAIL_STATE_DISCONNECTED);
    assert_non_null(strstr(rail_last_error(r), "lost"));
    assert_int_equal(rail_move_abs(r, 1.0, 1.0), RAIL_E_DISCONNECTED);
    rail_close(r);
}

static void test_alarm_after_time(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail_mock_params m = rail_mock_params_default();
    m.alarm_after_s = 0.5;
    m.alarm_code = 9;
    rail *r = open_mock(&vc, "shear", m);
    rail_status st;
    assert_int_equal(rail_move_abs(r, 50.0, 10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 10.0, &st), RAIL_E_DEVICE);
    assert_int_equal(st.state, RAIL_STATE_ALARM);
    assert_int_equal(st.code, 9);
    assert_true(st.position_mm < 5.0);
    assert_int_equal(rail_reset(r), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_IDLE);
    rail_close(r);
}

static void test_bad_mock_params(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail_params p = rail_params_default();
    rail_mock_params m = rail_mock_params_default();
    m.start_mm = -1.0;
    rail *r = NULL;
    char why[256];
    assert_int_equal(rail_mock_open(&r, &p, &m, rail_clock_virtual(&vc), why, sizeof why),
                     RAIL_E_INVALID);
    assert_null(r);
    assert_non_null(strstr(why, "start_mm"));
    m = rail_mock_params_default();
    p.poll_hz = 0.0;
    assert_int_equal(rail_mock_open(&r, &p, &m, rail_clock_virtual(&vc), why, sizeof why),
                     RAIL_E_INVALID);
    assert_non_null(strstr(why, "poll_hz"));
}

/* The external load: none until set, then every fresh reading carries the last value set;
 * NaN is refused and the value stands. */
static void test_external_load(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail *r = open_mock(&vc, "shear", rail_mock_params_default());
    rail_status st;
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_false(st.has_load);
    assert_int_equal(rail_mock_set_load(r, 2.5), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.has_load);
    assert_true(st.load == 2.5);
    assert_int_equal(rail_mock_set_load(r, NAN), RAIL_E_INVALID);
    assert_non_null(strstr(rail_last_error(r), "not finite"));
    assert_int_equal(rail_mock_set_load(r, -1.0), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.has_load && st.load == -1.0);
    assert_int_equal(rail_mock_set_load(NULL, 1.0), RAIL_E_INVALID);
    rail_close(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_compress_hold_shear_stop), cmocka_unit_test(test_stop_within_decel_distance),
        cmocka_unit_test(test_poll_rate_and_extrapolation), cmocka_unit_test(test_stall_is_a_fault),
        cmocka_unit_test(test_comm_loss_detected), cmocka_unit_test(test_alarm_after_time),
        cmocka_unit_test(test_bad_mock_params), cmocka_unit_test(test_external_load),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
