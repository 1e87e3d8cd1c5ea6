/* grbl_sim.c: the GRBL 1.1 subset simulator (see grbl_sim.h).
 *
 * Layout: bytes from the pty master are split into realtime commands (handled at once, as GRBL's
 * serial interrupt does) and line characters (executed on '\n' or '\r'). Motion blocks wait in a
 * ring of GRBL's usable size (15). Every iteration steps each axis's rail_axis by the real time
 * elapsed: the axes in the head block move toward the end of their look-ahead run (the farthest
 * target reached by consecutive blocks moving that axis in the same direction), and the head
 * block retires once each of its axes has reached or passed its target. */
#define _XOPEN_SOURCE 700
#include "grbl_sim.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rail_axis.h"
#include "rail_clock.h"
#include "rail_sim.h"

#define SIM_QUEUE 15
#define SIM_LINE_MAX 80

typedef struct sim_block {
    double target[GRBL_SIM_AXES];  /* mm, machine coordinates */
    bool has[GRBL_SIM_AXES];
    double start[GRBL_SIM_AXES];   /* mm, positions when the block became head */
    double feed_mm_min;
    bool jog;
    bool started;
} sim_block;

typedef enum sim_mode { M_IDLE, M_RUN, M_JOG, M_HOLD, M_ALARM, M_HOME } sim_mode;

struct grbl_sim {
    grbl_sim_params p;
    int master, slave;
    char path[128];
    rail_clock clock;
    double t_start, t_last;
    rail_axis ax[GRBL_SIM_AXES];
    bool stalled[GRBL_SIM_AXES];
    sim_block q[SIM_QUEUE];
    int q_head, q_len;
    sim_mode mode;
    bool cancelling;      /* jog cancel / jog hold: decelerate, then flush */
    bool home_pending;    /* "ok" owed at the end of homing */
    bool alarm_fired;
    bool absolute;        /* G90 (true) or G91 modal state for G0/G1 */
    char line[SIM_LINE_MAX + 2];
    size_t line_len;
    bool line_overflow;
    unsigned rng;
    unsigned long reports;  /* status reports sent */
};

grbl_sim_params grbl_sim_params_default(void)
{
    grbl_sim_params p;
    memset(&p, 0, sizeof p);
    p.n_axes = 2;
    for (int i = 0; i < GRBL_SIM_AXES; i++) {
        p.travel_mm[i] = 200.0;
        p.start_mm[i] = 0.0;
        p.stall_at_mm[i] = NAN;
    }
    p.accel_mm_s2 = 200.0;
    p.max_feed_mm_min = 3000.0;
    p.home_feed_mm_min = 1200.0;
    p.alarm_after_s = -1.0;
    p.alarm_code = 1;
    p.seed = 12345u;
    return p;
}

static void out_raw(grbl_sim *s, const char *b, size_t n)
{
    /* Non-blocking: if nobody reads and the pty buffer fills, replies are lost like on a
       disconnected USB link. */
    for (int i = 0; i < 8 && n > 0; i++) {
        ssize_t w = write(s->master, b, n);
        if (w <= 0)
            return;
        b += w;
        n -= (size_t)w;
    }
}

/* A reply line, possibly garbled by the fault injector. */
static void reply(grbl_sim *s, const char *text)
{
    char buf[256];
    if (s->p.garble_prob > 0.0 && rail_sim_rand(&s->rng) < s->p.garble_prob) {
        size_t n = strlen(text);
        size_t keep = n / 2;
        if (keep > 100)
            keep = 100;
        memcpy(buf, text, keep);
        /* Truncated line with a few non-text bytes in it. */
        buf[keep] = (char)0xff;
        buf[keep + 1] = '\x07';
        buf[keep + 2] = '#';
        memcpy(buf + keep + 3, "\r\n", 3);
        out_raw(s, buf, strlen(buf));
        return;
    }
    int k = snprintf(buf, sizeof buf, "%s\r\n", text);
    if (k > 0)
        out_raw(s, buf, (size_t)k < sizeof buf ? (size_t)k : sizeof buf - 1);
}

static void reply_error(grbl_sim *s, int code)
{
    char b[32];
    snprintf(b, sizeof b, "error:%d", code);
    reply(s, b);
}

