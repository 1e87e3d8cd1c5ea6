/* modbus_map_file.c: Modbus register map files -> rail_modbus_map (see modbus_map_file.h).
 *
 * Read through cfg_ini (line-exact). Each section's keys land in the map as they are read;
 * a [reg.ROLE] or [info.NAME] section is checked when the next section starts or the file ends
 * (address present, coil and discrete only one bit wide), naming the section's first line.
 * Duplicates are found by a small seen-list of "section.key" (a map file has ~100 keys). The
 * cross-field checks that need the rig file's overrides (counts_per_mm, required roles) are the
 * driver's (rail_modbus_map_check), run by the rail loader after the overrides. */
#include "modbus_map_file.h"

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg_ini.h"
#include "cfg_number.h"

#define SEEN_MAX 256

typedef struct ctx {
    const char *file;
    rail_modbus_map *m;
    cfg_error *err;
    bool have_name, have_verified;
    int map_line;        /* line of [map], 0 = not seen */
    rail_mb_reg *reg;    /* register of the current section (reg. or info.), NULL in [map] */
    rail_mb_info *info;  /* information register of the current section, or NULL */
    char section[64];
    int section_line;
    bool have_address;
    char seen[SEEN_MAX][80];
    int n_seen;
} ctx;

static int fail(ctx *c, cfg_status st, int line, const char *section, const char *key, const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));
static int fail(ctx *c, cfg_status st, int line, const char *section, const char *key, const char *fmt, ...)
{
    char msg[400], dotted[96];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    snprintf(dotted, sizeof dotted, "%.40s%s%.40s", section, key ? "." : "", key ? key : "");
    cfg_error_set(c->err, st, line > 0 ? CFG_ORIGIN_LINE : CFG_ORIGIN_FILE, c->file, line, NULL,
                  dotted[0] ? dotted : NULL, "%s", msg);
    return 1;
}

/* Decimal, or 0x hex for integers (addresses, codes, masks). */
static bool parse_integer(const char *v, double *x)
{
    if (v[0] == '0' && (v[1] == 'x' || v[1] == 'X')) {
        if (!v[2] || strlen(v + 2) > 8 || strspn(v + 2, "0123456789abcdefABCDEF") != strlen(v + 2))
            return false;
        *x = (double)strtoul(v + 2, NULL, 16);
        return true;
    }
    return cfg_number_parse(v, x) == CFG_NUMBER_OK && *x == floor(*x);
}

static bool parse_yes_no(const char *v, bool *out)
{
    if (!strcmp(v, "yes")) {
        *out = true;
        return true;
    }
    if (!strcmp(v, "no")) {
        *out = false;
        return true;
    }
    return false;
}

/* The end of a register section: what it must have. */
static int close_section(ctx *c)
{
    if (!c->reg)
        return 0;
    if (!c->have_address)
        return fail(c, CFG_ERR_MISSING, c->section_line, c->section, "address",
                    "a register section needs its address");
    if ((c->reg->kind == RAIL_MB_COIL || c->reg->kind == RAIL_MB_DISCRETE) && c->reg->words != 1)
        return fail(c, CFG_ERR_CHECK, c->section_line, c->section, "width",
                    "a %s is one bit: width 16 (the default) only", rail_mb_kind_name(c->reg->kind));
    c->reg = NULL;
    c->info = NULL;
    return 0;
}

