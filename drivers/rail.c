/* rail.c: the rail front end: limit checks, confirmation, rate-limited polling, error reasons.
 *
 * Everything here runs before a driver is called, so no driver can forget a check: a target is
 * finite and inside [soft_min, soft_max]; the clamp gap at the target is at least min_gap (the
 * gap is affine in position, so checking the end point of a straight move checks the whole
 * path); a speed is finite, positive and at most max_speed. A jog becomes a bounded move toward
 * the nearest limit in its direction, so even a jog can never cross a limit.
 * Polling: rail_status_get() reads the device at most poll_hz times a second and otherwise
 * reconstructs the position from the last reading and what the front end last commanded
 * (flagged `extrapolated`; the profile is in rail.h and in reconstruct() below).
 * Drivers that feed motion in segments (GRBL) get their poll call at that same rate. */
#include "rail.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The last motion command, as the reconstruction needs it. A jog is recorded as what it is
 * underneath: a move to the end of the allowed travel at |velocity|. */
typedef enum rail_cmd_kind {
    RAIL_CMD_NONE = 0, /* nothing known (open, reset, a command that failed): measured velocity */
    RAIL_CMD_MOVE,     /* move_abs / move_rel / jog: target_mm at speed_mm_s */
    RAIL_CMD_STOP,     /* stop / estop: decelerating to rest at accel_mm_s2 */
    RAIL_CMD_HOME      /* homing: the device's own search, measured velocity */
} rail_cmd_kind;

typedef struct rail_cmd {
    rail_cmd_kind kind;
    double target_mm;   /* mm, RAIL_CMD_MOVE only */
    double speed_mm_s;  /* mm/s, > 0, RAIL_CMD_MOVE only */
} rail_cmd;

struct rail {
    const rail_ops *ops;
    void *impl;
    rail_params p;
    rail_clock clock;
    rail_status last;   /* last device reading */
    bool have_last;
    rail_cmd cmd;       /* last motion command the driver accepted, for the reconstruction */
    char why[256];
};

static const char *const err_text[RAIL_E_COUNT] = {
    [RAIL_OK] = "ok",
    [RAIL_E_INVALID] = "invalid argument or configuration",
    [RAIL_E_LIMIT] = "outside the soft limits",
    [RAIL_E_SPEED] = "speed outside the allowed range",
    [RAIL_E_GAP] = "closer than the minimum clamp gap",
    [RAIL_E_CONFIRM] = "homing needs explicit confirmation",
    [RAIL_E_STATE] = "not allowed in the current state",
    [RAIL_E_IO] = "input/output error on the link",
    [RAIL_E_TIMEOUT] = "device did not answer in time",
    [RAIL_E_PROTOCOL] = "malformed or unexpected reply",
    [RAIL_E_DEVICE] = "device refused the command or is in alarm",
    [RAIL_E_DISCONNECTED] = "device disconnected",
    [RAIL_E_UNSUPPORTED] = "not supported by this driver",
    [RAIL_E_NOMEM] = "out of memory",
    [RAIL_E_UNVERIFIED] = "unverified drive preset needs explicit opt-in",
};

const char *rail_err_message(rail_err err)
{
    if ((int)err < 0 || err >= RAIL_E_COUNT)
        return "unknown error";
    return err_text[err];
}

static const char *const state_text[RAIL_STATE_COUNT] = {
    [RAIL_STATE_IDLE] = "idle",       [RAIL_STATE_MOVING] = "moving",
    [RAIL_STATE_HOMING] = "homing",   [RAIL_STATE_ALARM] = "alarm",
    [RAIL_STATE_FAULT] = "fault",     [RAIL_STATE_DISCONNECTED] = "disconnected",
};

const char *rail_state_name(rail_state s)
{
    if ((int)s < 0 || s >= RAIL_STATE_COUNT)
        return "unknown";
    return state_text[s];
}

