/* rail_modbus_map.c: register map presets and their checks, the roles by name, and the warning an
 * unverified map carries. The presets are also shipped as map files (config/maps/NAME.ini, read by
 * config/modbus_map_file.c); test_modbus_map_file keeps each file equal to its preset.
 *
 * "ribbon-sim": the simulated drive served by ribbon-mbsim (drivers/mb_sim.c), holding registers
 * (32-bit values high word first, counts = 1 um):
 *   0-1 target position (counts)   2-3 speed (counts/s)     4-5 acceleration (counts/s^2)
 *   6   command: 1 start absolute move, 2 stop, 3 emergency stop, 4 home, 5 alarm reset
 *   8-9 actual position (counts)  10-11 actual velocity (counts/s)
 *   12  status bits: 0 ready, 1 moving, 2 in position, 3 homing, 4 homed, 5 alarm
 *   13  alarm code                14 watchdog (ms, 0 = off)   16 identity 0x5242   17 version
 *   18  external load (signed 16-bit, written by whoever plays the load sensor; not in the
 *       preset: reg_load = 18 reads it)
 *
 * "oriental-az": Oriental Motor AZ series drivers with RS-485 (AZD-KD, AZD-CD, ...), direct data
 * operation, from "AZ Series / Motorized actuators equipped with AZ Series, Function Edition"
 * (Oriental Motor manual HM-60262E, chapter on Modbus RTU, "Direct data operation" and
 * "Monitor commands" register tables): operation type 0x005A, position 0x005C, speed 0x005E,
 * starting/changing rate 0x0060, stopping deceleration 0x0062, trigger 0x0066 (write 1),
 * driver input command (automatic OFF) 0x0078 (ZHOME 0x10, STOP 0x20, ALM-RST 0x80), driver
 * output status 0x007E (HOME-END 0x10, READY 0x20, ALM-A 0x80, MOVE 0x2000, IN-POS 0x4000, the
 * default R-OUT assignment), present alarm 0x0080, detection (feedback) position 0x00CC; all
 * 32-bit upper word first; position in steps, speed in Hz (steps/s), rates in Hz/s with the
 * default 0.001 kHz/s unit. NOT VERIFIED on a drive: the addresses must be checked against the
 * manual revision of the drive at hand (some sources list the feedback position at 0x0120),
 * and the R-OUT assignment against the drive's parameters. The AZ communication timeout is a
 * drive parameter, not mapped here: set it with the vendor's software and confirm with
 * watchdog_external. counts_per_mm depends on the mechanics and must be configured. The
 * operating current (0x0064) and operation data number (0x0058) are not written: the drive's
 * values stand. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "rail_modbus_map.h"

static rail_mb_reg R(int addr, int words)
{
    rail_mb_reg r = {.addr = addr, .words = words};
    return r;
}

static const rail_mb_reg NONE = {.addr = -1, .words = 1};

static void map_sim(rail_modbus_map *m)
{
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "ribbon-sim");
    m->verified = true;
    snprintf(m->source, sizeof m->source, "ribbon-mbsim simulated drive (drivers/mb_sim.c)");
    m->word_order = RAIL_MB_HIGH_FIRST;
    m->counts_per_mm = 1000.0;
    m->target_pos = R(0, 2);
    m->speed = R(2, 2);
    m->accel = R(4, 2);
    m->decel = NONE;
    m->op_type = NONE;
    m->trigger = R(6, 1);
    m->control = R(6, 1);
    m->actual_pos = R(8, 2);
    m->actual_vel = R(10, 2);
    m->status = R(12, 1);
    m->alarm = R(13, 1);
    m->watchdog = R(14, 1);
    m->ident = R(16, 1);
    m->trigger_value = 1;
    m->ctl_stop = 2;
    m->ctl_estop = 3;
    m->ctl_home = 4;
    m->ctl_reset = 5;
    m->st_ready = 1u << 0;
    m->st_moving = 1u << 1;
    m->st_in_pos = 1u << 2;
    m->st_homing = 1u << 3;
    m->st_home_end = 1u << 4;
    m->st_alarm = 1u << 5;
    m->ident_value = 0x5242;
    m->watchdog_units_per_s = 1000.0;
    m->load = NONE; /* register 18 serves the simulator's external load: reg_load = 18 to read it */
    m->load_scale = 1.0;
}