static int on_section(void *user, int line, const char *section)
{
    ctx *c = user;
    if (close_section(c))
        return 1;
    snprintf(c->section, sizeof c->section, "%.63s", section);
    c->section_line = line;
    c->have_address = false;
    for (int i = 0; i < c->n_seen; i++)
        if (c->seen[i][0] == '[' && !strcmp(c->seen[i] + 1, section))
            return fail(c, CFG_ERR_DUPLICATE, line, section, NULL, "section [%.60s] appears twice", section);
    if (c->n_seen < SEEN_MAX)
        snprintf(c->seen[c->n_seen++], sizeof c->seen[0], "[%.70s", section);
    if (!strcmp(section, "map")) {
        c->map_line = line;
        return 0;
    }
    if (!strncmp(section, "reg.", 4)) {
        for (int i = 0; i < RAIL_MB_ROLES; i++)
            if (!strcmp(section + 4, rail_modbus_role_name(i))) {
                c->reg = rail_modbus_role(c->m, i);
                *c->reg = (rail_mb_reg){.addr = -1, .words = 1};
                return 0;
            }
        return fail(c, CFG_ERR_UNKNOWN, line, section, NULL,
                    "no register role '%.40s' (target_pos speed accel decel op_type trigger control "
                    "actual_pos actual_vel status alarm watchdog ident load; a register only the "
                    "probe reads is an [info.NAME])", section + 4);
    }
    if (!strncmp(section, "info.", 5)) {
        const char *nm = section + 5;
        if (!nm[0] || strlen(nm) >= sizeof c->m->info[0].name || strspn(nm, "abcdefghijklmnopqrstuvwxyz"
                                                                        "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") != strlen(nm))
            return fail(c, CFG_ERR_VALUE, line, section, NULL,
                        "an information register's name is 1-31 letters, digits, '_' or '-'");
        if (c->m->n_info >= RAIL_MB_INFO_MAX)
            return fail(c, CFG_ERR_RANGE, line, section, NULL, "more than %d [info.*] registers",
                        RAIL_MB_INFO_MAX);
        c->info = &c->m->info[c->m->n_info++];
        memset(c->info, 0, sizeof *c->info);
        snprintf(c->info->name, sizeof c->info->name, "%s", nm);
        c->info->reg = (rail_mb_reg){.addr = -1, .words = 1};
        c->info->scale = 1.0;
        c->reg = &c->info->reg;
        return 0;
    }
    return fail(c, CFG_ERR_UNKNOWN, line, section, NULL,
                "unknown section [%.60s] (map, reg.ROLE, info.NAME)", section);
}

typedef enum { K_DOUBLE, K_LONG, K_MASK } num_kind;
typedef struct map_num {
    const char *key;
    num_kind kind;
    size_t offset;
    double min, max;
} map_num;

#define MO(f) offsetof(rail_modbus_map, f)
static const map_num map_nums[] = {
    {"counts_per_mm", K_DOUBLE, MO(counts_per_mm), 0, 1e9},
    {"speed_per_mm_s", K_DOUBLE, MO(speed_per_mm_s), 0, 1e9},
    {"accel_per_mm_s2", K_DOUBLE, MO(accel_per_mm_s2), 0, 1e9},
    {"watchdog_units_per_s", K_DOUBLE, MO(watchdog_units_per_s), 1e-9, 1e9},
    {"load_scale", K_DOUBLE, MO(load_scale), -1e9, 1e9},
    {"op_type_abs", K_LONG, MO(op_type_abs), -2147483648.0, 2147483647.0},
    {"trigger_value", K_LONG, MO(trigger_value), -2147483648.0, 2147483647.0},
    {"ctl_stop", K_LONG, MO(ctl_stop), 0, 4294967295.0},
    {"ctl_estop", K_LONG, MO(ctl_estop), 0, 4294967295.0},
    {"ctl_home", K_LONG, MO(ctl_home), 0, 4294967295.0},
    {"ctl_reset", K_LONG, MO(ctl_reset), 0, 4294967295.0},
    {"st_ready", K_MASK, MO(st_ready), 0, 4294967295.0},
    {"st_moving", K_MASK, MO(st_moving), 0, 4294967295.0},
    {"st_in_pos", K_MASK, MO(st_in_pos), 0, 4294967295.0},
    {"st_alarm", K_MASK, MO(st_alarm), 0, 4294967295.0},
    {"st_homing", K_MASK, MO(st_homing), 0, 4294967295.0},
    {"st_home_end", K_MASK, MO(st_home_end), 0, 4294967295.0},
    {"ident_value", K_LONG, MO(ident_value), -1, 4294967295.0},
};

