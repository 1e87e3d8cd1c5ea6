/* rail_modbus_probe.c: one read-only pass over a Modbus map's registers (see
 * rail_modbus_probe.h). Units follow the driver's own conversions, so what the probe prints is
 * what the driver would believe: positions counts / counts_per_mm, speeds counts /
 * speed_per_mm_s, accelerations counts / accel_per_mm_s2 (each 0 = counts_per_mm), the watchdog
 * in its units per second, the load times load_scale, an information register times its scale. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "rail_modbus_link.h"
#include "rail_modbus_probe.h"

/* Indices of rail_modbus_role_name(). */
enum { R_TARGET, R_SPEED, R_ACCEL, R_DECEL, R_OPTYPE, R_TRIGGER, R_CONTROL, R_POS, R_VEL, R_STATUS,
       R_ALARM, R_WATCHDOG, R_IDENT, R_LOAD };

static int role_of(const char *name)
{
    for (int i = 0; i < RAIL_MB_ROLES; i++)
        if (!strcmp(rail_modbus_role_name(i), name))
            return i;
    return -1;
}

/* The role's own signedness (rail_modbus.c reads positions, velocity and load signed). */
static bool role_signed(int role, rail_mb_reg g)
{
    if (g.sign != RAIL_MB_SIGN_ROLE)
        return g.sign == RAIL_MB_SIGNED;
    if (g.words == 2)
        return true;
    return role == R_POS || role == R_VEL || role == R_LOAD || role == R_TARGET;
}

static const char *role_unit(int role)
{
    switch (role) {
    case R_TARGET: case R_POS: return "mm";
    case R_SPEED: case R_VEL: return "mm/s";
    case R_ACCEL: case R_DECEL: return "mm/s^2";
    case R_WATCHDOG: return "s";
    default: return "";
    }
}

int rail_modbus_probe_rows(const rail_modbus_map *m, rail_mb_probe_row *rows, int max)
{
    int n = 0;
    for (int i = 0; i < RAIL_MB_ROLES && n < max; i++) {
        const rail_mb_reg *g = rail_modbus_role_c(m, i);
        if (g->addr < 0)
            continue;
        rail_mb_probe_row *r = &rows[n++];
        memset(r, 0, sizeof *r);
        snprintf(r->name, sizeof r->name, "%s", rail_modbus_role_name(i));
        r->reg = *g;
        r->is_signed = role_signed(i, *g);
        snprintf(r->unit, sizeof r->unit, "%s", role_unit(i));
        r->value = NAN;
    }
    for (int i = 0; i < m->n_info && n < max; i++) {
        rail_mb_probe_row *r = &rows[n++];
        memset(r, 0, sizeof *r);
        snprintf(r->name, sizeof r->name, "info.%.30s", m->info[i].name);
        r->reg = m->info[i].reg;
        r->is_signed = m->info[i].reg.sign == RAIL_MB_SIGNED;
        snprintf(r->unit, sizeof r->unit, "%s", m->info[i].unit);
        r->value = NAN;
    }
    return n;
}

/* Names of the status bits set in st, by the map's masks; bits no mask names are listed in hex. */
static void status_text(const rail_modbus_map *m, unsigned long st, char *out, size_t n)
{
    const struct {
        unsigned long mask;
        const char *name;
    } bits[] = {{m->st_ready, "ready"},   {m->st_moving, "moving"},  {m->st_in_pos, "in-position"},
                {m->st_homing, "homing"}, {m->st_home_end, "homed"}, {m->st_alarm, "ALARM"}};
    size_t used = 0;
    unsigned long named = 0;
    out[0] = 0;
    for (size_t i = 0; i < sizeof bits / sizeof bits[0]; i++) {
        named |= bits[i].mask;
        if (bits[i].mask && (st & bits[i].mask) == bits[i].mask && used < n)
            used += (size_t)snprintf(out + used, n - used, "%s%s", used ? " " : "", bits[i].name);
    }
    if (st & ~named && used < n)
        used += (size_t)snprintf(out + used, n - used, "%sother bits 0x%lx", used ? " " : "", st & ~named);
    if (!used)
        snprintf(out, n, "no bit set");
}

