/* test_rail_modbus.c: the Modbus driver against ribbon-mbsim's engine over 127.0.0.1: the
 * compress-hold-shear-stop sequence on two drives, stop within the deceleration distance, a
 * dead client stopped by the drive's watchdog and a reconnect that does not resume, homing,
 * alarms, stall, dropped / garbled / exception replies, wrong unit id, the unverified-preset
 * opt-in, the read-only probe refusing a wrong drive, a killed drive detected as disconnected
 * within 0.5 s, and the simulator answering a plain libmodbus client. */
#include <math.h>
#include <modbus.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "mbsim_spawn.h"
#include "rail_modbus.h"

#define NEAR(a, b, tol) assert_true(fabs((a) - (b)) <= (tol))
#define RES 1e-3 /* mm: one count of the simulated drive */

static rail_params params(const char *name)
{
    rail_params p = rail_params_default();
    snprintf(p.name, sizeof p.name, "%s", name);
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 150.0;
    p.max_speed_mm_s = 50.0;
    p.accel_mm_s2 = 200.0;
    p.poll_hz = 20.0;
    return p;
}

static rail_modbus_params mparams(int port)
{
    rail_modbus_params m = rail_modbus_params_default();
    snprintf(m.address, sizeof m.address, "127.0.0.1:%d", port);
    m.watchdog_s = 1.0;
    return m;
}

static rail *open_drive(int port, const char *name)
{
    rail_params p = params(name);
    rail_modbus_params m = mparams(port);
    rail *r = NULL;
    char why[300];
    rail_err e = rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why);
    if (e != RAIL_OK)
        print_error("open: %s\n", why);
    assert_int_equal(e, RAIL_OK);
    return r;
}

static rail_err wait_idle(rail *r, double timeout_s, rail_status *st)
{
    rail_err e = rail_wait_idle(r, timeout_s, st);
    if (e != RAIL_OK)
        print_message("wait_idle: %s (%s)\n", rail_last_error(r), st->message);
    return e;
}

static void test_sequence_two_drives(void **s)
{
    (void)s;
    int pc, ps;
    pid_t a = mbsim_spawn(mb_sim_params_default(), &pc);
    pid_t b = mbsim_spawn(mb_sim_params_default(), &ps);
    rail *comp = open_drive(pc, "compress");
    rail *shear = open_drive(ps, "shear");
    rail_status st;
    assert_int_equal(rail_move_abs(comp, 12.345, 40.0), RAIL_OK);
    assert_int_equal(wait_idle(comp, 5.0, &st), RAIL_OK);
    NEAR(st.position_mm, 12.345, RES);
    rail_clock_sleep(rail_clock_real(), 0.1);
    assert_int_equal(rail_jog(shear, 20.0), RAIL_OK);
    double t0 = rail_clock_now(rail_clock_real());
    while (rail_clock_now(rail_clock_real()) - t0 < 0.5) {
        assert_int_equal(rail_status_get(shear, &st), RAIL_OK);
        assert_int_equal(rail_status_get(comp, &st), RAIL_OK); /* keeps both watchdogs fed */
        rail_clock_sleep(rail_clock_real(), 0.01);
    }
    assert_int_equal(rail_status_poll(shear, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_MOVING);
    NEAR(st.velocity_mm_s, 20.0, 1e-6);
    double at = st.position_mm;
    double t_read = rail_clock_now(rail_clock_real());
    assert_int_equal(rail_stop(shear), RAIL_OK);
    double latency = rail_clock_now(rail_clock_real()) - t_read;
    assert_int_equal(wait_idle(shear, 3.0, &st), RAIL_OK);
    double d = st.position_mm - at;
    /* 20^2 / (2 * 200) = 1 mm, plus the measured request latency and 50 ms of scheduling slack. */
    assert_true(d >= 0.0 && d <= 1.0 + 20.0 * (latency + 0.05) + RES);
    assert_int_equal(rail_move_abs(shear, 3.25, 50.0), RAIL_OK);
    assert_int_equal(wait_idle(shear, 5.0, &st), RAIL_OK);
    NEAR(st.position_mm, 3.25, RES);
    assert_int_equal(rail_status_poll(comp, &st), RAIL_OK);
    NEAR(st.position_mm, 12.345, RES);
    rail_close(comp);
    rail_close(shear);
    mbsim_kill(a);
    mbsim_kill(b);
}

static void test_dead_client_watchdog_no_resume(void **s)
{
    (void)s;
    int port;
    pid_t pid = mbsim_spawn(mb_sim_params_default(), &port);
    fflush(NULL);
    pid_t client = fork();
    if (client == 0) {
        rail *r = NULL;
        rail_params p = params("shear");
        rail_modbus_params m = mparams(port);
        m.watchdog_s = 0.5;
        char why[300];
        if (rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why) != RAIL_OK)
            _exit(2);
        if (rail_move_abs(r, 140.0, 20.0) != RAIL_OK)
            _exit(3);
        _exit(0); /* dies mid-move without a word */
    }
    int wst = 0;
    waitpid(client, &wst, 0);
    assert_true(WIFEXITED(wst) && WEXITSTATUS(wst) == 0);
    rail_clock_sleep(rail_clock_real(), 1.0);
    rail *r = open_drive(port, "shear");
    rail_status st;
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_ALARM);
    assert_int_equal(st.code, 0x85); /* communication timeout */
    /* 0.5 s watchdog at 20 mm/s: stopped near 10 mm, far from the 140 mm target. */
    assert_true(st.position_mm > 2.0 && st.position_mm < 15.0);
    double p0 = st.position_mm;
    assert_int_equal(rail_reset(r), RAIL_OK);
    rail_clock_sleep(rail_clock_real(), 0.3);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_IDLE);
    assert_true(st.position_mm == p0);
    rail_close(r);
    mbsim_kill(pid);
}

