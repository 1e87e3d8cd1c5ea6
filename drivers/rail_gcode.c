/* rail_gcode.c: one axis of a GRBL controller as a rail (see rail_gcode.h).
 *
 * Motion state kept here: the goal (final target), the commanded speed and direction, and how
 * far segments have been sent (sent_to). Every poll reads a status report, then tops up the
 * planner so that at most segments_ahead segments of segment_s seconds lie ahead of the axis.
 * Stall detection: an axis that should be moving and has not advanced by 0.5 um for
 * stall_timeout_s is stopped (jog cancel) and reported as a fault until reset; an open-loop
 * controller cannot see a stalled motor, but it does stop advancing a starved or blocked jog. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "grbl_link.h"
#include "rail_gcode.h"

typedef struct gcode {
    grbl_link *l;
    rail_gcode_params g;
    int ax;               /* 0 = X, 1 = Y, 2 = Z */
    bool active;          /* we have a goal the axis is (or should be) moving to */
    double goal_mm;       /* mm */
    double speed_mm_s;    /* mm/s, > 0 */
    double dir;           /* +1 or -1 */
    double sent_to_mm;    /* mm, end of the last segment sent */
    bool homing;
    bool stopping;        /* stop sent; the controller has not reported rest yet */
    double prev_pos, prev_t; /* mm, s: previous reading, for the velocity while stopping */
    char fault[200];      /* sticky driver-detected fault (stall, reset under a move), "" = none */
    int resets_at_start;  /* link->resets_seen when the move began */
    double progress_pos;  /* mm, position at the last progress */
    double progress_t;    /* s */
    double pos_mm;        /* mm, last reported position of our axis */
    double axes_mm[GRBL_MAX_AXES]; /* mm, every axis at the last report (shared controllers) */
    double last_feed;     /* mm/min */
    double status_t;      /* s (rail clock): when the latest good status report was in */
    double prev_status_t; /* s: the one before it (the move's start for its first poll) */
    grbl_settings_check_out chk; /* the controller's settings checked for this axis at open */
} gcode;

static rail_err link_error(rail *r, gcode *k, rail_err e)
{
    return rail_set_error(r, e, "%s", k->l->why);
}

/* Segment length: segment_s of motion, but never below min_segment_mm (slow shear rates would
   otherwise send segments below the controller's step resolution). */
static double segment_mm(const gcode *k)
{
    double seg = k->speed_mm_s * k->g.segment_s;
    return seg > k->g.min_segment_mm ? seg : k->g.min_segment_mm;
}

/* What the user must do before this rail moves again, after its controller lost its position:
   the action first, so a status message cut at its length still says it. */
static void untrusted_text(const gcode *k, const rail *r, char *buf, size_t n)
{
    (void)r;
    if (k->chk.homing)
        snprintf(buf, n, "position not trusted, home it (home --confirm; $22=1): %s", k->l->zero_why);
    else
        snprintf(buf, n, "position not trusted, check the rail and confirm-zero --confirm: %s",
                 k->l->zero_why);
}

static rail_err untrusted(rail *r, gcode *k)
{
    char t[400];
    untrusted_text(k, r, t, sizeof t);
    return rail_set_error(r, RAIL_E_STATE, "rail '%s': %s", rail_get_params(r)->name, t);
}

static rail_err send_segment(rail *r, gcode *k)
{
    double seg = segment_mm(k);
    double remaining = (k->goal_mm - k->sent_to_mm) * k->dir;
    double next = remaining <= seg ? k->goal_mm : k->sent_to_mm + k->dir * seg;
    char cmd[96];
    snprintf(cmd, sizeof cmd, "$J=G53G21%c%.4fF%.3f", k->g.axis, next, k->speed_mm_s * 60.0);
    int code = 0;
    rail_err e = grbl_link_send(k->l, cmd, &code);
    if (e != RAIL_OK) {
        k->active = false;
        return link_error(r, k, e);
    }
    k->sent_to_mm = next;
    return RAIL_OK;
}

