/* test_rail_gcode_grbl.c: the G-code driver against GRBL as GRBL 1.1 documents itself (issue 34,
 * part A), on ribbon-grblsim's engine: the controller's settings read at open and checked
 * ($13=1 inches refused: the repro read 0.3937 mm for 10 mm and drove the wrong way; a
 * rig speed above the max rate $110 refused; $120 adopted), the simulator's own `$N=V` error
 * codes, the wait for a board that resets when its port opens (banner after a bootloader
 * delay), and a reset at any time (mid-move, or of the idle rail's controller during a trial)
 * stopping both rails and refusing motion until the zero is confirmed or the axis homed.
 * Real clock; every case runs in well under two seconds. */
#include <fcntl.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "grblsim_spawn.h"
#include "grbl_link.h"
#include "rail_gcode.h"
#include "rail_pair.h"

#define NEAR(a, b, tol) assert_true(fabs((a) - (b)) <= (tol))

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

static rail_gcode_params gparams(const char *path, char axis)
{
    rail_gcode_params g = rail_gcode_params_default();
    snprintf(g.port, sizeof g.port, "%s", path);
    g.axis = axis;
    g.segment_s = 0.2;
    g.stall_timeout_s = 0.5;
    return g;
}

static rail_err try_open(const char *path, const rail_params *p, rail **r, char *why, size_t n)
{
    rail_gcode_params g = gparams(path, 'X');
    return rail_gcode_open(r, p, &g, NULL, rail_clock_real(), why, n);
}

/* The repro: $13=1, the axis at 10 mm. GRBL says 0.3937 (inches); the rail refuses. */
static void test_inches_refused(void **s)
{
    (void)s;
    char path[128], why[600];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.start_mm[0] = 10.0;
    snprintf(sp.settings, sizeof sp.settings, "$13=1");
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    assert_true(pid > 0);
    /* What the controller really reports (the link does not convert). */
    rail_gcode_params g = gparams(path, 'X');
    grbl_link *l = NULL;
    assert_int_equal(grbl_link_open(&l, &g, rail_clock_real(), why, sizeof why), RAIL_OK);
    grbl_report rep;
    assert_int_equal(grbl_link_status(l, &rep), RAIL_OK);
    NEAR(rep.pos[0], 10.0 / 25.4, 1e-4);
    assert_true(l->settings.have[13] && l->settings.v[13] == 1.0);
    grbl_link_release(l);
    /* The rail refuses it, naming the setting, its value and what to set. */
    rail_params p = params("compress");
    rail *r = NULL;
    assert_int_equal(try_open(path, &p, &r, why, sizeof why), RAIL_E_DEVICE);
    assert_null(r);
    assert_non_null(strstr(why, "$13=1"));
    assert_non_null(strstr(why, "set $13=0"));
    assert_non_null(strstr(why, "inches"));
    grblsim_kill(pid);
}