static bool axes_busy(const grbl_sim *s)
{
    for (int i = 0; i < s->p.n_axes; i++)
        if (rail_axis_busy(&s->ax[i]))
            return true;
    return false;
}

static void flush_queue(grbl_sim *s)
{
    s->q_head = 0;
    s->q_len = 0;
}

static void raise_alarm(grbl_sim *s, int code)
{
    for (int i = 0; i < s->p.n_axes; i++)
        rail_axis_halt(&s->ax[i]);
    flush_queue(s);
    s->mode = M_ALARM;
    s->cancelling = false;
    if (s->home_pending) {
        s->home_pending = false;
    }
    char b[32];
    snprintf(b, sizeof b, "ALARM:%d", code);
    reply(s, b);
}

static void status_report(grbl_sim *s)
{
    const char *st = "Idle";
    char sub[8] = "";
    switch (s->mode) {
    case M_IDLE: st = "Idle"; break;
    case M_RUN: st = "Run"; break;
    case M_JOG: st = "Jog"; break;
    case M_HOLD:
        st = "Hold";
        snprintf(sub, sizeof sub, ":%d", axes_busy(s) ? 1 : 0);
        break;
    case M_ALARM: st = "Alarm"; break;
    case M_HOME: st = "Home"; break;
    }
    double v2 = 0.0;
    for (int i = 0; i < s->p.n_axes; i++)
        v2 += s->ax[i].vel_mm_s * s->ax[i].vel_mm_s;
    double pos[GRBL_SIM_AXES] = {0, 0, 0};
    for (int i = 0; i < s->p.n_axes; i++)
        pos[i] = s->ax[i].pos_mm;
    char b[240];
    if (s->p.report_wpos) {
        const double *w = s->p.wco_mm;
        char wco[80] = "";
        if (s->reports % 10 == 0)
            snprintf(wco, sizeof wco, "|WCO:%.3f,%.3f,%.3f", w[0], w[1], w[2]);
        snprintf(b, sizeof b, "<%s%s|WPos:%.3f,%.3f,%.3f|Bf:%d,127|FS:%.0f,0%s>", st, sub, pos[0] - w[0],
                 pos[1] - w[1], pos[2] - w[2], SIM_QUEUE - s->q_len, sqrt(v2) * 60.0, wco);
    } else {
        snprintf(b, sizeof b, "<%s%s|MPos:%.3f,%.3f,%.3f|Bf:%d,127|FS:%.0f,0>", st, sub, pos[0], pos[1],
                 pos[2], SIM_QUEUE - s->q_len, sqrt(v2) * 60.0);
    }
    s->reports++;
    reply(s, b);
}

static void soft_reset(grbl_sim *s)
{
    bool moving = axes_busy(s) && s->mode != M_HOLD;
    bool homing = s->mode == M_HOME;
    for (int i = 0; i < s->p.n_axes; i++)
        rail_axis_halt(&s->ax[i]);
    flush_queue(s);
    s->cancelling = false;
    s->home_pending = false;
    s->line_len = 0;
    s->absolute = true;
    out_raw(s, "\r\n", 2);
    if (moving || homing) {
        /* GRBL: a reset in motion loses position; ALARM:3 (6 during homing). */
        s->mode = M_ALARM;
        reply(s, homing ? "ALARM:6" : "ALARM:3");
        reply(s, "Grbl 1.1h ['$' for help]");
        reply(s, "[MSG:'$H'|'$X' to unlock]");
        return;
    }
    reply(s, "Grbl 1.1h ['$' for help]");
    if (s->mode == M_ALARM || s->p.start_in_alarm) {
        s->mode = M_ALARM;
        reply(s, "[MSG:'$H'|'$X' to unlock]");
    } else {
        s->mode = M_IDLE;
    }
}

