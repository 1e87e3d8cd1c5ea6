/* ctl_rail.c: `ribbonctl rail`: drive one rail from the command line, for bench-top use,
 * scripts and tests.
 *
 *   ribbonctl rail (--config F --rail compress|shear | --driver mock|gcode|modbus [--port PATH]
 *                  [--address HOST:PORT] [--axis X|Y] ...) ACTION [--json]
 *   ACTION: status | home --confirm | move-abs MM | move-rel MM | jog MM_S [--duration S] | stop
 *           | estop | reset | confirm-zero --confirm | bench | probe
 * (reset clears a device alarm, e.g. GRBL's "$X" unlock; it never moves the rail. confirm-zero
 * tells a G-code rail whose controller reset that its count is right where the rail stands.
 * probe reads every register of a Modbus rail's map once and prints it with its meaning and
 * units: it writes nothing, so the map can be checked against the drive's manual before anything
 * moves.)
 *
 * Moves and homing wait until the rail is at rest (polling at the rail's rate keeps GRBL jog
 * segments flowing and the Modbus watchdog fed), then print the final status. A jog runs for
 * --duration seconds (default 1) and then stops: a one-shot command never leaves a rail running.
 * Ctrl-C stops the rail (the handler only sets a flag). The rail's device is locked as ribbond
 * locks it (rail_lock.h): a rail a running daemon drives is refused, naming the daemon. Exit status: 0 done, 1 the rail refused
 * or failed (reason printed; with --json also in the JSON object), 2 usage. */
#include <jansson.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctl.h"
#include "cfg_number.h"
#include "modbus_map_file.h"
#include "rail_config.h"
#include "rig_config.h"
#include "rail_gcode.h"
#include "rail_lock.h"
#include "rail_mock.h"
#include "rail_modbus.h"
#include "rail_modbus_probe.h"

static volatile sig_atomic_t g_interrupted; /* set by SIGINT/SIGTERM only */

static void on_signal(int sig)
{
    (void)sig;
    g_interrupted = 1;
}

typedef struct rail_cli {
    const char *driver;       /* mock | gcode | modbus */
    const char *config;       /* rig INI file, or NULL */
    const char *rail_name;    /* compress | shear (with --config) */
    rail_params p;
    rail_gcode_params g;
    rail_modbus_params m;
    rail_mock_params k;
    double speed_mm_s;        /* mm/s for moves; 0 = half the speed limit */
    double timeout_s;         /* s to wait for a move or homing; 0 = estimate */
    double duration_s;        /* s a jog runs before it is stopped */
    int bench_polls;
    double counts_per_mm;     /* --counts-per-mm, 0 = the map's own */
    int json, confirm;
    const char *action;
    double value;
    int have_value;
} rail_cli;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ribbonctl rail SOURCE [options] ACTION [VALUE]\n"
            "SOURCE: --config RIG.ini --rail compress|shear\n"
            "     or --driver mock|gcode|modbus with:\n"
            "        --port PATH|usb:VID:PID[:SERIAL] --baud N --axis X|Y|Z      (gcode)\n"
            "        --address HOST:PORT | --rtu DEVICE --slave N --map NAME|FILE.ini\n"
            "        --counts-per-mm C --allow-unverified --watchdog-external    (modbus)\n"
            "        --start MM                                                   (mock)\n"
            "limits: --soft-min MM --soft-max MM --max-speed MM_S --accel MM_S2 --poll-hz HZ\n"
            "        --min-gap MM --gap-at-zero MM --gap-per-mm 1|-1\n"
            "ACTION: status | home --confirm | move-abs MM | move-rel MM | jog MM_S | stop | estop\n"
            "        | reset (clear a device alarm; never moves) | bench\n"
            "        | probe (modbus: read every mapped register once, print it; writes nothing)\n"
            "        | confirm-zero --confirm (gcode: after a controller reset, trust its count\n"
            "          where the rail stands; with homing on ($22=1) home instead)\n"
            "options: --speed MM_S  --timeout S  --duration S (jog)  --polls N (bench)  --json\n");
}