static void map_oriental_az(rail_modbus_map *m)
{
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "oriental-az");
    m->verified = false;
    snprintf(m->source, sizeof m->source,
             "Oriental Motor HM-60262E (AZ Series Function Edition), Modbus RTU: direct data "
             "operation and monitor register tables");
    m->word_order = RAIL_MB_HIGH_FIRST;
    m->counts_per_mm = 0.0; /* steps per mm: mechanics-dependent, must be configured */
    m->op_type = R(0x005A, 2);
    m->target_pos = R(0x005C, 2);
    m->speed = R(0x005E, 2);
    m->accel = R(0x0060, 2);
    m->decel = R(0x0062, 2);
    m->trigger = R(0x0066, 2);
    m->control = R(0x0078, 2);
    m->status = R(0x007E, 2);
    m->alarm = R(0x0080, 2);
    m->actual_pos = R(0x00CC, 2);
    m->actual_vel = NONE;
    m->watchdog = NONE;
    m->ident = NONE;
    m->op_type_abs = 1;
    m->trigger_value = 1;
    m->ctl_home = 0x10;
    m->ctl_stop = 0x20;
    m->ctl_estop = 0x20; /* STOP input; its stop action is a drive parameter */
    m->ctl_reset = 0x80;
    m->st_home_end = 0x10;
    m->st_ready = 0x20;
    m->st_alarm = 0x80;
    m->st_moving = 0x2000;
    m->st_in_pos = 0x4000;
    m->st_homing = 0;
    m->ident_value = -1;
    m->watchdog_units_per_s = 1000.0;
    m->load = NONE; /* the AZ monitors torque too, but no address is checked: configure reg_load */
    m->load_scale = 1.0;
}

rail_err rail_modbus_preset(const char *name, rail_modbus_map *out)
{
    if (name && strcmp(name, "ribbon-sim") == 0) {
        map_sim(out);
        return RAIL_OK;
    }
    if (name && strcmp(name, "oriental-az") == 0) {
        map_oriental_az(out);
        return RAIL_OK;
    }
    return RAIL_E_INVALID;
}

static const char *const role_names[RAIL_MB_ROLES] = {
    "target_pos", "speed",  "accel",  "decel",    "op_type", "trigger", "control",
    "actual_pos", "actual_vel", "status", "alarm", "watchdog", "ident", "load"};

const char *rail_modbus_role_name(int i)
{
    return i >= 0 && i < RAIL_MB_ROLES ? role_names[i] : NULL;
}

rail_mb_reg *rail_modbus_role(rail_modbus_map *m, int i)
{
    rail_mb_reg *const regs[RAIL_MB_ROLES] = {
        &m->target_pos, &m->speed,      &m->accel,  &m->decel, &m->op_type,   &m->trigger, &m->control,
        &m->actual_pos, &m->actual_vel, &m->status, &m->alarm, &m->watchdog, &m->ident,   &m->load};
    return i >= 0 && i < RAIL_MB_ROLES ? regs[i] : NULL;
}

const rail_mb_reg *rail_modbus_role_c(const rail_modbus_map *m, int i)
{
    return rail_modbus_role((rail_modbus_map *)m, i);
}

int rail_modbus_role_written(int i)
{
    /* target_pos speed accel decel op_type trigger control are written to move and stop;
       watchdog is written once at open. */
    return (i >= 0 && i <= 6) || i == 11;
}

const char *rail_mb_kind_name(rail_mb_kind k)
{
    switch (k) {
    case RAIL_MB_HOLDING: return "holding";
    case RAIL_MB_INPUT: return "input";
    case RAIL_MB_COIL: return "coil";
    case RAIL_MB_DISCRETE: return "discrete";
    }
    return "?";
}

static bool reg_ok(rail_mb_reg r)
{
    return r.addr < 0 || (r.addr <= 65534 && (r.words == 1 || r.words == 2) && r.addr + r.words <= 65536 &&
                          (int)r.kind >= RAIL_MB_HOLDING && (int)r.kind <= RAIL_MB_DISCRETE &&
                          (int)r.sign >= RAIL_MB_SIGN_ROLE && (int)r.sign <= RAIL_MB_UNSIGNED &&
                          ((r.kind != RAIL_MB_COIL && r.kind != RAIL_MB_DISCRETE) || r.words == 1));
}

