/* test_grbl_settings.c: `$$` lines parsed, and the driver's check of a controller's settings
 * against one rail: each refusal names the setting, its value and what to set; the
 * acceleration is adopted; the rest is warned about. Pure functions, no I/O. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "grbl_settings.h"

/* GRBL 1.1's defaults, except rates and accelerations a rig would set. */
static grbl_settings rig_settings(void)
{
    grbl_settings s;
    memset(&s, 0, sizeof s);
    static const char *const lines[] = {
        "$0=10", "$1=25", "$3=0", "$10=1", "$13=0", "$20=0", "$21=0", "$22=0",
        "$110=3000.000", "$111=3000.000", "$112=500.000", "$120=200.000", "$121=200.000",
        "$122=10.000", "$130=200.000", "$131=200.000", "$132=200.000",
    };
    for (size_t i = 0; i < sizeof lines / sizeof lines[0]; i++) {
        int n = -1;
        double v = 0.0;
        assert_true(grbl_setting_line_parse(lines[i], strlen(lines[i]), &n, &v));
        grbl_settings_set(&s, n, v);
    }
    return s;
}

static rail_params rail_p(void)
{
    rail_params p = rail_params_default();
    snprintf(p.name, sizeof p.name, "shear");
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 150.0;
    p.max_speed_mm_s = 50.0;
    p.accel_mm_s2 = 200.0;
    return p;
}

static void test_line_parse(void **st)
{
    (void)st;
    int n = 0;
    double v = 0.0;
    assert_true(grbl_setting_line_parse("$110=500.000\r", 13, &n, &v));
    assert_int_equal(n, 110);
    assert_true(v == 500.0);
    assert_true(grbl_setting_line_parse("$13=1", 5, &n, &v) && n == 13 && v == 1.0);
    static const char *const bad[] = {"$13", "$=1", "$13=", "$13=1x", "13=1", "$1a=2", "$110=5\xff\x07#",
                                      "$N0=G21", "$123456=1", "ok"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        assert_false(grbl_setting_line_parse(bad[i], strlen(bad[i]), &n, &v));
}

static void test_rig_settings_pass(void **st)
{
    (void)st;
    grbl_settings s = rig_settings();
    rail_params p = rail_p();
    grbl_settings_check_out o;
    grbl_settings_check(&s, 0, &p, &o);
    assert_false(o.refuse);
    assert_true(o.accel_mm_s2 == 200.0);
    assert_false(o.homing);
    assert_non_null(strstr(o.warn, "$20=0"));
    assert_non_null(strstr(o.warn, "$21=0"));
    char buf[400];
    grbl_settings_format(&s, buf, sizeof buf);
    assert_non_null(strstr(buf, "$0=10 $1=25 $3=0 $10=1 $13=0"));
    assert_non_null(strstr(buf, "$132=200"));
}

static void test_inches_refused(void **st)
{
    (void)st;
    grbl_settings s = rig_settings();
    grbl_settings_set(&s, 13, 1.0);
    rail_params p = rail_p();
    grbl_settings_check_out o;
    grbl_settings_check(&s, 0, &p, &o);
    assert_true(o.refuse);
    assert_non_null(strstr(o.refuse_why, "rail 'shear'"));
    assert_non_null(strstr(o.refuse_why, "$13=1"));
    assert_non_null(strstr(o.refuse_why, "set $13=0"));
}

static void test_rate_per_axis(void **st)
{
    (void)st;
    grbl_settings s = rig_settings();
    rail_params p = rail_p();
    grbl_settings_check_out o;
    grbl_settings_check(&s, 2, &p, &o); /* Z: $112 = 500 mm/min < 50 mm/s */
    assert_true(o.refuse);
    assert_non_null(strstr(o.refuse_why, "$112=500"));
    assert_non_null(strstr(o.refuse_why, "set $112=3000"));
    assert_non_null(strstr(o.refuse_why, "max_speed_mm_s = 8.33333"));
    p.max_speed_mm_s = 500.0 / 60.0;
    grbl_settings_check(&s, 2, &p, &o);
    assert_false(o.refuse);
    assert_true(o.accel_mm_s2 == 10.0); /* $122 adopted */
    assert_non_null(strstr(o.warn, "$122=10"));
}

static void test_missing_setting_refused(void **st)
{
    (void)st;
    grbl_settings s = rig_settings();
    s.have[111] = false;
    rail_params p = rail_p();
    grbl_settings_check_out o;
    grbl_settings_check(&s, 1, &p, &o);
    assert_true(o.refuse);
    assert_non_null(strstr(o.refuse_why, "no $111"));
    grbl_settings empty;
    memset(&empty, 0, sizeof empty);
    grbl_settings_check(&empty, 0, &p, &o);
    assert_true(o.refuse);
    assert_non_null(strstr(o.refuse_why, "no $13"));
}

static void test_work_pos_homing_and_travel(void **st)
{
    (void)st;
    grbl_settings s = rig_settings();
    grbl_settings_set(&s, 10, 2.0); /* WPos, with buffer data */
    grbl_settings_set(&s, 20, 1.0);
    grbl_settings_set(&s, 22, 1.0);
    grbl_settings_set(&s, 130, 100.0);
    rail_params p = rail_p();
    grbl_settings_check_out o;
    grbl_settings_check(&s, 0, &p, &o);
    assert_false(o.refuse);
    assert_true(o.work_pos && o.homing);
    assert_non_null(strstr(o.warn, "$10=2"));
    assert_non_null(strstr(o.warn, "$130=100"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_line_parse),
        cmocka_unit_test(test_rig_settings_pass),
        cmocka_unit_test(test_inches_refused),
        cmocka_unit_test(test_rate_per_axis),
        cmocka_unit_test(test_missing_setting_refused),
        cmocka_unit_test(test_work_pos_homing_and_travel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
