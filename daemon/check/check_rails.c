/* check_rails.c: are the rails a rig file names ready? Without moving them:
 *
 *   port    each serial port (G-code, Modbus RTU) resolves, exists and is writable by the
 *           service user (ribbond.service: group dialout);
 *   lock    a rail a running ribbond holds (rail_lock.h) is reported and not opened: the
 *           daemon's own checks are in its GET /status;
 *   map     each Modbus drive's map probed once, read only (rail_modbus_probe.h);
 *   open    both rails opened as ribbond opens them: the G-code driver reads `$$` and refuses
 *           what it cannot work with (grbl_settings.h), a Modbus drive is probed;
 *   settings  what the G-code driver adopted or tolerated (its warnings);
 *   state   one status read: idle is ok, an alarm (homing enabled and not homed, a limit) or a
 *           fault (a controller that reset and lost its zero) fails with what to do;
 *   limits  the trial's compression target and shear end inside the soft limits, the gap at the
 *           target not below the specimen's minimum clamp gap, a mock rail's soft range inside
 *           its travel (check_rail_limits: the rig file alone).
 * Opening a G-code rail cancels any motion its controller still runs (rail_gcode.h); closing
 * sends nothing that moves. */
#include <math.h>
#include <string.h>
#include <sys/stat.h>

#include "check.h"
#include "rail_gcode.h"
#include "rail_lock.h"
#include "rail_modbus_probe.h"
#include "rail_open.h"
#include "rail_serial.h"

static void part_name(const rail_open_spec *s, char *buf, size_t n)
{
    snprintf(buf, n, "rail %.20s", s->params.name);
}

/* The serial port a rail names, or NULL (mock, Modbus TCP). */
static const char *serial_spec(const rail_open_spec *s)
{
    if (!strcmp(s->driver, "gcode")) return s->gcode.port;
    if (!strcmp(s->driver, "modbus") && s->modbus.rtu) return s->modbus.address;
    return NULL;
}

/* Port present and writable; 0, or -1 after a fail line. */
static int check_port(const rail_open_spec *s, const check_env *env, check_report *r)
{
    char part[40], path[512], why[512];
    part_name(s, part, sizeof part);
    const char *spec = serial_spec(s);
    if (!spec) {
        if (!strcmp(s->driver, "modbus"))
            check_add(r, CHECK_OK, part, "port", "Modbus TCP drive at %s (no serial port)", s->modbus.address);
        else
            check_add(r, CHECK_OK, part, "port", "%s rail: no device", s->driver);
        return 0;
    }
    if (!spec[0]) {
        check_add(r, CHECK_FAIL, part, "port", "no port named: set rail.%s.port (ribbonctl ports lists them)",
                  s->params.name);
        return -1;
    }
    if (rail_serial_resolve(spec, path, sizeof path, why, sizeof why) != RAIL_OK) {
        check_add(r, CHECK_FAIL, part, "port", "%s; plug the controller in, or set the port ribbonctl ports lists",
                  why);
        return -1;
    }
    struct stat sb;
    if (stat(path, &sb) != 0) {
        check_add(r, CHECK_FAIL, part, "port",
                  "port %.200s does not exist: plug the controller in, or set rail.%s.port to one "
                  "`ribbonctl ports` lists", path, s->params.name);
        return -1;
    }
    if (check_writable_by(path, env->service_user, why, sizeof why)) {
        check_add(r, CHECK_FAIL, part, "port", "%s: add the user to the port's group (dialout: "
                  "docs/install.md) or fix the device's udev rule", why);
        return -1;
    }
    check_add(r, CHECK_OK, part, "port", "%.200s exists, writable by %s", path,
              env->service_user ? env->service_user : "this user");
    return 0;
}

