/* test_cfg_number.c: the one number grammar of outside numbers (config/cfg_number.h): plain
 * decimal accepted with its value exact to strtod's; hex floats, inf, nan, bare signs and dots,
 * dangling exponents refused with the right status (issue 17, defect 11: "0x1p1" was 2). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "cfg_number.h"

static void test_plain_decimal(void **s)
{
    (void)s;
    static const char *const ok[] = {"0", "-0", "+1", "1.", ".5", "-.5", "1e3", "1E-3", "2.5e+2",
                                     "  7\t", "123456789012345678901234567890", "2.3e-308"};
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; i++) {
        double v = NAN;
        assert_int_equal(cfg_number_parse(ok[i], &v), CFG_NUMBER_OK);
        assert_true(v == strtod(ok[i], NULL));
    }
}

static void test_refused(void **s)
{
    (void)s;
    static const struct {
        const char *text;
        cfg_number_status st;
    } bad[] = {
        {"0x1p1", CFG_NUMBER_NOT_DECIMAL}, {"0X10", CFG_NUMBER_NOT_DECIMAL},
        {"-0x1p-1", CFG_NUMBER_NOT_DECIMAL}, {"", CFG_NUMBER_NOT_DECIMAL},
        {"+", CFG_NUMBER_NOT_DECIMAL},     {".", CFG_NUMBER_NOT_DECIMAL},
        {"-.", CFG_NUMBER_NOT_DECIMAL},    {"e5", CFG_NUMBER_NOT_DECIMAL},
        {"1e", CFG_NUMBER_NOT_DECIMAL},    {"1e+", CFG_NUMBER_NOT_DECIMAL},
        {"abc", CFG_NUMBER_NOT_DECIMAL},   {"inf", CFG_NUMBER_NOT_FINITE},
        {"-Infinity", CFG_NUMBER_NOT_FINITE}, {"nan", CFG_NUMBER_NOT_FINITE},
        {"NAN(123)", CFG_NUMBER_NOT_FINITE}, {"1e999", CFG_NUMBER_NOT_FINITE},
        {"1 2", CFG_NUMBER_TRAILING},      {"2m", CFG_NUMBER_TRAILING},
        {"1.5.2", CFG_NUMBER_TRAILING},    {"1e-310", CFG_NUMBER_SUBNORMAL},
        {"-4.9e-324", CFG_NUMBER_SUBNORMAL},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        double v = 42.0;
        cfg_number_status st = cfg_number_parse(bad[i].text, &v);
        if (st != bad[i].st) print_error("'%s': status %d, expected %d\n", bad[i].text, st, bad[i].st);
        assert_int_equal(st, bad[i].st);
        assert_true(v == 42.0); /* untouched */
    }
    double v;
    assert_int_not_equal(cfg_number_parse(NULL, &v), CFG_NUMBER_OK);
}

static void test_strtod_shape_and_range(void **s)
{
    (void)s;
    char *end;
    const char *t = "0x1p1";
    assert_true(cfg_number_strtod(t, &end) == 0.0 && end == t);
    t = "2.5,3";
    assert_true(cfg_number_strtod(t, &end) == 2.5 && *end == ',');
    double a, b;
    int n;
    assert_int_equal(cfg_number_range("0.1:0.4:7", &a, &b, &n, 64), 0);
    assert_true(a == 0.1 && b == 0.4 && n == 7);
    assert_int_equal(cfg_number_range("0x1:2:3", &a, &b, &n, 64), -1);
    assert_int_equal(cfg_number_range("1:2:0", &a, &b, &n, 64), -1);
    assert_int_equal(cfg_number_range("1:2:65", &a, &b, &n, 64), -1);
    assert_int_equal(cfg_number_range("1:2:3x", &a, &b, &n, 64), -1);
    assert_int_equal(cfg_number_range("1:2:3.0", &a, &b, &n, 64), -1);
    assert_int_equal(cfg_number_range("1:inf:3", &a, &b, &n, 64), -1);
    /* A reversed range (issue 33, item 9) is its own refusal, so callers can say so. */
    assert_int_equal(cfg_number_range("0.30:0.05:6", &a, &b, &n, 64), -2);
    assert_int_equal(cfg_number_range("0.05:0.05:1", &a, &b, &n, 64), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plain_decimal),
        cmocka_unit_test(test_refused),
        cmocka_unit_test(test_strtod_shape_and_range),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
