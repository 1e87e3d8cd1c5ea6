/* rail_config.c: rail sections of rig INI files -> driver parameter structs (see rail_config.h).
 *
 * Two passes over the file with inih: the first reads only `map` (a Modbus preset) so that
 * per-register overrides apply on top of it whatever their order in the file; the second reads
 * every other key through one table {key, kind, field, min, max}. Cross-field checks are left
 * to the drivers' own checks (rail_params_check, rail_modbus_map_check), which name the field,
 * and are run here too so a bad file fails at load, not at the first motion. */
#include "rail_config.h"
#include "cfg_number.h"

#include <ini.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef enum kind { K_DOUBLE, K_INT, K_BOOL, K_STRING, K_CHAR, K_REG, K_LONG } kind;

typedef struct key_def {
    const char *key;
    kind k;
    size_t off;      /* offset into rail_config */
    size_t size;     /* for strings */
    double min, max; /* for numbers */
} key_def;

#define F(field) offsetof(rail_config, field)
#define D(key, field, lo, hi) {key, K_DOUBLE, F(field), 0, lo, hi}
#define I(key, field, lo, hi) {key, K_INT, F(field), 0, lo, hi}
#define L(key, field, lo, hi) {key, K_LONG, F(field), 0, lo, hi}
#define B(key, field) {key, K_BOOL, F(field), 0, 0, 1}
#define S(key, field) {key, K_STRING, F(field), sizeof(((rail_config *)0)->field), 0, 0}
#define REG(name) {"reg_" #name, K_REG, F(modbus.map.name), 0, -1, 65535}

static const key_def keys[] = {
    S("driver", driver),
    D("soft_min_mm", params.soft_min_mm, -1e6, 1e6),
    D("soft_max_mm", params.soft_max_mm, -1e6, 1e6),
    D("max_speed_mm_s", params.max_speed_mm_s, 1e-6, 1000),
    D("accel_mm_s2", params.accel_mm_s2, 1e-6, 1e5),
    D("poll_hz", params.poll_hz, 0.1, 1000),
    D("min_gap_mm", params.min_gap_mm, 0, 1e6),
    D("gap_at_zero_mm", params.gap_at_zero_mm, -1e6, 1e6),
    D("gap_per_mm", params.gap_per_mm, -1, 1),
    S("port", gcode.port),
    I("baud", gcode.baud, 1200, 3000000),
    {"axis", K_CHAR, F(gcode.axis), 0, 0, 0},
    D("segment_s", gcode.segment_s, 0.05, 2),
    I("segments_ahead", gcode.segments_ahead, 1, 4),
    D("reply_timeout_s", gcode.reply_timeout_s, 0.01, 10),
    D("stall_timeout_s", gcode.stall_timeout_s, 0.05, 60),
    D("min_segment_mm", gcode.min_segment_mm, 1e-4, 10),
    S("address", modbus.address),
    B("rtu", modbus.rtu),
    {"parity", K_CHAR, F(modbus.parity), 0, 0, 0},
    I("slave", modbus.slave, 1, 247),
    D("timeout_s", modbus.timeout_s, 0.01, 5),
    D("watchdog_s", modbus.watchdog_s, 0, 10),
    B("allow_unverified", modbus.allow_unverified),
    B("watchdog_external", modbus.watchdog_external),
    D("counts_per_mm", modbus.map.counts_per_mm, 1e-9, 1e9),
    D("speed_per_mm_s", modbus.map.speed_per_mm_s, 0, 1e9),
    D("accel_per_mm_s2", modbus.map.accel_per_mm_s2, 0, 1e9),
    REG(target_pos), REG(speed), REG(accel), REG(decel), REG(op_type), REG(trigger), REG(control),
    REG(actual_pos), REG(actual_vel), REG(status), REG(alarm), REG(watchdog), REG(ident), REG(load),
    D("load_scale", modbus.map.load_scale, -1e9, 1e9),
    L("op_type_abs", modbus.map.op_type_abs, -2147483648.0, 2147483647.0),
    L("trigger_value", modbus.map.trigger_value, -2147483648.0, 2147483647.0),
    L("ctl_stop", modbus.map.ctl_stop, 0, 4294967295.0),
    L("ctl_estop", modbus.map.ctl_estop, 0, 4294967295.0),
    L("ctl_home", modbus.map.ctl_home, 0, 4294967295.0),
    L("ctl_reset", modbus.map.ctl_reset, 0, 4294967295.0),
    L("st_ready", modbus.map.st_ready, 0, 4294967295.0),
    L("st_moving", modbus.map.st_moving, 0, 4294967295.0),
    L("st_in_pos", modbus.map.st_in_pos, 0, 4294967295.0),
    L("st_alarm", modbus.map.st_alarm, 0, 4294967295.0),
    L("st_homing", modbus.map.st_homing, 0, 4294967295.0),
    L("st_home_end", modbus.map.st_home_end, 0, 4294967295.0),
    L("ident_value", modbus.map.ident_value, -1, 4294967295.0),
    D("start_mm", mock.start_mm, 0, 1e6),
    D("travel_mm", mock.travel_mm, 1e-6, 1e6),
    D("home_speed_mm_s", mock.home_speed_mm_s, 1e-6, 1000),
    D("stall_at_mm", mock.stall_at_mm, -1e6, 1e6),
    D("comm_loss_after_s", mock.comm_loss_after_s, -1, 1e7),
    D("alarm_after_s", mock.alarm_after_s, -1, 1e7),
    I("alarm_code", mock.alarm_code, 0, 65535),
};

