/* test_rail_gcode_freeze.c: a G-code rail whose process freezes in the middle of a move must not
 * start the rail again by itself (house rule; issue 33 item 2 left one window open).
 *
 * The freeze is real: the rail runs on a clock whose next reading sleeps (1 s) when the test arms
 * it, so the process stands exactly there while ribbon-grblsim's engine, on its own process, runs
 * out of jog segments and stops. Two places: inside one poll, after the status report came in and
 * before the top-up (the driver reads the rail clock once before it asks for the report and next
 * right after the report), and between two polls. Either way the next top-up would rest on a
 * report older than the poll period plus RAIL_CLOCK_JUMP_S: the driver must cancel the jog and
 * fault instead (in that poll or, when no segment was due in it, the next), and the rail must
 * stand. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "grblsim_spawn.h"
#include "rail_gcode.h"

typedef struct freeze_clock {
    int arm;          /* the arm-th reading from now sleeps freeze_s first (0 = none) */
    double freeze_s;  /* s */
} freeze_clock;

static double fc_now(void *ctx)
{
    freeze_clock *f = ctx;
    if (f->arm > 0 && --f->arm == 0)
        rail_clock_sleep(rail_clock_real(), f->freeze_s);
    return rail_clock_now(rail_clock_real());
}

static void fc_sleep(void *ctx, double s)
{
    (void)ctx;
    rail_clock_sleep(rail_clock_real(), s);
}

static rail *open_frozen(const char *path, freeze_clock *f)
{
    rail_params p = rail_params_default();
    snprintf(p.name, sizeof p.name, "shear");
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 150.0;
    p.max_speed_mm_s = 50.0;
    p.accel_mm_s2 = 200.0;
    p.poll_hz = 20.0;
    rail_gcode_params g = rail_gcode_params_default();
    snprintf(g.port, sizeof g.port, "%s", path);
    g.axis = 'X';
    g.segment_s = 0.2;
    g.segments_ahead = 2; /* 0.4 s of segments ahead: a 1 s freeze starves the controller */
    g.stall_timeout_s = 2.0;
    rail_clock ck = {.now = fc_now, .sleep = fc_sleep, .ctx = f};
    rail *r = NULL;
    char why[300];
    rail_err e = rail_gcode_open(&r, &p, &g, NULL, ck, why, sizeof why);
    if (e != RAIL_OK)
        print_error("open: %s\n", why);
    assert_int_equal(e, RAIL_OK);
    return r;
}

/* Starts a long move and polls it at 20 Hz for 0.4 s (a healthy stream). */
static void start_moving(rail *r)
{
    rail_status st;
    assert_int_equal(rail_move_abs(r, 120.0, 20.0), RAIL_OK);
    for (int i = 0; i < 8; i++) {
        rail_clock_sleep(rail_clock_real(), 0.05);
        assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
        assert_int_equal(st.state, RAIL_STATE_MOVING);
    }
}

/* After the freeze, polled on at 20 Hz as a healthy front end does: within two polls the rail is a
 * fault naming the clock jump, and it stands (two fresh readings 0.4 s apart, taken well after
 * the controller's queued segments ran out, agree). */
static void assert_stands_faulted(rail *r, rail_status st)
{
    for (int i = 0; i < 2 && st.state == RAIL_STATE_MOVING; i++) {
        rail_clock_sleep(rail_clock_real(), 0.05);
        rail_status_poll(r, &st);
    }
    if (st.state != RAIL_STATE_FAULT)
        print_message("after the freeze: state %s, '%s'\n", rail_state_name(st.state), st.message);
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    assert_non_null(strstr(st.message, "clock jumped"));
    print_message("%s\n", st.message);
    rail_status a, b;
    rail_clock_sleep(rail_clock_real(), 0.3);
    rail_status_poll(r, &a);
    rail_clock_sleep(rail_clock_real(), 0.4);
    rail_status_poll(r, &b);
    print_message("after the freeze: %.3f mm, then %.3f mm 0.4 s later\n", a.position_mm, b.position_mm);
    assert_true(fabs(b.position_mm - a.position_mm) < 1e-3);
    assert_int_equal(b.state, RAIL_STATE_FAULT);
    /* A move is refused until the fault is reset. */
    assert_int_equal(rail_move_abs(r, 100.0, 20.0), RAIL_E_STATE);
}

static void test_freeze_inside_poll_before_top_up(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    assert_true(pid > 0);
    freeze_clock f = {0, 1.0};
    rail *r = open_frozen(path, &f);
    start_moving(r);
    rail_status st;
    f.arm = 2; /* the second rail-clock reading of the next poll: after its report, before the top-up */
    rail_status_poll(r, &st);
    assert_int_equal(f.arm, 0);
    assert_stands_faulted(r, st);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_freeze_between_polls(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    assert_true(pid > 0);
    freeze_clock f = {0, 1.0};
    rail *r = open_frozen(path, &f);
    start_moving(r);
    rail_clock_sleep(rail_clock_real(), 1.0); /* frozen between two polls */
    rail_status st;
    rail_status_poll(r, &st);
    assert_stands_faulted(r, st);
    rail_close(r);
    grblsim_kill(pid);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_freeze_inside_poll_before_top_up),
        cmocka_unit_test(test_freeze_between_polls),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
