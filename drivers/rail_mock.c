/* rail_mock.c: the mock rail driver (see rail_mock.h).
 *
 * The simulated axis advances lazily: every call first steps the kinematics by the clock time
 * elapsed since the previous call, so a virtual clock drives it deterministically and a real
 * clock drives it in real time, with no thread. Injected faults behave like the hardware's:
 * a stall halts the axis and reports a fault (as a drive with stall detection would), an alarm
 * halts it and reports the alarm code until reset, a communication loss halts it (the drive's
 * watchdog) and every later call fails as disconnected. */
#include "rail_mock.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rail_axis.h"

typedef struct mock {
    rail_mock_params m;
    rail_clock clock;
    rail_axis ax;
    double t_last;    /* s, clock time the axis was last advanced to */
    double t_open;    /* s */
    bool stalled, alarmed, lost, homing;
    bool has_load;    /* an external load was set (rail_mock_set_load) */
    double load;      /* its value, reported with every reading from then on */
} mock;

rail_mock_params rail_mock_params_default(void)
{
    rail_mock_params m;
    m.start_mm = 0.0;
    m.travel_mm = 200.0;
    m.home_speed_mm_s = 5.0;
    m.stall_at_mm = NAN;
    m.comm_loss_after_s = -1.0;
    m.alarm_after_s = -1.0;
    m.alarm_code = 1;
    return m;
}

static void advance(mock *k)
{
    double now = rail_clock_now(k->clock);
    if (!k->lost && k->m.comm_loss_after_s >= 0.0 && now - k->t_open >= k->m.comm_loss_after_s) {
        /* Step up to the moment of loss, then the watchdog halts the axis. */
        rail_axis_step(&k->ax, k->t_open + k->m.comm_loss_after_s - k->t_last);
        rail_axis_halt(&k->ax);
        k->lost = true;
        k->t_last = fmax(k->t_last, k->t_open + k->m.comm_loss_after_s);
    }
    if (!k->alarmed && k->m.alarm_after_s >= 0.0 && now - k->t_open >= k->m.alarm_after_s) {
        rail_axis_step(&k->ax, k->t_open + k->m.alarm_after_s - k->t_last);
        rail_axis_halt(&k->ax);
        k->alarmed = true;
        k->t_last = fmax(k->t_last, k->t_open + k->m.alarm_after_s);
    }
    if (now > k->t_last) {
        double before = k->ax.pos_mm;
        rail_axis_step(&k->ax, now - k->t_last);
        double s = k->m.stall_at_mm;
        if (!isnan(s) && !k->stalled &&
                   ((before < s && k->ax.pos_mm >= s) || (before > s && k->ax.pos_mm <= s))) {
            k->ax.pos_mm = s;
            rail_axis_halt(&k->ax);
            k->stalled = true;
        }
    }
    k->t_last = now > k->t_last ? now : k->t_last;
    if (k->homing && !rail_axis_busy(&k->ax))
        k->homing = false;
}

static rail_err link_ok(rail *r, mock *k)
{
    advance(k);
    if (k->lost)
        return rail_set_error(r, RAIL_E_DISCONNECTED, "mock link lost (injected after %.3f s)",
                              k->m.comm_loss_after_s);
    return RAIL_OK;
}

static rail_err mock_poll(rail *r, void *impl, rail_status *out)
{
    mock *k = impl;
    rail_err e = link_ok(r, k);
    out->position_mm = k->ax.pos_mm;
    out->velocity_mm_s = k->ax.vel_mm_s;
    out->code = 0;
    out->message[0] = 0;
    out->has_load = k->has_load && e == RAIL_OK;
    out->load = out->has_load ? k->load : 0.0;
    if (e != RAIL_OK) {
        out->state = RAIL_STATE_DISCONNECTED;
        rail_text_copy(out->message, sizeof out->message, rail_last_error(r));
        out->velocity_mm_s = 0.0;
        return e;
    }
    if (k->alarmed) {
        out->state = RAIL_STATE_ALARM;
        out->code = k->m.alarm_code;
        snprintf(out->message, sizeof out->message, "injected drive alarm %d", k->m.alarm_code);
    } else if (k->ax.limit_hit) {
        out->state = RAIL_STATE_ALARM;
        out->code = 2;
        snprintf(out->message, sizeof out->message, "hard limit hit at %.3f mm", k->ax.pos_mm);
    } else if (k->stalled) {
        out->state = RAIL_STATE_FAULT;
        out->code = 3;
        snprintf(out->message, sizeof out->message, "motor stalled at %.3f mm", k->ax.pos_mm);
    } else if (k->homing) {
        out->state = RAIL_STATE_HOMING;
    } else {
        out->state = rail_axis_busy(&k->ax) ? RAIL_STATE_MOVING : RAIL_STATE_IDLE;
    }
    return RAIL_OK;
}