static void test_home_alarm_stall(void **s)
{
    (void)s;
    int port;
    mb_sim_params sp = mb_sim_params_default();
    sp.start_mm = 5.0;
    sp.stall_at_mm = 8.0;
    pid_t pid = mbsim_spawn(sp, &port);
    rail *r = open_drive(port, "compress");
    rail_status st;
    assert_int_equal(rail_home(r, false), RAIL_E_CONFIRM);
    assert_int_equal(rail_home(r, true), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_HOMING);
    assert_int_equal(wait_idle(r, 3.0, &st), RAIL_OK);
    assert_true(st.position_mm == 0.0);
    assert_int_equal(rail_move_abs(r, 20.0, 20.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 3.0, &st), RAIL_E_DEVICE);
    assert_int_equal(st.state, RAIL_STATE_ALARM);
    assert_int_equal(st.code, 0x10);
    NEAR(st.position_mm, 8.0, RES);
    assert_int_equal(rail_move_abs(r, 2.0, 20.0), RAIL_E_STATE);
    assert_int_equal(rail_reset(r), RAIL_OK);
    assert_int_equal(rail_move_abs(r, 2.0, 20.0), RAIL_OK);
    assert_int_equal(wait_idle(r, 3.0, &st), RAIL_OK);
    NEAR(st.position_mm, 2.0, RES);
    rail_close(r);
    mbsim_kill(pid);
}

static void test_alarm_after_time(void **s)
{
    (void)s;
    int port;
    mb_sim_params sp = mb_sim_params_default();
    sp.alarm_after_s = 0.3;
    sp.alarm_code = 0x30;
    pid_t pid = mbsim_spawn(sp, &port);
    rail *r = open_drive(port, "shear");
    rail_status st;
    assert_int_equal(rail_jog(r, 10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 3.0, &st), RAIL_E_DEVICE);
    assert_int_equal(st.code, 0x30);
    assert_non_null(strstr(st.message, "0x30"));
    rail_close(r);
    mbsim_kill(pid);
}

static void expect_open_fails(mb_sim_params sp, rail_modbus_params *mpo, rail_err want, const char *needle)
{
    int port;
    pid_t pid = mbsim_spawn(sp, &port);
    rail_params p = params("shear");
    rail_modbus_params m = mpo ? *mpo : mparams(port);
    snprintf(m.address, sizeof m.address, "127.0.0.1:%d", port);
    rail *r = NULL;
    char why[300];
    rail_err e = rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why);
    if (e != want || !strstr(why, needle))
        print_error("got %d '%s', want %d '%s'\n", e, why, want, needle);
    assert_int_equal(e, want);
    assert_null(r);
    assert_non_null(strstr(why, needle));
    mbsim_kill(pid);
}