/* A freeze (SIGSTOP, a suspended machine, a stalled scheduler) anywhere between the previous
   good status and a segment about to go out: while frozen the controller ran out of segments and
   stopped, and the status this top-up rests on may predate the freeze, so sending would start the
   rail again by itself. The bound is the trial poller's (trial_rail_poller.h): one poll period
   plus RAIL_CLOCK_JUMP_S. Returns true (the jog cancelled, a sticky fault set) when it is past. */
static bool frozen_before_send(rail *r, gcode *k, double pos)
{
    double now = rail_clock_now(rail_get_clock(r));
    double bound = 1.0 / rail_get_params(r)->poll_hz + RAIL_CLOCK_JUMP_S;
    double gap = now - k->prev_status_t;
    if (gap <= bound)
        return false;
    grbl_link_realtime(k->l, 0x85);
    k->active = false;
    k->stopping = true;
    k->prev_pos = pos;
    k->prev_t = now;
    snprintf(k->fault, sizeof k->fault,
             "the monotonic clock jumped %.2f s between status reports (at most %.2f s): frozen; "
             "jog cancelled at %.3f mm, not topped up; reset to clear",
             gap, bound, pos);
    return true;
}

/* Keep segments_ahead segments queued ahead of pos. */
static rail_err top_up(rail *r, gcode *k, double pos)
{
    double seg = segment_mm(k);
    for (int i = 0; i < 4; i++) {
        double remaining = (k->goal_mm - k->sent_to_mm) * k->dir;
        double ahead = (k->sent_to_mm - pos) * k->dir;
        if (remaining <= 1e-6 || ahead >= k->g.segments_ahead * seg - 1e-9)
            break;
        if (frozen_before_send(r, k, pos))
            return rail_set_error(r, RAIL_E_STATE, "%s", k->fault);
        rail_err e = send_segment(r, k);
        if (e != RAIL_OK)
            return e;
    }
    return RAIL_OK;
}