/* Parse G-code words of a motion line. Returns 0 or a GRBL error code. */
static int parse_motion(grbl_sim *s, const char *t, bool jog, sim_block *b, bool *modal_abs)
{
    bool abs_mode = jog ? true : s->absolute;
    bool machine = false, have_f = false, any_axis = false, have_g01 = jog;
    double val[GRBL_SIM_AXES] = {0};
    memset(b, 0, sizeof *b);
    const char *c = t;
    for (int guard = 0; *c && guard < 40; guard++) {
        while (*c == ' ')
            c++;
        if (!*c)
            break;
        char letter = *c++;
        if (letter >= 'a' && letter <= 'z')
            letter = (char)(letter - 32);
        if (letter < 'A' || letter > 'Z')
            return 1;
        char *end = NULL;
        double v = strtod(c, &end);
        if (end == c || !isfinite(v))
            return 2;
        c = end;
        switch (letter) {
        case 'G': {
            int g = (int)lround(v * 10.0);
            if (g == 0 || g == 10)
                have_g01 = true;
            else if (g == 210)
                ;
            else if (g == 530)
                machine = true;
            else if (g == 900)
                abs_mode = true;
            else if (g == 910)
                abs_mode = false;
            else
                return 20;
            break;
        }
        case 'X':
        case 'Y':
        case 'Z': {
            int i = letter - 'X';
            if (i >= s->p.n_axes)
                return 20;
            if (b->has[i])
                return 25;
            b->has[i] = true;
            val[i] = v;
            any_axis = true;
            break;
        }
        case 'F':
            if (v <= 0.0)
                return 4;
            b->feed_mm_min = v;
            have_f = true;
            break;
        default:
            return 20;
        }
    }
    (void)machine; /* no work offsets in the simulator: machine = work coordinates */
    if (modal_abs)
        *modal_abs = abs_mode;
    if (!any_axis) {
        if (jog)
            return 16;
        return have_g01 ? 26 : 0;
    }
    if (!have_f)
        return jog ? 16 : 22;
    if (b->feed_mm_min > s->p.max_feed_mm_min)
        b->feed_mm_min = s->p.max_feed_mm_min;
    /* Targets are relative to the end of the queue (where the machine will be). */
    for (int i = 0; i < s->p.n_axes; i++) {
        double base = s->ax[i].pos_mm;
        for (int k = s->q_len - 1; k >= 0; k--) {
            const sim_block *o = &s->q[(s->q_head + k) % SIM_QUEUE];
            if (o->has[i]) {
                base = o->target[i];
                break;
            }
        }
        if (b->has[i])
            b->target[i] = abs_mode ? val[i] : base + val[i];
    }
    b->jog = jog;
    return 0;
}

static bool in_travel(const grbl_sim *s, const sim_block *b)
{
    for (int i = 0; i < s->p.n_axes; i++)
        if (b->has[i] && (b->target[i] < 0.0 || b->target[i] > s->p.travel_mm[i]))
            return false;
    return true;
}

static void enqueue(grbl_sim *s, const sim_block *b)
{
    s->q[(s->q_head + s->q_len) % SIM_QUEUE] = *b;
    s->q_len++;
    if (s->mode == M_IDLE)
        s->mode = b->jog ? M_JOG : M_RUN;
}