static void test_bad_replies_named(void **s)
{
    (void)s;
    mb_sim_params sp = mb_sim_params_default();
    sp.drop_prob = 1.0;
    expect_open_fails(sp, NULL, RAIL_E_TIMEOUT, "timed out");
    sp = mb_sim_params_default();
    sp.garble_prob = 1.0;
    expect_open_fails(sp, NULL, RAIL_E_PROTOCOL, "probe");
    sp = mb_sim_params_default();
    sp.exception_prob = 1.0;
    expect_open_fails(sp, NULL, RAIL_E_DEVICE, "exception");
    /* Wrong unit id: the simulator answers as a gateway with no such target. */
    sp = mb_sim_params_default();
    sp.slave = 2;
    expect_open_fails(sp, NULL, RAIL_E_DEVICE, "exception");
}

static void test_flaky_replies_survive(void **s)
{
    (void)s;
    int port;
    mb_sim_params sp = mb_sim_params_default();
    sp.garble_prob = 0.2;
    sp.seed = 99;
    pid_t pid = mbsim_spawn(sp, &port);
    rail_params p = params("shear");
    rail_modbus_params m = mparams(port);
    rail *r = NULL;
    char why[300];
    rail_err e = RAIL_E_PROTOCOL;
    for (int i = 0; i < 5 && e != RAIL_OK; i++)
        e = rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why);
    assert_int_equal(e, RAIL_OK);
    int ok = 0;
    rail_status st;
    for (int i = 0; i < 40; i++) {
        e = rail_status_poll(r, &st);
        if (e == RAIL_OK)
            ok++;
        else
            assert_true(e == RAIL_E_PROTOCOL || e == RAIL_E_TIMEOUT || e == RAIL_E_DISCONNECTED);
    }
    assert_true(ok > 25);
    rail_close(r);
    mbsim_kill(pid);
}

static void test_presets_and_probe(void **s)
{
    (void)s;
    rail_modbus_params m = rail_modbus_params_default();
    assert_int_equal(rail_modbus_preset("oriental-az", &m.map), RAIL_OK);
    assert_false(m.map.verified);
    assert_non_null(strstr(m.map.source, "HM-60262E"));
    assert_int_equal(rail_modbus_preset("no-such-drive", &m.map), RAIL_E_INVALID);
    rail_modbus_preset("oriental-az", &m.map);
    /* Unverified without opt-in: refused before any connection. */
    expect_open_fails(mb_sim_params_default(), &m, RAIL_E_UNVERIFIED, "not been verified");
    m.allow_unverified = true;
    expect_open_fails(mb_sim_params_default(), &m, RAIL_E_INVALID, "counts_per_mm");
    m.map.counts_per_mm = 400.0;
    expect_open_fails(mb_sim_params_default(), &m, RAIL_E_INVALID, "watchdog_external");
    m.watchdog_external = true;
    /* Against the simulated drive the AZ status register does not exist: the read-only probe
       fails with the drive's exception and nothing is written. */
    expect_open_fails(mb_sim_params_default(), &m, RAIL_E_DEVICE, "probe: status register");
    /* A map whose identity does not match. */
    rail_modbus_params w = rail_modbus_params_default();
    w.watchdog_s = 0.5;
    w.map.ident_value = 0x1234;
    expect_open_fails(mb_sim_params_default(), &w, RAIL_E_PROTOCOL, "wrong drive");
    /* Watchdog slower than two poll periods is refused. */
    w = rail_modbus_params_default();
    w.watchdog_s = 0.05;
    expect_open_fails(mb_sim_params_default(), &w, RAIL_E_INVALID, "watchdog_s");
}

static void test_killed_drive_disconnected(void **s)
{
    (void)s;
    int port;
    pid_t pid = mbsim_spawn(mb_sim_params_default(), &port);
    rail *r = open_drive(port, "shear");
    rail_status st;
    assert_int_equal(rail_jog(r, 10.0), RAIL_OK);
    rail_clock_sleep(rail_clock_real(), 0.2);
    mbsim_kill(pid);
    double t_kill = rail_clock_now(rail_clock_real());
    rail_err e = RAIL_OK;
    for (int i = 0; i < 100 && e == RAIL_OK; i++) {
        e = rail_status_get(r, &st);
        if (e == RAIL_OK)
            rail_clock_sleep(rail_clock_real(), 0.01);
    }
    double dt = rail_clock_now(rail_clock_real()) - t_kill;
    assert_int_equal(e, RAIL_E_DISCONNECTED);
    assert_int_equal(st.state, RAIL_STATE_DISCONNECTED);
    assert_true(dt <= 0.5);
    assert_int_equal(rail_status_poll(r, &st), RAIL_E_DISCONNECTED); /* reconnect refused */
    assert_int_equal(rail_move_abs(r, 1.0, 1.0), RAIL_E_DISCONNECTED);
    rail_close(r);
}