rail_err rail_modbus_map_check(const rail_modbus_map *m, char *why, size_t why_len)
{
    /* target_pos speed trigger control actual_pos status are required. */
    static const bool required[RAIL_MB_ROLES] = {true, true, false, false, false, true, true,
                                                 true, false, true, false, false, false, false};
    for (int i = 0; i < RAIL_MB_ROLES; i++) {
        const rail_mb_reg *r = rail_modbus_role_c(m, i);
        const char *name = rail_modbus_role_name(i);
        if (!reg_ok(*r)) {
            snprintf(why, why_len, "modbus map %s: register %s: address %d / width %d words / type %d invalid",
                     m->name, name, r->addr, r->words, (int)r->kind);
            return RAIL_E_INVALID;
        }
        if (required[i] && r->addr < 0) {
            snprintf(why, why_len, "modbus map %s: register %s is required", m->name, name);
            return RAIL_E_INVALID;
        }
        if (r->addr >= 0 && (r->kind == RAIL_MB_COIL || r->kind == RAIL_MB_DISCRETE)) {
            snprintf(why, why_len, "modbus map %s: register %s: type %s is one bit; the driver reads "
                     "it as a holding or input register", m->name, name, rail_mb_kind_name(r->kind));
            return RAIL_E_INVALID;
        }
        if (r->addr >= 0 && r->kind != RAIL_MB_HOLDING && rail_modbus_role_written(i)) {
            snprintf(why, why_len, "modbus map %s: register %s: type %s is read-only; the driver "
                     "writes this one (holding)", m->name, name, rail_mb_kind_name(r->kind));
            return RAIL_E_INVALID;
        }
    }
    if (m->n_info < 0 || m->n_info > RAIL_MB_INFO_MAX) {
        snprintf(why, why_len, "modbus map %s: %d information registers (at most %d)", m->name, m->n_info,
                 RAIL_MB_INFO_MAX);
        return RAIL_E_INVALID;
    }
    for (int i = 0; i < m->n_info; i++) {
        if (m->info[i].reg.addr < 0 || !reg_ok(m->info[i].reg) || !isfinite(m->info[i].scale)) {
            snprintf(why, why_len, "modbus map %s: information register %.32s: address %d / width %d "
                     "words / scale invalid", m->name, m->info[i].name, m->info[i].reg.addr,
                     m->info[i].reg.words);
            return RAIL_E_INVALID;
        }
    }
    if (!(m->counts_per_mm > 0.0) || !isfinite(m->counts_per_mm)) {
        snprintf(why, why_len, "modbus map %s: counts_per_mm must be set (> 0) for this rail's mechanics",
                 m->name);
        return RAIL_E_INVALID;
    }
    if (m->speed_per_mm_s < 0.0 || m->accel_per_mm_s2 < 0.0 || !isfinite(m->speed_per_mm_s) ||
        !isfinite(m->accel_per_mm_s2)) {
        snprintf(why, why_len, "modbus map %s: speed_per_mm_s and accel_per_mm_s2 must be >= 0", m->name);
        return RAIL_E_INVALID;
    }
    if (!isfinite(m->load_scale) || m->load_scale == 0.0) {
        snprintf(why, why_len, "modbus map %s: load_scale must be finite and non-zero", m->name);
        return RAIL_E_INVALID;
    }
    if (m->ctl_stop == 0 || m->st_moving == 0) {
        snprintf(why, why_len, "modbus map %s: a stop command (ctl_stop) and a moving status bit "
                         "(st_moving) are required", m->name);
        return RAIL_E_INVALID;
    }
    if (m->word_order != RAIL_MB_HIGH_FIRST && m->word_order != RAIL_MB_LOW_FIRST) {
        snprintf(why, why_len, "modbus map %s: word_order must be high_first or low_first", m->name);
        return RAIL_E_INVALID;
    }
    return RAIL_OK;
}

int rail_modbus_map_warning(const rail_modbus_map *m, char *out, size_t n)
{
    if (n)
        out[0] = 0;
    if (m->verified)
        return 0;
    snprintf(out, n,
             "Modbus map %s (%.160s) is not verified on a real drive (source: %.160s): compare every "
             "register with the drive's manual (ribbonctl rail --config RIG --rail NAME probe)",
             m->name, m->file[0] ? m->file : "built-in", m->source[0] ? m->source : "none given");
    return 1;
}

void rail_mb_put32(uint16_t *w, int32_t v, rail_mb_word_order o)
{
    uint32_t u = (uint32_t)v;
    uint16_t hi = (uint16_t)(u >> 16), lo = (uint16_t)(u & 0xffffu);
    w[0] = o == RAIL_MB_HIGH_FIRST ? hi : lo;
    w[1] = o == RAIL_MB_HIGH_FIRST ? lo : hi;
}

int32_t rail_mb_get32(const uint16_t *w, rail_mb_word_order o)
{
    uint32_t hi = o == RAIL_MB_HIGH_FIRST ? w[0] : w[1];
    uint32_t lo = o == RAIL_MB_HIGH_FIRST ? w[1] : w[0];
    return (int32_t)((hi << 16) | lo);
}
