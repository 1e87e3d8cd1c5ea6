/* grbl_link.c: one GRBL controller on one serial port: line assembly, send-and-wait-for-"ok",
 * status queries, asynchronous lines (ALARM:N, "ok" of a homing cycle, reset banner).
 *
 * Flow control is the simple GRBL "send-response" scheme: one line out, wait for its "ok" or
 * "error:N" before the next, so GRBL's 128-byte receive buffer can never overflow. Realtime
 * bytes ('?', '!', 0x18, 0x85) bypass it. Before every request, bytes already waiting are read
 * and handled, so a reply that arrived late cannot be mistaken for the answer to the next.
 *
 * Opening waits for the controller to boot: an Arduino-based board resets when the port opens
 * (the DTR line pulses its reset pin) and its bootloader (Optiboot on the Uno) listens for up to
 * 1 s before GRBL starts and prints "Grbl 1.1h ['$' for help]". The link asks '?' every half
 * reply timeout meanwhile (a byte that is no STK500 command makes Optiboot start the
 * application at once) for at most boot_wait_s: a banner first means the board reset, a status
 * report first means it did not (reset-on-open disabled). Then `$$` is read.
 *
 * Trust in the position: a reset loses GRBL's position (it counts from zero wherever the axes
 * stand), so any banner we did not cause by a soft reset at rest, any alarm whose documented
 * meaning is a lost position (1 hard limit, 3 reset in motion, 6-9 homing failed), a
 * "[MSG:Reset to continue]" and a reopened port set zero_lost until a homing cycle ends with
 * "ok" or the user confirms the zero (rail_gcode.h). The state outlives the process: a marker
 * file beside the device's lock (rail_trust.h) is written when it is lost, read at open and
 * removed when it is trusted again. */
#define _GNU_SOURCE /* memmem */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "grbl_link.h"
#include "rail_lock_name.h"
#include "rail_port_lock.h"
#include "rail_trust.h"

