/* rail_modbus.c: the Modbus rail driver (see rail_modbus.h).
 *
 * Every request goes through mb_call(), which maps libmodbus's errno to the layer's errors:
 * Modbus exception responses -> RAIL_E_DEVICE (named by libmodbus), bad CRC / bad data / wrong
 * slave / unknown exception -> RAIL_E_PROTOCOL, timeouts -> RAIL_E_TIMEOUT, a closed or reset
 * link -> RAIL_E_DISCONNECTED. After a protocol error or a timeout the receive side is flushed
 * so a late reply cannot pass for the next one. A lost link is retried (connect only) at the
 * next poll; a reconnect probes read-only and re-arms the watchdog, never resumes a move.
 * Writes use function 16 (write multiple registers) only, contiguous values in one request. */
#include <errno.h>
#include <math.h>
#include <modbus.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rail_modbus.h"
#include "rail_modbus_link.h"

typedef struct mb {
    modbus_t *ctx;
    rail_modbus_params m;
    double speed_scale, accel_scale;  /* drive units per mm/s, per mm/s^2 */
    double accel_mm_s2;               /* mm/s^2 from the rail parameters */
    bool lost;                        /* link down: reconnect (only) at the next poll */
    bool homing;                      /* home sent and not finished (maps without a homing bit) */
    double prev_pos, prev_t;          /* mm, s: for velocity when the map has no velocity register */
    double pos_mm;                    /* last position read */
} mb;

rail_modbus_params rail_modbus_params_default(void)
{
    rail_modbus_params p;
    memset(&p, 0, sizeof p);
    snprintf(p.address, sizeof p.address, "127.0.0.1:1502");
    p.rtu = false;
    p.baud = 19200;
    p.parity = 'E';
    p.slave = 1;
    p.timeout_s = 0.2;
    p.watchdog_s = 1.0;
    rail_modbus_preset("ribbon-sim", &p.map);
    return p;
}

static rail_err mb_fail(rail *r, mb *k, const char *what)
{
    int err = errno;
    rail_err e;
    if (err > MODBUS_ENOBASE && err <= EMBXGTAR)
        e = RAIL_E_DEVICE;
    else if (err == EMBBADCRC || err == EMBBADDATA || err == EMBBADEXC || err == EMBMDATA ||
             err == EMBBADSLAVE || err == EMBUNKEXC)
        e = RAIL_E_PROTOCOL;
    else if (err == ETIMEDOUT)
        e = RAIL_E_TIMEOUT;
    else
        e = RAIL_E_DISCONNECTED;
    if (e == RAIL_E_PROTOCOL || e == RAIL_E_TIMEOUT)
        modbus_flush(k->ctx);
    if (e == RAIL_E_DISCONNECTED)
        k->lost = true;
    if (e == RAIL_E_DEVICE)
        return rail_set_error(r, e, "%s: drive answered with exception: %s", what, modbus_strerror(err));
    return rail_set_error(r, e, "%s: %s", what, modbus_strerror(err));
}

/* n registers from addr of the table `kind` (holding: function 3, input: function 4; the map
 * check keeps coils and discrete inputs off the driver's roles). */
static rail_err read_regs(rail *r, mb *k, rail_mb_kind kind, int addr, int n, uint16_t *dst, const char *what)
{
    int got = kind == RAIL_MB_INPUT ? modbus_read_input_registers(k->ctx, addr, n, dst)
                                    : modbus_read_registers(k->ctx, addr, n, dst);
    if (got != n)
        return mb_fail(r, k, what);
    return RAIL_OK;
}

/* Value of reg from a block read starting at base; is_signed is the role's own reading, which
 * the map's sign (a map file's `signed`) overrides. */
static long reg_get(const mb *k, rail_mb_reg g, const uint16_t *blk, int base, bool is_signed)
{
    const uint16_t *w = blk + (g.addr - base);
    if (g.sign != RAIL_MB_SIGN_ROLE)
        is_signed = g.sign == RAIL_MB_SIGNED;
    if (g.words == 2) {
        int32_t v = rail_mb_get32(w, k->m.map.word_order);
        return g.sign == RAIL_MB_UNSIGNED ? (long)(uint32_t)v : (long)v;
    }
    return is_signed ? (long)(int16_t)w[0] : (long)w[0];
}

typedef struct wr {
    int addr;
    uint16_t v;
} wr;

static void batch_put(wr *b, int *n, rail_mb_reg g, long v, rail_mb_word_order o)
{
    if (g.addr < 0)
        return;
    if (g.words == 2) {
        uint16_t w[2];
        rail_mb_put32(w, (int32_t)v, o);
        b[(*n)++] = (wr){g.addr, w[0]};
        b[(*n)++] = (wr){g.addr + 1, w[1]};
    } else {
        b[(*n)++] = (wr){g.addr, (uint16_t)v};
    }
}

