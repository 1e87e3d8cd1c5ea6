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
#include <sys/inotify.h>
#include <unistd.h>

#include "grbl_settings.h"
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
    grbl_settings set;      /* the "EEPROM" */
    double origin[GRBL_SIM_AXES]; /* mm, physical position the controller counts as zero */
    bool critical;          /* hard or soft limit alarm: everything waits for a reset */
    int ino;                /* inotify watching the slave for opens (reset_on_open), -1 none */
    double boot_until;      /* controller time the bootloader ends; < 0 = running */
};

/* GRBL 1.1's settings and their documented defaults (defaults.h generic, settings.md). */
static const struct { int num; double def; bool integer; } sim_settings[] = {
    {0, 10, true}, {1, 25, true}, {2, 0, true}, {3, 0, true}, {4, 0, true}, {5, 0, true},
    {6, 0, true}, {10, 1, true}, {11, 0.010, false}, {12, 0.002, false}, {13, 0, true},
    {20, 0, true}, {21, 0, true}, {22, 0, true}, {23, 0, true}, {24, 25.0, false},
    {25, 500.0, false}, {26, 250, true}, {27, 1.0, false}, {30, 1000, true}, {31, 0, true},
    {32, 0, true}, {100, 250.0, false}, {101, 250.0, false}, {102, 250.0, false},
    {110, 500.0, false}, {111, 500.0, false}, {112, 500.0, false}, {120, 10.0, false},
    {121, 10.0, false}, {122, 10.0, false}, {130, 200.0, false}, {131, 200.0, false},
    {132, 200.0, false},
};
#define SIM_N_SETTINGS (int)(sizeof sim_settings / sizeof sim_settings[0])

static int setting_index(int num)
{
    for (int i = 0; i < SIM_N_SETTINGS; i++)
        if (sim_settings[i].num == num)
            return i;
    return -1;
}

/* Store $num=val as GRBL's settings_store_global_setting does; 0 or a GRBL error code. */
static int setting_store(grbl_sim *s, int num, double val)
{
    int k = setting_index(num);
    if (k < 0)
        return 3;
    if (val < 0.0)
        return 4;
    if (sim_settings[k].integer)
        val = (double)(long)val;
    if (num == 0 && val < 3.0)
        return 6;
    if (num == 20 && val != 0.0 && s->set.v[22] == 0.0)
        return 10;
    grbl_settings_set(&s->set, num, val);
    if (num == 22 && val == 0.0)
        grbl_settings_set(&s->set, 20, 0.0); /* GRBL forces soft limits off with homing */
    if (num >= 120 && num <= 122 && num - 120 < s->p.n_axes && val > 0.0)
        s->ax[num - 120].accel_mm_s2 = val;
    if (num >= 130 && num <= 132 && num - 130 < s->p.n_axes && val > 0.0)
        s->ax[num - 130].travel_mm = val;
    return 0;
}

/* "$N=V" text; 0 or a GRBL error code (3 not a setting line, 2 bad number). */
static int setting_line(grbl_sim *s, const char *t)
{
    const char *eq = strchr(t, '=');
    if (!eq || eq == t + 1)
        return 3;
    int num = 0;
    for (const char *c = t + 1; c < eq; c++) {
        if (*c < '0' || *c > '9' || c - t > 4)
            return 3;
        num = num * 10 + (*c - '0');
    }
    char *end = NULL;
    double v = strtod(eq + 1, &end);
    if (end == eq + 1 || *end || !isfinite(v))
        return 2;
    return setting_store(s, num, v);
}

static bool homing_enabled(const grbl_sim *s)
{
    return s->set.v[22] != 0.0;
}

