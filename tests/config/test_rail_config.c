/* test_rail_config.c: rail sections of rig INI files load into driver parameters; presets
 * apply before register overrides whatever the key order; bad values, unknown keys and missing
 * sections are refused naming file, line and key. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include <stdio.h>
#include <unistd.h>

#include "grblsim_spawn.h"
#include "rail_config.h"

static void expect_fail(const char *text, const char *rail, const char *needle)
{
    rail_config rc;
    char why[400] = "";
    assert_int_not_equal(rail_config_load_string(text, "rig.ini", rail, &rc, why, sizeof why), CFG_OK);
    if (!strstr(why, needle)) {
        print_error("reason '%s' lacks '%s'\n", why, needle);
        fail();
    }
}

static void test_load_gcode_and_modbus(void **s)
{
    (void)s;
    const char *text = "[rig]\nname = bench\n"
                       "[rail.compress]\ndriver = gcode\nport = /dev/ttyACM0\naxis = X\n"
                       "soft_min_mm = 0\nsoft_max_mm = 80\nmax_speed_mm_s = 5\nmin_gap_mm = 20\n"
                       "gap_at_zero_mm = 100\ngap_per_mm = -1\nsegment_s = 0.25\n"
                       "[rail.shear]\ndriver = modbus\naddress = 10.0.0.5:502\nslave = 3\n"
                       "reg_status = 0x20/1\nmap = ribbon-sim\ncounts_per_mm = 200\n"
                       "word_order = low_first\n";
    rail_config rc;
    char why[400] = "";
    assert_int_equal(rail_config_load_string(text, "rig.ini", "compress", &rc, why, sizeof why), 0);
    assert_string_equal(rc.driver, "gcode");
    assert_string_equal(rc.gcode.port, "/dev/ttyACM0");
    assert_string_equal(rc.params.name, "compress");
    assert_true(rc.params.soft_max_mm == 80.0 && rc.params.min_gap_mm == 20.0);
    assert_true(rc.params.gap_per_mm == -1.0 && rc.gcode.segment_s == 0.25);
    assert_int_equal(rail_config_load_string(text, "rig.ini", "shear", &rc, why, sizeof why), 0);
    assert_string_equal(rc.driver, "modbus");
    assert_int_equal(rc.modbus.slave, 3);
    assert_int_equal(rc.modbus.map.status.addr, 0x20); /* override kept although map came later */
    assert_int_equal(rc.modbus.map.status.words, 1);
    assert_int_equal(rc.modbus.map.actual_pos.addr, 8);
    assert_true(rc.modbus.map.counts_per_mm == 200.0);
    assert_int_equal(rc.modbus.map.word_order, RAIL_MB_LOW_FIRST);
}

static void test_errors_named(void **s)
{
    (void)s;
    expect_fail("[rail.shear]\ndriver = mock\nmax_speed_mm_s = fast\n", "shear",
                "rig.ini:3: [rail.shear] max_speed_mm_s: 'fast' is not a number");
    expect_fail("[rail.shear]\nspeeed = 3\n", "shear", "rig.ini:2: [rail.shear] speeed: unknown key");
    expect_fail("[rail.shear]\nmax_speed_mm_s = 5000\n", "shear", "outside");
    expect_fail("[rail.compress]\ndriver = mock\n", "shear", "no section [rail.shear]");
    expect_fail("[rail.shear]\ndriver = stepper\n", "shear", "driver: 'stepper'");
    expect_fail("[rail.shear]\nmap = acme\n", "shear", "rig.ini:2: [rail.shear] map: unknown preset");
    expect_fail("[rail.shear]\nsoft_min_mm = 5\nsoft_max_mm = 1\n", "shear", "soft_min_mm");
    expect_fail("[rail.shear]\ndriver = modbus\nreg_status = -1\n", "shear", "status is required");
    expect_fail("[rail.shear]\nreg_speed = 12/3\n", "shear", "ADDR/2");
    expect_fail("[rail.shear]\n", "sideways", "not compress or shear");
}

