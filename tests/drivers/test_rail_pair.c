/* test_rail_pair.c: a fault of either rail stops the other at once (mock rails, virtual clock):
 * an alarm on the compression rail halts a running shear, a lost shear link halts a moving
 * compression, and the error names the rail that failed. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "rail_mock.h"
#include "rail_pair.h"

static rail *open_mock(rail_vclock *vc, const char *name, rail_mock_params m)
{
    rail_params p = rail_params_default();
    snprintf(p.name, sizeof p.name, "%s", name);
    p.poll_hz = 10.0;
    rail *r = NULL;
    char why[256];
    assert_int_equal(rail_mock_open(&r, &p, &m, rail_clock_virtual(vc), why, sizeof why), RAIL_OK);
    return r;
}

static void test_alarm_stops_other(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail_mock_params mc = rail_mock_params_default();
    mc.alarm_after_s = 1.0;
    mc.alarm_code = 7;
    rail *c = open_mock(&vc, "compress", mc);
    rail *sh = open_mock(&vc, "shear", rail_mock_params_default());
    rail_status sc, ss;
    char why[300] = "";
    assert_int_equal(rail_jog(sh, 2.0), RAIL_OK);
    rail_err e = RAIL_OK;
    for (int i = 0; i < 50 && e == RAIL_OK; i++) {
        rail_clock_sleep(rail_clock_virtual(&vc), 0.1);
        e = rail_pair_poll(c, sh, &sc, &ss, why, sizeof why);
    }
    assert_int_equal(e, RAIL_E_DEVICE);
    assert_non_null(strstr(why, "rail compress: alarm"));
    double p0 = ss.position_mm;
    rail_clock_sleep(rail_clock_virtual(&vc), 1.0);
    assert_int_equal(rail_status_poll(sh, &ss), RAIL_OK);
    assert_int_equal(ss.state, RAIL_STATE_IDLE);
    assert_true(fabs(ss.position_mm - p0) < 0.25); /* halted at once, not run on */
    rail_close(c);
    rail_close(sh);
}

static void test_lost_link_stops_other(void **s)
{
    (void)s;
    rail_vclock vc = {0};
    rail_mock_params ms = rail_mock_params_default();
    ms.comm_loss_after_s = 0.5;
    rail *c = open_mock(&vc, "compress", rail_mock_params_default());
    rail *sh = open_mock(&vc, "shear", ms);
    rail_status sc, ss;
    char why[300] = "";
    assert_int_equal(rail_move_abs(c, 50.0, 5.0), RAIL_OK);
    rail_err e = RAIL_OK;
    for (int i = 0; i < 50 && e == RAIL_OK; i++) {
        rail_clock_sleep(rail_clock_virtual(&vc), 0.1);
        e = rail_pair_poll(c, sh, &sc, &ss, why, sizeof why);
    }
    assert_int_equal(e, RAIL_E_DISCONNECTED);
    assert_non_null(strstr(why, "shear"));
    rail_clock_sleep(rail_clock_virtual(&vc), 1.0);
    assert_int_equal(rail_status_poll(c, &sc), RAIL_OK);
    assert_int_equal(sc.state, RAIL_STATE_IDLE);
    assert_true(sc.position_mm < 5.0);
    assert_int_equal(rail_pair_estop(c, sh), RAIL_E_DISCONNECTED);
    rail_close(c);
    rail_close(sh);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_alarm_stops_other),
        cmocka_unit_test(test_lost_link_stops_other),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