static void exec_line(grbl_sim *s, char *t)
{
    /* Strip spaces at the ends and make letters upper case (GRBL does the same). */
    size_t n = strlen(t);
    while (n && (t[n - 1] == ' ' || t[n - 1] == '\t'))
        t[--n] = 0;
    while (*t == ' ')
        t++;
    for (char *c = t; *c; c++)
        if (*c >= 'a' && *c <= 'z')
            *c = (char)(*c - 32);
    if (!*t) {
        reply(s, "ok");
        return;
    }
    if (t[0] == '$') {
        if (strcmp(t, "$X") == 0) {
            if (s->mode == M_ALARM) {
                s->mode = M_IDLE;
                reply(s, "[MSG:Caution: Unlocked]");
            }
            reply(s, "ok");
        } else if (strcmp(t, "$H") == 0 || strcmp(t, "$HX") == 0 || strcmp(t, "$HY") == 0 ||
                   strcmp(t, "$HZ") == 0) {
            if (s->mode != M_IDLE && s->mode != M_ALARM) {
                reply_error(s, 8);
                return;
            }
            int only = t[2] ? t[2] - 'X' : -1;
            if (only >= s->p.n_axes) {
                reply_error(s, 3);
                return;
            }
            for (int i = 0; i < s->p.n_axes; i++)
                if (only < 0 || only == i)
                    rail_axis_home(&s->ax[i], s->p.home_feed_mm_min / 60.0);
            s->mode = M_HOME;
            s->home_pending = true;
        } else if (strncmp(t, "$J=", 3) == 0) {
            if (s->mode != M_IDLE && s->mode != M_JOG) {
                reply_error(s, s->mode == M_ALARM ? 9 : 8);
                return;
            }
            if (s->q_len >= SIM_QUEUE) {
                reply_error(s, 11); /* our client never fills the planner; a real GRBL would wait */
                return;
            }
            sim_block b;
            int e = parse_motion(s, t + 3, true, &b, NULL);
            if (e) {
                reply_error(s, e);
                return;
            }
            if (!in_travel(s, &b)) {
                reply_error(s, 15);
                return;
            }
            enqueue(s, &b);
            reply(s, "ok");
        } else if (strcmp(t, "$$") == 0) {
            char b[64];
            snprintf(b, sizeof b, "$20=1");
            reply(s, b);
            snprintf(b, sizeof b, "$22=1");
            reply(s, b);
            snprintf(b, sizeof b, "$110=%.3f", s->p.max_feed_mm_min);
            reply(s, b);
            snprintf(b, sizeof b, "$120=%.3f", s->p.accel_mm_s2 / 3600.0);
            reply(s, b);
            snprintf(b, sizeof b, "$130=%.3f", s->p.travel_mm[0]);
            reply(s, b);
            reply(s, "ok");
        } else if (strcmp(t, "$I") == 0) {
            reply(s, "[VER:1.1h.ribbon-grblsim:]");
            reply(s, "[OPT:V,15,128]");
            reply(s, "ok");
        } else {
            reply_error(s, 3);
        }
        return;
    }
    if (s->mode == M_ALARM || s->mode == M_JOG || s->mode == M_HOME) {
        reply_error(s, 9);
        return;
    }
    sim_block b;
    bool abs_mode = s->absolute;
    int e = parse_motion(s, t, false, &b, &abs_mode);
    if (e) {
        reply_error(s, e);
        return;
    }
    s->absolute = abs_mode;
    bool any = false;
    for (int i = 0; i < s->p.n_axes; i++)
        any = any || b.has[i];
    if (any) {
        if (!in_travel(s, &b)) {
            raise_alarm(s, 2); /* GRBL soft limit on a G-code move */
            return;
        }
        if (s->q_len >= SIM_QUEUE) {
            reply_error(s, 11);
            return;
        }
        enqueue(s, &b);
    }
    reply(s, "ok");
}

static void handle_byte(grbl_sim *s, unsigned char c)
{
    switch (c) {
    case '?':
        if (s->p.drop_prob > 0.0 && rail_sim_rand(&s->rng) < s->p.drop_prob)
            return;
        status_report(s);
        return;
    case '!':
        if (s->mode == M_JOG) {
            s->cancelling = true; /* GRBL 1.1: a feed hold during a jog cancels it */
            for (int i = 0; i < s->p.n_axes; i++)
                rail_axis_stop(&s->ax[i]);
        } else if (s->mode == M_RUN) {
            s->mode = M_HOLD;
            for (int i = 0; i < s->p.n_axes; i++)
                rail_axis_stop(&s->ax[i]);
        }
        return;
    case '~':
        if (s->mode == M_HOLD && !axes_busy(s))
            s->mode = s->q_len ? M_RUN : M_IDLE;
        return;
    case 0x18:
        soft_reset(s);
        return;
    case 0x85:
        if (s->mode == M_JOG) {
            s->cancelling = true;
            for (int i = 0; i < s->p.n_axes; i++)
                rail_axis_stop(&s->ax[i]);
        }
        return;
    case '\n':
    case '\r': {
        if (s->line_len == 0 && !s->line_overflow)
            return; /* the second half of "\r\n" */
        bool overflow = s->line_overflow;
        s->line[s->line_len] = 0;
        s->line_len = 0;
        s->line_overflow = false;
        if (s->p.drop_prob > 0.0 && rail_sim_rand(&s->rng) < s->p.drop_prob)
            return;
        if (overflow) {
            reply_error(s, 11);
            return;
        }
        exec_line(s, s->line);
        return;
    }
    default:
        if (c >= 0x80 || c < 0x20)
            return; /* other realtime or control bytes: ignored, as GRBL does */
        if (s->line_len < SIM_LINE_MAX)
            s->line[s->line_len++] = (char)c;
        else
            s->line_overflow = true;
    }
}