typedef struct ctx {
    const char *file;
    char section[64];
    rail_config *out;
    bool seen;
    bool pass_map;   /* first pass: only "map" */
    bool failed;
    char *why;
    size_t why_len;
    char detail[300];  /* "key: reason" of the first failure; inih returns its line number */
} ctx;

/* Record the first failure; returning 0 makes inih stop and report this line. */
static int fail(ctx *c, const char *key, const char *fmt, const char *val)
{
    if (!c->failed) {
        char d[200];
        snprintf(d, sizeof d, fmt, val);
        snprintf(c->detail, sizeof c->detail, "%s: %s", key, d);
        c->failed = true;
    }
    return 0;
}

static bool parse_num(const char *v, double *x)
{
    return cfg_number_parse(v, x) == CFG_NUMBER_OK; /* plain decimal only (cfg_number.h) */
}

/* Apply one key; 0, -1 (bad value) or -2 (unknown key), with the reason in why. */
static int set_key(rail_config *out, const char *name, const char *value, char *why, size_t why_len)
{
    if (!strcmp(name, "map")) {
        if (rail_modbus_preset(value, &out->modbus.map) != RAIL_OK) {
            snprintf(why, why_len, "unknown preset '%s' (ribbon-sim, oriental-az)", value);
            return -1;
        }
        return 0;
    }
    if (!strcmp(name, "word_order")) {
        if (!strcmp(value, "high_first"))
            out->modbus.map.word_order = RAIL_MB_HIGH_FIRST;
        else if (!strcmp(value, "low_first"))
            out->modbus.map.word_order = RAIL_MB_LOW_FIRST;
        else {
            snprintf(why, why_len, "'%s' is not high_first or low_first", value);
            return -1;
        }
        return 0;
    }
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        const key_def *k = &keys[i];
        if (strcmp(name, k->key) != 0)
            continue;
        char *field = (char *)out + k->off;
        double x = 0.0;
        switch (k->k) {
        case K_STRING:
            if (strlen(value) >= k->size) {
                snprintf(why, why_len, "value '%.60s' too long", value);
                return -1;
            }
            snprintf(field, k->size, "%s", value);
            return 0;
        case K_CHAR:
            if (strlen(value) != 1) {
                snprintf(why, why_len, "'%.60s' must be one letter", value);
                return -1;
            }
            *(char *)field = value[0];
            return 0;
        case K_BOOL:
            if (!strcmp(value, "true") || !strcmp(value, "1") || !strcmp(value, "yes"))
                *(bool *)field = true;
            else if (!strcmp(value, "false") || !strcmp(value, "0") || !strcmp(value, "no"))
                *(bool *)field = false;
            else {
                snprintf(why, why_len, "'%.60s' is not true or false", value);
                return -1;
            }
            return 0;
        case K_REG: {
            rail_mb_reg *r = (rail_mb_reg *)field;
            char buf[32];
            snprintf(buf, sizeof buf, "%s", value);
            char *slash = strchr(buf, '/');
            double words = 1.0;
            if (slash) {
                *slash = 0;
                if (!parse_num(slash + 1, &words) || (words != 1.0 && words != 2.0)) {
                    snprintf(why, why_len, "'%.60s' must be ADDR or ADDR/1 or ADDR/2", value);
                    return -1;
                }
            }
            if (!parse_num(buf, &x) && !(buf[0] == '0' && buf[1] == 'x')) {
                snprintf(why, why_len, "'%.60s' is not a register address", value);
                return -1;
            }
            if (buf[0] == '0' && buf[1] == 'x')
                x = (double)strtol(buf, NULL, 16);
            if (x < -1 || x > 65535 || x != floor(x)) {
                snprintf(why, why_len, "register address '%.60s' outside -1..65535", value);
                return -1;
            }
            r->addr = (int)x;
            r->words = (int)words;
            return 0;
        }
        default:
            if (!parse_num(value, &x) && !(value[0] == '0' && value[1] == 'x')) {
                snprintf(why, why_len, "'%.60s' is not a number", value);
                return -1;
            }
            if (value[0] == '0' && value[1] == 'x')
                x = (double)strtoul(value, NULL, 16);
            if (!(x >= k->min && x <= k->max)) {
                snprintf(why, why_len, "%.60s is outside [%g, %g]", value, k->min, k->max);
                return -1;
            }
            if (k->k == K_DOUBLE)
                *(double *)field = x;
            else if (k->k == K_INT) {
                if (x != floor(x)) {
                    snprintf(why, why_len, "'%.60s' must be an integer", value);
                    return -1;
                }
                *(int *)field = (int)x;
            } else {
                *(long *)field = (long)x;
            }
            return 0;
        }
    }
    snprintf(why, why_len, "unknown key");
    return -2;
}