rail_params rail_params_default(void)
{
    rail_params p;
    memset(&p, 0, sizeof p);
    snprintf(p.name, sizeof p.name, "rail");
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 100.0;
    p.max_speed_mm_s = 10.0;
    p.accel_mm_s2 = 50.0;
    p.poll_hz = 5.0;
    p.min_gap_mm = 0.0;
    p.gap_at_zero_mm = 0.0;
    p.gap_per_mm = 1.0;
    return p;
}

static rail_err fail(char *why, size_t why_len, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static rail_err fail(char *why, size_t why_len, const char *fmt, ...)
{
    if (why && why_len) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(why, why_len, fmt, ap);
        va_end(ap);
    }
    return RAIL_E_INVALID;
}

rail_err rail_params_check(const rail_params *p, char *why, size_t why_len)
{
    if (!p)
        return fail(why, why_len, "rail parameters missing");
    if (!isfinite(p->soft_min_mm) || !isfinite(p->soft_max_mm) || p->soft_min_mm >= p->soft_max_mm)
        return fail(why, why_len, "rail %s: soft_min_mm (%g) must be finite and below soft_max_mm (%g)",
                    p->name, p->soft_min_mm, p->soft_max_mm);
    if (!isfinite(p->max_speed_mm_s) || p->max_speed_mm_s <= 0.0 || p->max_speed_mm_s > 1000.0)
        return fail(why, why_len, "rail %s: max_speed_mm_s (%g) must be in (0, 1000]", p->name,
                    p->max_speed_mm_s);
    if (!isfinite(p->accel_mm_s2) || p->accel_mm_s2 <= 0.0 || p->accel_mm_s2 > 1e5)
        return fail(why, why_len, "rail %s: accel_mm_s2 (%g) must be in (0, 1e5]", p->name, p->accel_mm_s2);
    if (!isfinite(p->poll_hz) || p->poll_hz <= 0.0 || p->poll_hz > 1000.0)
        return fail(why, why_len, "rail %s: poll_hz (%g) must be in (0, 1000]", p->name, p->poll_hz);
    if (!isfinite(p->min_gap_mm) || p->min_gap_mm < 0.0)
        return fail(why, why_len, "rail %s: min_gap_mm (%g) must be >= 0", p->name, p->min_gap_mm);
    if (!isfinite(p->gap_at_zero_mm))
        return fail(why, why_len, "rail %s: gap_at_zero_mm must be finite", p->name);
    if (p->gap_per_mm != 1.0 && p->gap_per_mm != -1.0)
        return fail(why, why_len, "rail %s: gap_per_mm (%g) must be +1 or -1", p->name, p->gap_per_mm);
    return RAIL_OK;
}

void rail_text_copy(char *dst, size_t n, const char *src)
{
    if (!dst || n == 0)
        return;
    size_t k = src ? strnlen(src, n - 1) : 0;
    if (k)
        memcpy(dst, src, k);
    dst[k] = 0;
}

rail_err rail_set_error(rail *r, rail_err err, const char *fmt, ...)
{
    if (r) {
        int k = snprintf(r->why, sizeof r->why, "rail %s: ", r->p.name);
        if (k < 0 || (size_t)k >= sizeof r->why)
            k = 0;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(r->why + k, sizeof r->why - (size_t)k, fmt, ap);
        va_end(ap);
    }
    return err;
}

rail_err rail_create(rail **out, const rail_params *p, rail_clock clock, const rail_ops *ops,
                     void *impl, char *why, size_t why_len)
{
    *out = NULL;
    rail_err e = rail_params_check(p, why, why_len);
    if (e == RAIL_OK && (!ops || !ops->poll || !ops->move_abs || !ops->stop || !ops->estop)) {
        fail(why, why_len, "driver vtable incomplete");
        e = RAIL_E_INVALID;
    }
    rail *r = NULL;
    if (e == RAIL_OK) {
        r = calloc(1, sizeof *r);
        if (!r) {
            fail(why, why_len, "out of memory creating rail");
            e = RAIL_E_NOMEM;
        }
    }
    if (e != RAIL_OK) {
        if (ops && ops->close && impl)
            ops->close(impl);
        return e;
    }
    r->ops = ops;
    r->impl = impl;
    r->p = *p;
    r->clock = clock;
    r->last.state = RAIL_STATE_DISCONNECTED;
    *out = r;
    return RAIL_OK;
}