static int wr_cmp(const void *a, const void *b)
{
    return ((const wr *)a)->addr - ((const wr *)b)->addr;
}

/* Write a batch: sorted, each contiguous run in one function-16 request. */
static rail_err batch_write(rail *r, mb *k, wr *b, int n, const char *what)
{
    qsort(b, (size_t)n, sizeof *b, wr_cmp);
    for (int i = 0; i < n;) {
        int j = i + 1;
        while (j < n && b[j].addr == b[j - 1].addr + 1 && j - i < 120)
            j++;
        uint16_t vals[120];
        for (int q = i; q < j; q++)
            vals[q - i] = b[q].v;
        if (modbus_write_registers(k->ctx, b[i].addr, j - i, vals) != j - i)
            return mb_fail(r, k, what);
        i = j;
    }
    return RAIL_OK;
}

static rail_err write_one(rail *r, mb *k, rail_mb_reg g, long v, const char *what)
{
    wr b[2];
    int n = 0;
    batch_put(b, &n, g, v, k->m.map.word_order);
    return batch_write(r, k, b, n, what);
}

/* Read-only probe: identity (if mapped), status and position must answer. */
static rail_err probe(rail *r, mb *k)
{
    const rail_modbus_map *m = &k->m.map;
    uint16_t w[2];
    if (m->ident.addr >= 0) {
        rail_err e = read_regs(r, k, m->ident.kind, m->ident.addr, m->ident.words, w, "probe: identity register");
        if (e != RAIL_OK)
            return e;
        long id = reg_get(k, m->ident, w, m->ident.addr, false);
        if (m->ident_value >= 0 && id != m->ident_value)
            return rail_set_error(r, RAIL_E_PROTOCOL,
                                  "probe: identity register %d reads 0x%lx, map %s expects 0x%lx; "
                                  "wrong drive or wrong map, nothing written",
                                  m->ident.addr, id, m->name, m->ident_value);
    }
    rail_err e = read_regs(r, k, m->status.kind, m->status.addr, m->status.words, w, "probe: status register");
    if (e == RAIL_OK)
        e = read_regs(r, k, m->actual_pos.kind, m->actual_pos.addr, m->actual_pos.words, w,
                      "probe: position register");
    return e;
}

static rail_err arm_watchdog(rail *r, mb *k)
{
    const rail_modbus_map *m = &k->m.map;
    if (m->watchdog.addr < 0)
        return RAIL_OK;
    long v = lround(k->m.watchdog_s * m->watchdog_units_per_s);
    return write_one(r, k, m->watchdog, v, "arming the communication watchdog");
}

rail_state rail_mb_state_of(const rail_modbus_map *m, unsigned long st, long alarm, bool homing, char *msg,
                            size_t n)
{
    if (n)
        msg[0] = 0;
    if ((m->st_alarm && (st & m->st_alarm)) || (m->st_alarm == 0 && alarm != 0)) {
        snprintf(msg, n, "drive alarm code 0x%lx", (unsigned long)alarm);
        return RAIL_STATE_ALARM;
    }
    if ((m->st_homing && (st & m->st_homing)) || (homing && (st & m->st_moving)))
        return RAIL_STATE_HOMING;
    if (st & m->st_moving)
        return RAIL_STATE_MOVING;
    if (homing && m->st_home_end && !(st & m->st_home_end)) {
        snprintf(msg, n, "homing ended without the home-end bit");
        return RAIL_STATE_FAULT;
    }
    return RAIL_STATE_IDLE;
}