/* Switches are spelled on | off, as in the rest of a rig file; every key has a unit and a doc. */
static void test_switches_and_key_table(void **s)
{
    (void)s;
    rail_config rc;
    char why[400] = "";
    assert_int_equal(rail_config_load_string("[rail.shear]\ndriver = modbus\nrtu = on\n"
                                             "watchdog_external = off\nallow_unverified = on\n",
                                             "rig.ini", "shear", &rc, why, sizeof why),
                     CFG_OK);
    assert_true(rc.modbus.rtu && rc.modbus.allow_unverified && !rc.modbus.watchdog_external);
    assert_int_equal(rail_config_load_string("[rail.shear]\nrtu = true\n", "rig.ini", "shear", &rc,
                                             why, sizeof why),
                     CFG_ERR_VALUE);
    assert_non_null(strstr(why, "rig.ini:2: [rail.shear] rtu: 'true' is not on or off"));
    assert_int_equal(rail_config_load_string("[rail.shear]\nmax_speed_mm_s = 5000\n", "rig.ini",
                                             "shear", &rc, why, sizeof why),
                     CFG_ERR_RANGE);
    size_t n = 0;
    const rail_key *k = rail_config_keys(&n);
    assert_true(n > 50);
    for (size_t i = 0; i < n; i++) {
        assert_string_equal(k[i].name, rail_config_key_name(i));
        assert_true(k[i].unit && k[i].unit[0] && k[i].doc && k[i].doc[0]);
    }
    assert_null(rail_config_key_name(n));
}

static void test_missing_file(void **s)
{
    (void)s;
    rail_config rc;
    char why[400];
    assert_int_equal(rail_config_load("/nonexistent/rig.ini", "shear", &rc, why, sizeof why), CFG_ERR_IO);
    assert_non_null(strstr(why, "/nonexistent/rig.ini: cannot read"));
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs(text, f);
    fclose(f);
}

static void test_open_rig_shared_controller(void **s)
{
    (void)s;
    char pty[128], rig[128], text[1024], why[400];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, pty, sizeof pty);
    snprintf(rig, sizeof rig, "/tmp/ribbon-test-rig-%d.ini", (int)getpid());
    snprintf(text, sizeof text,
             "[rail.compress]\ndriver = gcode\nport = %s\naxis = X\nmax_speed_mm_s = 20\npoll_hz = 20\n"
             "[rail.shear]\ndriver = gcode\nport = %s\naxis = Y\nmax_speed_mm_s = 20\npoll_hz = 20\n",
             pty, pty);
    write_file(rig, text);
    rail *c = NULL, *sh = NULL;
    rail_err e = rail_config_open_rig(rig, rail_clock_real(), &c, &sh, why, sizeof why);
    if (e != RAIL_OK)
        print_error("%s\n", why);
    assert_int_equal(e, RAIL_OK);
    rail_status st;
    assert_int_equal(rail_move_abs(c, 2.0, 20.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(c, 3.0, &st), RAIL_OK);
    assert_int_equal(rail_move_abs(sh, 1.0, 20.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(sh, 3.0, &st), RAIL_OK);
    assert_true(fabs(st.position_mm - 1.0) < 1e-3);
    assert_int_equal(rail_status_poll(c, &st), RAIL_OK);
    assert_true(fabs(st.position_mm - 2.0) < 1e-3);
    rail_close(c);
    rail_close(sh);
    /* Both rails on the same axis of one controller is refused. */
    snprintf(text, sizeof text,
             "[rail.compress]\ndriver = gcode\nport = %s\naxis = X\n[rail.shear]\ndriver = gcode\n"
             "port = %s\naxis = X\n", pty, pty);
    write_file(rig, text);
    assert_int_equal(rail_config_open_rig(rig, rail_clock_real(), &c, &sh, why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "both rails are axis X"));
    assert_null(c);
    /* Mock faults from the file. */
    write_file(rig, "[rail.compress]\ndriver = mock\nstall_at_mm = 3\n[rail.shear]\ndriver = mock\n");
    assert_int_equal(rail_config_open_rig(rig, rail_clock_real(), &c, &sh, why, sizeof why), RAIL_OK);
    rail_close(c);
    rail_close(sh);
    unlink(rig);
    grblsim_kill(pid);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_load_gcode_and_modbus),
        cmocka_unit_test(test_errors_named),
        cmocka_unit_test(test_switches_and_key_table),
        cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_open_rig_shared_controller),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