void rail_close(rail *r)
{
    if (!r)
        return;
    if (r->ops->close)
        r->ops->close(r->impl);
    free(r);
}

const char *rail_last_error(const rail *r)
{
    return r ? r->why : "no rail";
}
const rail_params *rail_get_params(const rail *r)
{
    return &r->p;
}
void *rail_driver_impl(rail *r, const rail_ops *ops)
{
    return r && ops && r->ops == ops ? r->impl : NULL;
}

const char *rail_driver_name(const rail *r)
{
    return r->ops->name;
}
rail_clock rail_get_clock(const rail *r)
{
    return r->clock;
}

double rail_stop_distance_mm(const rail *r, double v)
{
    return v * v / (2.0 * r->p.accel_mm_s2);
}

rail_err rail_status_poll(rail *r, rail_status *out)
{
    rail_status st;
    memset(&st, 0, sizeof st);
    rail_err e = r->ops->poll(r, r->impl, &st);
    st.t_s = rail_clock_now(r->clock);
    st.extrapolated = false;
    if (e != RAIL_OK && st.state != RAIL_STATE_DISCONNECTED && st.state != RAIL_STATE_FAULT &&
        st.state != RAIL_STATE_ALARM) {
        /* A failed read with no state from the driver: keep the last position, mark the link. */
        st.state = (e == RAIL_E_TIMEOUT || e == RAIL_E_IO || e == RAIL_E_DISCONNECTED)
                       ? RAIL_STATE_DISCONNECTED
                       : RAIL_STATE_FAULT;
        st.position_mm = r->last.position_mm;
        st.velocity_mm_s = 0.0;
        if (!st.message[0])
            rail_text_copy(st.message, sizeof st.message, r->why);
    }
    r->last = st;
    r->have_last = true;
    if (out)
        *out = st;
    return e;
}

/* A move in its own frame: u is the distance travelled toward the target since the reading, w the
 * velocity toward it, w0 the measured one, s the commanded speed, L >= 0 the distance left at the
 * reading. The law is the devices' (and rail_axis's): head for the target at s, change velocity
 * at no more than a, and brake at a so as to come to rest on the target. In closed form:
 *   - if w0 > 0 and w0^2 / (2a) >= L the rail cannot stop in time: brake at a from the start
 *     and end on the target (drives that overshoot come back; the reconstruction does not);
 *   - otherwise three phases: ramp at +-a from w0 to the peak wp, cruise at wp, brake at a from
 *     wp to rest on the target. wp = s when w0 > s (slowing down; the stopping margin
 *     L - w^2/(2a) is constant while braking, so it stays positive); else wp = min(s,
 *     sqrt(a L + w0^2 / 2)), the second being the triangle's peak, where the distance ramping
 *     up, (wp^2 - w0^2)/(2a), plus the braking one, wp^2/(2a), is exactly L.
 * u is capped at L, so a reconstruction never passes the target. */