static rail_err mb_poll(rail *r, void *impl, rail_status *out)
{
    mb *k = impl;
    const rail_modbus_map *m = &k->m.map;
    out->code = 0;
    out->message[0] = 0;
    out->position_mm = k->pos_mm;
    if (k->lost) {
        /* Reconnect only: probe, re-arm the watchdog; any earlier move is forgotten. */
        modbus_close(k->ctx);
        rail_err e = RAIL_E_DISCONNECTED;
        if (modbus_connect(k->ctx) == 0) {
            k->lost = false;
            k->homing = false;
            e = probe(r, k);
            if (e == RAIL_OK)
                e = arm_watchdog(r, k);
        } else {
            e = rail_set_error(r, RAIL_E_DISCONNECTED, "drive at %s unreachable: %s", k->m.address,
                               modbus_strerror(errno));
        }
        if (e != RAIL_OK) {
            out->state = RAIL_STATE_DISCONNECTED;
            rail_text_copy(out->message, sizeof out->message, rail_last_error(r));
            return e;
        }
    }
    /* Position, velocity, status, alarm and load: one block read when they lie within 64
     * registers of each other in one table, else one read each. */
    rail_mb_reg regs[5] = {m->actual_pos, m->actual_vel, m->status, m->alarm, m->load};
    const bool is_signed[5] = {true, true, false, false, true};
    int lo = 65536, hi = -1;
    bool one_table = true;
    for (int i = 0; i < 5; i++)
        if (regs[i].addr >= 0) {
            lo = regs[i].addr < lo ? regs[i].addr : lo;
            hi = regs[i].addr + regs[i].words - 1 > hi ? regs[i].addr + regs[i].words - 1 : hi;
            one_table = one_table && regs[i].kind == m->actual_pos.kind;
        }
    uint16_t blk[64];
    long val[5] = {0, 0, 0, 0, 0};
    rail_err e = RAIL_E_TIMEOUT;
    for (int attempt = 0; attempt < 2; attempt++) { /* one retry for a single bad reply */
        if (hi - lo + 1 <= 64 && one_table) {
            e = read_regs(r, k, m->actual_pos.kind, lo, hi - lo + 1, blk, "reading status");
            for (int i = 0; i < 5 && e == RAIL_OK; i++)
                val[i] = regs[i].addr >= 0 ? reg_get(k, regs[i], blk, lo, is_signed[i]) : 0;
        } else {
            e = RAIL_OK;
            for (int i = 0; i < 5 && e == RAIL_OK; i++) {
                if (regs[i].addr < 0)
                    continue;
                e = read_regs(r, k, regs[i].kind, regs[i].addr, regs[i].words, blk,
                              i == 4 ? "reading the load" : "reading status");
                val[i] = e == RAIL_OK ? reg_get(k, regs[i], blk, regs[i].addr, is_signed[i]) : 0;
            }
        }
        if (e == RAIL_OK || e == RAIL_E_DISCONNECTED || e == RAIL_E_DEVICE)
            break;
    }
    long pos_c = val[0], vel_c = val[1], status = val[2], alarm = val[3];
    if (e != RAIL_OK) {
        out->state = e == RAIL_E_DEVICE || e == RAIL_E_PROTOCOL ? RAIL_STATE_FAULT : RAIL_STATE_DISCONNECTED;
        rail_text_copy(out->message, sizeof out->message, rail_last_error(r));
        return e;
    }
    double now = rail_clock_now(rail_get_clock(r));
    double pos = (double)pos_c / m->counts_per_mm;
    out->position_mm = pos;
    k->pos_mm = pos;
    out->has_load = m->load.addr >= 0;
    out->load = out->has_load ? (double)val[4] * m->load_scale : 0.0;
    if (m->actual_vel.addr >= 0)
        out->velocity_mm_s = (double)vel_c / k->speed_scale;
    else
        out->velocity_mm_s = now > k->prev_t ? (pos - k->prev_pos) / (now - k->prev_t) : 0.0;
    k->prev_pos = pos;
    k->prev_t = now;
    char msg[sizeof out->message];
    rail_state state = rail_mb_state_of(m, (unsigned long)status, alarm, k->homing, msg, sizeof msg);
    out->state = state;
    rail_text_copy(out->message, sizeof out->message, msg);
    if (state == RAIL_STATE_ALARM)
        out->code = (int)alarm;
    if (state != RAIL_STATE_MOVING && state != RAIL_STATE_HOMING) {
        k->homing = false;
        out->velocity_mm_s = 0.0;
    }
    return RAIL_OK;
}

static rail_err mb_move_abs(rail *r, void *impl, double target, double speed)
{
    mb *k = impl;
    const rail_modbus_map *m = &k->m.map;
    double tc = target * m->counts_per_mm;
    double sc = speed * k->speed_scale;
    double ac = k->accel_mm_s2 * k->accel_scale;
    if (fabs(tc) > 2147483647.0 || sc > 2147483647.0 || ac > 2147483647.0)
        return rail_set_error(r, RAIL_E_INVALID, "target, speed or acceleration overflows 32-bit drive counts");
    wr b[16];
    int n = 0;
    batch_put(b, &n, m->target_pos, lround(tc), m->word_order);
    batch_put(b, &n, m->speed, lround(sc) > 0 ? lround(sc) : 1, m->word_order);
    batch_put(b, &n, m->accel, lround(ac) > 0 ? lround(ac) : 1, m->word_order);
    batch_put(b, &n, m->decel, lround(ac) > 0 ? lround(ac) : 1, m->word_order);
    batch_put(b, &n, m->op_type, m->op_type_abs, m->word_order);
    rail_err e = batch_write(r, k, b, n, "writing move data");
    if (e == RAIL_OK)
        e = write_one(r, k, m->trigger, m->trigger_value, "triggering the move");
    return e;
}