static int num(const char *opt, const char *v, double *out)
{
    char *end = NULL;
    double x = v ? cfg_number_strtod(v, &end) : NAN;
    if (!v || end == v || *end || !isfinite(x)) {
        fprintf(stderr, "ribbonctl rail: %s needs a number, got '%s'\n", opt, v ? v : "");
        return -1;
    }
    *out = x;
    return 0;
}

static int parse(rail_cli *c, int argc, char **argv)
{
    double x;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0, takes = 1;
#define OPT(name) (!strcmp(a, name))
        if (OPT("--help") || OPT("-h")) {
            usage(stdout);
            exit(0);
        } else if (OPT("--json")) {
            c->json = 1;
            takes = 0;
        } else if (OPT("--confirm")) {
            c->confirm = 1;
            takes = 0;
        } else if (OPT("--allow-unverified")) {
            c->m.allow_unverified = true;
            takes = 0;
        } else if (OPT("--watchdog-external")) {
            c->m.watchdog_external = true;
            takes = 0;
        } else if (OPT("--driver")) {
            c->driver = v;
        } else if (OPT("--config")) {
            c->config = v;
        } else if (OPT("--rail")) {
            c->rail_name = v;
        } else if (OPT("--port")) {
            if (v)
                snprintf(c->g.port, sizeof c->g.port, "%s", v);
        } else if (OPT("--baud")) {
            bad = num(a, v, &x);
            c->g.baud = c->m.baud = (int)x;
        } else if (OPT("--axis")) {
            bad = !v || strlen(v) != 1;
            if (!bad)
                c->g.axis = v[0];
        } else if (OPT("--address")) {
            if (v)
                snprintf(c->m.address, sizeof c->m.address, "%s", v);
        } else if (OPT("--rtu")) {
            c->m.rtu = true;
            if (v)
                snprintf(c->m.address, sizeof c->m.address, "%s", v);
        } else if (OPT("--slave")) {
            bad = num(a, v, &x);
            c->m.slave = (int)x;
        } else if (OPT("--map")) {
            size_t vn = v ? strlen(v) : 0;
            if (vn > 4 && !strcmp(v + vn - 4, ".ini")) { /* a map file (modbus_map_file.h) */
                cfg_error ce;
                bad = modbus_map_file_load(v, &c->m.map, &ce) != CFG_OK;
                if (bad) {
                    char msg[600];
                    fprintf(stderr, "ribbonctl rail: --map: %s\n", cfg_error_format(&ce, msg, sizeof msg));
                }
            } else {
                bad = !v || rail_modbus_preset(v, &c->m.map) != RAIL_OK;
                if (bad)
                    fprintf(stderr, "ribbonctl rail: unknown --map '%s' (ribbon-sim, oriental-az, or a "
                                    "map file NAME.ini)\n", v ? v : "");
            }
        } else if (OPT("--counts-per-mm")) {
            bad = num(a, v, &c->counts_per_mm); /* applied after --map, whatever the order */
        } else if (OPT("--start")) {
            bad = num(a, v, &c->k.start_mm);
        } else if (OPT("--soft-min")) {
            bad = num(a, v, &c->p.soft_min_mm);
        } else if (OPT("--soft-max")) {
            bad = num(a, v, &c->p.soft_max_mm);
        } else if (OPT("--max-speed")) {
            bad = num(a, v, &c->p.max_speed_mm_s);
        } else if (OPT("--accel")) {
            bad = num(a, v, &c->p.accel_mm_s2);
        } else if (OPT("--poll-hz")) {
            bad = num(a, v, &c->p.poll_hz);
        } else if (OPT("--min-gap")) {
            bad = num(a, v, &c->p.min_gap_mm);
        } else if (OPT("--gap-at-zero")) {
            bad = num(a, v, &c->p.gap_at_zero_mm);
        } else if (OPT("--gap-per-mm")) {
            bad = num(a, v, &c->p.gap_per_mm);
        } else if (OPT("--speed")) {
            bad = num(a, v, &c->speed_mm_s);
        } else if (OPT("--timeout")) {
            bad = num(a, v, &c->timeout_s);
        } else if (OPT("--duration")) {
            bad = num(a, v, &c->duration_s);
        } else if (OPT("--polls")) {
            bad = num(a, v, &x);
            c->bench_polls = (int)x;
        } else if (a[0] == '-' && !(a[1] >= '0' && a[1] <= '9') && a[1] != '.') {
            fprintf(stderr, "ribbonctl rail: unknown option '%s'\n", a);
            return 2;
        } else {
            takes = 0;
            if (!c->action) {
                c->action = a;
            } else if (!c->have_value) {
                if (num(c->action, a, &c->value))
                    return 2;
                c->have_value = 1;
            } else {
                fprintf(stderr, "ribbonctl rail: unexpected argument '%s'\n", a);
                return 2;
            }
        }
#undef OPT
        if (takes && !v) {
            fprintf(stderr, "ribbonctl rail: %s needs a value\n", a);
            return 2;
        }
        if (bad)
            return 2;
        i += takes;
    }
    return 0;
}