static void test_speed_above_max_rate_refused(void **s)
{
    (void)s;
    char path[128], why[600];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.max_feed_mm_min = 1200.0; /* $110 = 20 mm/s */
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_params p = params("shear"); /* max_speed_mm_s = 50 */
    rail *r = NULL;
    assert_int_equal(try_open(path, &p, &r, why, sizeof why), RAIL_E_DEVICE);
    assert_non_null(strstr(why, "$110=1200"));
    assert_non_null(strstr(why, "max_speed_mm_s = 50"));
    assert_non_null(strstr(why, "set $110=3000"));
    p.max_speed_mm_s = 20.0; /* at the limit: accepted */
    assert_int_equal(try_open(path, &p, &r, why, sizeof why), RAIL_OK);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_accel_adopted_and_settings_described(void **s)
{
    (void)s;
    char path[128], why[600];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.accel_mm_s2 = 100.0; /* $120 */
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_params p = params("shear"); /* accel_mm_s2 = 200 */
    rail *r = NULL;
    assert_int_equal(try_open(path, &p, &r, why, sizeof why), RAIL_OK);
    assert_true(rail_get_params(r)->accel_mm_s2 == 100.0);
    assert_non_null(strstr(rail_gcode_warnings(r), "$120=100"));
    assert_non_null(strstr(rail_gcode_warnings(r), "$20=0")); /* soft limits off: warned */
    char d[2000];
    rail_gcode_describe(r, d, sizeof d);
    assert_non_null(strstr(d, "$13=0"));
    assert_non_null(strstr(d, "$110=3000"));
    assert_non_null(strstr(d, "$132=200"));
    assert_non_null(strstr(d, "reset on open: no"));
    rail_close(r);
    grblsim_kill(pid);
}

/* The simulator's settings as GRBL documents them: defaults, `$N=V` and its error codes. */
static void test_sim_settings_commands(void **s)
{
    (void)s;
    char path[128], why[600];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_gcode_params g = gparams(path, 'X');
    grbl_link *l = NULL;
    assert_int_equal(grbl_link_open(&l, &g, rail_clock_real(), why, sizeof why), RAIL_OK);
    assert_int_equal(l->settings.count, 34); /* $0-$6, $10-$13, $20-$27, $30-$32, $100-$132 */
    assert_true(l->settings.v[0] == 10 && l->settings.v[1] == 25 && l->settings.v[100] == 250.0);
    assert_true(l->settings.v[10] == 1 && l->settings.v[13] == 0 && l->settings.v[22] == 0);
    int code = 0;
    assert_int_equal(grbl_link_send(l, "$13=1", &code), RAIL_OK);
    assert_int_equal(grbl_link_send(l, "$13=0", &code), RAIL_OK);
    static const struct { const char *cmd; int code; } bad[] = {
        {"$99=1", 3},    /* no such setting */
        {"$110=x", 2},   /* bad number */
        {"$110=-5", 4},  /* negative */
        {"$0=2", 6},     /* step pulse below 3 us */
        {"$20=1", 10},   /* soft limits without homing */
        {"$H", 5},       /* homing disabled */
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(grbl_link_send(l, bad[i].cmd, &code), RAIL_E_DEVICE);
        assert_int_equal(code, bad[i].code);
    }
    assert_int_equal(grbl_link_send(l, "$22=1", &code), RAIL_OK);
    assert_int_equal(grbl_link_send(l, "$20=1", &code), RAIL_OK);
    assert_int_equal(grbl_link_read_settings(l), RAIL_OK);
    assert_true(l->settings.v[20] == 1 && l->settings.v[22] == 1);
    assert_int_equal(grbl_link_send(l, "$22=0", &code), RAIL_OK); /* also clears $20 */
    assert_int_equal(grbl_link_read_settings(l), RAIL_OK);
    assert_true(l->settings.v[20] == 0);
    grbl_link_release(l);
    grblsim_kill(pid);
}

/* An Arduino resets when its port opens: no answer during the bootloader (1 s here, as
   Optiboot), then the banner. The open waits for it, and the position is not trusted. */
static void test_banner_wait_on_reset_at_open(void **s)
{
    (void)s;
    char path[128], why[600];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.reset_on_open = true;
    sp.reset_delay_s = 1.0;
    sp.start_mm[0] = 10.0;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_params p = params("compress");
    rail *r = NULL;
    double t0 = rail_clock_now(rail_clock_real());
    assert_int_equal(try_open(path, &p, &r, why, sizeof why), RAIL_OK);
    double waited = rail_clock_now(rail_clock_real()) - t0;
    assert_true(waited >= 0.9 && waited < 2.5);
    rail_status st;
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    assert_true(st.position_mm == 0.0); /* GRBL counts from zero where the axis stood */
    assert_non_null(strstr(st.message, "reset when the port opened"));
    assert_non_null(strstr(st.message, "confirm-zero --confirm"));
    assert_int_equal(rail_move_abs(r, 5.0, 20.0), RAIL_E_STATE);
    assert_non_null(strstr(rail_last_error(r), "not trusted"));
    assert_int_equal(rail_stop(r), RAIL_OK); /* a stop after the refusal clears nothing */
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    char d[2000];
    rail_gcode_describe(r, d, sizeof d);
    assert_non_null(strstr(d, "reset on open: yes"));
    assert_int_equal(rail_gcode_confirm_zero(r, false), RAIL_E_CONFIRM);
    assert_int_equal(rail_gcode_confirm_zero(r, true), RAIL_OK);
    assert_int_equal(rail_move_abs(r, 2.0, 20.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 3.0, &st), RAIL_OK);
    NEAR(st.position_mm, 2.0, 1e-3);
    rail_close(r);
    /* A boot wait shorter than the bootloader: refused, naming the wait. */
    rail_gcode_params g = gparams(path, 'X');
    g.boot_wait_s = 0.3;
    assert_int_equal(rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why), RAIL_E_TIMEOUT);
    assert_non_null(strstr(why, "boot_wait_s = 0.30"));
    grblsim_kill(pid);
}