static rail_err lfail(grbl_link *l, rail_err e, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static rail_err lfail(grbl_link *l, rail_err e, const char *fmt, ...)
{
    if (e == RAIL_E_DISCONNECTED)
        l->lost = true;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(l->why, sizeof l->why, fmt, ap);
    va_end(ap);
    return e;
}

/* A copy of a device line fit for a message: non-printable bytes become '?'. */
static const char *printable(const char *line, char *buf, size_t n)
{
    size_t i = 0;
    for (; line[i] && i + 1 < n; i++)
        buf[i] = (line[i] >= 0x20 && line[i] < 0x7f) ? line[i] : '?';
    buf[i] = 0;
    return buf;
}

void grbl_link_zero_lost(grbl_link *l, const char *fmt, ...)
{
    char was[sizeof l->zero_why];
    memcpy(was, l->zero_why, sizeof was);
    bool lost = l->zero_lost;
    l->zero_lost = true;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(l->zero_why, sizeof l->zero_why, fmt, ap);
    va_end(ap);
    if (!lost || strcmp(was, l->zero_why) != 0)
        rail_trust_mark(l->spec, l->zero_why); /* a restarted process must refuse motion too */
}

void grbl_link_zero_trusted(grbl_link *l)
{
    l->zero_lost = false;
    l->zero_why[0] = 0;
    rail_trust_clear(l->spec);
}

/* GRBL 1.1's alarm table: 1 (hard limit) and 3 (reset in motion) say the machine position is
   likely lost; 6-9 end a homing cycle unfinished; 2 (soft limit) retains the position, 4 and 5
   (probe) do not move the axes off their count. */
static bool alarm_loses_position(int code)
{
    return code == 1 || code == 3 || (code >= 6 && code <= 9) || code < 0;
}

/* Handle a line that is not the answer being waited for. */
static void async_line(grbl_link *l, const char *line, size_t len)
{
    int code = 0;
    switch (grbl_line_classify(line, len, &code)) {
    case GRBL_LINE_ALARM:
        l->alarm_code = code;
        if (l->home_pending) {
            l->home_pending = false;
            l->home_error = -code;
        }
        if (alarm_loses_position(code))
            grbl_link_zero_lost(l, "ALARM:%d (%s)", code, grbl_alarm_text(code));
        break;
    case GRBL_LINE_OK:
        if (l->home_pending) {
            l->home_pending = false;
            grbl_link_zero_trusted(l); /* homed: the machine zero is the switches' again */
        }
        break;
    case GRBL_LINE_MESSAGE:
        if (len >= 22 && memmem(line, len, "Reset to continue", 17))
            l->critical = true;
        if (l->critical)
            grbl_link_zero_lost(l, "the controller halted on a critical alarm%s%d "
                                "([MSG:Reset to continue])", l->alarm_code ? " ALARM:" : "",
                                l->alarm_code);
        break;
    case GRBL_LINE_ERROR:
        if (l->home_pending) {
            l->home_pending = false;
            l->home_error = code;
        }
        break;
    case GRBL_LINE_WELCOME:
        l->resets_seen++;
        l->critical = false;
        if (l->own_resets > 0 &&
            rail_clock_now(l->clock) - l->own_reset_t <= l->reply_timeout_s + GRBL_OWN_RESET_SLACK_S) {
            l->own_resets--; /* our own reset at rest: GRBL keeps the position */
        } else {
            l->own_resets = 0; /* a banner of ours that never came is not one to wait for */
            char pb[48];
            grbl_link_zero_lost(l, "the controller restarted ('%s': power, USB or reset line), "
                                "counting from zero where it stood",
                                printable(line, pb, sizeof pb));
        }
        break;
    default:
        break;
    }
}

/* Read one line within timeout_s. *len = 0 and RAIL_E_TIMEOUT if none completed. */
static rail_err read_line(grbl_link *l, char *out, size_t cap, size_t *len, double timeout_s)
{
    double t0 = rail_clock_now(l->clock);
    bool last_look = false;
    *len = 0;
    for (int guard = 0; guard < 4096; guard++) {
        /* A complete line already buffered? */
        for (size_t i = 0; i < l->rx_len; i++) {
            if (l->rx[i] == '\n') {
                size_t n = i;
                if (n > 0 && l->rx[n - 1] == '\r')
                    n--;
                size_t k = n < cap - 1 ? n : cap - 1;
                memcpy(out, l->rx, k);
                out[k] = 0;
                *len = k;
                memmove(l->rx, l->rx + i + 1, l->rx_len - i - 1);
                l->rx_len -= i + 1;
                return RAIL_OK;
            }
        }
        if (l->rx_len == sizeof l->rx) {
            l->rx_len = 0; /* a line longer than any GRBL line: drop it, report it */
            return lfail(l, RAIL_E_PROTOCOL, "reply line longer than %zu bytes without a newline",
                         sizeof l->rx);
        }
        double left = timeout_s - (rail_clock_now(l->clock) - t0);
        if (guard > 0 && left <= 0.0 && last_look)
            return lfail(l, RAIL_E_TIMEOUT, "no reply from %.100s within %.3f s", l->ser->path, timeout_s);
        /* Past the deadline, one last look without waiting: if this thread was not scheduled
           while the reply arrived, the reply is waiting; only the controller's silence is a
           timeout, never our own stall. */
        if (guard > 0 && left <= 0.0)
            last_look = true;
        size_t got = 0;
        rail_err e = rail_serial_read(l->ser, l->rx + l->rx_len, sizeof l->rx - l->rx_len, &got,
                                      left > 0.05 ? 0.05 : left > 0.0 ? left : 0.0);
        if (e != RAIL_OK)
            return lfail(l, e, "%s", l->ser->why);
        l->rx_len += got;
        if (got > 0)
            last_look = false;
    }
    return lfail(l, RAIL_E_TIMEOUT, "no complete reply line");
}

rail_err grbl_link_drain(grbl_link *l)
{
    char line[300];
    size_t len;
    for (int i = 0; i < 64; i++) {
        rail_err e = read_line(l, line, sizeof line, &len, 0.0);
        if (e == RAIL_E_TIMEOUT)
            return RAIL_OK;
        if (e == RAIL_E_PROTOCOL)
            continue;
        if (e != RAIL_OK)
            return e;
        async_line(l, line, len);
    }
    return RAIL_OK;
}

rail_err grbl_link_realtime(grbl_link *l, unsigned char c)
{
    rail_err e = rail_serial_write(l->ser, &c, 1, l->reply_timeout_s);
    if (e != RAIL_OK)
        return lfail(l, e, "%s", l->ser->why);
    return RAIL_OK;
}

rail_err grbl_link_send(grbl_link *l, const char *cmd, int *err_code)
{
    *err_code = 0;
    rail_err e = grbl_link_drain(l);
    if (e != RAIL_OK)
        return e;
    char buf[128];
    int n = snprintf(buf, sizeof buf, "%s\n", cmd);
    if (n < 0 || (size_t)n >= sizeof buf || n > 80)
        return lfail(l, RAIL_E_INVALID, "command '%.40s' longer than GRBL's 80-character line", cmd);
    e = rail_serial_write(l->ser, buf, (size_t)n, l->reply_timeout_s);
    if (e != RAIL_OK)
        return lfail(l, e, "%s", l->ser->why);
    double t0 = rail_clock_now(l->clock);
    char line[300];
    size_t len;
    for (int i = 0; i < 64; i++) {
        double left = l->reply_timeout_s - (rail_clock_now(l->clock) - t0);
        e = read_line(l, line, sizeof line, &len, left > 0.0 ? left : 0.0);
        if (e == RAIL_E_PROTOCOL)
            continue;
        if (e == RAIL_E_TIMEOUT)
            return lfail(l, e, "no 'ok' for '%s' from %.100s within %.3f s", cmd, l->ser->path,
                         l->reply_timeout_s);
        if (e != RAIL_OK)
            return e;
        int code = 0;
        grbl_line_kind k = grbl_line_classify(line, len, &code);
        if (k == GRBL_LINE_OK)
            return RAIL_OK;
        if (k == GRBL_LINE_ERROR) {
            *err_code = code;
            return lfail(l, RAIL_E_DEVICE, "GRBL refused '%s': error:%d (%s)", cmd, code,
                         grbl_error_text(code));
        }
        async_line(l, line, len);
    }
    return lfail(l, RAIL_E_PROTOCOL, "too many unrelated lines while waiting for 'ok' to '%s'", cmd);
}

/* Reopen a lost port. The controller may have been reset or replaced: cancel whatever it runs
   and count it as a reset, so a move in progress is abandoned, never carried on. */
static rail_err reopen(grbl_link *l, grbl_report *rep)
{
    rail_serial *ser = NULL;
    char why[700];
    /* The name may lead to another device now (USB re-enumeration): its lock first, before a byte
       goes to it; the lock held since the open covers the original device only. */
    char key[200], name[240];
    rail_lock_serial_key(l->spec, key, sizeof key, name, sizeof name);
    if (strcmp(key, l->key) == 0) {
        rail_port_lock_release(l->relock); /* back on the device the opener locked */
        l->relock = NULL;
        l->relock_key[0] = 0;
    } else if (!l->relock || strcmp(key, l->relock_key) != 0) {
        int held = 0;
        struct rail_port_lock *pl = rail_port_lock_take(l->spec, "ribbon rig: a rail's port reopened", &held, why,
                                                        sizeof why);
        if (!pl)
            return lfail(l, RAIL_E_DISCONNECTED, "port leads to another device, not reopened: %.230s", why);
        rail_port_lock_release(l->relock);
        l->relock = pl;
        rail_text_copy(l->relock_key, sizeof l->relock_key, key);
    }
    rail_err e = rail_serial_open(&ser, l->spec, l->baud, why, sizeof why);
    if (e != RAIL_OK)
        return lfail(l, RAIL_E_DISCONNECTED, "controller lost; reopening failed: %s", why);
    rail_serial_close(l->ser);
    l->ser = ser;
    l->rx_len = 0;
    l->lost = false;
    l->home_pending = false;
    l->own_resets = 0; /* no banner still due is ours on a new port */
    l->resets_seen++;
    grbl_link_zero_lost(l, "the port was lost and reopened: the controller may have reset");
    e = grbl_link_status(l, rep);
    if (e == RAIL_OK)
        e = grbl_link_quiesce(l, rep);
    return e;
}

rail_err grbl_link_status(grbl_link *l, grbl_report *rep)
{
    if (l->lost)
        return reopen(l, rep);
    rail_err e = grbl_link_drain(l);
    if (e != RAIL_OK)
        return e;
    e = grbl_link_realtime(l, '?');
    if (e != RAIL_OK)
        return e;
    double t0 = rail_clock_now(l->clock);
    char line[300];
    size_t len;
    rail_err bad = RAIL_OK;
    bool asked_again = false;
    for (int i = 0; i < 64; i++) {
        /* Half the reply timeout without a report: ask once more (a '?' lost on the line is not
           a lost controller); the controller is silent, and the link lost, only when neither
           request is answered within reply_timeout_s of the first. */
        double el = rail_clock_now(l->clock) - t0;
        double left = (asked_again ? l->reply_timeout_s : 0.5 * l->reply_timeout_s) - el;
        e = read_line(l, line, sizeof line, &len, left > 0.0 ? left : 0.0);
        if (e == RAIL_E_TIMEOUT && !asked_again) {
            asked_again = true;
            e = grbl_link_realtime(l, '?');
            if (e != RAIL_OK)
                return e;
            continue;
        }
        if (e == RAIL_E_PROTOCOL) {
            bad = e;
            continue;
        }
        if (e == RAIL_E_TIMEOUT && bad != RAIL_OK)
            return bad;
        if (e == RAIL_E_TIMEOUT)
            return lfail(l, e, "no reply to '?' from %.100s within %.3f s (asked twice)", l->ser->path,
                         l->reply_timeout_s);
        if (e != RAIL_OK)
            return e;
        int code = 0;
        grbl_line_kind k = grbl_line_classify(line, len, &code);
        if (k == GRBL_LINE_STATUS) {
            char why[200], pb[64];
            if (!grbl_status_parse(line, len, rep, why, sizeof why))
                return lfail(l, RAIL_E_PROTOCOL, "%s: '%s'", why, printable(line, pb, sizeof pb));
            if (rep->have_wco) {
                memcpy(l->wco, rep->wco, sizeof l->wco);
                l->have_wco = true;
            }
            if (rep->work_pos && !rep->have_wco) {
                /* Work position without an offset in this report: use the last one seen. */
                if (!l->have_wco)
                    return lfail(l, RAIL_E_PROTOCOL,
                                 "controller reports work positions (WPos) and no offset (WCO) "
                                 "has been seen yet; set $10=1 so it reports machine positions");
                for (int q = 0; q < GRBL_MAX_AXES; q++)
                    rep->pos[q] += l->wco[q];
            }
            return RAIL_OK;
        }
        if (k == GRBL_LINE_OTHER) {
            /* Garbage where a report belongs: remember it, keep waiting for a real report. */
            char pb[64];
            bad = lfail(l, RAIL_E_PROTOCOL, "garbled reply to '?': '%s'", printable(line, pb, sizeof pb));
            continue;
        }
        async_line(l, line, len);
    }
    return lfail(l, RAIL_E_PROTOCOL, "too many lines without a status report");
}

/* Ask '?' until a status report arrives, at most boot_wait_s (at least three asks). A banner on
   the way means the board reset when the port opened. */
static rail_err boot_wait(grbl_link *l, double boot_wait_s, grbl_report *rep)
{
    double t0 = rail_clock_now(l->clock);
    int resets0 = l->resets_seen;
    rail_err e = RAIL_E_TIMEOUT;
    for (int i = 0; i < 1000; i++) {
        e = grbl_link_status(l, rep);
        if (e == RAIL_OK || (e != RAIL_E_TIMEOUT && e != RAIL_E_PROTOCOL))
            break;
        if (i >= 2 && rail_clock_now(l->clock) - t0 >= boot_wait_s)
            break;
    }
    if (l->resets_seen != resets0) {
        l->reset_on_open = true;
        grbl_link_zero_lost(l, "the controller reset when the port opened (start-up banner), "
                            "counting from zero where it stood");
    }
    return e;
}

rail_err grbl_link_open(grbl_link **out, const rail_gcode_params *g, rail_clock clock, char *why,
                        size_t why_len)
{
    *out = NULL;
    if (!g || !(g->reply_timeout_s > 0.0) || g->reply_timeout_s > 10.0) {
        snprintf(why, why_len, "gcode: reply_timeout_s must be in (0, 10]");
        return RAIL_E_INVALID;
    }
    grbl_link *l = calloc(1, sizeof *l);
    if (!l) {
        snprintf(why, why_len, "gcode: out of memory");
        return RAIL_E_NOMEM;
    }
    /* Reply timeouts are real time whatever clock the rail runs on: a virtual clock does not
       advance while we wait for bytes. */
    (void)clock;
    l->clock = rail_clock_real();
    l->reply_timeout_s = g->reply_timeout_s;
    l->refs = 1;
    rail_text_copy(l->spec, sizeof l->spec, g->port);
    char kname[240];
    rail_lock_serial_key(g->port, l->key, sizeof l->key, kname, sizeof kname);
    l->baud = g->baud;
    rail_err e = rail_serial_open(&l->ser, g->port, g->baud, why, why_len);
    if (e != RAIL_OK) {
        free(l);
        return e;
    }
    /* Wait for the board to boot (banner) or answer (no reset), then make sure nothing is
       left moving, then read its settings. */
    grbl_report rep;
    e = boot_wait(l, g->boot_wait_s, &rep);
    if (e == RAIL_OK)
        e = grbl_link_quiesce(l, &rep);
    if (e != RAIL_OK) {
        snprintf(why, why_len, "gcode: no usable GRBL status from %.100s within boot_wait_s = %.2f s: %.200s",
                 l->ser->path, g->boot_wait_s, l->why);
        grbl_link_release(l);
        return e;
    }
    if (rep.state == GRBL_ALARM && !l->zero_lost)
        grbl_link_zero_lost(l, "the controller is in alarm at open (homing required, or an alarm "
                            "from before)");
    char kept[600];
    if (!l->zero_lost && rail_trust_marked(l->spec, kept, sizeof kept)) {
        /* An earlier process saw it lose its position and nobody homed or confirmed it since. */
        l->zero_lost = true;
        rail_text_copy(l->zero_why, sizeof l->zero_why, kept);
    }
    e = grbl_link_read_settings(l);
    if (e != RAIL_OK) {
        snprintf(why, why_len, "gcode: cannot read the settings ($$) of %.100s: %.200s", l->ser->path, l->why);
        grbl_link_release(l);
        return e;
    }
    *out = l;
    return RAIL_OK;
}

/* One "$$": the lines that parse are added to l->settings (a garbled line never parses: GRBL
   lines end in a digit), so several rounds add up over a noisy link. */
static rail_err settings_round(grbl_link *l)
{
    rail_err e = grbl_link_drain(l);
    if (e != RAIL_OK)
        return e;
    e = rail_serial_write(l->ser, "$$\n", 3, l->reply_timeout_s);
    if (e != RAIL_OK)
        return lfail(l, e, "%s", l->ser->why);
    /* About 34 lines of up to 16 bytes: 50 ms at 115200 baud, 0.5 s at 9600. */
    double limit = l->reply_timeout_s + 0.5;
    double t0 = rail_clock_now(l->clock);
    char line[300];
    size_t len;
    for (int i = 0; i < 200; i++) {
        double left = limit - (rail_clock_now(l->clock) - t0);
        e = read_line(l, line, sizeof line, &len, left > 0.0 ? left : 0.0);
        if (e == RAIL_E_PROTOCOL)
            continue;
        if (e == RAIL_E_TIMEOUT)
            return lfail(l, e, "no 'ok' after '$$' within %.2f s (%d settings read)", limit,
                         l->settings.count);
        if (e != RAIL_OK)
            return e;
        int code = 0, num = 0;
        double val = 0.0;
        grbl_line_kind k = grbl_line_classify(line, len, &code);
        if (k == GRBL_LINE_OK)
            return RAIL_OK;
        if (k == GRBL_LINE_ERROR)
            return lfail(l, RAIL_E_DEVICE, "GRBL refused '$$': error:%d (%s)", code, grbl_error_text(code));
        if (k == GRBL_LINE_OTHER && grbl_setting_line_parse(line, len, &num, &val))
            grbl_settings_set(&l->settings, num, val);
        else
            async_line(l, line, len);
    }
    return lfail(l, RAIL_E_PROTOCOL, "too many lines after '$$'");
}

rail_err grbl_link_read_settings(grbl_link *l)
{
    /* The settings the driver's check reads (grbl_settings.h). */
    static const int needed[] = {10, 13, 20, 21, 22, 110, 111, 112, 120, 121, 122, 130, 131, 132};
    memset(&l->settings, 0, sizeof l->settings);
    rail_err e = RAIL_OK;
    for (int round = 0; round < 5; round++) {
        e = settings_round(l);
        if (e == RAIL_E_DEVICE || e == RAIL_E_DISCONNECTED || e == RAIL_E_IO)
            return e;
        bool all = true;
        for (size_t i = 0; i < sizeof needed / sizeof needed[0]; i++)
            all = all && l->settings.have[needed[i]];
        if (all)
            return RAIL_OK;
    }
    /* Settings still missing: the check names the first one the driver needs. */
    return e == RAIL_E_TIMEOUT && l->settings.count == 0 ? e : RAIL_OK;
}

rail_err grbl_link_soft_reset(grbl_link *l)
{
    rail_err e = grbl_link_realtime(l, 0x18);
    if (e == RAIL_OK) {
        l->own_resets++;
        l->own_reset_t = rail_clock_now(l->clock);
    }
    return e;
}

rail_err grbl_link_quiesce(grbl_link *l, grbl_report *rep)
{
    if (rep->state == GRBL_JOG) {
        rail_err e = grbl_link_realtime(l, 0x85);
        if (e != RAIL_OK)
            return e;
    } else if (rep->state == GRBL_RUN) {
        rail_err e = grbl_link_realtime(l, '!');
        if (e != RAIL_OK)
            return e;
    } else if (rep->state != GRBL_HOLD) {
        return RAIL_OK;
    }
    /* Wait (bounded) for rest, then empty the planner so a cycle start cannot resume it. */
    for (int i = 0; i < 100; i++) {
        rail_err e = grbl_link_status(l, rep);
        if (e != RAIL_OK)
            return e;
        if (rep->state == GRBL_IDLE || (rep->state == GRBL_HOLD && rep->substate == 0) ||
            rep->state == GRBL_ALARM)
            break;
        rail_clock_sleep(l->clock, 0.05);
    }
    if (rep->state == GRBL_HOLD) {
        rail_err e = grbl_link_soft_reset(l);
        if (e != RAIL_OK)
            return e;
        rail_clock_sleep(l->clock, 0.05);
        return grbl_link_status(l, rep);
    }
    return RAIL_OK;
}

void grbl_link_retain(grbl_link *l)
{
    l->refs++;
}

void grbl_link_release(grbl_link *l)
{
    if (!l || --l->refs > 0)
        return;
    rail_serial_close(l->ser);
    rail_port_lock_release(l->relock);
    free(l);
}