static void print_status(const rail_cli *c, const rail *r, const rail_status *st, rail_err e, const char *why)
{
    const char *name = r ? rail_get_params(r)->name : (c->rail_name ? c->rail_name : "rail");
    const char *msg = e != RAIL_OK ? why : st->message;
    if (c->json) {
        json_t *o = json_object();
        json_object_set_new(o, "rail", json_string(name));
        json_object_set_new(o, "state", json_string(rail_state_name(st->state)));
        json_object_set_new(o, "position_mm", json_real(st->position_mm));
        json_object_set_new(o, "velocity_mm_s", json_real(st->velocity_mm_s));
        json_object_set_new(o, "code", json_integer(st->code));
        json_object_set_new(o, "message", json_string(msg ? msg : ""));
        json_object_set_new(o, "ok", json_boolean(e == RAIL_OK));
        if (e != RAIL_OK)
            json_object_set_new(o, "error", json_string(rail_err_message(e)));
        char *s = json_dumps(o, JSON_COMPACT | JSON_REAL_PRECISION(10));
        printf("%s\n", s ? s : "{}");
        free(s);
        json_decref(o);
        return;
    }
    printf("%s: %s at %.4f mm, %.4f mm/s", name, rail_state_name(st->state), st->position_mm,
           st->velocity_mm_s);
    if (st->code)
        printf(", code %d", st->code);
    if (st->message[0])
        printf(" (%s)", st->message);
    printf("\n");
    if (e != RAIL_OK)
        fprintf(stderr, "ribbonctl rail: %s\n", why);
}

/* Consecutive read errors a wait rides out (a drive's "busy" exception, a garbled reply) before it
 * gives up on the rail's word and stops it. */
#define WAIT_READ_RETRIES 5

/* One good reading: up to `tries` polls, a poll period apart. */
static rail_err poll_retry(rail *r, rail_status *st, int tries)
{
    rail_err e = RAIL_E_IO;
    for (int i = 0; i < tries; i++) {
        e = rail_status_poll(r, st);
        if (e == RAIL_OK) return e;
        rail_clock_sleep(rail_get_clock(r), 1.0 / rail_get_params(r)->poll_hz);
    }
    return e;
}

/* After a command that moved the rail failed: send stop (retried), then poll (each read retried)
 * until the rail is at rest or timeout_s passes, so the command never exits with the rail moving
 * and *st is what the rail did. Returns RAIL_OK once a reading shows it at rest. */
static rail_err stop_and_settle(rail *r, double timeout_s, rail_status *st)
{
    rail_clock ck = rail_get_clock(r);
    double period = 1.0 / rail_get_params(r)->poll_hz;
    rail_err e = RAIL_E_IO;
    for (int i = 0; i < WAIT_READ_RETRIES && e != RAIL_OK; i++) {
        e = rail_stop(r);
        if (e != RAIL_OK) rail_clock_sleep(ck, period);
    }
    double t0 = rail_clock_now(ck);
    long cap = (long)(timeout_s / period) + 3;
    for (long i = 0; i < cap; i++) {
        rail_err ep = poll_retry(r, st, WAIT_READ_RETRIES);
        if (ep == RAIL_OK && st->state != RAIL_STATE_MOVING && st->state != RAIL_STATE_HOMING) return RAIL_OK;
        if (ep == RAIL_OK && e != RAIL_OK) e = rail_stop(r); /* the stop did not get through yet */
        if (rail_clock_now(ck) - t0 > timeout_s) break;
        rail_clock_sleep(ck, period);
    }
    return RAIL_E_TIMEOUT;
}

