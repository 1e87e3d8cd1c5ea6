/* test_rail_gcode_reenum.c: a USB-serial adapter re-enumerated under its stable name (a by-id
 * link, usb:VID:PID) comes back as another device number; the G-code link's reopen follows the
 * name, so it must lock the new device before it drives it (rail_port_lock.h).
 * Simulated with ribbon-grblsim on two pseudo-terminals and a symlink standing for the by-id name:
 * the link opens the symlink (device A); A dies and the symlink now leads to device B. While
 * another owner holds B's lock, the reopen is refused naming that lock file and B is not driven;
 * once it is free, the reopen takes B's lock, which another owner is then refused until the rail
 * closes. Lock files go to a temporary RIBBON_LOCK_DIR. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "grblsim_spawn.h"
#include "rail_gcode.h"
#include "rail_port_lock.h"

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
    rail *r = NULL;
    char why[300];
    rail_err e = rail_gcode_open(&r, &p, &g, NULL, rail_clock_real(), why, sizeof why);
    if (e != RAIL_OK)
        print_error("open: %s\n", why);
    assert_int_equal(e, RAIL_OK);
    return r;
}

/* Polls until the status message contains want (or the link is up again, when want is NULL). */
static rail_status poll_until(rail *r, const char *want, double max_s)
{
    rail_status st;
    memset(&st, 0, sizeof st);
    for (double t = 0; t < max_s; t += 0.1) {
        rail_err e = rail_status_poll(r, &st);
        if (want ? strstr(st.message, want) != NULL : e == RAIL_OK && st.state != RAIL_STATE_DISCONNECTED)
            break;
        rail_clock_sleep(rail_clock_real(), 0.1);
    }
    return st;
}

static void test_reopen_on_another_device_takes_its_lock(void **s)
{
    (void)s;
    char dir[] = "/tmp/rail-reenum-XXXXXX", a[128], b[128], link[160], why[800], cmd[160];
    assert_non_null(mkdtemp(dir));
    setenv("RIBBON_LOCK_DIR", dir, 1);
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pa = grblsim_spawn(&sp, a, sizeof a);
    pid_t pb = grblsim_spawn(&sp, b, sizeof b); /* B exists before A goes: another pts number */
    assert_true(pa > 0 && pb > 0);
    assert_string_not_equal(a, b);
    snprintf(link, sizeof link, "%s/by-id-grbl", dir);
    assert_int_equal(symlink(a, link), 0);

    rail *r = open_rail(link);
    rail_status st;
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);

    /* Another daemon holds B (it opened B by its own name). */
    int held = 0;
    rail_port_lock *other = rail_port_lock_take(b, "another ribbond", &held, why, sizeof why);
    assert_non_null(other);
    /* Re-enumeration: A is gone, the stable name leads to B. */
    grblsim_kill(pa);
    assert_int_equal(unlink(link), 0);
    assert_int_equal(symlink(b, link), 0);
    st = poll_until(r, "in use", 3.0);
    print_message("while B is held: %s, '%s'\n", rail_state_name(st.state), rail_last_error(r));
    assert_int_equal(st.state, RAIL_STATE_DISCONNECTED);
    assert_non_null(strstr(st.message, "another device"));
    assert_non_null(strstr(rail_last_error(r), ".lock is held by"));
    assert_non_null(strstr(rail_last_error(r), "(another ribbond)"));
    rail_port_lock_release(other);

    /* B free: the reopen takes it (the position is lost over a reopen: a fault, not a link error). */
    st = poll_until(r, NULL, 3.0);
    print_message("B free: %s, '%s'\n", rail_state_name(st.state), st.message);
    assert_int_not_equal(st.state, RAIL_STATE_DISCONNECTED);
    other = rail_port_lock_take(b, "another ribbond", &held, why, sizeof why);
    print_message("another owner of B: %s\n", other ? "took it" : why);
    assert_null(other);
    assert_int_equal(held, 1);
    rail_close(r);
    other = rail_port_lock_take(b, "another ribbond", &held, why, sizeof why);
    assert_non_null(other); /* released with the link */
    rail_port_lock_release(other);

    grblsim_kill(pb);
    unsetenv("RIBBON_LOCK_DIR");
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reopen_on_another_device_takes_its_lock),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