/* Inches when $13=1: positions, offsets and feeds as GRBL reports them. */
static double rep_unit(const grbl_sim *s)
{
    return s->set.v[13] != 0.0 ? 1.0 / 25.4 : 1.0;
}

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
    p.reset_delay_s = 1.0;
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
    if (code == 1 || code == 2) {
        /* GRBL 1.1: hard and soft limit alarms are critical; only a reset goes on. */
        s->critical = true;
        reply(s, "[MSG:Reset to continue]");
    }
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
    double u = rep_unit(s);
    const char *nf = u != 1.0 ? "%.4f" : "%.3f";
    double v2 = 0.0;
    for (int i = 0; i < s->p.n_axes; i++)
        v2 += s->ax[i].vel_mm_s * s->ax[i].vel_mm_s;
    double pos[GRBL_SIM_AXES] = {0, 0, 0};
    for (int i = 0; i < s->p.n_axes; i++)
        pos[i] = s->ax[i].pos_mm - s->origin[i];
    int mask = (int)s->set.v[10];
    bool wpos = (mask & 1) == 0;
    char b[240], f[40];
    size_t n = 0;
    n += (size_t)snprintf(b + n, sizeof b - n, "<%s%s|%s:", st, sub, wpos ? "WPos" : "MPos");
    for (int i = 0; i < GRBL_SIM_AXES; i++) {
        snprintf(f, sizeof f, nf, (pos[i] - (wpos ? s->p.wco_mm[i] : 0.0)) * u);
        n += (size_t)snprintf(b + n, sizeof b - n, "%s%s", i ? "," : "", f);
    }
    if (mask & 2)
        n += (size_t)snprintf(b + n, sizeof b - n, "|Bf:%d,127", SIM_QUEUE - s->q_len);
    n += (size_t)snprintf(b + n, sizeof b - n, "|FS:%.0f,0", sqrt(v2) * 60.0 * u);
    if (wpos && s->reports % 10 == 0) {
        n += (size_t)snprintf(b + n, sizeof b - n, "|WCO:");
        for (int i = 0; i < GRBL_SIM_AXES; i++) {
            snprintf(f, sizeof f, nf, s->p.wco_mm[i] * u);
            n += (size_t)snprintf(b + n, sizeof b - n, "%s%s", i ? "," : "", f);
        }
    }
    snprintf(b + n, sizeof b - n, ">");
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
    s->critical = false;
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
    if (s->mode == M_ALARM) {
        s->mode = M_ALARM;
        reply(s, "[MSG:'$H'|'$X' to unlock]");
    } else {
        s->mode = M_IDLE;
    }
}

/* A hardware reset (power, the reset line pulsed by DTR when a client opens the port): the
   board forgets everything but its EEPROM; GRBL counts from zero where the axes stand once its
   bootloader hands over (boot_until). */
static void hard_reset(grbl_sim *s)
{
    for (int i = 0; i < s->p.n_axes; i++)
        rail_axis_halt(&s->ax[i]);
    flush_queue(s);
    s->cancelling = false;
    s->home_pending = false;
    s->line_len = 0;
    s->line_overflow = false;
    s->absolute = true;
    s->critical = false;
    s->mode = M_ALARM; /* nothing runs while booting */
    s->boot_until = rail_clock_now(s->clock) + s->p.reset_delay_s;
}