/* Poll until at rest; Ctrl-C stops the rail. A read error is retried WAIT_READ_RETRIES times in a
 * row; after that, and on any other way out but arrival, the rail is stopped before returning. */
static rail_err wait_rest(rail *r, double timeout_s, rail_status *st)
{
    double period = 1.0 / rail_get_params(r)->poll_hz;
    rail_clock ck = rail_get_clock(r);
    double t0 = rail_clock_now(ck);
    long cap = (long)(timeout_s / period) + 3;
    int read_errors = 0;
    for (long i = 0; i < cap; i++) {
        if (g_interrupted) {
            stop_and_settle(r, 5.0, st);
            g_interrupted = 0;
            return rail_set_error(r, RAIL_E_STATE, "interrupted: rail stopped at %.4f mm", st->position_mm);
        }
        rail_err e = rail_status_poll(r, st);
        if (e != RAIL_OK) {
            if (++read_errors < WAIT_READ_RETRIES && rail_clock_now(ck) - t0 <= timeout_s) {
                rail_clock_sleep(ck, period);
                continue;
            }
            char first[256];
            rail_text_copy(first, sizeof first, rail_last_error(r));
            rail_err es = stop_and_settle(r, 5.0, st);
            return rail_set_error(r, e, "%s (%d reads in a row failed); %s at %.4f mm", first, read_errors,
                                  es == RAIL_OK ? "rail stopped" : "stop sent, rest not confirmed", st->position_mm);
        }
        read_errors = 0;
        if (st->state == RAIL_STATE_IDLE)
            return RAIL_OK;
        if (st->state != RAIL_STATE_MOVING && st->state != RAIL_STATE_HOMING) {
            rail_status bad = *st;
            stop_and_settle(r, 5.0, st);
            return rail_set_error(r, bad.state == RAIL_STATE_ALARM ? RAIL_E_DEVICE : RAIL_E_STATE,
                                  "rail in state %s: %s", rail_state_name(bad.state), bad.message);
        }
        if (rail_clock_now(ck) - t0 > timeout_s)
            break;
        rail_clock_sleep(ck, period);
    }
    stop_and_settle(r, 5.0, st);
    return rail_set_error(r, RAIL_E_TIMEOUT, "not at rest after %.1f s; stopped at %.4f mm", timeout_s,
                          st->position_mm);
}

/* The lock of the device the rail names (rail_lock.h), held from the open to the close: a rail a
 * running ribbond drives is refused, naming it (issue 33, item 1). */
static rail_locks *held;
static rail_err open_rail_unlocked(rail_cli *c, rail_clock ck, rail **r, char *why, size_t why_len);

static void close_rail(rail *r)
{
    rail_close(r);
    rail_locks_release(held);
    held = NULL;
}

static rail_err open_rail(rail_cli *c, rail **r, char *why, size_t why_len)
{
    rail_clock ck = rail_clock_real();
    if (!c->driver) {
        snprintf(why, why_len, "no driver: give --driver mock|gcode|modbus or --config F --rail NAME");
        return RAIL_E_INVALID;
    }
    rail_open_spec spec;
    memset(&spec, 0, sizeof spec);
    snprintf(spec.driver, sizeof spec.driver, "%s", c->driver);
    spec.params = c->p;
    spec.gcode = c->g;
    spec.modbus = c->m;
    spec.mock = c->k;
    rail_err le = rail_locks_take(&spec, NULL, "ribbonctl rail", &held, why, why_len);
    if (le != RAIL_OK) return le;
    rail_err e = open_rail_unlocked(c, ck, r, why, why_len);
    if (e != RAIL_OK) {
        rail_locks_release(held);
        held = NULL;
    } else if (rail_gcode_warnings(*r)[0]) {
        /* What the controller's settings ($$) mean for this rail, adopted or tolerated. */
        fprintf(stderr, "ribbonctl rail: %s: %s\n", c->p.name, rail_gcode_warnings(*r));
    }
    return e;
}