static void move_profile(double w0, double s, double L, double a, double t, double *u, double *w)
{
    if (w0 > 0.0 && w0 * w0 >= 2.0 * a * L) {
        double tt = fmin(t, w0 / a);
        *u = w0 * tt - 0.5 * a * tt * tt;
        *w = w0 - a * tt;
        if (*u >= L) {
            *u = L;
            *w = 0.0;
        }
        return;
    }
    double wp, acc;
    if (w0 > s) {
        wp = s;
        acc = -a;
    } else {
        wp = fmin(s, sqrt(a * L + 0.5 * w0 * w0));
        acc = a;
    }
    double t1 = fabs(wp - w0) / a;
    double d1 = (wp * wp - w0 * w0) / (2.0 * acc);
    double db = wp * wp / (2.0 * a);
    double dc = fmax(0.0, L - d1 - db);
    double t2 = wp > 0.0 ? dc / wp : 0.0;
    double t3 = wp / a;
    if (t <= t1) {
        *u = w0 * t + 0.5 * acc * t * t;
        *w = w0 + acc * t;
    } else if (t <= t1 + t2) {
        *u = d1 + wp * (t - t1);
        *w = wp;
    } else if (t <= t1 + t2 + t3) {
        double tau = t - t1 - t2;
        *u = d1 + dc + wp * tau - 0.5 * a * tau * tau;
        *w = wp - a * tau;
    } else {
        *u = L;
        *w = 0.0;
    }
    if (*u > L) {
        *u = L;
        *w = 0.0;
    }
}

/* Position and velocity dt seconds after the reading st, from the last command (rail.h). */
static void reconstruct(const rail *r, rail_status *st, double dt)
{
    double a = r->p.accel_mm_s2, p0 = st->position_mm, v0 = st->velocity_mm_s;
    switch (r->cmd.kind) {
    case RAIL_CMD_MOVE: {
        double T = r->cmd.target_mm;
        double dir = T >= p0 ? 1.0 : -1.0;
        double u, w;
        move_profile(dir * v0, r->cmd.speed_mm_s, fabs(T - p0), a, dt, &u, &w);
        st->position_mm = p0 + dir * u;
        /* Rounding must not carry the position past the target either. */
        if ((st->position_mm - T) * dir > 0.0)
            st->position_mm = T;
        st->velocity_mm_s = dir * w;
        break;
    }
    case RAIL_CMD_STOP: {
        double tt = fmin(dt, fabs(v0) / a);
        double sg = v0 > 0.0 ? 1.0 : v0 < 0.0 ? -1.0 : 0.0;
        st->position_mm = p0 + v0 * tt - sg * 0.5 * a * tt * tt;
        st->velocity_mm_s = v0 - sg * a * tt;
        break;
    }
    case RAIL_CMD_HOME:
    case RAIL_CMD_NONE:
        st->position_mm = p0 + v0 * dt;
        break;
    }
}

rail_err rail_status_get(rail *r, rail_status *out)
{
    double now = rail_clock_now(r->clock);
    if (r->have_last && now - r->last.t_s < 1.0 / r->p.poll_hz && now >= r->last.t_s) {
        rail_status st = r->last;
        if (st.state == RAIL_STATE_MOVING || st.state == RAIL_STATE_HOMING) {
            reconstruct(r, &st, now - st.t_s);
            st.extrapolated = true;
        }
        *out = st;
        return RAIL_OK;
    }
    return rail_status_poll(r, out);
}

/* Allowed travel interval: soft limits intersected with the clamp-gap half line. */
static void allowed_interval(const rail *r, double *lo, double *hi)
{
    *lo = r->p.soft_min_mm;
    *hi = r->p.soft_max_mm;
    if (r->p.min_gap_mm > 0.0) {
        double edge = (r->p.min_gap_mm - r->p.gap_at_zero_mm) / r->p.gap_per_mm;
        if (r->p.gap_per_mm > 0.0 && edge > *lo)
            *lo = edge;
        if (r->p.gap_per_mm < 0.0 && edge < *hi)
            *hi = edge;
    }
}