static void check_map(const rail_open_spec *s, check_report *r)
{
    char part[40], why[512], warn[600];
    part_name(s, part, sizeof part);
    rail_mb_probe_row rows[RAIL_MB_PROBE_MAX];
    int n = 0;
    rail_err e = rail_modbus_probe(&s->modbus, rows, RAIL_MB_PROBE_MAX, &n, why, sizeof why);
    if (e != RAIL_OK) {
        int bad = 0;
        const rail_mb_probe_row *first = NULL;
        for (int i = 0; i < n; i++)
            if (!rows[i].ok && !bad++) first = &rows[i];
        if (first)
            check_add(r, CHECK_FAIL, part, "map",
                      "map %s: %d of %d registers unreadable, first %s at %d: %.120s; compare the map with "
                      "the drive's manual (ribbonctl rail --config RIG --rail %s probe)",
                      s->modbus.map.name, bad, n, first->name, first->reg.addr, first->error, s->params.name);
        else
            check_add(r, CHECK_FAIL, part, "map", "map %s: %s", s->modbus.map.name, why);
        return;
    }
    if (rail_modbus_map_warning(&s->modbus.map, warn, sizeof warn))
        check_add(r, CHECK_WARN, part, "map", "%d registers read; %s: check them with ribbonctl rail ... probe, "
                  "then set verified = yes", n, warn);
    else
        check_add(r, CHECK_OK, part, "map", "map %s: %d registers read", s->modbus.map.name, n);
}

/* One status read of an open rail, and the driver's settings warnings. */
static void check_open_rail(const rail_open_spec *s, rail *rl, check_report *r)
{
    char part[40];
    part_name(s, part, sizeof part);
    if (!strcmp(s->driver, "gcode")) {
        const char *w = rail_gcode_warnings(rl);
        if (w && w[0])
            check_add(r, CHECK_WARN, part, "settings", "%s", w);
        else
            check_add(r, CHECK_OK, part, "settings", "GRBL settings ($$) fit the rail");
    }
    rail_status st;
    memset(&st, 0, sizeof st);
    if (rail_status_poll(rl, &st) != RAIL_OK) {
        check_add(r, CHECK_FAIL, part, "state", "no status: %s", rail_last_error(rl));
        return;
    }
    switch (st.state) {
    case RAIL_STATE_IDLE:
        check_add(r, CHECK_OK, part, "state", "idle at %.3f mm", st.position_mm);
        break;
    case RAIL_STATE_ALARM:
        if (strstr(st.message, "home it") || strstr(st.message, "confirm-zero")) /* says what to do */
            check_add(r, CHECK_FAIL, part, "state", "alarm at %.3f mm: %s (ribbonctl rail --config RIG --rail %s)",
                      st.position_mm, st.message, s->params.name);
        else
            check_add(r, CHECK_FAIL, part, "state", "alarm at %.3f mm: %s; home it (ribbonctl rail --config RIG --rail "
                      "%s home --confirm) or, once you know why, clear it (reset)", st.position_mm, st.message,
                      s->params.name);
        break;
    case RAIL_STATE_FAULT:
        check_add(r, CHECK_FAIL, part, "state", "fault at %.3f mm: %s", st.position_mm, st.message);
        break;
    default:
        check_add(r, CHECK_WARN, part, "state", "%s at %.3f mm%s%s", rail_state_name(st.state), st.position_mm,
                  st.message[0] ? ": " : "", st.message);
        break;
    }
}

