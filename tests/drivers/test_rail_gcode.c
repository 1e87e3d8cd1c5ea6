/* test_rail_gcode.c: the G-code driver against ribbon-grblsim's engine on a pseudo-terminal:
 * the compress-hold-shear-stop sequence on one controller (two axes) and on two controllers,
 * stops within the deceleration distance, a dead client leaves the rail stopped within its
 * segment bound and a reopen does not resume, homing, alarms, GRBL error codes, stall, garbled
 * and dropped replies, and a killed controller detected as disconnected within 0.5 s.
 * Real clock: motions are short and fast so the whole file runs in a few seconds. */
#include <math.h>
#include <signal.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "grblsim_spawn.h"
#include "grbl_link.h"
#include "rail_gcode.h"

#define NEAR(a, b, tol) assert_true(fabs((a) - (b)) <= (tol))
#define SIM_RES 1e-3 /* mm: the simulator reports three decimals */

/* rail_wait_idle with the reason printed when it is not the expected result. */
static rail_err wait_idle(rail *r, double timeout_s, rail_status *st)
{
    rail_err e = rail_wait_idle(r, timeout_s, st);
    if (e != RAIL_OK)
        print_message("wait_idle: %s (%s)\n", rail_last_error(r), st->message);
    return e;
}

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
    g.segments_ahead = 2;
    g.stall_timeout_s = 0.5;
    return g;
}

static rail *open_axis(const char *path, char axis, const char *name, grbl_link *shared)
{
    rail_params p = params(name);
    rail_gcode_params g = gparams(path, axis);
    rail *r = NULL;
    char why[300];
    rail_err e = rail_gcode_open(&r, &p, &g, shared, rail_clock_real(), why, sizeof why);
    if (e != RAIL_OK)
        print_error("open: %s\n", why);
    assert_int_equal(e, RAIL_OK);
    return r;
}