static rail_err gcode_poll(rail *r, void *impl, rail_status *out)
{
    gcode *k = impl;
    grbl_report rep;
    rail_err e = RAIL_E_TIMEOUT;
    /* One retry after a garbled report: a single bad line is not yet a fault. A silent
       controller is not retried here: grbl_link_status has already asked twice within
       reply_timeout_s, which is the bound on detecting a lost link. */
    /* The report's time is taken before it is asked for: a freeze after the reply came in (before
       this reading) must count against it, not be hidden inside a fresh time stamp. */
    double t_ask = rail_clock_now(rail_get_clock(r));
    for (int i = 0; i < 2; i++) {
        e = grbl_link_status(k->l, &rep);
        if (e != RAIL_E_PROTOCOL)
            break;
    }
    out->code = 0;
    out->message[0] = 0;
    if (e != RAIL_OK) {
        k->active = false; /* the controller stops when starved of segments */
        out->state = (e == RAIL_E_PROTOCOL) ? RAIL_STATE_FAULT : RAIL_STATE_DISCONNECTED;
        out->position_mm = k->pos_mm;
        rail_err ee = link_error(r, k, e);
        rail_text_copy(out->message, sizeof out->message, rail_last_error(r));
        return ee;
    }
    double now = rail_clock_now(rail_get_clock(r));
    double pos = rep.pos[k->ax];
    k->pos_mm = pos;
    k->prev_status_t = k->status_t;
    k->status_t = t_ask;
    out->position_mm = pos;
    out->velocity_mm_s = 0.0;
    k->last_feed = rep.feed_mm_min;
    if (fabs(pos - k->progress_pos) > 5e-4) {
        k->progress_pos = pos;
        k->progress_t = now;
    }
    /* On a shared controller our queued segments wait while another axis runs: that is not a
       stall, so any other axis moving counts as progress. */
    bool others_moved = false, ours_still = fabs(pos - k->axes_mm[k->ax]) < 1e-4;
    for (int i = 0; i < GRBL_MAX_AXES; i++) {
        if (i != k->ax && fabs(rep.pos[i] - k->axes_mm[i]) > 5e-4)
            others_moved = true;
        k->axes_mm[i] = rep.pos[i];
    }
    if (others_moved)
        k->progress_t = now;
    switch (rep.state) {
    case GRBL_ALARM:
        k->active = false;
        k->homing = false;
        out->state = RAIL_STATE_ALARM;
        out->code = k->l->alarm_code;
        if (out->code) {
            snprintf(out->message, sizeof out->message, "GRBL alarm %d: %s", out->code,
                     grbl_alarm_text(out->code));
        } else if (k->l->zero_lost) {
            char t[400];
            rail_text_copy(t, sizeof t, "GRBL locked in alarm; ");
            untrusted_text(k, r, t + strlen(t), sizeof t - strlen(t));
            rail_text_copy(out->message, sizeof out->message, t);
        } else {
            snprintf(out->message, sizeof out->message, "GRBL locked in alarm (home or unlock)");
        }
        return RAIL_OK;
    case GRBL_HOME:
        out->state = RAIL_STATE_HOMING;
        return RAIL_OK;
    case GRBL_DOOR:
    case GRBL_SLEEP:
    case GRBL_CHECK:
        k->active = false;
        out->state = RAIL_STATE_FAULT;
        snprintf(out->message, sizeof out->message, "controller in %s state", grbl_state_name(rep.state));
        return RAIL_OK;
    default:
        break;
    }
    if (k->homing) {
        if (k->l->home_pending) {
            out->state = RAIL_STATE_HOMING;
            return RAIL_OK;
        }
        k->homing = false;
        if (k->l->home_error == 0 && !k->l->zero_lost)
            k->fault[0] = 0; /* homed: a reset's fault is over, the zero is the switch's */
        if (k->l->home_error > 0) {
            out->state = RAIL_STATE_FAULT;
            out->code = k->l->home_error;
            snprintf(out->message, sizeof out->message, "homing refused: error:%d (%s)",
                     k->l->home_error, grbl_error_text(k->l->home_error));
            k->l->home_error = 0;
            return RAIL_OK;
        }
    }
    if (k->active && (k->l->resets_seen != k->resets_at_start || k->l->zero_lost)) {
        /* The controller restarted under a move: never carry the move on by ourselves. */
        k->active = false;
        snprintf(k->fault, sizeof k->fault,
                 "controller reset during the move at %.3f mm (%.60s); move abandoned, reset to clear",
                 pos, k->l->zero_lost ? k->l->zero_why : "banner");
    }
    if (k->active && now - k->progress_t > k->g.stall_timeout_s) {
        grbl_link_realtime(k->l, 0x85);
        k->active = false;
        snprintf(k->fault, sizeof k->fault,
                 "stall: no progress for %.2f s at %.3f mm while moving; jog cancelled, reset to clear",
                 k->g.stall_timeout_s, pos);
    }
    if (k->fault[0]) {
        out->state = RAIL_STATE_FAULT;
        rail_text_copy(out->message, sizeof out->message, k->fault);
        return RAIL_OK;
    }
    if (k->l->zero_lost && !k->homing) {
        /* A rail whose controller lost its count is a fault wherever it stands: a trial (through
           rail_pair) stops both rails on it, and nothing moves until homed or confirmed. */
        k->active = false;
        out->state = RAIL_STATE_FAULT;
        char t[400];
        untrusted_text(k, r, t, sizeof t);
        rail_text_copy(out->message, sizeof out->message, t);
        return RAIL_OK;
    }
    if (k->active) {
        bool there = fabs(pos - k->goal_mm) < 1e-3 && fabs(k->sent_to_mm - k->goal_mm) < 1e-9;
        /* Done when on the goal and at rest: the controller idle, or (another axis's moves
           queued behind ours keep it busy) our axis unchanged since the last report. */
        if (there && (rep.state == GRBL_IDLE || ours_still)) {
            k->active = false;
            out->state = RAIL_STATE_IDLE;
            return RAIL_OK;
        }
        e = top_up(r, k, pos);
        if (e != RAIL_OK) {
            out->state = RAIL_STATE_FAULT;
            rail_text_copy(out->message, sizeof out->message, rail_last_error(r));
            return e;
        }
        out->state = RAIL_STATE_MOVING;
        out->velocity_mm_s = k->dir * rep.feed_mm_min / 60.0;
        return RAIL_OK;
    }
    if (k->stopping && (rep.state == GRBL_JOG || rep.state == GRBL_RUN ||
                        (rep.state == GRBL_HOLD && rep.substate != 0))) {
        /* Decelerating after our stop: moving until the controller says it is at rest, so no
           new jog is sent into a cancel in progress (GRBL would drop it). */
        out->state = RAIL_STATE_MOVING;
        if (now > k->prev_t)
            out->velocity_mm_s = (pos - k->prev_pos) / (now - k->prev_t);
        k->prev_pos = pos;
        k->prev_t = now;
        return RAIL_OK;
    }
    if (!ours_still && (rep.state == GRBL_JOG || rep.state == GRBL_RUN || rep.state == GRBL_HOLD)) {
        /* Our axis still runs segments of a move given up after a failed read: moving until
           they end (segments_ahead at most), so nobody takes a position on the way for rest. */
        out->state = RAIL_STATE_MOVING;
        if (now > k->prev_t)
            out->velocity_mm_s = (pos - k->prev_pos) / (now - k->prev_t);
        k->prev_pos = pos;
        k->prev_t = now;
        return RAIL_OK;
    }
    k->stopping = false;
    out->state = RAIL_STATE_IDLE;
    if (rep.state == GRBL_JOG || rep.state == GRBL_RUN) {
        snprintf(out->message, sizeof out->message, "controller busy (%s) with another axis",
                 grbl_state_name(rep.state));
    } else if (rep.state == GRBL_HOLD) {
        snprintf(out->message, sizeof out->message, "controller in feed hold");
    }
    return RAIL_OK;
}