static void boot_done(grbl_sim *s)
{
    s->boot_until = -1.0;
    for (int i = 0; i < s->p.n_axes; i++)
        s->origin[i] = s->ax[i].pos_mm;
    reply(s, "Grbl 1.1h ['$' for help]");
    if (homing_enabled(s)) {
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
    for (int i = 0; i < s->p.n_axes; i++)
        if (b->has[i] && b->feed_mm_min > s->set.v[110 + i])
            b->feed_mm_min = s->set.v[110 + i]; /* GRBL limits a block to its axes' max rates */
    /* Targets are relative to the end of the queue (where the machine will be), in machine
       coordinates: physical = machine + origin. */
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
            b->target[i] = abs_mode ? val[i] + s->origin[i] : base + val[i];
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
    if (s->critical)
        return; /* after a critical alarm GRBL serves nothing but a reset */
    if (t[0] == '$') {
        if (strcmp(t, "$X") == 0) {
            if (s->mode == M_ALARM) {
                s->mode = M_IDLE;
                reply(s, "[MSG:Caution: Unlocked]");
            }
            reply(s, "ok");
        } else if (strcmp(t, "$H") == 0 || strcmp(t, "$HX") == 0 || strcmp(t, "$HY") == 0 ||
                   strcmp(t, "$HZ") == 0) {
            if (!homing_enabled(s)) {
                reply_error(s, 5);
                return;
            }
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
            if (s->set.v[20] != 0.0 && !in_travel(s, &b)) {
                reply_error(s, 15);
                return;
            }
            enqueue(s, &b);
            reply(s, "ok");
        } else if (strcmp(t, "$$") == 0) {
            if (s->mode != M_IDLE && s->mode != M_ALARM) {
                reply_error(s, 8);
                return;
            }
            for (int i = 0; i < SIM_N_SETTINGS; i++) {
                char b[48];
                int num = sim_settings[i].num;
                if (sim_settings[i].integer)
                    snprintf(b, sizeof b, "$%d=%ld", num, (long)s->set.v[num]);
                else
                    snprintf(b, sizeof b, "$%d=%.3f", num, s->set.v[num]);
                reply(s, b);
            }
            reply(s, "ok");
        } else if (t[1] >= '0' && t[1] <= '9') {
            if (s->mode != M_IDLE && s->mode != M_ALARM) {
                reply_error(s, 8);
                return;
            }
            int e = setting_line(s, t);
            if (e)
                reply_error(s, e);
            else
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
        if (s->set.v[20] != 0.0 && !in_travel(s, &b)) {
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
    if (s->boot_until >= 0.0)
        return; /* the bootloader has the line: bytes sent now are lost */
    if (s->critical && c != '?' && c != 0x18)
        return;
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
    if (s->boot_until >= 0.0 && now >= s->boot_until)
        boot_done(s);
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
            for (int i = 0; i < s->p.n_axes; i++)
                s->origin[i] = 0.0; /* homed: machine zero is the switch again */
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
    struct pollfd pf[2] = {{s->master, POLLIN, 0}, {s->ino, POLLIN, 0}};
    int ms = max_wait_s > 0.0 ? (int)(max_wait_s * 1000.0) : 0;
    if (s->boot_until >= 0.0) {
        int left = (int)ceil((s->boot_until - rail_clock_now(s->clock)) * 1000.0);
        if (left < ms)
            ms = left > 0 ? left : 0;
    }
    int r = poll(pf, s->ino >= 0 ? 2 : 1, ms);
    if (r > 0 && s->ino >= 0 && (pf[1].revents & POLLIN)) {
        /* A client opened the port: DTR resets the board (an Arduino's auto-reset). */
        char ev[1024];
        ssize_t n = read(s->ino, ev, sizeof ev);
        bool opened = false;
        for (ssize_t off = 0; n > 0 && off + (ssize_t)sizeof(struct inotify_event) <= n;) {
            const struct inotify_event *ie = (const void *)(ev + off);
            if (ie->mask & IN_OPEN)
                opened = true;
            off += (ssize_t)sizeof(struct inotify_event) + ie->len;
        }
        if (opened)
            hard_reset(s);
    }
    advance(s);
    if (r > 0 && (pf[0].revents & POLLIN)) {
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
    s->boot_until = -1.0;
    /* The EEPROM: GRBL's defaults, then what the parameters say, then p->settings. */
    for (int i = 0; i < SIM_N_SETTINGS; i++)
        grbl_settings_set(&s->set, sim_settings[i].num, sim_settings[i].def);
    for (int i = 0; i < GRBL_SIM_AXES; i++) {
        grbl_settings_set(&s->set, 110 + i, p->max_feed_mm_min);
        grbl_settings_set(&s->set, 120 + i, p->accel_mm_s2);
        grbl_settings_set(&s->set, 130 + i, p->travel_mm[i] > 0.0 ? p->travel_mm[i] : 200.0);
    }
    grbl_settings_set(&s->set, 10, p->report_wpos ? 0.0 : 1.0);
    grbl_settings_set(&s->set, 21, 1.0); /* the simulated ends are limit switches */
    grbl_settings_set(&s->set, 22, p->start_in_alarm ? 1.0 : 0.0);
    grbl_settings_set(&s->set, 25, p->home_feed_mm_min);
    int se = p->soft_limits ? setting_store(s, 20, 1.0) : 0;
    char text[sizeof p->settings + 1];
    snprintf(text, sizeof text, "%s", p->settings);
    char *save = NULL;
    for (char *tok = strtok_r(text, " ,", &save); tok && !se; tok = strtok_r(NULL, " ,", &save)) {
        se = tok[0] == '$' ? setting_line(s, tok) : 3;
        if (se)
            snprintf(why, why_len, "grblsim: setting '%s' refused: error:%d", tok, se);
    }
    if (se) {
        if (p->soft_limits && se == 10)
            snprintf(why, why_len, "grblsim: soft limits ($20=1) need homing ($22=1): error:10");
        grbl_sim_close(s);
        return RAIL_E_INVALID;
    }
    /* Powered before anyone listened: no banner reaches a client, as with a real board. */
    s->mode = homing_enabled(s) ? M_ALARM : M_IDLE;
    s->ino = -1;
    if (p->reset_on_open) {
        s->ino = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
        if (s->ino < 0 || inotify_add_watch(s->ino, s->path, IN_OPEN) < 0) {
            snprintf(why, why_len, "grblsim: cannot watch %s for opens: %s", s->path, strerror(errno));
            grbl_sim_close(s);
            return RAIL_E_IO;
        }
    }
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
    if (s->ino > 0)
        close(s->ino);
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