void rail_modbus_probe_decode(const rail_modbus_map *m, rail_mb_probe_row *row, long raw)
{
    row->raw = raw;
    row->value = NAN;
    row->text[0] = 0;
    double speed = m->speed_per_mm_s > 0.0 ? m->speed_per_mm_s : m->counts_per_mm;
    double accel = m->accel_per_mm_s2 > 0.0 ? m->accel_per_mm_s2 : m->counts_per_mm;
    if (!strncmp(row->name, "info.", 5)) {
        const char *nm = row->name + 5;
        for (int i = 0; i < m->n_info; i++)
            if (!strcmp(m->info[i].name, nm))
                row->value = (double)raw * (m->info[i].scale != 0.0 ? m->info[i].scale : 1.0);
        return;
    }
    switch (role_of(row->name)) {
    case R_TARGET: case R_POS:
        row->value = (double)raw / m->counts_per_mm;
        break;
    case R_SPEED: case R_VEL:
        row->value = (double)raw / speed;
        break;
    case R_ACCEL: case R_DECEL:
        row->value = (double)raw / accel;
        break;
    case R_WATCHDOG:
        row->value = m->watchdog_units_per_s > 0.0 ? (double)raw / m->watchdog_units_per_s : NAN;
        if (raw == 0)
            snprintf(row->text, sizeof row->text, "off");
        break;
    case R_LOAD:
        row->value = (double)raw * m->load_scale;
        break;
    case R_STATUS:
        status_text(m, (unsigned long)raw, row->text, sizeof row->text);
        break;
    case R_ALARM:
        snprintf(row->text, sizeof row->text, raw ? "alarm code 0x%lx" : "no alarm", (unsigned long)raw);
        break;
    case R_IDENT:
        if (m->ident_value < 0)
            snprintf(row->text, sizeof row->text, "any identity accepted");
        else if (raw == m->ident_value)
            snprintf(row->text, sizeof row->text, "as the map expects (0x%lx)", m->ident_value);
        else
            snprintf(row->text, sizeof row->text, "MISMATCH: the map expects 0x%lx (wrong drive or map)",
                     m->ident_value);
        break;
    default:
        break;
    }
    if (isnan(row->value))
        row->unit[0] = 0;
}

/* One register of any table, joined and signed as the row says: 0, or the errno of the failure. */
static int read_row(modbus_t *ctx, const rail_modbus_map *m, rail_mb_probe_row *r)
{
    uint16_t w[2] = {0, 0};
    uint8_t bit = 0;
    int got;
    switch (r->reg.kind) {
    case RAIL_MB_INPUT: got = modbus_read_input_registers(ctx, r->reg.addr, r->reg.words, w); break;
    case RAIL_MB_COIL: got = modbus_read_bits(ctx, r->reg.addr, 1, &bit); break;
    case RAIL_MB_DISCRETE: got = modbus_read_input_bits(ctx, r->reg.addr, 1, &bit); break;
    default: got = modbus_read_registers(ctx, r->reg.addr, r->reg.words, w); break;
    }
    int want = r->reg.kind == RAIL_MB_COIL || r->reg.kind == RAIL_MB_DISCRETE ? 1 : r->reg.words;
    if (got != want) {
        int err = errno;
        snprintf(r->error, sizeof r->error, "%s", modbus_strerror(err));
        if (err == ETIMEDOUT || err == EMBBADCRC || err == EMBBADDATA)
            modbus_flush(ctx);
        return err ? err : EIO;
    }
    long raw;
    if (r->reg.kind == RAIL_MB_COIL || r->reg.kind == RAIL_MB_DISCRETE)
        raw = bit ? 1 : 0;
    else if (r->reg.words == 2) {
        int32_t v = rail_mb_get32(w, m->word_order);
        raw = r->is_signed ? (long)v : (long)(uint32_t)v;
    } else
        raw = r->is_signed ? (long)(int16_t)w[0] : (long)w[0];
    r->ok = true;
    rail_modbus_probe_decode(m, r, raw);
    return 0;
}

rail_err rail_modbus_probe(const rail_modbus_params *mp, rail_mb_probe_row *rows, int max, int *n,
                           char *why, size_t why_len)
{
    *n = 0;
    const rail_modbus_map *m = &mp->map;
    rail_err e = rail_modbus_map_check(m, why, why_len);
    if (e != RAIL_OK)
        return e;
    if (mp->slave < 1 || mp->slave > 247) {
        snprintf(why, why_len, "modbus: slave id %d outside 1..247", mp->slave);
        return RAIL_E_INVALID;
    }
    if (!(mp->timeout_s >= 0.01 && mp->timeout_s <= 5.0)) {
        snprintf(why, why_len, "modbus: timeout_s %g outside [0.01, 5]", mp->timeout_s);
        return RAIL_E_INVALID;
    }
    modbus_t *ctx = NULL;
    e = rail_modbus_link_open(&ctx, mp->address, mp->rtu, mp->baud, mp->parity, mp->slave, mp->timeout_s, why,
                              why_len);
    if (e != RAIL_OK)
        return e;
    *n = rail_modbus_probe_rows(m, rows, max);
    int failed = 0;
    rail_err first = RAIL_OK;
    for (int i = 0; i < *n; i++) {
        int err = read_row(ctx, m, &rows[i]);
        if (err == 0)
            continue;
        failed++;
        if (first == RAIL_OK)
            first = err == ETIMEDOUT ? RAIL_E_TIMEOUT
                    : err > MODBUS_ENOBASE && err <= EMBXGTAR ? RAIL_E_DEVICE : RAIL_E_PROTOCOL;
    }
    rail_modbus_link_close(ctx);
    if (failed)
        snprintf(why, why_len, "%d of %d registers did not answer (see their rows)", failed, *n);
    return first;
}