static void test_plain_client_and_word_order(void **s)
{
    (void)s;
    int port;
    pid_t pid = mbsim_spawn(mb_sim_params_default(), &port);
    modbus_t *c = modbus_new_tcp("127.0.0.1", port);
    assert_non_null(c);
    modbus_set_slave(c, 1);
    assert_int_equal(modbus_connect(c), 0);
    uint16_t regs[64];
    assert_int_equal(modbus_read_registers(c, 0, 64, regs), 64);
    assert_int_equal(regs[16], 0x5242);
    assert_int_equal(regs[40], 0);
    assert_int_equal(modbus_write_register(c, 14, 0), 1); /* function 6 */
    assert_int_equal(modbus_read_registers(c, 60, 5, regs), -1); /* past register 63 */
    modbus_close(c);
    modbus_free(c);
    mbsim_kill(pid);
    uint16_t w[2];
    rail_mb_put32(w, -2, RAIL_MB_HIGH_FIRST);
    assert_int_equal(w[0], 0xffff);
    assert_int_equal(w[1], 0xfffe);
    assert_int_equal(rail_mb_get32(w, RAIL_MB_HIGH_FIRST), -2);
    rail_mb_put32(w, 0x12345678, RAIL_MB_LOW_FIRST);
    assert_int_equal(w[0], 0x5678);
    assert_int_equal(rail_mb_get32(w, RAIL_MB_LOW_FIRST), 0x12345678);
}

/* The load witness: reg_load names the simulator's external load register (18); every status
 * carries it times load_scale, signed, and follows what the "load sensor" (a plain client here)
 * writes into it. Without reg_load the same drive reports no load. */
static void test_load_register_read_and_scaled(void **s)
{
    (void)s;
    int port;
    mb_sim_params sp = mb_sim_params_default();
    sp.load_counts = 1234;
    pid_t pid = mbsim_spawn(sp, &port);
    assert_true(pid > 0);
    rail *plain = open_drive(port, "plain");
    rail_status st;
    assert_int_equal(rail_status_poll(plain, &st), RAIL_OK);
    assert_false(st.has_load);
    rail_close(plain);

    rail_params p = params("shear");
    rail_modbus_params m = mparams(port);
    m.map.load = (rail_mb_reg){.addr = 18, .words = 1};
    m.map.load_scale = 0.1; /* 0.1 % of rated torque per count */
    rail *r = NULL;
    char why[300];
    assert_int_equal(rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.has_load);
    assert_true(fabs(st.load - 123.4) < 1e-9);

    modbus_t *c = modbus_new_tcp("127.0.0.1", port);
    assert_non_null(c);
    modbus_set_slave(c, 1);
    assert_int_equal(modbus_connect(c), 0);
    assert_int_equal(modbus_write_register(c, 18, (uint16_t)(int16_t)-250), 1);
    modbus_close(c);
    modbus_free(c);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.has_load);
    assert_true(fabs(st.load + 25.0) < 1e-9);
    /* Between readings the front end carries the last reading's load. */
    assert_int_equal(rail_status_get(r, &st), RAIL_OK);
    assert_true(st.has_load && fabs(st.load + 25.0) < 1e-9);
    rail_close(r);

    /* A zero scale is refused with the field named. */
    m.map.load_scale = 0.0;
    assert_int_equal(rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "load_scale"));
    mbsim_kill(pid);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sequence_two_drives),
        cmocka_unit_test(test_dead_client_watchdog_no_resume),
        cmocka_unit_test(test_home_alarm_stall),
        cmocka_unit_test(test_alarm_after_time),
        cmocka_unit_test(test_bad_replies_named),
        cmocka_unit_test(test_flaky_replies_survive),
        cmocka_unit_test(test_presets_and_probe),
        cmocka_unit_test(test_killed_drive_disconnected),
        cmocka_unit_test(test_plain_client_and_word_order),
        cmocka_unit_test(test_load_register_read_and_scaled),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