static int map_key(ctx *c, int line, const char *name, const char *value)
{
    rail_modbus_map *m = c->m;
    if (!strcmp(name, "name")) {
        if (!value[0] || strlen(value) >= sizeof m->name)
            return fail(c, CFG_ERR_VALUE, line, "map", name, "1 to %zu characters", sizeof m->name - 1);
        snprintf(m->name, sizeof m->name, "%s", value);
        c->have_name = true;
        return 0;
    }
    if (!strcmp(name, "verified")) {
        if (!parse_yes_no(value, &m->verified))
            return fail(c, CFG_ERR_VALUE, line, "map", name, "'%.60s' is not yes or no", value);
        c->have_verified = true;
        return 0;
    }
    if (!strcmp(name, "source")) {
        if (strlen(value) >= sizeof m->source)
            return fail(c, CFG_ERR_VALUE, line, "map", name, "longer than %zu characters", sizeof m->source - 1);
        snprintf(m->source, sizeof m->source, "%s", value);
        return 0;
    }
    if (!strcmp(name, "word_order")) {
        if (!strcmp(value, "high_first"))
            m->word_order = RAIL_MB_HIGH_FIRST;
        else if (!strcmp(value, "low_first"))
            m->word_order = RAIL_MB_LOW_FIRST;
        else
            return fail(c, CFG_ERR_VALUE, line, "map", name, "'%.60s' is not high_first or low_first", value);
        return 0;
    }
    for (size_t i = 0; i < sizeof map_nums / sizeof map_nums[0]; i++) {
        const map_num *k = &map_nums[i];
        if (strcmp(name, k->key))
            continue;
        double x = 0.0;
        bool ok = k->kind == K_DOUBLE ? cfg_number_parse(value, &x) == CFG_NUMBER_OK : parse_integer(value, &x);
        if (!ok)
            return fail(c, CFG_ERR_VALUE, line, "map", name, "'%.60s' is not %s", value,
                        k->kind == K_DOUBLE ? "a number" : "an integer (decimal or 0x hex)");
        if (!(x >= k->min && x <= k->max))
            return fail(c, CFG_ERR_RANGE, line, "map", name, "%.60s is outside [%g, %g]", value, k->min, k->max);
        char *f = (char *)m + k->offset;
        if (k->kind == K_DOUBLE)
            *(double *)f = x;
        else if (k->kind == K_MASK)
            *(unsigned long *)f = (unsigned long)x;
        else
            *(long *)f = (long)x;
        return 0;
    }
    return fail(c, CFG_ERR_UNKNOWN, line, "map", name, "unknown key in [map]");
}

static int reg_key(ctx *c, int line, const char *name, const char *value)
{
    rail_mb_reg *r = c->reg;
    double x = 0.0;
    if (!strcmp(name, "address")) {
        if (!parse_integer(value, &x))
            return fail(c, CFG_ERR_VALUE, line, c->section, name, "'%.60s' is not a register address", value);
        if (x < 0 || x > 65535)
            return fail(c, CFG_ERR_RANGE, line, c->section, name, "%.60s is outside 0..65535", value);
        r->addr = (int)x;
        c->have_address = true;
        return 0;
    }
    if (!strcmp(name, "type")) {
        static const char *const kinds[] = {"holding", "input", "coil", "discrete"};
        for (int i = 0; i < 4; i++)
            if (!strcmp(value, kinds[i])) {
                r->kind = (rail_mb_kind)i;
                if (!c->info && i > RAIL_MB_INPUT)
                    return fail(c, CFG_ERR_VALUE, line, c->section, name,
                                "a %s is one bit; the driver's registers are holding or input", value);
                return 0;
            }
        return fail(c, CFG_ERR_VALUE, line, c->section, name, "'%.60s' is not holding, input, coil or discrete",
                    value);
    }
    if (!strcmp(name, "width")) {
        if (!strcmp(value, "16"))
            r->words = 1;
        else if (!strcmp(value, "32"))
            r->words = 2;
        else
            return fail(c, CFG_ERR_VALUE, line, c->section, name, "'%.60s' is not 16 or 32 (bits)", value);
        return 0;
    }
    if (!strcmp(name, "signed")) {
        bool s = false;
        if (!parse_yes_no(value, &s))
            return fail(c, CFG_ERR_VALUE, line, c->section, name, "'%.60s' is not yes or no", value);
        r->sign = s ? RAIL_MB_SIGNED : RAIL_MB_UNSIGNED;
        return 0;
    }
    if (!strcmp(name, "meaning")) {
        if (strlen(value) >= sizeof r->meaning)
            return fail(c, CFG_ERR_VALUE, line, c->section, name, "longer than %zu characters",
                        sizeof r->meaning - 1);
        snprintf(r->meaning, sizeof r->meaning, "%s", value);
        return 0;
    }
    if (c->info && !strcmp(name, "scale")) {
        if (cfg_number_parse(value, &x) != CFG_NUMBER_OK || x == 0.0)
            return fail(c, CFG_ERR_VALUE, line, c->section, name, "'%.60s' is not a non-zero number", value);
        c->info->scale = x;
        return 0;
    }
    if (c->info && !strcmp(name, "unit")) {
        if (strlen(value) >= sizeof c->info->unit)
            return fail(c, CFG_ERR_VALUE, line, c->section, name, "longer than %zu characters",
                        sizeof c->info->unit - 1);
        snprintf(c->info->unit, sizeof c->info->unit, "%s", value);
        return 0;
    }
    if (!c->info && (!strcmp(name, "scale") || !strcmp(name, "unit")))
        return fail(c, CFG_ERR_UNKNOWN, line, c->section, name,
                    "a role's scale comes from [map] (counts_per_mm, speed_per_mm_s, accel_per_mm_s2, "
                    "watchdog_units_per_s, load_scale), so the driver and the probe share it");
    return fail(c, CFG_ERR_UNKNOWN, line, c->section, name,
                "unknown key (address, type, width, signed, meaning%s)", c->info ? ", scale, unit" : "");
}

