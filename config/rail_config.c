/* rail_config.c: rail sections of rig INI files -> driver parameter structs (see rail_config.h).
 *
 * Read through cfg_ini (line-exact, the same reader as the rig and scene loaders), every key
 * through one table (rail_keys: kind, offset, bounds, unit, doc; looked up with cfg_keys), in two
 * passes: the first applies only `map` (a Modbus preset) so that per-register overrides apply on
 * top of it whatever their order in the file; the second every other key. Cross-field checks are
 * left to the drivers' own checks (rail_params_check, rail_modbus_map_check), which name the
 * field, and are run here too so a bad file fails at load, not at the first motion. */
#include "rail_config.h"
#include "cfg_number.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg_ini.h"
#include "cfg_keys.h"
#include "modbus_map_file.h"

#define F(field) offsetof(rail_config, field)
#define D(key, field, lo, hi, unit, doc) {"rail", key, RAIL_KEY_DOUBLE, F(field), 0, lo, hi, unit, doc}
#define I(key, field, lo, hi, unit, doc) {"rail", key, RAIL_KEY_INT, F(field), 0, lo, hi, unit, doc}
#define L(key, field, lo, hi, doc) {"rail", key, RAIL_KEY_LONG, F(field), 0, lo, hi, "-", doc}
#define B(key, field, doc) {"rail", key, RAIL_KEY_SWITCH, F(field), 0, 0, 1, "-", doc}
#define S(key, field, doc) \
    {"rail", key, RAIL_KEY_TEXT, F(field), sizeof(((rail_config *)0)->field), 0, 0, "-", doc}
