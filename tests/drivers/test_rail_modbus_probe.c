/* test_rail_modbus_probe.c: the read-only register probe (rail_modbus_probe.h) against
 * ribbon-mbsim's engine on 127.0.0.1, and the register table and sign a map gives the driver:
 * every mapped register read once with its value in the driver's units (position 12.5 mm from
 * 12500 counts, the load -42 signed), status bits and identity decoded, a register of the wrong
 * table reported on its own row with the drive's exception while the others still read, the
 * probe writing nothing (the drive's watchdog register stays 0 where an open arms it), the
 * driver reading a role from the input table when the map says so (refused by a drive that has
 * none), and the map check refusing a written role in a read-only table or a one-bit type. */
#include <math.h>
#include <modbus.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "mbsim_spawn.h"
#include "rail_modbus.h"
#include "rail_modbus_probe.h"

static pid_t sim_pid;
static int sim_port;

static int start_sim(void **state)
{
    (void)state;
    mb_sim_params sp = mb_sim_params_default();
    sp.start_mm = 12.5;
    sp.load_counts = -42;
    sim_pid = mbsim_spawn(sp, &sim_port);
    return sim_pid > 0 ? 0 : -1;
}

static int stop_sim(void **state)
{
    (void)state;
    if (sim_pid > 0) {
        kill(sim_pid, SIGKILL);
        waitpid(sim_pid, NULL, 0);
    }
    return 0;
}

static rail_modbus_params mparams(void)
{
    rail_modbus_params m = rail_modbus_params_default();
    snprintf(m.address, sizeof m.address, "127.0.0.1:%d", sim_port);
    return m;
}

static const rail_mb_probe_row *row(const rail_mb_probe_row *rows, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(rows[i].name, name))
            return &rows[i];
    fail_msg("no row %s", name);
    return NULL;
}

/* The watchdog register (14) as a plain libmodbus client reads it; disarm: write 0 first (so
   the drive does not alarm once the test stops polling). */
static int watchdog_reg(bool disarm)
{
    modbus_t *ctx = modbus_new_tcp("127.0.0.1", sim_port);
    assert_non_null(ctx);
    assert_int_equal(modbus_connect(ctx), 0);
    uint16_t w = 0xffff;
    if (disarm)
        assert_int_equal(modbus_write_register(ctx, 14, 0), 1);
    assert_int_equal(modbus_read_registers(ctx, 14, 1, &w), 1);
    modbus_close(ctx);
    modbus_free(ctx);
    return w;
}

static int read_watchdog(void)
{
    return watchdog_reg(false);
}

static void test_probe_reads_every_register(void **state)
{
    (void)state;
    rail_modbus_params m = mparams();
    rail_mb_info *v = &m.map.info[m.map.n_info++];
    snprintf(v->name, sizeof v->name, "load_in");
    v->reg = (rail_mb_reg){.addr = 18, .words = 1, .sign = RAIL_MB_SIGNED};
    v->scale = 0.5;
    snprintf(v->unit, sizeof v->unit, "N");
    rail_mb_probe_row rows[RAIL_MB_PROBE_MAX];
    int n = 0;
    char why[300] = "";
    rail_err e = rail_modbus_probe(&m, rows, RAIL_MB_PROBE_MAX, &n, why, sizeof why);
    if (e != RAIL_OK)
        print_error("probe: %s\n", why);
    assert_int_equal(e, RAIL_OK);
    /* the preset maps 11 roles (no decel, op_type, load), plus one information register */
    assert_int_equal(n, 12);
    for (int i = 0; i < n; i++)
        assert_true(rows[i].ok);
    const rail_mb_probe_row *pos = row(rows, n, "actual_pos");
    assert_int_equal(pos->raw, 12500);
    assert_true(fabs(pos->value - 12.5) < 1e-12);
    assert_string_equal(pos->unit, "mm");
    const rail_mb_probe_row *st = row(rows, n, "status");
    assert_int_equal(st->raw, 0x05);
    assert_string_equal(st->text, "ready in-position");
    assert_true(isnan(st->value));
    const rail_mb_probe_row *id = row(rows, n, "ident");
    assert_int_equal(id->raw, 0x5242);
    assert_non_null(strstr(id->text, "as the map expects"));
    const rail_mb_probe_row *ld = row(rows, n, "info.load_in");
    assert_int_equal(ld->raw, -42);
    assert_true(fabs(ld->value - -21.0) < 1e-12);
    assert_string_equal(ld->unit, "N");
    const rail_mb_probe_row *wd = row(rows, n, "watchdog");
    assert_int_equal(wd->raw, 0);
    assert_string_equal(wd->text, "off");
}