static void sequence(rail *comp, rail *shear)
{
    rail_status st;
    assert_int_equal(rail_move_abs(comp, 12.5, 40.0), RAIL_OK);
    assert_int_equal(wait_idle(comp, 5.0, &st), RAIL_OK);
    NEAR(st.position_mm, 12.5, SIM_RES);
    rail_clock_sleep(rail_clock_real(), 0.1); /* hold */
    assert_int_equal(rail_status_poll(comp, &st), RAIL_OK);
    NEAR(st.position_mm, 12.5, SIM_RES);
    assert_int_equal(rail_jog(shear, 20.0), RAIL_OK);
    double t0 = rail_clock_now(rail_clock_real());
    int at_speed = 0;
    for (int i = 0; i < 200 && rail_clock_now(rail_clock_real()) - t0 < 0.6; i++) {
        assert_int_equal(rail_status_get(shear, &st), RAIL_OK);
        if (!st.extrapolated && fabs(st.velocity_mm_s - 20.0) <= 0.5)
            at_speed++; /* segments join without stopping */
        rail_clock_sleep(rail_clock_real(), 0.01);
    }
    assert_true(at_speed >= 3);
    assert_int_equal(rail_status_poll(shear, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_MOVING);
    double at = st.position_mm, v = st.velocity_mm_s;
    double t_read = rail_clock_now(rail_clock_real());
    assert_int_equal(rail_stop(shear), RAIL_OK);
    double latency = rail_clock_now(rail_clock_real()) - t_read;
    assert_int_equal(wait_idle(shear, 3.0, &st), RAIL_OK);
    double d = st.position_mm - at;
    /* Deceleration distance v^2 / (2 * 200) (1 mm at 20 mm/s), plus the distance covered between
       the reading and the stop reaching the simulator (measured here, plus 50 ms of scheduling
       slack on a loaded machine). */
    assert_true(d >= 0.0);
    assert_true(d <= v * v / 400.0 + v * (latency + 0.05) + SIM_RES);
    assert_int_equal(rail_status_poll(comp, &st), RAIL_OK);
    NEAR(st.position_mm, 12.5, SIM_RES);
    /* And back to a commanded shear position exactly. */
    assert_int_equal(rail_move_abs(shear, 3.25, 50.0), RAIL_OK);
    assert_int_equal(wait_idle(shear, 5.0, &st), RAIL_OK);
    NEAR(st.position_mm, 3.25, SIM_RES);
}

static void test_sequence_one_controller(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    assert_true(pid > 0);
    rail_gcode_params g = gparams(path, 'X');
    grbl_link *l = NULL;
    char why[300];
    assert_int_equal(grbl_link_open(&l, &g, rail_clock_real(), why, sizeof why), RAIL_OK);
    rail *comp = open_axis(path, 'X', "compress", l);
    rail *shear = open_axis(path, 'Y', "shear", l);
    grbl_link_release(l);
    sequence(comp, shear);
    rail_close(comp);
    rail_close(shear);
    grblsim_kill(pid);
}

static void test_one_controller_both_axes_at_once(void **s)
{
    (void)s;
    char path[128], why[300];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_gcode_params g = gparams(path, 'X');
    grbl_link *l = NULL;
    assert_int_equal(grbl_link_open(&l, &g, rail_clock_real(), why, sizeof why), RAIL_OK);
    rail *x = open_axis(path, 'X', "compress", l);
    rail *y = open_axis(path, 'Y', "shear", l);
    grbl_link_release(l);
    /* The controller runs the two axes' segments one after the other: neither is a stall. */
    assert_int_equal(rail_move_abs(x, 9.0, 15.0), RAIL_OK);
    assert_int_equal(rail_move_abs(y, 6.0, 15.0), RAIL_OK);
    rail_status sx, sy;
    double t0 = rail_clock_now(rail_clock_real());
    int done = 0;
    while (!done && rail_clock_now(rail_clock_real()) - t0 < 8.0) {
        assert_int_equal(rail_status_get(x, &sx), RAIL_OK);
        assert_int_equal(rail_status_get(y, &sy), RAIL_OK);
        assert_true(sx.state == RAIL_STATE_MOVING || sx.state == RAIL_STATE_IDLE);
        assert_true(sy.state == RAIL_STATE_MOVING || sy.state == RAIL_STATE_IDLE);
        done = sx.state == RAIL_STATE_IDLE && sy.state == RAIL_STATE_IDLE && !sx.extrapolated &&
               !sy.extrapolated;
        rail_clock_sleep(rail_clock_real(), 0.01);
    }
    assert_true(done);
    NEAR(sx.position_mm, 9.0, SIM_RES);
    NEAR(sy.position_mm, 6.0, SIM_RES);
    rail_close(x);
    rail_close(y);
    grblsim_kill(pid);
}

static void test_sequence_two_controllers(void **s)
{
    (void)s;
    char p1[128], p2[128];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t a = grblsim_spawn(&sp, p1, sizeof p1);
    pid_t b = grblsim_spawn(&sp, p2, sizeof p2);
    rail *comp = open_axis(p1, 'X', "compress", NULL);
    rail *shear = open_axis(p2, 'X', "shear", NULL);
    sequence(comp, shear);
    rail_close(comp);
    rail_close(shear);
    grblsim_kill(a);
    grblsim_kill(b);
}

static void test_dead_client_stops_and_no_resume(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    fflush(NULL);
    pid_t client = fork();
    if (client == 0) {
        /* A client that starts a long move and dies without a word. */
        rail *r = NULL;
        rail_params p = params("shear");
        rail_gcode_params g = gparams(path, 'X');
        char why[300];
        if (rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why) != RAIL_OK)
            _exit(2);
        if (rail_move_abs(r, 140.0, 30.0) != RAIL_OK)
            _exit(3);
        _exit(0);
    }
    int wst = 0;
    waitpid(client, &wst, 0);
    assert_true(WIFEXITED(wst) && WEXITSTATUS(wst) == 0);
    rail_clock_sleep(rail_clock_real(), 1.0);
    rail *r = open_axis(path, 'X', "shear", NULL);
    rail_status st;
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_IDLE);
    /* Two segments of 0.2 s at 30 mm/s were queued: at most 12 mm of travel. */
    assert_true(st.position_mm > 1.0 && st.position_mm <= 12.0 + SIM_RES);
    double p0 = st.position_mm;
    rail_clock_sleep(rail_clock_real(), 0.3);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.position_mm == p0);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_home_alarm_reset(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.start_mm[0] = 6.0;
    sp.start_in_alarm = true;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail *r = open_axis(path, 'X', "compress", NULL);
    rail_status st;
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_ALARM);
    assert_int_equal(rail_move_abs(r, 10.0, 10.0), RAIL_E_STATE);
    assert_int_equal(rail_home(r, false), RAIL_E_CONFIRM);
    assert_int_equal(rail_home(r, true), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_HOMING);
    assert_int_equal(wait_idle(r, 5.0, &st), RAIL_OK);
    assert_true(st.position_mm == 0.0);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_injected_alarm_and_unlock(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.alarm_after_s = 0.4;
    sp.alarm_code = 1;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail *r = open_axis(path, 'X', "shear", NULL);
    rail_status st;
    assert_int_equal(rail_jog(r, 10.0), RAIL_OK);
    assert_int_equal(wait_idle(r, 3.0, &st), RAIL_E_DEVICE);
    assert_int_equal(st.state, RAIL_STATE_ALARM);
    assert_int_equal(st.code, 1);
    assert_non_null(strstr(st.message, "Hard limit"));
    /* A hard limit is critical in GRBL ("Reset to continue"): reset soft-resets, then unlocks;
       the position is lost, so the rail stays a fault until its zero is confirmed. */
    assert_int_equal(rail_reset(r), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    assert_non_null(strstr(st.message, "not trusted"));
    assert_int_equal(rail_move_abs(r, 1.0, 10.0), RAIL_E_STATE);
    assert_int_equal(rail_gcode_confirm_zero(r, true), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_IDLE);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_grbl_error_code_named(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.travel_mm[0] = 5.0;
    sp.start_in_alarm = true; /* $22=1, which GRBL's soft limits ($20=1) need */
    sp.soft_limits = true;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail *r = open_axis(path, 'X', "shear", NULL); /* soft max 150 > machine travel 5 */
    rail_status st;
    assert_int_equal(rail_home(r, true), RAIL_OK);
    assert_int_equal(wait_idle(r, 3.0, &st), RAIL_OK);
    assert_int_equal(rail_move_abs(r, 20.0, 50.0), RAIL_E_DEVICE); /* a 10 mm segment */
    assert_non_null(strstr(rail_last_error(r), "error:15"));
    assert_non_null(strstr(rail_last_error(r), "travel"));
    rail_close(r);
    grblsim_kill(pid);
}

static void test_stall_detected(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.stall_at_mm[0] = 4.0;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail *r = open_axis(path, 'X', "compress", NULL);
    rail_status st;
    assert_int_equal(rail_move_abs(r, 20.0, 20.0), RAIL_OK);
    assert_int_equal(wait_idle(r, 3.0, &st), RAIL_E_STATE);
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    assert_non_null(strstr(st.message, "stall"));
    NEAR(st.position_mm, 4.0, SIM_RES);
    assert_int_equal(rail_move_abs(r, 2.0, 20.0), RAIL_E_STATE);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_estop_mid_move(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail *r = open_axis(path, 'X', "shear", NULL);
    rail_status st;
    assert_int_equal(rail_move_abs(r, 100.0, 40.0), RAIL_OK);
    for (int i = 0; i < 30; i++) {
        rail_status_get(r, &st);
        rail_clock_sleep(rail_clock_real(), 0.01);
    }
    assert_int_equal(rail_estop(r), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    double p0 = st.position_mm;
    assert_true(p0 > 1.0 && p0 < 60.0); /* stopped well short of the 100 mm target */
    rail_clock_sleep(rail_clock_real(), 0.3);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.position_mm == p0);
    assert_int_equal(st.state, RAIL_STATE_IDLE);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_garbled_and_dropped_replies(void **s)
{
    (void)s;
    char path[128], why[300];
    rail_params p = params("shear");
    rail *r = NULL;
    grbl_sim_params sp = grbl_sim_params_default();
    sp.garble_prob = 1.0;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_gcode_params g = gparams(path, 'X');
    assert_int_equal(rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why), RAIL_E_PROTOCOL);
    assert_null(r);
    assert_non_null(strstr(why, "status report truncated"));
    for (const char *c = why; *c; c++)
        assert_true(*c >= 0x20 && *c < 0x7f); /* device bytes are escaped in messages */
    grblsim_kill(pid);

    sp = grbl_sim_params_default();
    sp.drop_prob = 1.0;
    pid = grblsim_spawn(&sp, path, sizeof path);
    g = gparams(path, 'X');
    assert_int_equal(rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why), RAIL_E_TIMEOUT);
    assert_non_null(strstr(why, "no reply"));
    grblsim_kill(pid);

    /* One reply in three garbled: polls retry, and a failure is a named protocol error. */
    sp = grbl_sim_params_default();
    sp.garble_prob = 0.3;
    sp.seed = 7;
    pid = grblsim_spawn(&sp, path, sizeof path);
    g = gparams(path, 'X');
    rail_err e = RAIL_E_PROTOCOL;
    for (int i = 0; i < 5 && e != RAIL_OK; i++)
        e = rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why);
    assert_int_equal(e, RAIL_OK);
    int ok = 0, bad = 0;
    rail_status st;
    for (int i = 0; i < 40; i++) {
        e = rail_status_poll(r, &st);
        if (e == RAIL_OK)
            ok++;
        else {
            bad++;
            assert_true(e == RAIL_E_PROTOCOL || e == RAIL_E_TIMEOUT);
            assert_true(rail_last_error(r)[0] != 0);
        }
    }
    assert_true(ok > 20);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_killed_controller_is_disconnected(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail *r = open_axis(path, 'X', "shear", NULL);
    rail_status st;
    assert_int_equal(rail_jog(r, 10.0), RAIL_OK);
    rail_clock_sleep(rail_clock_real(), 0.2);
    grblsim_kill(pid);
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
    assert_int_equal(rail_move_abs(r, 1.0, 1.0), RAIL_E_DISCONNECTED);
    rail_close(r);
}

/* A controller that goes silent (its process stopped, the pty still open): the status request is
 * asked again at half the reply timeout and the link is lost after reply_timeout_s of silence in
 * all, not after two full timeouts; once it answers again, polls succeed. */
static void test_silent_controller_lost_within_reply_timeout(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail *r = open_axis(path, 'X', "shear", NULL);
    rail_status st;
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    const double reply_timeout = rail_gcode_params_default().reply_timeout_s;
    kill(pid, SIGSTOP);
    double t0 = rail_clock_now(rail_clock_real());
    rail_err e = rail_status_poll(r, &st);
    double dt = rail_clock_now(rail_clock_real()) - t0;
    kill(pid, SIGCONT);
    assert_int_equal(e, RAIL_E_TIMEOUT);
    assert_non_null(strstr(rail_last_error(r), "asked twice"));
    assert_true(dt >= reply_timeout);
    assert_true(dt < reply_timeout + 0.1); /* one timeout, not two */
    e = RAIL_E_TIMEOUT;
    for (int i = 0; i < 5 && e != RAIL_OK; i++) e = rail_status_poll(r, &st);
    assert_int_equal(e, RAIL_OK);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_slow_shear_rate(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail *r = open_axis(path, 'Y', "shear", NULL);
    rail_status st;
    /* 0.5 mm/s: segments of max(0.2 s * 0.5 mm/s, 0.05 mm) = 0.1 mm, joined without stops. */
    assert_int_equal(rail_jog(r, 0.5), RAIL_OK);
    double t0 = rail_clock_now(rail_clock_real());
    int fresh = 0, off = 0;
    while (rail_clock_now(rail_clock_real()) - t0 < 1.2) {
        assert_int_equal(rail_status_get(r, &st), RAIL_OK);
        if (rail_clock_now(rail_clock_real()) - t0 > 0.3 && !st.extrapolated) {
            fresh++;
            off += fabs(st.velocity_mm_s - 0.5) > 0.02;
        }
        rail_clock_sleep(rail_clock_real(), 0.01);
    }
    /* Steady at the commanded rate (a reading or two off is allowed if this machine stalled the
       test long enough to starve the queue, which is the safe behaviour). */
    assert_true(fresh >= 5);
    assert_true(off <= fresh / 3);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    NEAR(st.position_mm, 0.5 * (rail_clock_now(rail_clock_real()) - t0), 0.03);
    assert_int_equal(rail_stop(r), RAIL_OK);
    assert_int_equal(wait_idle(r, 2.0, &st), RAIL_OK);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_reconnect_never_resumes(void **s)
{
    (void)s;
    char p1[128], p2[128], link[128];
    snprintf(link, sizeof link, "/tmp/ribbon-test-grbl-%d", (int)getpid());
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t a = grblsim_spawn(&sp, p1, sizeof p1);
    unlink(link);
    assert_int_equal(symlink(p1, link), 0);
    rail *r = open_axis(link, 'X', "shear", NULL);
    rail_status st;
    assert_int_equal(rail_jog(r, 10.0), RAIL_OK);
    rail_clock_sleep(rail_clock_real(), 0.2);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    grblsim_kill(a); /* cable pulled mid-jog */
    assert_int_equal(rail_status_poll(r, &st), RAIL_E_DISCONNECTED);
    assert_int_equal(rail_status_poll(r, &st), RAIL_E_DISCONNECTED); /* reopening fails */
    /* A controller comes back on the same path (here: another simulator, at 7 mm). */
    sp.start_mm[0] = 7.0;
    pid_t b = grblsim_spawn(&sp, p2, sizeof p2);
    unlink(link);
    assert_int_equal(symlink(p2, link), 0);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.position_mm == 7.0);
    rail_clock_sleep(rail_clock_real(), 0.4);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.position_mm == 7.0); /* the jog was not resumed */
    /* A controller that came back may have reset: no move until its zero is confirmed. */
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    assert_int_equal(rail_move_abs(r, 8.0, 10.0), RAIL_E_STATE);
    assert_int_equal(rail_gcode_confirm_zero(r, true), RAIL_OK);
    assert_int_equal(rail_move_abs(r, 8.0, 10.0), RAIL_OK); /* and new commands work */
    assert_int_equal(wait_idle(r, 3.0, &st), RAIL_OK);
    NEAR(st.position_mm, 8.0, SIM_RES);
    rail_close(r);
    unlink(link);
    grblsim_kill(b);
}

static void test_work_positions_with_offset(void **s)
{
    (void)s;
    char path[128];
    grbl_sim_params sp = grbl_sim_params_default();
    sp.report_wpos = true; /* $10=0: WPos, with WCO only in every 10th report */
    sp.wco_mm[0] = 5.0;
    sp.start_mm[0] = 7.0;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail *r = open_axis(path, 'X', "compress", NULL);
    rail_status st;
    for (int i = 0; i < 25; i++) { /* machine position whether or not this report has a WCO */
        assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
        NEAR(st.position_mm, 7.0, SIM_RES);
    }
    assert_int_equal(rail_move_abs(r, 9.0, 10.0), RAIL_OK);
    assert_int_equal(wait_idle(r, 3.0, &st), RAIL_OK);
    NEAR(st.position_mm, 9.0, SIM_RES);
    rail_close(r);
    grblsim_kill(pid);
}

static void test_open_missing_port(void **s)
{
    (void)s;
    rail_params p = params("shear");
    rail_gcode_params g = gparams("/nonexistent/ttyACM9", 'X');
    rail *r = NULL;
    char why[300];
    assert_int_equal(rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why), RAIL_E_IO);
    assert_non_null(strstr(why, "/nonexistent/ttyACM9"));
    g = gparams("usb:zz:1", 'X');
    assert_int_equal(rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why), RAIL_E_INVALID);
    g = gparams("/dev/null", 'Q');
    assert_int_equal(rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "axis"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sequence_one_controller),
        cmocka_unit_test(test_one_controller_both_axes_at_once),
        cmocka_unit_test(test_sequence_two_controllers),
        cmocka_unit_test(test_dead_client_stops_and_no_resume),
        cmocka_unit_test(test_home_alarm_reset),
        cmocka_unit_test(test_injected_alarm_and_unlock),
        cmocka_unit_test(test_grbl_error_code_named),
        cmocka_unit_test(test_stall_detected),
        cmocka_unit_test(test_estop_mid_move),
        cmocka_unit_test(test_garbled_and_dropped_replies),
        cmocka_unit_test(test_silent_controller_lost_within_reply_timeout),
        cmocka_unit_test(test_killed_controller_is_disconnected),
        cmocka_unit_test(test_slow_shear_rate),
        cmocka_unit_test(test_reconnect_never_resumes),
        cmocka_unit_test(test_work_positions_with_offset),
        cmocka_unit_test(test_open_missing_port),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