static int on_key(void *user, int line, const char *section, const char *name, const char *value)
{
    ctx *c = user;
    char dotted[80];
    snprintf(dotted, sizeof dotted, "%.40s.%.38s", section, name);
    for (int i = 0; i < c->n_seen; i++)
        if (!strcmp(c->seen[i], dotted))
            return fail(c, CFG_ERR_DUPLICATE, line, section, name, "set twice");
    if (c->n_seen >= SEEN_MAX)
        return fail(c, CFG_ERR_RANGE, line, section, name, "more than %d keys and sections", SEEN_MAX);
    snprintf(c->seen[c->n_seen++], sizeof c->seen[0], "%s", dotted);
    if (!strcmp(section, "map"))
        return map_key(c, line, name, value);
    return reg_key(c, line, name, value);
}

cfg_status modbus_map_file_parse(const char *name, const char *text, size_t len, rail_modbus_map *out,
                                 cfg_error *err)
{
    cfg_error local;
    if (!err)
        err = &local;
    cfg_error_clear(err);
    if (!name)
        name = "(map)";
    ctx *c = calloc(1, sizeof *c);
    if (!c)
        return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, name, 0, NULL, NULL, "out of memory");
    rail_modbus_map m;
    memset(&m, 0, sizeof m);
    for (int i = 0; i < RAIL_MB_ROLES; i++)
        *rail_modbus_role(&m, i) = (rail_mb_reg){.addr = -1, .words = 1};
    m.load_scale = 1.0;
    m.watchdog_units_per_s = 1000.0;
    m.ident_value = -1;
    snprintf(m.file, sizeof m.file, "%.159s", name);
    c->file = name;
    c->m = &m;
    c->err = err;
    const cfg_ini_handler h = {.section = on_section, .key = on_key};
    cfg_status st = cfg_ini_parse(name, text ? text : "", text ? len : 0, &h, c, err);
    if (st == CFG_OK && close_section(c))
        st = err->status;
    if (st == CFG_OK && !c->map_line)
        st = cfg_error_set(err, CFG_ERR_MISSING, CFG_ORIGIN_FILE, name, 0, NULL, "map",
                           "no [map] section (name, verified, ...)");
    if (st == CFG_OK && (!c->have_name || !c->have_verified))
        st = cfg_error_set(err, CFG_ERR_MISSING, CFG_ORIGIN_LINE, name, c->map_line, NULL,
                           c->have_name ? "map.verified" : "map.name",
                           c->have_name ? "a map says whether it was tried on a real drive: verified = yes | no"
                                        : "a map needs its name");
    free(c);
    if (st == CFG_OK)
        *out = m;
    return st;
}

cfg_status modbus_map_file_load(const char *path, rail_modbus_map *out, cfg_error *err)
{
    cfg_error local;
    if (!err)
        err = &local;
    char *text = NULL;
    size_t len = 0;
    cfg_status st = cfg_ini_read_file(path, MODBUS_MAP_FILE_MAX_BYTES, &text, &len, err);
    if (st != CFG_OK)
        return st;
    st = modbus_map_file_parse(path, text, len, out, err);
    free(text);
    return st;
}