void check_rail_limits(const rig_config *cfg, check_report *r)
{
    const rail_params *pc = &cfg->compress.params, *ps = &cfg->shear.params;
    const double tc = cfg->trial.compress_target_mm, te = cfg->trial.shear_end_mm;
    int bad = 0;
    for (int k = 0; k < 2; k++) {
        const rail_open_spec *s = k ? &cfg->shear : &cfg->compress;
        if (!strcmp(s->driver, "mock") && s->params.soft_max_mm > s->mock.travel_mm) {
            check_add(r, CHECK_FAIL, k ? "rail shear" : "rail compress", "limits",
                      "soft_max_mm %.3f mm is beyond the rail's travel %.3f mm: lower soft_max_mm",
                      s->params.soft_max_mm, s->mock.travel_mm);
            bad = 1;
        }
    }
    if (!(tc >= pc->soft_min_mm && tc <= pc->soft_max_mm)) {
        check_add(r, CHECK_FAIL, "rail compress", "limits",
                  "the trial's compression target %.3f mm (Delta L %.3g) is outside the soft limits [%.3f, %.3f] mm: "
                  "fix [calibration] or the soft limits", tc, cfg->scene.compression, pc->soft_min_mm, pc->soft_max_mm);
        bad = 1;
    }
    if (!(te >= ps->soft_min_mm && te <= ps->soft_max_mm)) {
        check_add(r, CHECK_FAIL, "rail shear", "limits",
                  "the shear's end %.3f mm (Delta W %.3g) is outside the soft limits [%.3f, %.3f] mm: fix "
                  "[calibration], the soft limits or protocol.shear_max", te, cfg->scene.shear_max, ps->soft_min_mm,
                  ps->soft_max_mm);
        bad = 1;
    }
    double gap = pc->gap_at_zero_mm + pc->gap_per_mm * tc;
    double min_gap = cfg->specimen.min_clamp_gap_mm;
    if (min_gap <= 0.0) {
        check_add(r, CHECK_WARN, "rail compress", "limits",
                  "no specimen.min_clamp_gap_mm: only the soft limits keep the clamps apart; set it");
    } else if (gap < min_gap) {
        check_add(r, CHECK_FAIL, "rail compress", "limits",
                  "the clamp gap at the compression target is %.3f mm, below the specimen's minimum %.3f mm: "
                  "lower protocol.compression or fix specimen.min_clamp_gap_mm", gap, min_gap);
        bad = 1;
    }
    if (!bad)
        check_add(r, CHECK_OK, "rails", "limits",
                  "compression target %.3f mm in [%.3f, %.3f], gap there %.3f mm (minimum %.3f); shear end %.3f mm "
                  "in [%.3f, %.3f]", tc, pc->soft_min_mm, pc->soft_max_mm, gap, min_gap, te, ps->soft_min_mm,
                  ps->soft_max_mm);
}

void check_rails(const rig_config *cfg, const check_env *env, check_report *r)
{
    const rail_open_spec *spec[2] = {&cfg->compress, &cfg->shear};
    check_rail_limits(cfg, r);
    if (env->compress && env->shear) { /* the caller's own rails (ribbond) */
        check_open_rail(spec[0], env->compress, r);
        check_open_rail(spec[1], env->shear, r);
        return;
    }
    int ports_ok = 1;
    for (int k = 0; k < 2; k++) ports_ok &= check_port(spec[k], env, r) == 0;
    if (env->rails_why) {
        check_add(r, CHECK_FAIL, "rails", "open", "%s", env->rails_why);
        return;
    }
    rail_locks *locks = NULL;
    char why[900];
    rail_err le = rail_locks_take(spec[0], spec[1], "ribbonctl check", &locks, why, sizeof why);
    if (le == RAIL_E_STATE) {
        check_add(r, CHECK_WARN, "rails", "lock", "%s; not opened: the running daemon's checks are in its "
                  "GET /status (ribbonctl status)", why);
        return;
    }
    if (le != RAIL_OK) {
        check_add(r, CHECK_FAIL, "rails", "lock", "%s", why);
        return;
    }
    if (!ports_ok) {
        check_add(r, CHECK_FAIL, "rails", "open", "not opened: a port above is missing or not writable");
        rail_locks_release(locks);
        return;
    }
    for (int k = 0; k < 2; k++)
        if (!strcmp(spec[k]->driver, "modbus")) check_map(spec[k], r);
    rail *rc = NULL, *rs = NULL;
    rail_err e = rail_open_pair(spec[0], spec[1], rail_clock_real(), &rc, &rs, why, sizeof why);
    if (e != RAIL_OK) {
        check_add(r, CHECK_FAIL, "rails", "open", "%s", why);
    } else {
        check_open_rail(spec[0], rc, r);
        check_open_rail(spec[1], rs, r);
    }
    rail_close(rs);
    rail_close(rc);
    rail_locks_release(locks);
}