static rail_err check_target(rail *r, double target)
{
    if (!isfinite(target))
        return rail_set_error(r, RAIL_E_INVALID, "target position is not a finite number");
    if (target < r->p.soft_min_mm || target > r->p.soft_max_mm)
        return rail_set_error(r, RAIL_E_LIMIT,
                              "target %.4f mm is outside the soft limits [%.4f, %.4f] mm; nothing sent",
                              target, r->p.soft_min_mm, r->p.soft_max_mm);
    if (r->p.min_gap_mm > 0.0) {
        double gap = r->p.gap_at_zero_mm + r->p.gap_per_mm * target;
        if (gap < r->p.min_gap_mm)
            return rail_set_error(r, RAIL_E_GAP,
                                  "target %.4f mm gives a clamp gap of %.4f mm, below the minimum "
                                  "%.4f mm; nothing sent",
                                  target, gap, r->p.min_gap_mm);
    }
    return RAIL_OK;
}

static rail_err check_speed(rail *r, double speed)
{
    if (!isfinite(speed) || speed <= 0.0)
        return rail_set_error(r, RAIL_E_SPEED, "speed %g mm/s must be finite and positive", speed);
    if (speed > r->p.max_speed_mm_s)
        return rail_set_error(r, RAIL_E_SPEED,
                              "speed %.4f mm/s is above the limit %.4f mm/s; nothing sent", speed,
                              r->p.max_speed_mm_s);
    return RAIL_OK;
}

/* Fresh reading, and refuse motion unless the rail is idle or already moving under our command. */
static rail_err ready_for_motion(rail *r, rail_status *st)
{
    rail_err e = rail_status_poll(r, st);
    if (e != RAIL_OK)
        return e;
    if (st->state == RAIL_STATE_ALARM || st->state == RAIL_STATE_FAULT ||
        st->state == RAIL_STATE_DISCONNECTED || st->state == RAIL_STATE_HOMING)
        return rail_set_error(r, RAIL_E_STATE, "rail is %s (%s); no motion sent",
                              rail_state_name(st->state), st->message[0] ? st->message : "no detail");
    return RAIL_OK;
}

/* Remember what the driver was told. A command refused by the front end sends nothing and leaves
 * the previous one standing; one the driver failed to send leaves the device's motion unknown, so
 * the reconstruction falls back to the measured velocity. */
static void record_sent(rail *r, rail_err e, double target, double speed)
{
    if (e != RAIL_OK) {
        r->cmd.kind = RAIL_CMD_NONE;
        return;
    }
    r->cmd.kind = RAIL_CMD_MOVE;
    r->cmd.target_mm = target;
    r->cmd.speed_mm_s = speed;
}

static rail_err send_move(rail *r, double target, double speed)
{
    rail_err e = r->ops->move_abs(r, r->impl, target, speed);
    record_sent(r, e, target, speed);
    return e;
}

rail_err rail_move_abs(rail *r, double target, double speed)
{
    rail_err e = check_target(r, target);
    if (e == RAIL_OK)
        e = check_speed(r, speed);
    rail_status st;
    if (e == RAIL_OK)
        e = ready_for_motion(r, &st);
    if (e == RAIL_OK)
        e = send_move(r, target, speed);
    r->have_last = false;
    return e;
}

rail_err rail_move_rel(rail *r, double delta, double speed)
{
    if (!isfinite(delta))
        return rail_set_error(r, RAIL_E_INVALID, "relative distance is not a finite number");
    rail_err e = check_speed(r, speed);
    rail_status st;
    if (e == RAIL_OK)
        e = ready_for_motion(r, &st);
    if (e != RAIL_OK)
        return e;
    double target = st.position_mm + delta;
    e = check_target(r, target);
    if (e == RAIL_OK)
        e = send_move(r, target, speed);
    r->have_last = false;
    return e;
}