static rail_err open_rail_unlocked(rail_cli *c, rail_clock ck, rail **r, char *why, size_t why_len)
{
    if (!strcmp(c->driver, "mock"))
        return rail_mock_open(r, &c->p, &c->k, ck, why, why_len);
    if (!strcmp(c->driver, "gcode")) {
        if (!c->g.port[0]) {
            snprintf(why, why_len, "driver gcode needs --port PATH or usb:VID:PID[:SERIAL]");
            return RAIL_E_INVALID;
        }
        return rail_gcode_open(r, &c->p, &c->g, NULL, ck, why, why_len);
    }
    if (!strcmp(c->driver, "modbus"))
        return rail_modbus_open(r, &c->p, &c->m, ck, why, why_len);
    snprintf(why, why_len, "unknown driver '%s' (mock, gcode, modbus)", c->driver);
    return RAIL_E_INVALID;
}

static int bench(rail_cli *c, rail *r)
{
    int n = c->bench_polls > 0 ? c->bench_polls : 500;
    rail_status st;
    rail_clock ck = rail_get_clock(r);
    double t0 = rail_clock_now(ck);
    int fails = 0;
    for (int i = 0; i < n; i++)
        if (rail_status_poll(r, &st) != RAIL_OK)
            fails++;
    double dt = rail_clock_now(ck) - t0;
    /* Stop latency: jog at half the speed limit for 0.5 s, then time stop() until a reading
       shows the rail decelerating (or at rest). */
    double lat = NAN, v = 0.5 * rail_get_params(r)->max_speed_mm_s;
    if (rail_jog(r, st.position_mm < 0.5 * (rail_get_params(r)->soft_min_mm + rail_get_params(r)->soft_max_mm) ? v : -v) == RAIL_OK) {
        double tj = rail_clock_now(ck);
        while (rail_clock_now(ck) - tj < 0.5 && rail_status_get(r, &st) == RAIL_OK)
            rail_clock_sleep(ck, 0.005);
        rail_status_poll(r, &st);
        double v0 = fabs(st.velocity_mm_s);
        double ts = rail_clock_now(ck);
        if (rail_stop(r) == RAIL_OK) {
            for (int i = 0; i < 2000; i++) {
                if (rail_status_poll(r, &st) != RAIL_OK)
                    break;
                if (st.state == RAIL_STATE_IDLE || fabs(st.velocity_mm_s) < v0 - 1e-6) {
                    lat = rail_clock_now(ck) - ts;
                    break;
                }
            }
        }
        rail_wait_idle(r, 10.0, &st);
    }
    printf("{\"bench\":\"rail_status\",\"driver\":\"%s\",\"polls\":%d,\"failed\":%d,\"polls_per_s\":%.1f,"
           "\"stop_latency_ms\":%.2f}\n",
           rail_driver_name(r), n, fails, n / dt, isnan(lat) ? -1.0 : lat * 1e3);
    return fails ? 1 : 0;
}

/* `probe`: every register of the map read once, printed with its meaning and units. Writes
 * nothing (no watchdog, no stop); the rail's device lock is held as for any other action. */