static void test_probe_writes_nothing(void **state)
{
    (void)state;
    assert_int_equal(read_watchdog(), 0);
    rail_modbus_params m = mparams();
    rail_mb_probe_row rows[RAIL_MB_PROBE_MAX];
    int n = 0;
    char why[300];
    assert_int_equal(rail_modbus_probe(&m, rows, RAIL_MB_PROBE_MAX, &n, why, sizeof why), RAIL_OK);
    assert_int_equal(read_watchdog(), 0); /* the probe armed nothing */
    /* The control: opening the driver arms it (1 s = 1000 ms), so the read above can see a write. */
    rail_params p = rail_params_default();
    snprintf(p.name, sizeof p.name, "shear");
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 150.0;
    p.poll_hz = 20.0;
    rail *r = NULL;
    assert_int_equal(rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why), RAIL_OK);
    assert_int_equal(read_watchdog(), 1000);
    rail_close(r);
    assert_int_equal(watchdog_reg(true), 0);
}

static void test_probe_wrong_table_row(void **state)
{
    (void)state;
    rail_modbus_params m = mparams();
    /* The simulated drive has holding registers only: a map that puts a value in the input
       table or the coils gets the drive's exception on that row; every other row still reads. */
    rail_mb_info *v = &m.map.info[m.map.n_info++];
    snprintf(v->name, sizeof v->name, "version_in");
    v->reg = (rail_mb_reg){.addr = 17, .words = 1, .kind = RAIL_MB_INPUT};
    v = &m.map.info[m.map.n_info++];
    snprintf(v->name, sizeof v->name, "enable");
    v->reg = (rail_mb_reg){.addr = 3, .words = 1, .kind = RAIL_MB_COIL};
    rail_mb_probe_row rows[RAIL_MB_PROBE_MAX];
    int n = 0;
    char why[300] = "";
    rail_err e = rail_modbus_probe(&m, rows, RAIL_MB_PROBE_MAX, &n, why, sizeof why);
    assert_int_equal(e, RAIL_E_DEVICE);
    assert_non_null(strstr(why, "2 of 13 registers did not answer"));
    const rail_mb_probe_row *bad = row(rows, n, "info.version_in");
    assert_false(bad->ok);
    assert_non_null(strstr(bad->error, "Illegal data address"));
    assert_false(row(rows, n, "info.enable")->ok);
    assert_true(row(rows, n, "actual_pos")->ok);
    assert_true(row(rows, n, "ident")->ok); /* read after the failing rows' neighbours */
}

static void test_probe_unreachable(void **state)
{
    (void)state;
    rail_modbus_params m = rail_modbus_params_default();
    snprintf(m.address, sizeof m.address, "127.0.0.1:1"); /* nothing listens on port 1 */
    rail_mb_probe_row rows[RAIL_MB_PROBE_MAX];
    int n = -1;
    char why[300] = "";
    assert_int_equal(rail_modbus_probe(&m, rows, RAIL_MB_PROBE_MAX, &n, why, sizeof why), RAIL_E_IO);
    assert_int_equal(n, 0);
    assert_non_null(strstr(why, "cannot connect"));
}

/* The driver reads a role from the table the map names: position in the input table is read
   with function 4, which this drive refuses, so the open fails naming the exception; the same
   map with the holding table opens. */
static void test_driver_reads_the_mapped_table(void **state)
{
    (void)state;
    rail_params p = rail_params_default();
    snprintf(p.name, sizeof p.name, "shear");
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 150.0;
    p.poll_hz = 20.0;
    rail_modbus_params m = mparams();
    m.map.actual_pos.kind = RAIL_MB_INPUT;
    rail *r = NULL;
    char why[300] = "";
    rail_err e = rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why);
    assert_int_equal(e, RAIL_E_DEVICE);
    assert_non_null(strstr(why, "position register"));
    assert_non_null(strstr(why, "Illegal data address"));
    assert_null(r);
    m.map.actual_pos.kind = RAIL_MB_HOLDING;
    assert_int_equal(rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why), RAIL_OK);
    rail_close(r);
}

/* A map's sign overrides the role's reading: the load register (-42 as signed 16-bit) read
   unsigned is 65494. */
static void test_driver_honours_sign(void **state)
{
    (void)state;
    rail_params p = rail_params_default();
    snprintf(p.name, sizeof p.name, "shear");
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 150.0;
    p.poll_hz = 20.0;
    rail_modbus_params m = mparams();
    m.map.load = (rail_mb_reg){.addr = 18, .words = 1};
    rail *r = NULL;
    char why[300];
    rail_status st;
    assert_int_equal(rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.load == -42.0);
    rail_close(r);
    m.map.load.sign = RAIL_MB_UNSIGNED;
    assert_int_equal(rail_modbus_open(&r, &p, &m, rail_clock_real(), why, sizeof why), RAIL_OK);
    assert_int_equal(rail_status_poll(r, &st), RAIL_OK);
    assert_true(st.load == 65494.0);
    rail_close(r);
}