static rail_err gcode_stop(rail *r, void *impl)
{
    gcode *k = impl;
    k->active = false;
    k->stopping = true;
    k->prev_pos = k->pos_mm;
    k->prev_t = rail_clock_now(rail_get_clock(r));
    rail_err e = grbl_link_realtime(k->l, 0x85);
    return e == RAIL_OK ? e : link_error(r, k, e);
}

static rail_err gcode_move_abs(rail *r, void *impl, double target, double speed)
{
    gcode *k = impl;
    if (k->l->zero_lost)
        return untrusted(r, k);
    if (k->fault[0])
        return rail_set_error(r, RAIL_E_STATE, "%s", k->fault);
    if (k->active || k->stopping) {
        /* Change of plan mid-move: cancel the queued segments and let the axis come to rest. */
        rail_err e = k->active ? gcode_stop(r, impl) : RAIL_OK;
        if (e != RAIL_OK)
            return e;
        rail_status st;
        e = rail_wait_idle(r, 5.0 + speed / rail_get_params(r)->accel_mm_s2, &st);
        if (e != RAIL_OK)
            return e;
    }
    rail_status st;
    memset(&st, 0, sizeof st);
    rail_err e = gcode_poll(r, impl, &st);
    if (e != RAIL_OK)
        return e;
    if (k->l->zero_lost)
        return untrusted(r, k);
    if (fabs(target - st.position_mm) < 1e-4)
        return RAIL_OK;
    k->goal_mm = target;
    k->speed_mm_s = speed;
    k->dir = target > st.position_mm ? 1.0 : -1.0;
    k->sent_to_mm = st.position_mm;
    k->progress_pos = st.position_mm;
    k->progress_t = rail_clock_now(rail_get_clock(r));
    k->resets_at_start = k->l->resets_seen;
    k->prev_status_t = k->status_t; /* the move starts from the report just read */
    k->active = true;
    return top_up(r, k, st.position_mm);
}