static rail_err mb_control(rail *r, mb *k, long v, const char *what)
{
    if (v == 0)
        return rail_set_error(r, RAIL_E_UNSUPPORTED, "map %s has no %s command", k->m.map.name, what);
    return write_one(r, k, k->m.map.control, v, what);
}

static rail_err mb_stop(rail *r, void *impl)
{
    mb *k = impl;
    return mb_control(r, k, k->m.map.ctl_stop, "stop");
}

static rail_err mb_estop(rail *r, void *impl)
{
    mb *k = impl;
    long v = k->m.map.ctl_estop ? k->m.map.ctl_estop : k->m.map.ctl_stop;
    return mb_control(r, k, v, "emergency stop");
}

static rail_err mb_home(rail *r, void *impl)
{
    mb *k = impl;
    rail_err e = mb_control(r, k, k->m.map.ctl_home, "home");
    if (e == RAIL_OK)
        k->homing = true;
    return e;
}

static rail_err mb_reset(rail *r, void *impl)
{
    mb *k = impl;
    return mb_control(r, k, k->m.map.ctl_reset, "alarm reset");
}

static void mb_close(void *impl)
{
    mb *k = impl;
    rail_modbus_link_close(k->ctx);
    free(k);
}

static const rail_ops mb_ops = {
    .name = "modbus",
    .poll = mb_poll,
    .move_abs = mb_move_abs,
    .jog = NULL, /* bounded move to the limit in the jog's direction */
    .stop = mb_stop,
    .estop = mb_estop,
    .home = mb_home,
    .reset = mb_reset,
    .close = mb_close,
};

rail_err rail_modbus_open(rail **out, const rail_params *p, const rail_modbus_params *mp,
                          rail_clock clock, char *why, size_t why_len)
{
    *out = NULL;
    rail_err e = rail_params_check(p, why, why_len);
    if (e != RAIL_OK)
        return e;
    const rail_modbus_map *m = &mp->map;
    if (!m->verified && !mp->allow_unverified) {
        snprintf(why, why_len,
                 "modbus: map '%s' has not been verified on a real drive (source: %.120s); check "
                 "it against the drive's manual and opt in explicitly (allow_unverified / "
                 "--allow-unverified)",
                 m->name, m->source);
        return RAIL_E_UNVERIFIED;
    }
    e = rail_modbus_map_check(m, why, why_len);
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
    if (m->watchdog.addr >= 0) {
        if (!(mp->watchdog_s >= 2.0 / p->poll_hz && mp->watchdog_s <= 10.0)) {
            snprintf(why, why_len,
                     "modbus: watchdog_s %g must be within [2 poll periods = %.3f s, 10 s] so "
                     "polls keep it alive and a dead process stops the drive",
                     mp->watchdog_s, 2.0 / p->poll_hz);
            return RAIL_E_INVALID;
        }
    } else if (!mp->watchdog_external) {
        snprintf(why, why_len,
                 "modbus: map '%s' has no watchdog register; configure the drive's own "
                 "communication timeout and confirm it (watchdog_external = true), or a dead "
                 "process could leave the rail running",
                 m->name);
        return RAIL_E_INVALID;
    }
    mb *k = calloc(1, sizeof *k);
    if (!k) {
        snprintf(why, why_len, "modbus: out of memory");
        return RAIL_E_NOMEM;
    }
    k->m = *mp;
    k->speed_scale = m->speed_per_mm_s > 0.0 ? m->speed_per_mm_s : m->counts_per_mm;
    k->accel_scale = m->accel_per_mm_s2 > 0.0 ? m->accel_per_mm_s2 : m->counts_per_mm;
    k->accel_mm_s2 = p->accel_mm_s2;
    k->prev_t = rail_clock_now(clock);
    e = rail_modbus_link_open(&k->ctx, mp->address, mp->rtu, mp->baud, mp->parity, mp->slave, mp->timeout_s,
                              why, why_len);
    if (e != RAIL_OK) {
        free(k);
        return e;
    }
    /* Create the rail first so the probe's failures have a rail to carry their reason. */
    rail *r = NULL;
    e = rail_create(&r, p, clock, &mb_ops, k, why, why_len);
    if (e != RAIL_OK)
        return e;
    e = probe(r, k);
    rail_status st;
    memset(&st, 0, sizeof st);
    if (e == RAIL_OK)
        e = mb_poll(r, k, &st);
    if (e == RAIL_OK && st.state == RAIL_STATE_MOVING)
        e = mb_stop(r, k); /* found moving (an earlier process): stop it, never adopt it */
    if (e == RAIL_OK)
        e = arm_watchdog(r, k);
    if (e != RAIL_OK) {
        snprintf(why, why_len, "modbus: %.200s", rail_last_error(r));
        rail_close(r);
        return e;
    }
    *out = r;
    return RAIL_OK;
}