static int probe_main(rail_cli *c)
{
    char why[512] = "";
    if (!c->driver || strcmp(c->driver, "modbus")) {
        fprintf(stderr, "ribbonctl rail: probe reads a Modbus drive's register map; rail '%s' has driver %s\n",
                c->p.name, c->driver ? c->driver : "(none)");
        return 2;
    }
    const rail_modbus_map *m = &c->m.map;
    rail_open_spec spec;
    memset(&spec, 0, sizeof spec);
    snprintf(spec.driver, sizeof spec.driver, "modbus");
    spec.params = c->p;
    spec.modbus = c->m;
    if (rail_locks_take(&spec, NULL, "ribbonctl rail probe", &held, why, sizeof why) != RAIL_OK) {
        fprintf(stderr, "ribbonctl rail: %s\n", why);
        return 1;
    }
    rail_mb_probe_row rows[RAIL_MB_PROBE_MAX];
    int n = 0;
    rail_err e = rail_modbus_probe(&c->m, rows, RAIL_MB_PROBE_MAX, &n, why, sizeof why);
    rail_locks_release(held);
    held = NULL;
    if (c->json) {
        json_t *o = json_object();
        json_object_set_new(o, "rail", json_string(c->p.name));
        json_object_set_new(o, "map", json_string(m->name));
        json_object_set_new(o, "map_file", json_string(m->file));
        json_object_set_new(o, "verified", json_boolean(m->verified));
        json_object_set_new(o, "address", json_string(c->m.address));
        json_object_set_new(o, "slave", json_integer(c->m.slave));
        json_t *a = json_array();
        for (int i = 0; i < n; i++) {
            const rail_mb_probe_row *r = &rows[i];
            json_t *x = json_object();
            json_object_set_new(x, "name", json_string(r->name));
            json_object_set_new(x, "address", json_integer(r->reg.addr));
            json_object_set_new(x, "type", json_string(rail_mb_kind_name(r->reg.kind)));
            json_object_set_new(x, "bits", json_integer(16 * r->reg.words));
            json_object_set_new(x, "signed", json_boolean(r->is_signed));
            json_object_set_new(x, "meaning", json_string(r->reg.meaning));
            json_object_set_new(x, "ok", json_boolean(r->ok));
            if (r->ok) {
                json_object_set_new(x, "raw", json_integer(r->raw));
                json_object_set_new(x, "value", isnan(r->value) ? json_null() : json_real(r->value));
                json_object_set_new(x, "unit", json_string(r->unit));
                json_object_set_new(x, "text", json_string(r->text));
            } else {
                json_object_set_new(x, "error", json_string(r->error));
            }
            json_array_append_new(a, x);
        }
        json_object_set_new(o, "registers", a);
        json_object_set_new(o, "ok", json_boolean(e == RAIL_OK));
        if (e != RAIL_OK)
            json_object_set_new(o, "error", json_string(why));
        char *s = json_dumps(o, JSON_COMPACT | JSON_REAL_PRECISION(10));
        printf("%s\n", s ? s : "{}");
        free(s);
        json_decref(o);
    } else {
        printf("%s: map %s%s%s%s, %s, drive %s slave %d\n", c->p.name, m->name, m->file[0] ? " (" : "",
               m->file, m->file[0] ? ")" : "", m->verified ? "verified" : "NOT verified on a real drive",
               c->m.address, c->m.slave);
        if (n)
            printf("%-20s %7s %-8s %-4s %12s  %-26s %s\n", "register", "address", "type", "bits", "raw", "value",
                   "meaning");
        for (int i = 0; i < n; i++) {
            const rail_mb_probe_row *r = &rows[i];
            char bits[8], raw[24], val[128];
            snprintf(bits, sizeof bits, "%d%s", 16 * r->reg.words,
                     r->reg.kind >= RAIL_MB_COIL ? "" : r->is_signed ? "s" : "u");
            if (r->reg.kind >= RAIL_MB_COIL)
                snprintf(bits, sizeof bits, "1");
            if (!r->ok) {
                snprintf(raw, sizeof raw, "-");
                snprintf(val, sizeof val, "UNREADABLE: %.48s", r->error);
            } else {
                if (r->is_signed || r->reg.kind >= RAIL_MB_COIL)
                    snprintf(raw, sizeof raw, "%ld", r->raw);
                else
                    snprintf(raw, sizeof raw, "0x%0*lx", 4 * r->reg.words, (unsigned long)r->raw);
                if (!isnan(r->value) && r->text[0])
                    snprintf(val, sizeof val, "%.6g %s (%.40s)", r->value, r->unit, r->text);
                else if (!isnan(r->value))
                    snprintf(val, sizeof val, "%.6g %s", r->value, r->unit);
                else
                    snprintf(val, sizeof val, "%.60s", r->text[0] ? r->text : "");
            }
            printf("%-20s %7d %-8s %-4s %12s  %-26s %s\n", r->name, r->reg.addr, rail_mb_kind_name(r->reg.kind),
                   bits, raw, val, r->reg.meaning);
        }
        char warn[600];
        if (rail_modbus_map_warning(m, warn, sizeof warn))
            printf("warning: %s; then set verified = yes in the map file, or allow_unverified = on\n", warn);
        fflush(stdout); /* the table before the verdict, when both go to one pipe */
        if (e != RAIL_OK)
            fprintf(stderr, "ribbonctl rail: probe: %s\n", why);
    }
    return e == RAIL_OK ? 0 : 1;
}