static rail_err gcode_estop(rail *r, void *impl)
{
    gcode *k = impl;
    k->active = false;
    /* Feed hold decelerates at once (it also cancels a jog); when at rest, a soft reset
       empties the planner so nothing queued can ever resume. */
    rail_err e = grbl_link_realtime(k->l, '!');
    if (e != RAIL_OK)
        return link_error(r, k, e);
    grbl_report rep;
    double t_max = 1.0 + rail_get_params(r)->max_speed_mm_s / rail_get_params(r)->accel_mm_s2;
    double t0 = rail_clock_now(rail_get_clock(r));
    for (int i = 0; i < 200; i++) {
        e = grbl_link_status(k->l, &rep);
        if (e == RAIL_OK && (rep.state == GRBL_IDLE || rep.state == GRBL_ALARM ||
                             (rep.state == GRBL_HOLD && rep.substate == 0)))
            break;
        if (rail_clock_now(rail_get_clock(r)) - t0 > t_max)
            break;
        rail_clock_sleep(rail_get_clock(r), 0.02);
    }
    e = grbl_link_soft_reset(k->l);
    return e == RAIL_OK ? e : link_error(r, k, e);
}

static rail_err gcode_home(rail *r, void *impl)
{
    gcode *k = impl;
    rail_err e = grbl_link_drain(k->l);
    if (e != RAIL_OK)
        return link_error(r, k, e);
    /* "$H" answers "ok" only when the cycle ends: send it and let polls collect the answer. */
    const char *cmd = "$H\n";
    k->l->home_error = 0;
    k->l->home_pending = true;
    k->homing = true;
    k->active = false;
    e = rail_serial_write(k->l->ser, cmd, strlen(cmd), k->l->reply_timeout_s);
    if (e != RAIL_OK) {
        k->l->home_pending = false;
        k->homing = false;
        return rail_set_error(r, e, "%s", k->l->ser->why);
    }
    return RAIL_OK;
}

static rail_err gcode_reset(rail *r, void *impl)
{
    gcode *k = impl;
    k->fault[0] = 0;
    k->active = false;
    int code = 0;
    rail_err e = RAIL_OK;
    if (k->l->critical) {
        /* After a hard or soft limit alarm GRBL waits for a soft reset before anything else
           (its "[MSG:Reset to continue]"); the axes are at rest, the position already lost. */
        int resets0 = k->l->resets_seen;
        e = grbl_link_soft_reset(k->l);
        double t0 = rail_clock_now(k->l->clock);
        for (int i = 0; e == RAIL_OK && i < 100 && k->l->resets_seen == resets0; i++) {
            if (rail_clock_now(k->l->clock) - t0 > k->l->reply_timeout_s + 0.5)
                break;
            rail_clock_sleep(k->l->clock, 0.01);
            e = grbl_link_drain(k->l);
        }
        if (e != RAIL_OK)
            return link_error(r, k, e);
    }
    e = grbl_link_send(k->l, "$X", &code);
    if (e != RAIL_OK)
        return link_error(r, k, e);
    k->l->alarm_code = 0;
    return RAIL_OK;
}

static void gcode_close(void *impl)
{
    gcode *k = impl;
    if (k->active)
        grbl_link_realtime(k->l, 0x85);
    grbl_link_release(k->l);
    free(k);
}

static const rail_ops gcode_ops = {
    .name = "gcode",
    .poll = gcode_poll,
    .move_abs = gcode_move_abs,
    .jog = NULL, /* a jog is a segmented move to the limit in its direction */
    .stop = gcode_stop,
    .estop = gcode_estop,
    .home = gcode_home,
    .reset = gcode_reset,
    .close = gcode_close,
};