#define C(key, field, doc) {"rail", key, RAIL_KEY_LETTER, F(field), 0, 0, 0, "-", doc}
#define REG(name, doc) \
    {"rail", "reg_" #name, RAIL_KEY_REGISTER, F(modbus.map.name), 0, -1, 65535, "-", doc}
#define MASK(key, field, doc) L(key, field, 0, 4294967295.0, "status bit mask: " doc)
#define CTL(key, field, doc) L(key, field, 0, 4294967295.0, "control value (0 = none): " doc)

static const rail_key rail_keys[] = {
    S("driver", driver, "mock | gcode | modbus: which driver runs this rail"),
    D("soft_min_mm", params.soft_min_mm, -1e6, 1e6, "mm", "lowest position any command may target"),
    D("soft_max_mm", params.soft_max_mm, -1e6, 1e6, "mm", "highest position any command may target"),
    D("max_speed_mm_s", params.max_speed_mm_s, 1e-6, 1000, "mm/s", "highest speed any command may ask for"),
    D("accel_mm_s2", params.accel_mm_s2, 1e-6, 1e5, "mm/s^2",
      "acceleration the drive is configured for (stop distances, the mock's profile)"),
    D("poll_hz", params.poll_hz, 0.1, 1000, "Hz", "highest rate of device status reads"),
    D("min_gap_mm", params.min_gap_mm, 0, 1e6, "mm", "minimum clamp gap (compression rail; 0 = no check)"),
    D("gap_at_zero_mm", params.gap_at_zero_mm, -1e6, 1e6, "mm", "clamp gap when this rail is at position 0"),
    D("gap_per_mm", params.gap_per_mm, -1, 1, "1", "mm of clamp gap per mm of rail travel (+1 or -1)"),
    S("port", gcode.port, "gcode: device path or usb:VID:PID[:SERIAL]"),
    I("baud", gcode.baud, 1200, 3000000, "baud", "gcode: serial speed"),
    C("axis", gcode.axis, "gcode: X, Y or Z, the controller axis this rail is"),
    D("segment_s", gcode.segment_s, 0.05, 2, "s", "gcode: motion per jog segment"),
    I("segments_ahead", gcode.segments_ahead, 1, 4, "1", "gcode: segments queued beyond the position"),
    D("reply_timeout_s", gcode.reply_timeout_s, 0.01, 10, "s", "gcode: wait for ok or a status report (asked again at half of it; lost after it)"),
    D("stall_timeout_s", gcode.stall_timeout_s, 0.05, 60, "s",
      "gcode: time without progress while moving before a stall fault"),
    D("min_segment_mm", gcode.min_segment_mm, 1e-4, 10, "mm", "gcode: shortest jog segment"),
    D("boot_wait_s", gcode.boot_wait_s, 0, 30, "s",
      "gcode: longest wait at open for the controller to boot and answer (an Arduino resets when the port opens)"),
    S("address", modbus.address, "modbus: TCP HOST:PORT, or for RTU a device path or usb:VID:PID[:SERIAL]"),
    B("rtu", modbus.rtu, "modbus: on = RTU on a serial line, off = TCP"),
    C("parity", modbus.parity, "modbus RTU: N, E or O"),
    I("slave", modbus.slave, 1, 247, "1", "modbus: unit / slave id"),
    D("timeout_s", modbus.timeout_s, 0.01, 5, "s", "modbus: response timeout per request"),
    D("watchdog_s", modbus.watchdog_s, 0, 10, "s", "modbus: communication watchdog programmed into the drive"),
    B("allow_unverified", modbus.allow_unverified, "modbus: on = use a map not tried on hardware"),
    B("watchdog_external", modbus.watchdog_external,
      "modbus: on = the drive's own communication timeout is configured (map without a watchdog)"),
    {"rail", "map", RAIL_KEY_PRESET, 0, 0, 0, 0, "-",
     "modbus: register map: a preset (ribbon-sim, oriental-az) or a map file NAME.ini (relative to the rig file), applied before the reg_ keys"},
    {"rail", "word_order", RAIL_KEY_WORD_ORDER, 0, 0, 0, 0, "-",
     "modbus: high_first | low_first, word order of 32-bit values"},
    D("counts_per_mm", modbus.map.counts_per_mm, 1e-9, 1e9, "1/mm", "modbus: position counts per mm"),
    D("speed_per_mm_s", modbus.map.speed_per_mm_s, 0, 1e9, "s/mm",
      "modbus: drive speed units per mm/s (0 = counts_per_mm)"),
    D("accel_per_mm_s2", modbus.map.accel_per_mm_s2, 0, 1e9, "s^2/mm",
      "modbus: drive acceleration units per mm/s^2 (0 = counts_per_mm)"),
    REG(target_pos, "modbus: ADDR[/WORDS] of the target position (-1 = none)"),
    REG(speed, "modbus: ADDR[/WORDS] of the speed"),
    REG(accel, "modbus: ADDR[/WORDS] of the acceleration"),
    REG(decel, "modbus: ADDR[/WORDS] of the deceleration"),
    REG(op_type, "modbus: ADDR[/WORDS] of the operation type"),
    REG(trigger, "modbus: ADDR[/WORDS] of the start trigger"),
    REG(control, "modbus: ADDR[/WORDS] of the control word"),
    REG(actual_pos, "modbus: ADDR[/WORDS] of the actual position"),
    REG(actual_vel, "modbus: ADDR[/WORDS] of the actual velocity"),
    REG(status, "modbus: ADDR[/WORDS] of the status bits"),
    REG(alarm, "modbus: ADDR[/WORDS] of the alarm code"),
    REG(watchdog, "modbus: ADDR[/WORDS] of the communication watchdog"),
    REG(ident, "modbus: ADDR[/WORDS] of the identity"),
    REG(load, "modbus: ADDR[/WORDS] of a signed load reading (torque or following error)"),
    D("load_scale", modbus.map.load_scale, -1e9, 1e9, "-", "modbus: rail_status.load per load register count"),
    L("op_type_abs", modbus.map.op_type_abs, -2147483648.0, 2147483647.0,
      "modbus: operation type value meaning absolute positioning"),
    L("trigger_value", modbus.map.trigger_value, -2147483648.0, 2147483647.0,
      "modbus: value written to trigger to start a move"),
    CTL("ctl_stop", modbus.map.ctl_stop, "stop"),
    CTL("ctl_estop", modbus.map.ctl_estop, "emergency stop"),
    CTL("ctl_home", modbus.map.ctl_home, "home"),
    CTL("ctl_reset", modbus.map.ctl_reset, "alarm reset"),
    MASK("st_ready", modbus.map.st_ready, "ready"),
    MASK("st_moving", modbus.map.st_moving, "moving"),
    MASK("st_in_pos", modbus.map.st_in_pos, "in position"),
    MASK("st_alarm", modbus.map.st_alarm, "alarm"),
    MASK("st_homing", modbus.map.st_homing, "homing"),
    MASK("st_home_end", modbus.map.st_home_end, "homed"),
    L("ident_value", modbus.map.ident_value, -1, 4294967295.0, "modbus: expected identity value (-1 = any)"),
    D("start_mm", mock.start_mm, 0, 1e6, "mm", "mock: position at open"),
    D("travel_mm", mock.travel_mm, 1e-6, 1e6, "mm", "mock: hard travel [0, travel] of the simulated rail"),
    D("home_speed_mm_s", mock.home_speed_mm_s, 1e-6, 1000, "mm/s", "mock: speed of the homing run"),
    D("stall_at_mm", mock.stall_at_mm, -1e6, 1e6, "mm", "mock fault: the motor stalls at this position"),
    D("comm_loss_after_s", mock.comm_loss_after_s, -1, 1e7, "s",
      "mock fault: the link goes silent this long after open (negative = off)"),
    D("alarm_after_s", mock.alarm_after_s, -1, 1e7, "s",
      "mock fault: the drive raises an alarm this long after open (negative = off)"),
    I("alarm_code", mock.alarm_code, 0, 65535, "1", "mock fault: device code of the injected alarm"),
};

static const cfg_key_table key_table = CFG_KEY_TABLE(rail_keys, rail_key);

const rail_key *rail_config_keys(size_t *n)
{
    if (n)
        *n = sizeof rail_keys / sizeof rail_keys[0];
    return rail_keys;
}

static bool parse_num(const char *v, double *x)
{
    return cfg_number_parse(v, x) == CFG_NUMBER_OK; /* plain decimal only (cfg_number.h) */
}

static cfg_status set_register(rail_mb_reg *r, const char *value, char *why, size_t why_len)
{
    char buf[32];
    double x = 0.0;
    snprintf(buf, sizeof buf, "%s", value);
    char *slash = strchr(buf, '/');
    double words = 1.0;
    if (slash) {
        *slash = 0;
        if (!parse_num(slash + 1, &words) || (words != 1.0 && words != 2.0)) {
            snprintf(why, why_len, "'%.60s' must be ADDR or ADDR/1 or ADDR/2", value);
            return CFG_ERR_VALUE;
        }
    }
    if (!parse_num(buf, &x) && !(buf[0] == '0' && buf[1] == 'x')) {
        snprintf(why, why_len, "'%.60s' is not a register address", value);
        return CFG_ERR_VALUE;
    }
    if (buf[0] == '0' && buf[1] == 'x')
        x = (double)strtol(buf, NULL, 16);
    if (x < -1 || x > 65535 || x != floor(x)) {
        snprintf(why, why_len, "register address '%.60s' outside -1..65535", value);
        return CFG_ERR_RANGE;
    }
    r->addr = (int)x;
    r->words = (int)words;
    return CFG_OK;
}

static cfg_status set_number(const rail_key *k, char *field, const char *value, char *why,
                             size_t why_len)
{
    double x = 0.0;
    if (!parse_num(value, &x) && !(value[0] == '0' && value[1] == 'x')) {
        snprintf(why, why_len, "'%.60s' is not a number", value);
        return CFG_ERR_VALUE;
    }
    if (value[0] == '0' && value[1] == 'x')
        x = (double)strtoul(value, NULL, 16);
    if (!(x >= k->min && x <= k->max)) {
        snprintf(why, why_len, "%.60s is outside [%g, %g]", value, k->min, k->max);
        return CFG_ERR_RANGE;
    }
    if (k->kind == RAIL_KEY_DOUBLE)
        *(double *)field = x;
    else if (k->kind == RAIL_KEY_INT) {
        if (x != floor(x)) {
            snprintf(why, why_len, "'%.60s' must be an integer", value);
            return CFG_ERR_VALUE;
        }
        *(int *)field = (int)x;
    } else {
        *(long *)field = (long)x;
    }
    return CFG_OK;
}

/* 1 when a map value names a file (maps/NAME.ini) rather than a built-in preset. */
static int map_is_file(const char *v)
{
    size_t n = strlen(v);
    return n > 4 && !strcmp(v + n - 4, ".ini");
}

/* map = FILE: read the map file, relative to base_dir unless absolute. */
static cfg_status set_map_file(rail_config *out, const char *value, const char *base_dir, char *why,
                               size_t why_len)
{
    char path[512];
    int n = value[0] == '/' || !base_dir ? snprintf(path, sizeof path, "%s", value)
                                         : snprintf(path, sizeof path, "%s/%s", base_dir, value);
    if (n < 0 || (size_t)n >= sizeof path) {
        snprintf(why, why_len, "map file path too long");
        return CFG_ERR_VALUE;
    }
    cfg_error err;
    rail_modbus_map m;
    cfg_status st = modbus_map_file_load(path, &m, &err);
    if (st != CFG_OK) {
        char msg[600];
        cfg_error_format(&err, msg, sizeof msg);
        snprintf(why, why_len, "%s", msg);
        return st == CFG_ERR_IO ? CFG_ERR_VALUE : st;
    }
    out->modbus.map = m;
    return CFG_OK;
}

/* Apply one key, with the reason (without the key) in why. base_dir: where a relative map file
 * is found; NULL = do not read map files (the name is only checked). */
static cfg_status set_key(rail_config *out, const char *name, const char *value, const char *base_dir,
                          char *why, size_t why_len)
{
    int i = cfg_keys_find(&key_table, "rail", name);
    if (i < 0) {
        snprintf(why, why_len, "unknown key");
        return CFG_ERR_UNKNOWN;
    }
    const rail_key *k = &rail_keys[i];
    char *field = (char *)out + k->offset;
    switch (k->kind) {
    case RAIL_KEY_PRESET:
        if (map_is_file(value))
            return base_dir ? set_map_file(out, value, base_dir, why, why_len) : CFG_OK;
        if (rail_modbus_preset(value, &out->modbus.map) != RAIL_OK) {
            snprintf(why, why_len, "unknown preset '%s' (ribbon-sim, oriental-az, or a map file NAME.ini)",
                     value);
            return CFG_ERR_VALUE;
        }
        return CFG_OK;
    case RAIL_KEY_WORD_ORDER:
        if (!strcmp(value, "high_first"))
            out->modbus.map.word_order = RAIL_MB_HIGH_FIRST;
        else if (!strcmp(value, "low_first"))
            out->modbus.map.word_order = RAIL_MB_LOW_FIRST;
        else {
            snprintf(why, why_len, "'%s' is not high_first or low_first", value);
            return CFG_ERR_VALUE;
        }
        return CFG_OK;
    case RAIL_KEY_TEXT:
        if (strlen(value) >= k->size) {
            snprintf(why, why_len, "value '%.60s' too long", value);
            return CFG_ERR_VALUE;
        }
        snprintf(field, k->size, "%s", value);
        return CFG_OK;
    case RAIL_KEY_LETTER:
        if (strlen(value) != 1) {
            snprintf(why, why_len, "'%.60s' must be one letter", value);
            return CFG_ERR_VALUE;
        }
        *(char *)field = value[0];
        return CFG_OK;
    case RAIL_KEY_SWITCH:
        /* The rig file's spelling for every switch (rig_config's SWITCH keys). */
        if (!strcmp(value, "on"))
            *(bool *)field = true;
        else if (!strcmp(value, "off"))
            *(bool *)field = false;
        else {
            snprintf(why, why_len, "'%.60s' is not on or off", value);
            return CFG_ERR_VALUE;
        }
        return CFG_OK;
    case RAIL_KEY_REGISTER:
        return set_register((rail_mb_reg *)field, value, why, why_len);
    case RAIL_KEY_DOUBLE:
    case RAIL_KEY_INT:
    case RAIL_KEY_LONG:
        return set_number(k, field, value, why, why_len);
    }
    snprintf(why, why_len, "unknown key");
    return CFG_ERR_UNKNOWN;
}

cfg_status rail_config_set(rail_config *c, const char *key, const char *value, char *why,
                           size_t why_len)
{
    return rail_config_set_in(c, key, value, NULL, why, why_len);
}

cfg_status rail_config_set_in(rail_config *c, const char *key, const char *value, const char *base_dir,
                              char *why, size_t why_len)
{
    char local[8];
    if (!why || why_len == 0) {
        why = local;
        why_len = sizeof local;
    }
    if (!c || !key || !value) {
        snprintf(why, why_len, "missing argument");
        return CFG_ERR_VALUE;
    }
    return set_key(c, key, value, base_dir, why, why_len);
}

void rail_config_init(rail_config *out, const char *rail_name)
{
    memset(out, 0, sizeof *out);
    snprintf(out->driver, sizeof out->driver, "mock");
    out->params = rail_params_default();
    snprintf(out->params.name, sizeof out->params.name, "%s", rail_name ? rail_name : "rail");
    out->gcode = rail_gcode_params_default();
    out->modbus = rail_modbus_params_default();
    out->mock = rail_mock_params_default();
}

/* One read of the file: the section this load is for, what it has seen, the first failure. */
typedef struct load_ctx {
    const char *file;
    char dir[512];      /* the file's directory: where a relative map file is found */
    char section[64];   /* "rail.compress" or "rail.shear" */
    rail_config *out;
    bool seen;          /* a key of the section was read */
    bool pass_map;      /* first pass: only "map" */
    cfg_error *err;     /* where a failing key leaves its status and line for cfg_ini */
    char detail[800];   /* "key: reason" of the first failure */
} load_ctx;

static int on_section(void *user, int line, const char *section)
{
    (void)user;
    (void)line;
    (void)section; /* other sections belong to other loaders */
    return 0;
}

static int on_key(void *user, int line, const char *section, const char *name, const char *value)
{
    load_ctx *c = user;
    if (strcmp(section, c->section) != 0)
        return 0;
    c->seen = true;
    /* The preset goes first (pass 1), every other key on top of it (pass 2). */
    if (c->pass_map != (strcmp(name, "map") == 0))
        return 0;
    char why[700];
    cfg_status st = set_key(c->out, name, value, c->dir, why, sizeof why);
    if (st != CFG_OK) {
        snprintf(c->detail, sizeof c->detail, "%s: %s", name, why);
        cfg_error_set(c->err, st, CFG_ORIGIN_LINE, c->file, line, NULL, NULL, "%s", c->detail);
        return 1;
    }
    return 0;
}

/* The key a driver check blames: rail_params_check() starts its reasons "rail NAME: FIELD (...)",
 * rail_modbus_map_check() "modbus map NAME: FIELD ..." or "...: register NAME is required". */
static void blamed_key(const char *why, char *key, size_t key_len)
{
    static const char *const fields[] = {"soft_min_mm",    "soft_max_mm",    "max_speed_mm_s",
                                         "accel_mm_s2",    "poll_hz",        "min_gap_mm",
                                         "gap_at_zero_mm", "gap_per_mm",     "counts_per_mm",
                                         "speed_per_mm_s", "word_order",     "load_scale"};
    const char *p = strstr(why, ": ");
    p = p ? p + 2 : why;
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++) {
        if (strncmp(p, fields[i], strlen(fields[i])) == 0) {
            snprintf(key, key_len, "%s", fields[i]);
            return;
        }
    }
    if (strncmp(p, "register ", 9) == 0) {
        size_t n = strcspn(p + 9, " :");
        snprintf(key, key_len, "reg_%.*s", (int)(n < 24 ? n : 24), p + 9);
        return;
    }
    if (strstr(p, "(ctl_stop)")) {
        snprintf(key, key_len, "ctl_stop");
        return;
    }
    snprintf(key, key_len, "%s", strncmp(why, "modbus map", 10) == 0 ? "map" : "");
}