/* The controller of the idle compression rail resets in the middle of a shear (its reset line
   pulsed: here another process opening its port): the pair stops the shear and names why; the
   shear's controller is fine, the compression rail refuses motion until its zero is confirmed. */
static void test_reset_during_trial_stops_both(void **s)
{
    (void)s;
    char pa[128], pb[128], why[600];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.reset_on_open = true;
    sp.reset_delay_s = 0.1;
    sp.start_mm[0] = 12.0;
    pid_t a = grblsim_spawn(&sp, pa, sizeof pa);
    grbl_sim_params sq = grbl_sim_params_default();
    pid_t b = grblsim_spawn(&sq, pb, sizeof pb);
    rail_params pc = params("compress"), ps = params("shear");
    rail *comp = NULL, *shear = NULL;
    assert_int_equal(try_open(pa, &pc, &comp, why, sizeof why), RAIL_OK);
    assert_int_equal(rail_gcode_confirm_zero(comp, true), RAIL_OK); /* a reset at open */
    assert_int_equal(try_open(pb, &ps, &shear, why, sizeof why), RAIL_OK);
    rail_status sc, ss;
    assert_int_equal(rail_move_abs(shear, 100.0, 20.0), RAIL_OK);
    for (int i = 0; i < 10; i++) {
        assert_int_equal(rail_pair_poll(comp, shear, &sc, &ss, why, sizeof why), RAIL_OK);
        rail_clock_sleep(rail_clock_real(), 0.03);
    }
    assert_int_equal(ss.state, RAIL_STATE_MOVING);
    int fd = open(pa, O_RDWR | O_NOCTTY); /* DTR: the compression controller resets */
    assert_true(fd >= 0);
    close(fd);
    rail_err e = RAIL_OK;
    for (int i = 0; i < 40 && e == RAIL_OK; i++) {
        rail_clock_sleep(rail_clock_real(), 0.03);
        e = rail_pair_poll(comp, shear, &sc, &ss, why, sizeof why);
    }
    assert_int_not_equal(e, RAIL_OK);
    assert_non_null(strstr(why, "compress"));
    assert_non_null(strstr(why, "restarted"));
    /* Both at rest: the shear stopped, the compression rail never moved. */
    rail_clock_sleep(rail_clock_real(), 0.5);
    double p1 = 0.0;
    assert_int_equal(rail_status_poll(shear, &ss), RAIL_OK);
    p1 = ss.position_mm;
    rail_clock_sleep(rail_clock_real(), 0.2);
    assert_int_equal(rail_status_poll(shear, &ss), RAIL_OK);
    assert_true(ss.position_mm == p1 && p1 < 100.0);
    assert_int_equal(rail_move_abs(comp, 1.0, 10.0), RAIL_E_STATE);
    assert_non_null(strstr(rail_last_error(comp), "not trusted"));
    rail_close(comp);
    rail_close(shear);
    grblsim_kill(a);
    grblsim_kill(b);
}

/* A soft reset of ours whose banner never came (lost on the line, or waited out) is no licence to
   swallow a later genuine restart: only a banner within the reply timeout of our own 0x18 is
   ours. Here the link counts one due from 2 s ago, then the controller really restarts (its
   port opened by another process): the rail must read the position lost (review of issue 34). */
