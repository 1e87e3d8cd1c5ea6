/* grbl_link.c: one GRBL controller on one serial port: line assembly, send-and-wait-for-"ok",
 * status queries, asynchronous lines (ALARM:N, "ok" of a homing cycle, reset banner).
 *
 * Flow control is the simple GRBL "send-response" scheme: one line out, wait for its "ok" or
 * "error:N" before the next, so GRBL's 128-byte receive buffer can never overflow. Realtime
 * bytes ('?', '!', 0x18, 0x85) bypass it. Before every request, bytes already waiting are read
 * and handled, so a reply that arrived late cannot be mistaken for the answer to the next. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "grbl_link.h"

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
        break;
    case GRBL_LINE_OK:
        if (l->home_pending)
            l->home_pending = false;
        break;
    case GRBL_LINE_ERROR:
        if (l->home_pending) {
            l->home_pending = false;
            l->home_error = code;
        }
        break;
    case GRBL_LINE_WELCOME:
        l->resets_seen++;
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
    char why[256];
    rail_err e = rail_serial_open(&ser, l->spec, l->baud, why, sizeof why);
    if (e != RAIL_OK)
        return lfail(l, RAIL_E_DISCONNECTED, "controller lost; reopening failed: %s", why);
    rail_serial_close(l->ser);
    l->ser = ser;
    l->rx_len = 0;
    l->lost = false;
    l->home_pending = false;
    l->resets_seen++;
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
    l->baud = g->baud;
    rail_err e = rail_serial_open(&l->ser, g->port, g->baud, why, why_len);
    if (e != RAIL_OK) {
        free(l);
        return e;
    }
    /* Read whatever the controller printed (banner), then make sure nothing is left moving. */
    grbl_report rep;
    e = RAIL_E_TIMEOUT;
    for (int i = 0; i < 3 && e != RAIL_OK; i++)
        e = grbl_link_status(l, &rep);
    if (e == RAIL_OK)
        e = grbl_link_quiesce(l, &rep);
    if (e != RAIL_OK) {
        snprintf(why, why_len, "gcode: no usable GRBL status from %.100s: %.200s", l->ser->path, l->why);
        grbl_link_release(l);
        return e;
    }
    *out = l;
    return RAIL_OK;
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
        rail_err e = grbl_link_realtime(l, 0x18);
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
    free(l);
}