static void test_map_check_tables(void **state)
{
    (void)state;
    rail_modbus_map m;
    char why[300];
    assert_int_equal(rail_modbus_preset("ribbon-sim", &m), RAIL_OK);
    assert_int_equal(rail_modbus_map_check(&m, why, sizeof why), RAIL_OK);
    m.target_pos.kind = RAIL_MB_INPUT; /* the driver writes it */
    assert_int_equal(rail_modbus_map_check(&m, why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "register target_pos: type input is read-only"));
    assert_int_equal(rail_modbus_preset("ribbon-sim", &m), RAIL_OK);
    m.status.kind = RAIL_MB_COIL; /* one bit cannot hold a status word */
    assert_int_equal(rail_modbus_map_check(&m, why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "register status: type coil is one bit"));
    assert_int_equal(rail_modbus_preset("ribbon-sim", &m), RAIL_OK);
    m.status.kind = RAIL_MB_INPUT; /* read-only roles may live in the input table */
    assert_int_equal(rail_modbus_map_check(&m, why, sizeof why), RAIL_OK);
    m.n_info = 1;
    m.info[0] = (rail_mb_info){.name = "x", .reg = {.addr = 5, .words = 2, .kind = RAIL_MB_COIL}};
    assert_int_equal(rail_modbus_map_check(&m, why, sizeof why), RAIL_E_INVALID);
    assert_non_null(strstr(why, "information register x"));
}

/* Decoding is pure: status bits by the map's masks, with unnamed bits listed; alarm and
   identity texts; 32-bit values in the driver's units. */
static void test_decode(void **state)
{
    (void)state;
    rail_modbus_map m;
    assert_int_equal(rail_modbus_preset("ribbon-sim", &m), RAIL_OK);
    rail_mb_probe_row rows[RAIL_MB_PROBE_MAX];
    int n = rail_modbus_probe_rows(&m, rows, RAIL_MB_PROBE_MAX);
    assert_int_equal(n, 11);
    rail_mb_probe_row st = *row(rows, n, "status");
    rail_modbus_probe_decode(&m, &st, 0x22 | 0x40);
    assert_string_equal(st.text, "moving ALARM other bits 0x40");
    rail_modbus_probe_decode(&m, &st, 0);
    assert_string_equal(st.text, "no bit set");
    rail_mb_probe_row al = *row(rows, n, "alarm");
    rail_modbus_probe_decode(&m, &al, 0x66);
    assert_string_equal(al.text, "alarm code 0x66");
    rail_mb_probe_row sp = *row(rows, n, "speed");
    rail_modbus_probe_decode(&m, &sp, 2500);
    assert_true(fabs(sp.value - 2.5) < 1e-12);
    assert_string_equal(sp.unit, "mm/s");
    rail_mb_probe_row id = *row(rows, n, "ident");
    rail_modbus_probe_decode(&m, &id, 0x1234);
    assert_non_null(strstr(id.text, "MISMATCH"));
}

/* An unverified map carries a warning naming it, its file and its source; a verified one none. */
static void test_unverified_warning(void **state)
{
    (void)state;
    rail_modbus_map m;
    char w[600];
    assert_int_equal(rail_modbus_preset("ribbon-sim", &m), RAIL_OK);
    assert_int_equal(rail_modbus_map_warning(&m, w, sizeof w), 0);
    assert_string_equal(w, "");
    assert_int_equal(rail_modbus_preset("oriental-az", &m), RAIL_OK);
    assert_int_equal(rail_modbus_map_warning(&m, w, sizeof w), 1);
    assert_non_null(strstr(w, "Modbus map oriental-az (built-in) is not verified"));
    assert_non_null(strstr(w, "HM-60262E"));
    snprintf(m.file, sizeof m.file, "maps/oriental-az.ini");
    assert_int_equal(rail_modbus_map_warning(&m, w, sizeof w), 1);
    assert_non_null(strstr(w, "(maps/oriental-az.ini)"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_probe_reads_every_register),
        cmocka_unit_test(test_probe_writes_nothing),
        cmocka_unit_test(test_probe_wrong_table_row),
        cmocka_unit_test(test_probe_unreachable),
        cmocka_unit_test(test_driver_reads_the_mapped_table),
        cmocka_unit_test(test_driver_honours_sign),
        cmocka_unit_test(test_map_check_tables),
        cmocka_unit_test(test_decode),
        cmocka_unit_test(test_unverified_warning),
    };
    return cmocka_run_group_tests(tests, start_sim, stop_sim);
}