rail_err rail_gcode_open(rail **out, const rail_params *p, const rail_gcode_params *g, grbl_link *shared,
                         rail_clock clock, char *why, size_t why_len)
{
    *out = NULL;
    if (!g || (g->axis != 'X' && g->axis != 'Y' && g->axis != 'Z')) {
        snprintf(why, why_len, "gcode: axis must be X, Y or Z");
        return RAIL_E_INVALID;
    }
    if (!(g->segment_s >= 0.05 && g->segment_s <= 2.0) || g->segments_ahead < 1 || g->segments_ahead > 4) {
        snprintf(why, why_len, "gcode: segment_s must be in [0.05, 2] s and segments_ahead in 1..4");
        return RAIL_E_INVALID;
    }
    if (p && g->segment_s * g->segments_ahead <= 1.0 / p->poll_hz) {
        snprintf(why, why_len,
                 "gcode: segments_ahead * segment_s (%.3f s) must exceed the poll period (%.3f s) "
                 "or the rail starves between polls",
                 g->segment_s * g->segments_ahead, 1.0 / p->poll_hz);
        return RAIL_E_INVALID;
    }
    if (!(g->stall_timeout_s > 0.0) || !(g->min_segment_mm > 0.0 && g->min_segment_mm <= 10.0)) {
        snprintf(why, why_len, "gcode: stall_timeout_s must be positive and min_segment_mm in (0, 10]");
        return RAIL_E_INVALID;
    }
    if (!(g->boot_wait_s >= 0.0 && g->boot_wait_s <= 30.0)) {
        snprintf(why, why_len, "gcode: boot_wait_s must be in [0, 30] s");
        return RAIL_E_INVALID;
    }
    if (!p) {
        snprintf(why, why_len, "gcode: no rail parameters");
        return RAIL_E_INVALID;
    }
    gcode *k = calloc(1, sizeof *k);
    if (!k) {
        snprintf(why, why_len, "gcode: out of memory");
        return RAIL_E_NOMEM;
    }
    k->g = *g;
    k->ax = g->axis - 'X';
    if (shared) {
        grbl_link_retain(shared);
        k->l = shared;
    } else {
        rail_err e = grbl_link_open(&k->l, g, clock, why, why_len);
        if (e != RAIL_OK) {
            free(k);
            return e;
        }
    }
    /* What the controller is set to, against what this rail needs of it. */
    grbl_settings_check(&k->l->settings, k->ax, p, &k->chk);
    if (k->chk.refuse) {
        snprintf(why, why_len, "gcode: %s", k->chk.refuse_why);
        grbl_link_release(k->l);
        free(k);
        return RAIL_E_DEVICE;
    }
    rail_params pa = *p;
    pa.accel_mm_s2 = k->chk.accel_mm_s2; /* the controller's own, which it will really use */
    return rail_create(out, &pa, clock, &gcode_ops, k, why, why_len);
}

rail_err rail_gcode_confirm_zero(rail *r, bool confirmed)
{
    gcode *k = rail_driver_impl(r, &gcode_ops);
    if (!k)
        return rail_set_error(r, RAIL_E_UNSUPPORTED, "confirm-zero: rail '%s' is not a G-code rail",
                              rail_get_params(r)->name);
    if (!confirmed)
        return rail_set_error(r, RAIL_E_CONFIRM,
                              "confirm-zero: rail '%s' needs --confirm: the controller's count "
                              "is taken as right where the rail stands",
                              rail_get_params(r)->name);
    if (k->chk.homing && k->l->zero_lost)
        return rail_set_error(r, RAIL_E_STATE,
                              "confirm-zero: rail '%s': homing is enabled ($22=1): home it "
                              "instead (home --confirm)",
                              rail_get_params(r)->name);
    grbl_link_zero_trusted(k->l);
    k->fault[0] = 0;
    return RAIL_OK;
}

size_t rail_gcode_describe(const rail *r, char *buf, size_t n)
{
    gcode *k = rail_driver_impl((rail *)r, &gcode_ops);
    if (n)
        buf[0] = 0;
    if (!k || !n)
        return 0;
    char set[1200];
    grbl_settings_format(&k->l->settings, set, sizeof set);
    int w = snprintf(buf, n, "GRBL axis %c, reset on open: %s; settings: %s%s%s", k->g.axis,
                     k->l->reset_on_open ? "yes" : "no", set, k->chk.warn[0] ? "; warnings: " : "",
                     k->chk.warn);
    return w < 0 ? 0 : (size_t)w < n ? (size_t)w : n - 1;
}

const char *rail_gcode_warnings(const rail *r)
{
    gcode *k = rail_driver_impl((rail *)r, &gcode_ops);
    return k ? k->chk.warn : "";
}
