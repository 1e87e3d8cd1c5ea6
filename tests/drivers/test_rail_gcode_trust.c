/* test_rail_gcode_trust.c: "position not trusted" outlives the process that saw it (issue 34 A).
 * A GRBL hard-limit alarm (ribbon-grblsim, injected) loses the position; the rail is reset
 * (soft reset + unlock: the controller is idle and unlocked again) and closed. A rail opened
 * afterwards on the same port (a restarted ribbond, a ribbonctl) finds an idle controller with
 * no alarm: it must still refuse motion, from the marker beside the device lock, until the zero
 * is confirmed; then the marker is gone and the next open moves. A marker an earlier simulator
 * left on another pty of the same number is not this one's. Lock files and markers go to a
 * temporary RIBBON_LOCK_DIR (and the other lock directories this process may write). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <cmocka.h>

#include "grblsim_spawn.h"
#include "rail_gcode.h"
#include "rail_lock.h"

static rail *open_rail(const char *path)
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
    g.segment_s = 0.2;
    rail *r = NULL;
    char why[300];
    rail_err e = rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why);
    if (e != RAIL_OK)
        print_error("open: %s\n", why);
    assert_int_equal(e, RAIL_OK);
    return r;
}

static void marker_of(const char *dir, const char *port, char *out, size_t n)
{
    char key[200], name[240];
    rail_lock_serial_key(port, key, sizeof key, name, sizeof name);
    snprintf(out, n, "%s/ribbon-rig-%s.untrusted", dir, key);
}

static void test_untrusted_survives_reopen_until_confirmed(void **s)
{
    (void)s;
    char dir[] = "/tmp/rail-trust-XXXXXX", path[128], marker[512], cmd[160];
    assert_non_null(mkdtemp(dir));
    setenv("RIBBON_LOCK_DIR", dir, 1);
    grbl_sim_params sp = grbl_sim_params_default();
    sp.alarm_after_s = 0.4;
    sp.alarm_code = 1;
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    assert_true(pid > 0);
    marker_of(dir, path, marker, sizeof marker);

    rail *r = open_rail(path);
    rail_status st;
    assert_int_equal(rail_jog(r, 10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 3.0, &st), RAIL_E_DEVICE);
    assert_int_equal(st.code, 1);
    assert_int_equal(rail_reset(r), RAIL_OK); /* idle and unlocked: only the zero is lost */
    rail_close(r);

    /* A new process's view: a link with no memory of the alarm. */
    r = open_rail(path);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    print_message("reopened: %s, '%s'\n", rail_state_name(st.state), st.message);
    assert_int_equal(st.state, RAIL_STATE_FAULT);
    assert_non_null(strstr(st.message, "not trusted"));
    assert_non_null(strstr(st.message, "earlier process"));
    assert_int_equal(rail_move_abs(r, 5.0, 10.0), RAIL_E_STATE);
    print_message("move refused: %s\n", rail_last_error(r));
    struct stat sb;
    assert_int_equal(stat(marker, &sb), 0);
    assert_int_equal(rail_gcode_confirm_zero(r, true), RAIL_OK);
    rail_close(r);
    assert_int_not_equal(stat(marker, &sb), 0); /* confirmed: the marker is gone */

    r = open_rail(path);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_IDLE);
    assert_int_equal(rail_move_abs(r, 2.0, 10.0), RAIL_OK);
    assert_int_equal(rail_wait_idle(r, 3.0, &st), RAIL_OK);
    rail_close(r);

    /* An earlier simulator's marker on a pty of this number (another creation time). */
    FILE *f = fopen(marker, "w");
    assert_non_null(f);
    fprintf(f, "instance pty 1.000000000\nthe controller restarted\n");
    fclose(f);
    r = open_rail(path);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_int_equal(st.state, RAIL_STATE_IDLE);
    rail_close(r);
    assert_int_not_equal(stat(marker, &sb), 0);

    grblsim_kill(pid);
    unsetenv("RIBBON_LOCK_DIR");
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_untrusted_survives_reopen_until_confirmed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