/* 1 when the file has a [rig] section (a whole rig file), 0 for a file of rail sections only. */
static int rail_file_is_rig(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) return 0; /* rail_config_load reports the reason */
    char line[512];
    int rig = 0;
    while (!rig && fgets(line, sizeof line, f)) {
        const char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        rig = !strncmp(p, "[rig]", 5);
    }
    fclose(f);
    return rig;
}

/* The named rail of a rig file, as the rig loader checked and completed it. */
static int load_rig_rail(const char *path, const char *name, rail_config *out, char *why, size_t why_len)
{
    rig_config *rig = malloc(sizeof *rig);
    if (!rig) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    cfg_error ce;
    int rc = -1;
    if (rig_config_load(path, NULL, 0, rig, &ce) != CFG_OK) {
        cfg_error_format(&ce, why, why_len);
    } else if (!rig->has_rails) {
        snprintf(why, why_len, "%.300s: a %s-mode rig file has no rails", path, rig_mode_name(rig->mode));
    } else if (strcmp(name, "compress") && strcmp(name, "shear")) {
        snprintf(why, why_len, "--rail must be compress or shear");
    } else {
        *out = !strcmp(name, "compress") ? rig->compress : rig->shear;
        rc = 0;
    }
    free(rig);
    return rc;
}