rail_err rail_jog(rail *r, double v)
{
    if (!isfinite(v) || v == 0.0)
        return rail_set_error(r, RAIL_E_SPEED, "jog velocity %g mm/s must be finite and non-zero", v);
    rail_err e = check_speed(r, fabs(v));
    rail_status st;
    if (e == RAIL_OK)
        e = ready_for_motion(r, &st);
    if (e != RAIL_OK)
        return e;
    double lo, hi;
    allowed_interval(r, &lo, &hi);
    double end = v > 0.0 ? hi : lo;
    if ((v > 0.0 && st.position_mm >= end) || (v < 0.0 && st.position_mm <= end))
        return rail_set_error(r, RAIL_E_LIMIT,
                              "jog at %.4f mm/s from %.4f mm would leave the allowed travel "
                              "[%.4f, %.4f] mm at once; nothing sent",
                              v, st.position_mm, lo, hi);
    r->have_last = false;
    if (!r->ops->jog)
        return send_move(r, end, fabs(v));
    e = r->ops->jog(r, r->impl, v, end);
    record_sent(r, e, end, fabs(v));
    return e;
}

rail_err rail_stop(rail *r)
{
    r->have_last = false; /* the next status is a fresh reading, never an extrapolation */
    rail_err e = r->ops->stop(r, r->impl);
    r->cmd.kind = e == RAIL_OK ? RAIL_CMD_STOP : RAIL_CMD_NONE;
    return e;
}

rail_err rail_estop(rail *r)
{
    r->have_last = false;
    rail_err e = r->ops->estop(r, r->impl);
    r->cmd.kind = e == RAIL_OK ? RAIL_CMD_STOP : RAIL_CMD_NONE;
    return e;
}

rail_err rail_home(rail *r, bool confirmed)
{
    if (!confirmed)
        return rail_set_error(r, RAIL_E_CONFIRM,
                              "homing moves to the end stop and would crush a clamped specimen; "
                              "remove the specimen and confirm explicitly (--confirm)");
    if (!r->ops->home)
        return rail_set_error(r, RAIL_E_UNSUPPORTED, "driver %s cannot home", r->ops->name);
    r->have_last = false;
    rail_err e = r->ops->home(r, r->impl);
    r->cmd.kind = e == RAIL_OK ? RAIL_CMD_HOME : RAIL_CMD_NONE;
    return e;
}

rail_err rail_reset(rail *r)
{
    if (!r->ops->reset)
        return rail_set_error(r, RAIL_E_UNSUPPORTED, "driver %s has no alarm reset", r->ops->name);
    r->have_last = false;
    r->cmd.kind = RAIL_CMD_NONE;
    return r->ops->reset(r, r->impl);
}

rail_err rail_wait_idle(rail *r, double timeout_s, rail_status *out)
{
    if (!isfinite(timeout_s) || timeout_s < 0.0)
        return rail_set_error(r, RAIL_E_INVALID, "wait timeout %g s is invalid", timeout_s);
    double period = 1.0 / r->p.poll_hz;
    double t0 = rail_clock_now(r->clock);
    long cap = (long)(timeout_s / period) + 3;
    rail_status st;
    memset(&st, 0, sizeof st);
    for (long i = 0; i < cap; i++) {
        rail_err e = rail_status_poll(r, &st);
        if (out)
            *out = st;
        if (e != RAIL_OK)
            return e;
        if (st.state == RAIL_STATE_IDLE)
            return RAIL_OK;
        if (st.state != RAIL_STATE_MOVING && st.state != RAIL_STATE_HOMING)
            return rail_set_error(r, st.state == RAIL_STATE_ALARM ? RAIL_E_DEVICE : RAIL_E_STATE,
                                  "rail stopped in state %s at %.4f mm: %s", rail_state_name(st.state),
                                  st.position_mm, st.message[0] ? st.message : "no detail");
        if (rail_clock_now(r->clock) - t0 > timeout_s)
            break;
        rail_clock_sleep(r->clock, period);
    }
    return rail_set_error(r, RAIL_E_TIMEOUT, "still %s at %.4f mm after %.3f s",
                          rail_state_name(st.state), st.position_mm, timeout_s);
}