/* Advance the machine to the present. */
static void advance(grbl_sim *s)
{
    double now = rail_clock_now(s->clock);
    double dt = now - s->t_last;
    s->t_last = now;
    if (!s->alarm_fired && s->p.alarm_after_s >= 0.0 && now - s->t_start >= s->p.alarm_after_s) {
        s->alarm_fired = true;
        raise_alarm(s, s->p.alarm_code);
    }
    if (!(dt > 0.0))
        return;
    if (s->mode == M_RUN || s->mode == M_JOG) {
        if (!s->cancelling && s->q_len > 0) {
            sim_block *h = &s->q[s->q_head];
            if (!h->started) {
                for (int i = 0; i < s->p.n_axes; i++)
                    h->start[i] = s->ax[i].pos_mm;
                h->started = true;
            }
            double len2 = 0.0;
            for (int i = 0; i < s->p.n_axes; i++)
                if (h->has[i])
                    len2 += (h->target[i] - h->start[i]) * (h->target[i] - h->start[i]);
            for (int i = 0; i < s->p.n_axes; i++) {
                if (!h->has[i] || s->stalled[i])
                    continue;
                double d = h->target[i] - h->start[i];
                double dir = d >= 0.0 ? 1.0 : -1.0;
                double end = h->target[i];
                for (int k = 1; k < s->q_len; k++) {
                    const sim_block *o = &s->q[(s->q_head + k) % SIM_QUEUE];
                    if (!o->has[i] || o->jog != h->jog || (o->target[i] - end) * dir < 0.0)
                        break;
                    end = o->target[i];
                }
                double frac = len2 > 0.0 ? fabs(d) / sqrt(len2) : 1.0;
                double v = h->feed_mm_min / 60.0 * frac;
                if (v > 0.0)
                    rail_axis_move_to(&s->ax[i], end, v);
            }
        }
    }
    if (s->mode == M_HOME) {
        for (int i = 0; i < s->p.n_axes; i++)
            rail_axis_step(&s->ax[i], dt);
        if (!axes_busy(s)) {
            s->mode = M_IDLE;
            if (s->home_pending) {
                s->home_pending = false;
                reply(s, "ok");
            }
        }
        return;
    }
    for (int i = 0; i < s->p.n_axes; i++) {
        double before = s->ax[i].pos_mm;
        rail_axis_step(&s->ax[i], dt);
        double st = s->p.stall_at_mm[i];
        if (!isnan(st) && !s->stalled[i] && rail_sim_crossed(before, s->ax[i].pos_mm, st)) {
            s->stalled[i] = true;
        }
        if (s->stalled[i]) {
            s->ax[i].pos_mm = st;
            rail_axis_halt(&s->ax[i]);
        }
        if (s->ax[i].limit_hit) {
            s->ax[i].limit_hit = false;
            raise_alarm(s, 1);
            return;
        }
    }
    if (s->cancelling) {
        if (!axes_busy(s)) {
            s->cancelling = false;
            flush_queue(s);
            s->mode = M_IDLE;
        }
        return;
    }
    if (s->mode == M_HOLD)
        return;
    /* Retire finished head blocks (at most the whole queue per iteration). */
    for (int guard = 0; guard < SIM_QUEUE && s->q_len > 0; guard++) {
        sim_block *h = &s->q[s->q_head];
        if (!h->started)
            break;
        bool done = true;
        for (int i = 0; i < s->p.n_axes; i++) {
            if (!h->has[i])
                continue;
            double dir = h->target[i] >= h->start[i] ? 1.0 : -1.0;
            if ((s->ax[i].pos_mm - h->target[i]) * dir < -1e-9)
                done = false;
        }
        if (!done)
            break;
        s->q_head = (s->q_head + 1) % SIM_QUEUE;
        s->q_len--;
        if (s->q_len > 0) {
            sim_block *n = &s->q[s->q_head];
            for (int i = 0; i < s->p.n_axes; i++)
                n->start[i] = s->ax[i].pos_mm;
            n->started = true;
        }
    }
    if (s->q_len == 0 && !axes_busy(s) && (s->mode == M_RUN || s->mode == M_JOG))
        s->mode = M_IDLE;
}