cfg_status rail_config_check(const rail_config *rc, char *why, size_t why_len, char *key,
                             size_t key_len)
{
    char local[8], key_local[32];
    if (!why || why_len == 0) {
        why = local;
        why_len = sizeof local;
    }
    if (!key || key_len == 0) {
        key = key_local;
        key_len = sizeof key_local;
    }
    key[0] = '\0';
    const char *d = rc->driver;
    if (strcmp(d, "mock") && strcmp(d, "gcode") && strcmp(d, "modbus")) {
        snprintf(why, why_len, "driver: '%s' is not mock, gcode or modbus", d);
        snprintf(key, key_len, "driver");
        return CFG_ERR_CHECK;
    }
    char w[300];
    if (rail_params_check(&rc->params, w, sizeof w) != RAIL_OK) {
        snprintf(why, why_len, "%s", w);
        blamed_key(w, key, key_len);
        return CFG_ERR_CHECK;
    }
    if (!strcmp(d, "modbus") && rail_modbus_map_check(&rc->modbus.map, w, sizeof w) != RAIL_OK) {
        snprintf(why, why_len, "%s", w);
        blamed_key(w, key, key_len);
        return CFG_ERR_CHECK;
    }
    return CFG_OK;
}

const char *rail_config_key_name(size_t i)
{
    return i < sizeof rail_keys / sizeof rail_keys[0] ? rail_keys[i].name : NULL;
}