int rail_config_set(rail_config *c, const char *key, const char *value, char *why, size_t why_len)
{
    char local[8];
    if (!why || why_len == 0) {
        why = local;
        why_len = sizeof local;
    }
    if (!c || !key || !value) {
        snprintf(why, why_len, "missing argument");
        return -1;
    }
    return set_key(c, key, value, why, why_len);
}

static int handler(void *user, const char *section, const char *name, const char *value)
{
    ctx *c = user;
    if (c->failed || strcmp(section, c->section) != 0)
        return 1;
    c->seen = true;
    /* The preset goes first (pass 1), every other key on top of it (pass 2). */
    if (c->pass_map != (strcmp(name, "map") == 0))
        return 1;
    char why[200];
    if (set_key(c->out, name, value, why, sizeof why) != 0)
        return fail(c, name, "%s", why);
    return 1;
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

static int finish(ctx *c, int rc)
{
    if (rc < 0) {
        snprintf(c->why, c->why_len, "%s: cannot read the file", c->file);
        return -1;
    }
    if (c->failed) {
        snprintf(c->why, c->why_len, "%s:%d: [%s] %s", c->file, rc, c->section, c->detail);
        return -1;
    }
    if (rc > 0) {
        snprintf(c->why, c->why_len, "%s:%d: syntax error", c->file, rc);
        return -1;
    }
    if (!c->seen) {
        snprintf(c->why, c->why_len, "%s: no section [%s]", c->file, c->section);
        return -1;
    }
    char w[300];
    if (rail_config_check(c->out, w, sizeof w, NULL, 0) != 0) {
        snprintf(c->why, c->why_len, "%s: [%s] %s", c->file, c->section, w);
        return -1;
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

int rail_config_check(const rail_config *rc, char *why, size_t why_len, char *key, size_t key_len)
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
        return -1;
    }
    char w[300];
    if (rail_params_check(&rc->params, w, sizeof w) != RAIL_OK) {
        snprintf(why, why_len, "%s", w);
        blamed_key(w, key, key_len);
        return -1;
    }
    if (!strcmp(d, "modbus") && rail_modbus_map_check(&rc->modbus.map, w, sizeof w) != RAIL_OK) {
        snprintf(why, why_len, "%s", w);
        blamed_key(w, key, key_len);
        return -1;
    }
    return 0;
}

const char *rail_config_key_name(size_t i)
{
    static const char *const extra[] = {"map", "word_order"};
    size_t n = sizeof keys / sizeof keys[0];
    if (i < n)
        return keys[i].key;
    if (i - n < sizeof extra / sizeof extra[0])
        return extra[i - n];
    return NULL;
}

static int load(const char *path, const char *text, const char *name, const char *rail_name,
                rail_config *out, char *why, size_t why_len)
{
    if (!rail_name || (strcmp(rail_name, "compress") && strcmp(rail_name, "shear"))) {
        snprintf(why, why_len, "rail name '%s' is not compress or shear", rail_name ? rail_name : "");
        return -1;
    }
    rail_config_init(out, rail_name);
    ctx c;
    memset(&c, 0, sizeof c);
    c.file = name;
    snprintf(c.section, sizeof c.section, "rail.%s", rail_name);
    c.out = out;
    c.why = why;
    c.why_len = why_len;
    int rc = 0;
    for (int pass = 0; pass < 2 && rc == 0; pass++) {
        c.pass_map = pass == 0;
        rc = text ? ini_parse_string(text, handler, &c) : ini_parse(path, handler, &c);
    }
    return finish(&c, rc);
}

int rail_config_load(const char *path, const char *rail_name, rail_config *out, char *why, size_t why_len)
{
    return load(path, NULL, path, rail_name, out, why, why_len);
}

int rail_config_load_string(const char *text, const char *name, const char *rail_name, rail_config *out,
                            char *why, size_t why_len)
{
    return load(NULL, text, name, rail_name, out, why, why_len);
}

rail_err rail_config_open(const rail_config *c, rail_clock clock, grbl_link *shared, rail **out, char *why,
                          size_t why_len)
{
    *out = NULL;
    if (!strcmp(c->driver, "mock"))
        return rail_mock_open(out, &c->params, &c->mock, clock, why, why_len);
    if (!strcmp(c->driver, "gcode"))
        return rail_gcode_open(out, &c->params, &c->gcode, shared, clock, why, why_len);
    if (!strcmp(c->driver, "modbus"))
        return rail_modbus_open(out, &c->params, &c->modbus, clock, why, why_len);
    snprintf(why, why_len, "rail %s: unknown driver '%s'", c->params.name, c->driver);
    return RAIL_E_INVALID;
}

rail_err rail_config_open_pair(const rail_config *cc, const rail_config *cs, rail_clock clock, rail **compress,
                               rail **shear, char *why, size_t why_len)
{
    *compress = *shear = NULL;
    grbl_link *link = NULL;
    bool share = !strcmp(cc->driver, "gcode") && !strcmp(cs->driver, "gcode") &&
                 !strcmp(cc->gcode.port, cs->gcode.port);
    if (share) {
        if (cc->gcode.axis == cs->gcode.axis) {
            snprintf(why, why_len, "both rails are axis %c of controller %s", cc->gcode.axis, cc->gcode.port);
            return RAIL_E_INVALID;
        }
        rail_err e = grbl_link_open(&link, &cc->gcode, clock, why, why_len);
        if (e != RAIL_OK)
            return e;
    }
    rail_err e = rail_config_open(cc, clock, link, compress, why, why_len);
    if (e == RAIL_OK)
        e = rail_config_open(cs, clock, link, shear, why, why_len);
    grbl_link_release(link); /* the rails hold their own references */
    if (e != RAIL_OK) {
        rail_close(*compress);
        *compress = NULL;
    }
    return e;
}

rail_err rail_config_open_rig(const char *path, rail_clock clock, rail **compress, rail **shear, char *why,
                              size_t why_len)
{
    *compress = *shear = NULL;
    rail_config cc, cs;
    if (rail_config_load(path, "compress", &cc, why, why_len) != 0 ||
        rail_config_load(path, "shear", &cs, why, why_len) != 0)
        return RAIL_E_INVALID;
    return rail_config_open_pair(&cc, &cs, clock, compress, shear, why, why_len);
}