static rail_err mock_blocked(rail *r, mock *k)
{
    rail_err e = link_ok(r, k);
    if (e != RAIL_OK)
        return e;
    if (k->alarmed || k->stalled || k->ax.limit_hit)
        return rail_set_error(r, RAIL_E_STATE, "mock rail in %s; reset first",
                              k->alarmed ? "alarm" : k->stalled ? "stall fault" : "limit alarm");
    return RAIL_OK;
}

static rail_err mock_move_abs(rail *r, void *impl, double target, double speed)
{
    mock *k = impl;
    rail_err e = mock_blocked(r, k);
    if (e == RAIL_OK)
        rail_axis_move_to(&k->ax, target, speed);
    return e;
}

static rail_err mock_stop(rail *r, void *impl)
{
    mock *k = impl;
    rail_err e = link_ok(r, k);
    if (e == RAIL_OK)
        rail_axis_stop(&k->ax);
    return e;
}

static rail_err mock_estop(rail *r, void *impl)
{
    mock *k = impl;
    rail_err e = link_ok(r, k);
    if (e == RAIL_OK)
        rail_axis_halt(&k->ax);
    return e;
}

static rail_err mock_home(rail *r, void *impl)
{
    mock *k = impl;
    rail_err e = link_ok(r, k);
    if (e != RAIL_OK)
        return e;
    k->ax.limit_hit = false;
    rail_axis_home(&k->ax, k->m.home_speed_mm_s);
    k->homing = true;
    return RAIL_OK;
}

static rail_err mock_reset(rail *r, void *impl)
{
    mock *k = impl;
    rail_err e = link_ok(r, k);
    if (e != RAIL_OK)
        return e;
    rail_axis_halt(&k->ax);
    k->alarmed = false;
    k->m.alarm_after_s = -1.0;
    k->stalled = false;
    k->m.stall_at_mm = NAN;
    k->ax.limit_hit = false;
    return RAIL_OK;
}

static void mock_close(void *impl)
{
    free(impl);
}

static const rail_ops mock_ops = {
    .name = "mock",
    .poll = mock_poll,
    .move_abs = mock_move_abs,
    .jog = NULL, /* the front end turns a jog into a move to the limit, which is what it is */
    .stop = mock_stop,
    .estop = mock_estop,
    .home = mock_home,
    .reset = mock_reset,
    .close = mock_close,
};

rail_err rail_mock_set_load(rail *r, double load)
{
    mock *k = rail_driver_impl(r, &mock_ops);
    if (!k)
        return r ? rail_set_error(r, RAIL_E_UNSUPPORTED, "rail %s runs the %s driver, not the mock: no external load",
                                  rail_get_params(r)->name, rail_driver_name(r))
                 : RAIL_E_INVALID;
    if (!isfinite(load))
        return rail_set_error(r, RAIL_E_INVALID, "external load %g is not finite", load);
    k->has_load = true;
    k->load = load;
    return RAIL_OK;
}

rail_err rail_mock_open(rail **out, const rail_params *p, const rail_mock_params *m, rail_clock clock,
                        char *why, size_t why_len)
{
    *out = NULL;
    if (!m || !isfinite(m->travel_mm) || m->travel_mm <= 0.0 || !isfinite(m->start_mm) ||
        m->start_mm < 0.0 || m->start_mm > m->travel_mm || !(m->home_speed_mm_s > 0.0)) {
        if (why && why_len)
            snprintf(why, why_len, "mock: start_mm must lie in [0, travel_mm] and travel_mm, "
                                   "home_speed_mm_s must be positive");
        return RAIL_E_INVALID;
    }
    mock *k = calloc(1, sizeof *k);
    if (!k) {
        if (why && why_len)
            snprintf(why, why_len, "mock: out of memory");
        return RAIL_E_NOMEM;
    }
    k->m = *m;
    k->clock = clock;
    k->ax = rail_axis_make(m->start_mm, p ? p->accel_mm_s2 : 1.0, m->travel_mm);
    k->t_open = k->t_last = rail_clock_now(clock);
    return rail_create(out, p, clock, &mock_ops, k, why, why_len);
}