static cfg_status load(const char *name, const char *text, size_t len, const char *rail_name,
                       rail_config *out, char *why, size_t why_len)
{
    if (!rail_name || (strcmp(rail_name, "compress") && strcmp(rail_name, "shear"))) {
        snprintf(why, why_len, "rail name '%s' is not compress or shear", rail_name ? rail_name : "");
        return CFG_ERR_VALUE;
    }
    rail_config_init(out, rail_name);
    cfg_error err;
    cfg_error_clear(&err);
    load_ctx c;
    memset(&c, 0, sizeof c);
    c.file = name;
    const char *slash = name ? strrchr(name, '/') : NULL;
    if (slash)
        snprintf(c.dir, sizeof c.dir, "%.*s", (int)(slash == name ? 1 : slash - name), name);
    else
        snprintf(c.dir, sizeof c.dir, ".");
    snprintf(c.section, sizeof c.section, "rail.%s", rail_name);
    c.out = out;
    c.err = &err;
    cfg_ini_handler h = {.section = on_section, .key = on_key};
    for (int pass = 0; pass < 2; pass++) {
        c.pass_map = pass == 0;
        cfg_status st = cfg_ini_parse(name, text, len, &h, &c, &err);
        if (st != CFG_OK && c.detail[0]) {
            /* A key of this section: cfg_ini stopped at its line. */
            snprintf(why, why_len, "%s:%d: [%s] %s", c.file, err.line, c.section, c.detail);
            return st;
        }
        if (st != CFG_OK) {
            cfg_error_format(&err, why, why_len);
            return st;
        }
    }
    if (!c.seen) {
        snprintf(why, why_len, "%s: no section [%s]", c.file, c.section);
        return CFG_ERR_MISSING;
    }
    char w[300];
    if (rail_config_check(out, w, sizeof w, NULL, 0) != CFG_OK) {
        snprintf(why, why_len, "%s: [%s] %s", c.file, c.section, w);
        return CFG_ERR_CHECK;
    }
    return CFG_OK;
}

