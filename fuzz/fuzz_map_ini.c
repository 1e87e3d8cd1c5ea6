/* fuzz_map_ini.c: fuzz target for Modbus register map files (config/modbus_map_file.c, on text in
 * memory): a refusal carries a status, a message and the file's name; an accepted map holds only
 * registers the driver can address (address -1..65535, 16 or 32 bits, a known table, one-bit
 * tables only on probe-only registers), finite scales and terminated text. */
#include <math.h>
#include <string.h>

#include "fuzz_inputs.h"
#include "modbus_map_file.h"

static void check_reg(const rail_mb_reg *r, int role)
{
    if (r->addr < -1 || r->addr > 65535 || (r->words != 1 && r->words != 2))
        fuzz_fail("map_ini", "an accepted register out of range");
    if ((int)r->kind < RAIL_MB_HOLDING || (int)r->kind > RAIL_MB_DISCRETE ||
        (int)r->sign < RAIL_MB_SIGN_ROLE || (int)r->sign > RAIL_MB_UNSIGNED)
        fuzz_fail("map_ini", "a register table or sign out of its enum");
    if (role && (r->kind == RAIL_MB_COIL || r->kind == RAIL_MB_DISCRETE))
        fuzz_fail("map_ini", "a one-bit table on a driver role");
    if (!memchr(r->meaning, '\0', sizeof r->meaning))
        fuzz_fail("map_ini", "unterminated meaning");
}

int fuzz_map_ini_one(const uint8_t *data, size_t size)
{
    rail_modbus_map m;
    cfg_error err;
    cfg_status st = modbus_map_file_parse("fuzz-map.ini", (const char *)data, size, &m, &err);
    if (st != CFG_OK) {
        if (err.status != st || err.message[0] == '\0' || strcmp(err.file, "fuzz-map.ini"))
            fuzz_fail("map_ini", "a refusal without a reason or a file");
        return 0;
    }
    for (int i = 0; i < RAIL_MB_ROLES; i++)
        check_reg(rail_modbus_role_c(&m, i), 1);
    if (m.n_info < 0 || m.n_info > RAIL_MB_INFO_MAX)
        fuzz_fail("map_ini", "information register count out of range");
    for (int i = 0; i < m.n_info; i++) {
        check_reg(&m.info[i].reg, 0);
        if (m.info[i].reg.addr < 0 || !isfinite(m.info[i].scale) || m.info[i].scale == 0.0 ||
            !m.info[i].name[0] || !memchr(m.info[i].unit, '\0', sizeof m.info[i].unit))
            fuzz_fail("map_ini", "an accepted information register without address, scale or name");
    }
    const double v[] = {m.counts_per_mm, m.speed_per_mm_s, m.accel_per_mm_s2, m.load_scale,
                        m.watchdog_units_per_s};
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
        if (!isfinite(v[i]))
            fuzz_fail("map_ini", "an accepted map holds a non-finite value");
    if (!m.name[0] || !memchr(m.name, '\0', sizeof m.name) || !memchr(m.source, '\0', sizeof m.source))
        fuzz_fail("map_ini", "an accepted map without a terminated name");
    return 0;
}

FUZZ_ENTRY(fuzz_map_ini_one)
