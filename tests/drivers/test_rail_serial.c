/* test_rail_serial.c: the serial transports. A pseudo-terminal (the GRBL simulator's) opens
 * through the termios path when libserialport refuses it, carries bytes both ways with read
 * timeouts, and reads as disconnected once the other side is gone; port specs resolve or fail
 * with a reason; listing ports works on a machine without any. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "grblsim_spawn.h"
#include "rail_serial.h"
#include "rail_serial_tty.h"

static void test_pty_transport(void **s)
{
    (void)s;
    char path[128], why[300];
    grbl_sim_params sp = grbl_sim_params_default();
    pid_t pid = grblsim_spawn(&sp, path, sizeof path);
    rail_serial *sp_port = NULL;
    rail_err e_sp = rail_serial_open_sp(&sp_port, path, 115200, why, sizeof why);
    if (e_sp == RAIL_OK)
        rail_serial_close(sp_port); /* a libserialport that accepts ptys is fine too */
    rail_serial *ser = NULL;
    assert_int_equal(rail_serial_open(&ser, path, 115200, why, sizeof why), RAIL_OK);
    if (e_sp != RAIL_OK)
        assert_string_equal(rail_serial_kind(ser), "termios");
    /* Nothing to read yet after draining: a timeout returns no bytes and no error. */
    char buf[256];
    size_t got = 0;
    for (int i = 0; i < 10; i++) {
        assert_int_equal(rail_serial_read(ser, buf, sizeof buf, &got, 0.05), RAIL_OK);
        if (got == 0)
            break;
    }
    assert_int_equal(got, 0);
    assert_int_equal(rail_serial_write(ser, "?", 1, 0.2), RAIL_OK);
    size_t total = 0;
    for (int i = 0; i < 20 && !memchr(buf, '\n', total); i++) {
        assert_int_equal(rail_serial_read(ser, buf + total, sizeof buf - 1 - total, &got, 0.2), RAIL_OK);
        total += got;
    }
    buf[total] = 0;
    assert_non_null(strstr(buf, "<Idle|MPos:"));
    grblsim_kill(pid);
    rail_err e = RAIL_OK;
    for (int i = 0; i < 10 && e == RAIL_OK; i++)
        e = rail_serial_read(ser, buf, sizeof buf, &got, 0.05);
    assert_int_equal(e, RAIL_E_DISCONNECTED);
    rail_serial_close(ser);
}

static void test_specs(void **s)
{
    (void)s;
    char path[256], why[300];
    assert_int_equal(rail_serial_resolve("/dev/ttyACM0", path, sizeof path, why, sizeof why), RAIL_OK);
    assert_string_equal(path, "/dev/ttyACM0");
    assert_int_equal(rail_serial_resolve("", path, sizeof path, why, sizeof why), RAIL_E_INVALID);
    assert_int_equal(rail_serial_resolve("usb:zz", path, sizeof path, why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "usb:VID:PID"));
    assert_int_equal(rail_serial_resolve("usb:fffe:fffd:NOPE", path, sizeof path, why, sizeof why), RAIL_E_IO);
    assert_non_null(strstr(why, "fffe:fffd"));
    rail_serial *ser = NULL;
    assert_int_equal(rail_serial_open(&ser, "/nonexistent/tty", 115200, why, sizeof why), RAIL_E_IO);
    assert_non_null(strstr(why, "libserialport"));
    assert_non_null(strstr(why, "termios"));
    assert_int_equal(rail_serial_open_tty(&ser, "/dev/null", 115200, why, sizeof why), RAIL_E_IO);
    assert_non_null(strstr(why, "not a terminal"));
    assert_int_equal(rail_serial_open_tty(&ser, "/dev/null", 12345, why, sizeof why), RAIL_E_INVALID);
    rail_serial_port_info ports[16];
    size_t n = 99;
    assert_int_equal(rail_serial_list(ports, 16, &n, why, sizeof why), RAIL_OK);
    assert_true(n <= 16);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pty_transport),
        cmocka_unit_test(test_specs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