cfg_status rail_config_load(const char *path, const char *rail_name, rail_config *out, char *why,
                            size_t why_len)
{
    char *text = NULL;
    size_t len = 0;
    cfg_error err;
    if (cfg_ini_read_file(path, RAIL_CONFIG_MAX_FILE_BYTES, &text, &len, &err) != CFG_OK) {
        snprintf(why, why_len, "%s: cannot read the file", path);
        return CFG_ERR_IO;
    }
    cfg_status st = load(path, text, len, rail_name, out, why, why_len);
    free(text);
    return st;
}

cfg_status rail_config_load_string(const char *text, const char *name, const char *rail_name,
                                   rail_config *out, char *why, size_t why_len)
{
    return load(name, text, text ? strlen(text) : 0, rail_name, out, why, why_len);
}

rail_err rail_config_open_rig(const char *path, rail_clock clock, rail **compress, rail **shear, char *why,
                              size_t why_len)
{
    *compress = *shear = NULL;
    rail_config cc, cs;
    if (rail_config_load(path, "compress", &cc, why, why_len) != CFG_OK ||
        rail_config_load(path, "shear", &cs, why, why_len) != CFG_OK)
        return RAIL_E_INVALID;
    return rail_open_pair(&cc, &cs, clock, compress, shear, why, why_len);
}