static void test_stale_own_reset_hides_no_restart(void **s)
{
    (void)s;
    char path[128], why[600];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.reset_on_open = true;
    sp.reset_delay_s = 0.1;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_gcode_params g = gparams(path, 'X');
    grbl_link *l = NULL;
    assert_int_equal(grbl_link_open(&l, &g, rail_clock_real(), why, sizeof why), RAIL_OK);
    rail_params p = params("shear");
    rail *r = NULL;
    assert_int_equal(rail_gcode_open(&r, &p, &g, l, rail_clock_real(), why, sizeof why), RAIL_OK);
    assert_int_equal(rail_gcode_confirm_zero(r, true), RAIL_OK); /* the reset at open */
    rail_status st;
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_IDLE);
    l->own_resets = 1; /* our 0x18 of 2 s ago, its banner lost */
    l->own_reset_t = rail_clock_now(rail_clock_real()) - 2.0;
    int fd = open(path, O_RDWR | O_NOCTTY); /* DTR: the controller restarts */
    assert_true(fd >= 0);
    close(fd);
    for (int i = 0; i < 50; i++) {
        rail_clock_sleep(rail_clock_real(), 0.03);
        rail_status_poll(r, &st);
        if (st.state == RAIL_STATE_FAULT) break;
    }
    printf("# after the restart: %s: %s\n", rail_state_name(st.state), st.message);
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    assert_int_equal(rail_move_abs(r, 5.0, 10.0), RAIL_E_STATE);
    assert_non_null(strstr(rail_last_error(r), "not trusted"));
    rail_close(r);
    grbl_link_release(l);
    grblsim_kill(pid);
}

/* A reset under the moving rail itself: the move is abandoned, the rail stops and stays a
   fault; with homing enabled ($22=1) only a homing cycle makes it move again. */
static void test_reset_mid_move_needs_homing(void **s)
{
    (void)s;
    char path[128], why[600];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.reset_on_open = true;
    sp.reset_delay_s = 0.1;
    sp.start_in_alarm = true; /* $22=1 */
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_params p = params("shear");
    rail *r = NULL;
    assert_int_equal(try_open(path, &p, &r, why, sizeof why), RAIL_OK);
    rail_status st;
    assert_int_equal(rail_gcode_confirm_zero(r, true), RAIL_E_STATE); /* homing enabled */
    assert_non_null(strstr(rail_last_error(r), "$22=1"));
    assert_int_equal(rail_home(r, true), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 3.0, &st), RAIL_OK);
    assert_int_equal(rail_move_abs(r, 100.0, 20.0), RAIL_OK);
    rail_clock_sleep(rail_clock_real(), 0.3);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_MOVING);
    int fd = open(path, O_RDWR | O_NOCTTY);
    assert_true(fd >= 0);
    close(fd);
    rail_err e = rail_wait_idle(r, 2.0, &st);
    assert_int_not_equal(e, RAIL_OK);
    assert_true(st.state == RAIL_STATE_FAULT || st.state == RAIL_STATE_ALARM);
    assert_int_equal(rail_move_abs(r, 1.0, 10.0), RAIL_E_STATE);
    assert_non_null(strstr(rail_last_error(r), "home it"));
    assert_int_equal(rail_home(r, true), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 3.0, &st), RAIL_OK);
    assert_int_equal(rail_move_abs(r, 1.0, 10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 3.0, &st), RAIL_OK);
    NEAR(st.position_mm, 1.0, 1e-3);
    rail_close(r);
    grblsim_kill(pid);
}

/* Each alarm is named from GRBL's table; alarms that lose the position lose the rail's trust. */
static void test_alarm_named_and_position_lost(void **s)
{
    (void)s;
    char path[128], why[600];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.alarm_after_s = 0.3;
    sp.alarm_code = 9;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_params p = params("compress");
    rail *r = NULL;
    assert_int_equal(try_open(path, &p, &r, why, sizeof why), RAIL_OK);
    rail_clock_sleep(rail_clock_real(), 0.4);
    rail_status st;
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_ALARM);
    assert_int_equal(st.code, 9);
    assert_non_null(strstr(st.message, "Homing fail"));
    assert_int_equal(rail_reset(r), RAIL_OK); /* $X */
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    assert_non_null(strstr(st.message, "ALARM:9"));
    rail_close(r);
    grblsim_kill(pid);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_inches_refused),
        cmocka_unit_test(test_speed_above_max_rate_refused),
        cmocka_unit_test(test_accel_adopted_and_settings_described),
        cmocka_unit_test(test_sim_settings_commands),
        cmocka_unit_test(test_banner_wait_on_reset_at_open),
        cmocka_unit_test(test_reset_during_trial_stops_both),
        cmocka_unit_test(test_reset_mid_move_needs_homing),
        cmocka_unit_test(test_stale_own_reset_hides_no_restart),
        cmocka_unit_test(test_alarm_named_and_position_lost),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