int ctl_rail_main(int argc, char **argv)
{
    rail_cli c;
    memset(&c, 0, sizeof c);
    c.p = rail_params_default();
    snprintf(c.p.name, sizeof c.p.name, "rail");
    c.p.poll_hz = 20.0;
    c.g = rail_gcode_params_default();
    c.m = rail_modbus_params_default();
    c.k = rail_mock_params_default();
    c.duration_s = 1.0;
    int u = parse(&c, argc, argv);
    if (u)
        return u;
    if (c.counts_per_mm != 0.0)
        c.m.map.counts_per_mm = c.counts_per_mm;
    char why[512] = "";
    rail_config cfg; /* outlives the block below: c.driver points into it */
    if (c.config) {
        if (!c.rail_name) {
            fprintf(stderr, "ribbonctl rail: --config needs --rail compress|shear\n");
            return 2;
        }
        if (rail_file_is_rig(c.config)) {
            /* A whole rig file: its loader also pushes the specimen's minimum clamp gap and the
             * calibration's gap model into the compression rail, as ribbond does. */
            if (load_rig_rail(c.config, c.rail_name, &cfg, why, sizeof why)) {
                fprintf(stderr, "ribbonctl rail: %s\n", why);
                return 1;
            }
        } else if (rail_config_load(c.config, c.rail_name, &cfg, why, sizeof why) != 0) {
            fprintf(stderr, "ribbonctl rail: %s\n", why);
            return 1;
        }
        c.driver = cfg.driver;
        c.p = cfg.params;
        c.g = cfg.gcode;
        c.m = cfg.modbus;
        c.k = cfg.mock;
    } else {
        /* Name the rail after its source so every reason says which rail it is about. */
        if (c.rail_name)
            snprintf(c.p.name, sizeof c.p.name, "%s", c.rail_name);
        else if (c.driver && !strcmp(c.driver, "gcode"))
            snprintf(c.p.name, sizeof c.p.name, "gcode-%c", c.g.axis);
        else if (c.driver)
            snprintf(c.p.name, sizeof c.p.name, "%.20s", c.driver);
    }
    if (!c.action) {
        usage(stderr);
        return 2;
    }
    const char *A = c.action;
    int needs_value = !strcmp(A, "move-abs") || !strcmp(A, "move-rel") || !strcmp(A, "jog");
    if (strcmp(A, "status") && strcmp(A, "home") && strcmp(A, "stop") && strcmp(A, "estop") &&
        strcmp(A, "reset") && strcmp(A, "bench") && strcmp(A, "probe") && strcmp(A, "confirm-zero") &&
        !needs_value) {
        fprintf(stderr, "ribbonctl rail: unknown action '%s'\n", A);
        usage(stderr);
        return 2;
    }
    if (needs_value != c.have_value) {
        fprintf(stderr, "ribbonctl rail: %s %s\n", A, needs_value ? "needs a value" : "takes no value");
        return 2;
    }
    if (!strcmp(A, "probe"))
        return probe_main(&c);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    rail *r = NULL;
    rail_status st;
    memset(&st, 0, sizeof st);
    st.state = RAIL_STATE_DISCONNECTED;
    rail_err e = open_rail(&c, &r, why, sizeof why);
    if (e != RAIL_OK) {
        print_status(&c, NULL, &st, e, why);
        return 1;
    }
    double speed = c.speed_mm_s > 0.0 ? c.speed_mm_s : 0.5 * c.p.max_speed_mm_s;
    double span = c.p.soft_max_mm - c.p.soft_min_mm;
    double timeout = c.timeout_s > 0.0 ? c.timeout_s : 10.0 + 2.0 * span / speed;
    int rc = 0;
    if (!strcmp(A, "bench")) {
        rc = bench(&c, r);
        close_rail(r);
        return rc;
    }
    if (!strcmp(A, "status")) {
        e = rail_status_poll(r, &st);
    } else if (!strcmp(A, "estop")) {
        e = rail_estop(r);
        if (e == RAIL_OK)
            e = rail_status_poll(r, &st);
    } else if (!strcmp(A, "reset")) {
        e = rail_reset(r);
        if (e == RAIL_OK)
            e = rail_status_poll(r, &st);
    } else if (!strcmp(A, "confirm-zero")) {
        e = rail_gcode_confirm_zero(r, c.confirm != 0);
        if (e == RAIL_OK)
            e = rail_status_poll(r, &st);
    } else if (!strcmp(A, "stop")) {
        e = rail_stop(r);
        if (e == RAIL_OK)
            e = wait_rest(r, timeout, &st);
    } else if (!strcmp(A, "home")) {
        e = rail_home(r, c.confirm != 0);
        if (e == RAIL_OK)
            e = wait_rest(r, timeout, &st);
    } else if (!strcmp(A, "move-abs") || !strcmp(A, "move-rel")) {
        e = A[5] == 'a' ? rail_move_abs(r, c.value, speed) : rail_move_rel(r, c.value, speed);
        if (e == RAIL_OK)
            e = wait_rest(r, timeout, &st);
    } else { /* jog */
        e = rail_jog(r, c.value);
        double t0 = rail_clock_now(rail_clock_real());
        long cap = (long)(c.duration_s * c.p.poll_hz) + 3;
        for (long i = 0; e == RAIL_OK && i < cap && !g_interrupted; i++) {
            if (rail_clock_now(rail_clock_real()) - t0 >= c.duration_s)
                break;
            e = rail_status_get(r, &st);
            if (e == RAIL_OK && st.state != RAIL_STATE_MOVING)
                break; /* reached a limit, or a fault */
            rail_clock_sleep(rail_clock_real(), 1.0 / c.p.poll_hz);
        }
        rail_err es = rail_stop(r);
        if (e == RAIL_OK)
            e = es;
        if (e == RAIL_OK)
            e = wait_rest(r, timeout, &st);
    }
    /* Every way out of a command that may have set the rail moving stops it first, and what is
       reported is a reading taken after that (issue 17, defect 3). */
    int moved = needs_value || !strcmp(A, "home") || !strcmp(A, "stop");
    if (e != RAIL_OK) {
        rail_text_copy(why, sizeof why, rail_last_error(r));
        if (moved) {
            if (stop_and_settle(r, 5.0 + timeout, &st) != RAIL_OK) {
                size_t used = strlen(why);
                snprintf(why + used, sizeof why - used, "; stop sent, but no reading confirmed the rail at rest");
            }
        } else {
            poll_retry(r, &st, WAIT_READ_RETRIES);
        }
        rc = 1;
    } else if (strcmp(A, "status")) {
        if (poll_retry(r, &st, WAIT_READ_RETRIES) != RAIL_OK) {
            rail_text_copy(why, sizeof why, rail_last_error(r));
            e = RAIL_E_IO;
            rc = 1;
        }
    }
    print_status(&c, r, &st, e, why);
    close_rail(r);
    return rc;
}