rail_err grbl_sim_step(grbl_sim *s, double max_wait_s)
{
    struct pollfd pf = {s->master, POLLIN, 0};
    int ms = max_wait_s > 0.0 ? (int)(max_wait_s * 1000.0) : 0;
    int r = poll(&pf, 1, ms);
    advance(s);
    if (r > 0 && (pf.revents & POLLIN)) {
        unsigned char buf[512];
        ssize_t n = read(s->master, buf, sizeof buf);
        for (ssize_t i = 0; i < n; i++)
            handle_byte(s, buf[i]);
        advance(s);
    }
    return RAIL_OK;
}

static rail_err step_any(void *s, double max_wait_s)
{
    return grbl_sim_step(s, max_wait_s);
}

rail_err grbl_sim_run(grbl_sim *s, double duration_s, volatile sig_atomic_t *stop)
{
    return rail_sim_run(step_any, s, s->clock, duration_s, stop);
}

rail_err grbl_sim_open(grbl_sim **out, const grbl_sim_params *p, char *why, size_t why_len)
{
    *out = NULL;
    if (!p || p->n_axes < 1 || p->n_axes > GRBL_SIM_AXES || !(p->accel_mm_s2 > 0.0) ||
        !(p->max_feed_mm_min > 0.0) || !(p->home_feed_mm_min > 0.0)) {
        snprintf(why, why_len, "grblsim: n_axes must be 1..3 and accel, max feed, home feed positive");
        return RAIL_E_INVALID;
    }
    for (int i = 0; i < p->n_axes; i++)
        if (!(p->travel_mm[i] > 0.0) || !(p->start_mm[i] >= 0.0) || p->start_mm[i] > p->travel_mm[i]) {
            snprintf(why, why_len, "grblsim: axis %c start must lie in [0, travel]", 'X' + i);
            return RAIL_E_INVALID;
        }
    grbl_sim *s = calloc(1, sizeof *s);
    if (!s) {
        snprintf(why, why_len, "grblsim: out of memory");
        return RAIL_E_NOMEM;
    }
    s->p = *p;
    /* The slave is held open in raw mode (rail_sim_pty_open); replies must not block. */
    rail_sim_pty_err pe = rail_sim_pty_open(&s->master, &s->slave, s->path, sizeof s->path);
    if (pe != RAIL_SIM_PTY_OK) {
        if (pe == RAIL_SIM_PTY_MASTER)
            snprintf(why, why_len, "grblsim: cannot create a pseudo-terminal: %s", strerror(errno));
        else
            snprintf(why, why_len, "grblsim: cannot open %s: %s", s->path, strerror(errno));
        grbl_sim_close(s);
        return RAIL_E_IO;
    }
    int fl = fcntl(s->master, F_GETFL);
    fcntl(s->master, F_SETFL, fl | O_NONBLOCK);
    s->clock = rail_clock_real();
    s->t_start = s->t_last = rail_clock_now(s->clock);
    for (int i = 0; i < p->n_axes; i++)
        s->ax[i] = rail_axis_make(p->start_mm[i], p->accel_mm_s2, p->travel_mm[i]);
    s->absolute = true;
    s->rng = rail_sim_seed(p->seed);
    s->mode = p->start_in_alarm ? M_ALARM : M_IDLE;
    reply(s, "Grbl 1.1h ['$' for help]");
    if (p->start_in_alarm)
        reply(s, "[MSG:'$H'|'$X' to unlock]");
    *out = s;
    return RAIL_OK;
}

const char *grbl_sim_path(const grbl_sim *s)
{
    return s->path;
}

void grbl_sim_positions(const grbl_sim *s, double mm[GRBL_SIM_AXES], double *t_s)
{
    for (int i = 0; i < GRBL_SIM_AXES; i++) mm[i] = i < s->p.n_axes ? s->ax[i].pos_mm : 0.0;
    if (t_s) *t_s = s->t_last;
}

void grbl_sim_close(grbl_sim *s)
{
    if (!s)
        return;
    if (s->slave >= 0)
        close(s->slave);
    if (s->master >= 0)
        close(s->master);
    free(s);
}

void grbl_sim_raise_alarm(grbl_sim *s, int code)
{
    raise_alarm(s, code);
}
