/* test_grbl_proto.c: GRBL status reports and reply lines are parsed exactly, malformed ones are
 * refused with a reason naming the byte, and random or mutated input never crashes the parser
 * (a deterministic in-test fuzz loop; fuzz/fuzz_grbl_status.c is the libFuzzer target). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "grbl_proto.h"

static void test_status_idle(void **s)
{
    (void)s;
    grbl_report r;
    char why[200];
    const char *l = "<Idle|MPos:10.000,-2.500,0.000|FS:0,0>";
    assert_true(grbl_status_parse(l, strlen(l), &r, why, sizeof why));
    assert_int_equal(r.state, GRBL_IDLE);
    assert_true(r.pos[0] == 10.0 && r.pos[1] == -2.5 && r.pos[2] == 0.0);
    assert_int_equal(r.n_axes, 3);
    assert_true(r.feed_mm_min == 0.0);
}

static void test_status_variants(void **s)
{
    (void)s;
    grbl_report r;
    char why[200];
    const char *a = "<Hold:1|MPos:1.000,2.000,3.000|Bf:15,128|FS:500,0|Pn:XY|Ov:100,100,100>\r\n";
    assert_true(grbl_status_parse(a, strlen(a), &r, why, sizeof why));
    assert_int_equal(r.state, GRBL_HOLD);
    assert_int_equal(r.substate, 1);
    assert_int_equal(r.buffer_blocks, 15);
    assert_true(r.feed_mm_min == 500.0);
    const char *b = "<Jog|WPos:1.000,2.000,3.000|F:120|WCO:10.000,0.000,0.000>";
    assert_true(grbl_status_parse(b, strlen(b), &r, why, sizeof why));
    assert_int_equal(r.state, GRBL_JOG);
    assert_true(r.pos[0] == 11.0 && r.pos[1] == 2.0);
    assert_true(r.work_pos && r.have_wco && r.wco[0] == 10.0);
    const char *w = "<Idle|WPos:1.000,2.000,3.000|FS:0,0>"; /* no WCO in this one */
    assert_true(grbl_status_parse(w, strlen(w), &r, why, sizeof why));
    assert_true(r.work_pos && !r.have_wco && r.pos[0] == 1.0);
    const char *c = "<Door:2|MPos:0,0|FS:0,0>";
    assert_true(grbl_status_parse(c, strlen(c), &r, why, sizeof why));
    assert_int_equal(r.state, GRBL_DOOR);
    assert_int_equal(r.n_axes, 2);
    const char *names[] = {"<Run|MPos:0,0,0>", "<Alarm|MPos:0,0,0>", "<Home|MPos:0,0,0>",
                           "<Check|MPos:0,0,0>", "<Sleep|MPos:0,0,0>"};
    grbl_state want[] = {GRBL_RUN, GRBL_ALARM, GRBL_HOME, GRBL_CHECK, GRBL_SLEEP};
    for (int i = 0; i < 5; i++) {
        assert_true(grbl_status_parse(names[i], strlen(names[i]), &r, why, sizeof why));
        assert_int_equal(r.state, want[i]);
    }
}

static void expect_bad(const char *line, const char *needle)
{
    grbl_report r;
    char why[200] = "";
    assert_false(grbl_status_parse(line, strlen(line), &r, why, sizeof why));
    if (!strstr(why, needle)) {
        print_error("reason '%s' lacks '%s'\n", why, needle);
        fail();
    }
}

static void test_status_malformed(void **s)
{
    (void)s;
    expect_bad("Idle|MPos:0,0,0>", "expected '<' at byte 0");
    expect_bad("<Idle|MPos:0,0,0", "truncated");
    expect_bad("<Walk|MPos:0,0,0>", "unknown state");
    expect_bad("<Idle|MPos:1.0,x,0>", "bad position number at byte 15");
    expect_bad("<Idle|MPos:1,2,3,4>", "bad position number");
    expect_bad("<Idle|FS:0,0>", "without MPos");
    expect_bad("<Idle||MPos:0,0,0>", "empty field");
    expect_bad("<Hold:x|MPos:0,0,0>", "bad substate");
    expect_bad("<Idle|MPos:1e99,0,0>", "bad position number");
    expect_bad("<Idle|FS:-5,0|MPos:0,0,0>", "bad feed");
    expect_bad("", "expected '<'");
}

static void test_line_classify(void **s)
{
    (void)s;
    int code;
    assert_int_equal(grbl_line_classify("ok", 2, &code), GRBL_LINE_OK);
    assert_int_equal(grbl_line_classify("ok\r", 3, &code), GRBL_LINE_OK);
    assert_int_equal(grbl_line_classify("error:15", 8, &code), GRBL_LINE_ERROR);
    assert_int_equal(code, 15);
    assert_int_equal(grbl_line_classify("error:x", 7, &code), GRBL_LINE_ERROR);
    assert_int_equal(code, -1);
    assert_int_equal(grbl_line_classify("ALARM:3", 7, &code), GRBL_LINE_ALARM);
    assert_int_equal(code, 3);
    assert_int_equal(grbl_line_classify("Grbl 1.1h ['$' for help]", 24, &code), GRBL_LINE_WELCOME);
    assert_int_equal(grbl_line_classify("[MSG:Caution: Unlocked]", 23, &code), GRBL_LINE_MESSAGE);
    assert_int_equal(grbl_line_classify("okay", 4, &code), GRBL_LINE_OTHER);
    assert_int_equal(grbl_line_classify("", 0, &code), GRBL_LINE_EMPTY);
    assert_string_equal(grbl_error_text(15), "jog target exceeds machine travel; jog ignored");
    assert_string_equal(grbl_alarm_text(99), "unknown GRBL alarm");
}

static uint32_t xs(uint32_t *st)
{
    uint32_t x = *st;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *st = x;
}

static void test_fuzz_no_crash(void **s)
{
    (void)s;
    const char *seed = "<Hold:1|MPos:1.000,2.000,3.000|Bf:15,128|FS:500,0|WCO:1,2,3>";
    size_t L = strlen(seed);
    char buf[128];
    uint32_t st = 2463534242u;
    grbl_report r;
    char why[200];
    int ok = 0;
    for (int it = 0; it < 20000; it++) {
        size_t n = xs(&st) % (L + 8);
        if (it % 2) {
            for (size_t i = 0; i < n; i++)
                buf[i] = (char)(xs(&st) & 0xff);
        } else {
            memcpy(buf, seed, n < L ? n : L);
            for (size_t i = L; i < n; i++)
                buf[i] = ',';
            for (int m = 0; m < 3; m++)
                buf[xs(&st) % (n ? n : 1)] = "<>|:,.-0123456789MPosFS"[xs(&st) % 23];
        }
        if (grbl_status_parse(buf, n, &r, why, sizeof why)) {
            ok++;
            for (int i = 0; i < GRBL_MAX_AXES; i++)
                assert_true(isfinite(r.pos[i]));
        } else {
            assert_true(why[0] != 0);
        }
        int code;
        grbl_line_classify(buf, n, &code);
    }
    assert_true(ok > 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_status_idle),    cmocka_unit_test(test_status_variants),
        cmocka_unit_test(test_status_malformed), cmocka_unit_test(test_line_classify),
        cmocka_unit_test(test_fuzz_no_crash),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
