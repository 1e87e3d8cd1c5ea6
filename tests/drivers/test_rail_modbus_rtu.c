/* test_rail_modbus_rtu.c: the Modbus driver over RTU, against the simulated drive on a
 * pseudo-terminal: a move ends where commanded; a bad CRC, a reply from another slave id and a
 * silent bus (request for a slave that is not there) give named errors; a killed drive is
 * reported disconnected within 0.5 s. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "mbsim_spawn.h"
#include "rail_modbus.h"

#define NEAR(a, b, tol) assert_true(fabs((a) - (b)) <= (tol))

static rail_params params(void)
{
    rail_params p = rail_params_default();
    snprintf(p.name, sizeof p.name, "shear");
    p.soft_max_mm = 150.0;
    p.max_speed_mm_s = 50.0;
    p.accel_mm_s2 = 200.0;
    p.poll_hz = 20.0;
    return p;
}

static rail_modbus_params rtu(const char *path)
{
    rail_modbus_params m = rail_modbus_params_default();
    m.rtu = true;
    snprintf(m.address, sizeof m.address, "%s", path);
    m.baud = 19200;
    m.parity = 'E';
    m.watchdog_s = 0.5;
    return m;
}

static void test_rtu_move(void **s)
{
    (void)s;
    char path[128], why[300];
    pid_t pid = mbsim_spawn_rtu(mb_sim_params_default(), path, sizeof path);
    rail_params p = params();
    rail_modbus_params m = rtu(path);
    rail *r = NULL;
    rail_err e = rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why);
    if (e != RAIL_OK)
        print_error("open: %s\n", why);
    assert_int_equal(e, RAIL_OK);
    rail_status st;
    assert_int_equal(rail_move_abs(r, 5.5, 20.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 3.0, &st), RAIL_OK);
    NEAR(st.position_mm, 5.5, 1e-3);
    rail_close(r);
    mbsim_kill(pid);
}

static void expect_open_fails(mb_sim_params sp, rail_err want, const char *needle)
{
    char path[128], why[300] = "";
    pid_t pid = mbsim_spawn_rtu(sp, path, sizeof path);
    rail_params p = params();
    rail_modbus_params m = rtu(path);
    rail *r = NULL;
    rail_err e = rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why);
    if (e != want || !strstr(why, needle))
        print_error("got %d '%s', want %d '%s'\n", e, why, want, needle);
    assert_int_equal(e, want);
    assert_null(r);
    assert_non_null(strstr(why, needle));
    mbsim_kill(pid);
}

static void test_rtu_bad_frames(void **s)
{
    (void)s;
    mb_sim_params sp = mb_sim_params_default();
    sp.garble_prob = 1.0;
    expect_open_fails(sp, RAIL_E_PROTOCOL, "CRC");
    sp = mb_sim_params_default();
    sp.wrong_id_prob = 1.0;
    expect_open_fails(sp, RAIL_E_PROTOCOL, "slave");
    sp = mb_sim_params_default();
    sp.slave = 7; /* nobody answers slave 1 */
    expect_open_fails(sp, RAIL_E_TIMEOUT, "timed out");
    sp = mb_sim_params_default();
    sp.exception_prob = 1.0;
    expect_open_fails(sp, RAIL_E_DEVICE, "exception");
}

static void test_rtu_killed_drive(void **s)
{
    (void)s;
    char path[128], why[300];
    pid_t pid = mbsim_spawn_rtu(mb_sim_params_default(), path, sizeof path);
    rail_params p = params();
    rail_modbus_params m = rtu(path);
    rail *r = NULL;
    assert_int_equal(rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why), RAIL_OK);
    rail_status st;
    assert_int_equal(rail_jog(r, 10.0), RAIL_OK);
    rail_clock_sleep(rail_clock_real(), 0.2);
    mbsim_kill(pid);
    double t0 = rail_clock_now(rail_clock_real());
    rail_err e = RAIL_OK;
    for (int i = 0; i < 100 && e == RAIL_OK; i++) {
        e = rail_status_get(r, &st);
        if (e == RAIL_OK)
            rail_clock_sleep(rail_clock_real(), 0.01);
    }
    assert_true(rail_clock_now(rail_clock_real()) - t0 <= 0.5);
    assert_true(e == RAIL_E_DISCONNECTED || e == RAIL_E_TIMEOUT);
    assert_int_equal(st.state, RAIL_STATE_DISCONNECTED);
    rail_close(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rtu_move),
        cmocka_unit_test(test_rtu_bad_frames),
        cmocka_unit_test(test_rtu_killed_drive),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
