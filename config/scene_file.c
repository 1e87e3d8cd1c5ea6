/* scene_file.c: the scene INI loader. Owns the scene key table: which sections and keys a scene has
 * and what their values may be.
 *
 * Design, in the spirit of Redis's config.c: one static table lists every key with its type,
 * bounds, offset into rod_scene, unit and doc; parsing, range checks, the "missing key" rule and
 * the README table all follow from it, so adding a key is one row here plus one line of README.
 *
 * The file format's rules (line numbers, NUL bytes, over-long lines, "key: value", text after
 * "[section]", indented lines, keys before any section) are cfg_ini's, shared with the rig
 * loader; this file says which sections and keys exist and what their values may be. Scene lines
 * are at most CFG_SCENE_MAX_LINE long, and the two key-line syntax errors name the key.
 *
 * The first error wins and is reported with file, line (or `--set` text, or "default") and
 * "section.key". Nothing is written to the caller's scene unless the whole load succeeds. */
#include "scene_file.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg_ini.h"
#include "cfg_keys.h"
#include "cfg_number.h"

_Static_assert(sizeof(rod_route) == sizeof(int), "rod_route is stored as an int");

#define OFF(field) offsetof(rod_scene, field)
#define REQ CFG_KEY_REQUIRED
#define MINO CFG_KEY_MIN_OPEN
#define MAXO CFG_KEY_MAX_OPEN

static const char *const route_names[] = {"compress-then-fold", "together", NULL};
static const char *const rigid_word[] = {"rigid", NULL};

/* The key table. Bounds are the single-field physics limits (positive lengths, moduli, density;
 * Gamma in (0, 0.5); |phi| < 180), plus generous upper limits that only catch typos of many
 * orders of magnitude and keep every later product finite. Cross-field limits (a fold inside a
 * clamp, creases that cannot be clamped at this Delta L) are rod_scene_check()'s. */
static const cfg_scene_key scene_keys[] = {
    {"ribbon", "length", CFG_TYPE_DOUBLE, OFF(length), 0.0, 100.0, REQ | MINO, NULL, "m",
     "free length l between the two clamp points (Gamma, Delta L, Delta W are fractions of it)"},
    {"ribbon", "width", CFG_TYPE_DOUBLE, OFF(width), 0.0, 10.0, REQ | MINO, NULL, "m",
     "width w of the ribbon (the shear direction)"},
    {"ribbon", "thickness", CFG_TYPE_DOUBLE, OFF(thickness), 0.0, 1.0, REQ | MINO, NULL, "m",
     "thickness b of the ribbon"},
    {"ribbon", "youngs_modulus", CFG_TYPE_DOUBLE, OFF(youngs_modulus), 0.0, 1e13, REQ | MINO, NULL,
     "Pa", "Young's modulus E"},
    {"ribbon", "shear_modulus", CFG_TYPE_DOUBLE, OFF(shear_modulus), 0.0, 1e13, REQ | MINO, NULL,
     "Pa", "shear modulus G (isotropic: E / (2 (1 + nu)))"},
    {"ribbon", "density", CFG_TYPE_DOUBLE, OFF(density), 0.0, 1e5, REQ | MINO, NULL, "kg/m^3",
     "mass density rho"},
    {"ribbon", "gravity", CFG_TYPE_VEC3, OFF(gravity), -1e3, 1e3, 0, NULL, "m/s^2",
     "gravity vector (x along compression, y along shear, z up), e.g. \"0 0 -9.81\"; default 0 0 0 (off)"},

    {"folds", "angle_deg", CFG_TYPE_DOUBLE, OFF(fold_angle_deg), -180.0, 180.0, REQ | MINO | MAXO,
     NULL, "deg",
     "crease angle phi of the symmetric pair; 0 means no folds; positive turns the tangent toward "
     "the surface normal (up); 180 would fold the ribbon flat onto itself"},
    {"folds", "position", CFG_TYPE_DOUBLE, OFF(fold_position), 0.0, 0.5, REQ | MINO | MAXO, NULL,
     "1", "Gamma: the creases sit at Gamma and 1 - Gamma of the free length"},
    {"folds", "angle_left_deg", CFG_TYPE_DOUBLE, OFF(fold_angle_left_deg), -180.0, 180.0, MINO | MAXO,
     NULL, "deg",
     "the left crease's own angle (the crease near the x = 0 clamp), same sign convention; default "
     "angle_deg"},
    {"folds", "angle_right_deg", CFG_TYPE_DOUBLE, OFF(fold_angle_right_deg), -180.0, 180.0,
     MINO | MAXO, NULL, "deg", "the right crease's own angle; default angle_deg"},
    {"folds", "position_left", CFG_TYPE_DOUBLE, OFF(fold_position_left), 0.0, 1.0, MINO | MAXO, NULL,
     "1", "the left crease's position, from the left clamp point over the free length; default position"},
    {"folds", "position_right", CFG_TYPE_DOUBLE, OFF(fold_position_right), 0.0, 1.0, MINO | MAXO,
     NULL, "1",
     "the right crease's position, from the left clamp point over the free length; default "
     "1 - position"},
    {"folds", "hinge_stiffness", CFG_TYPE_DOUBLE_OR_WORD, OFF(fold_hinge_stiffness), 0.0, 1e6, MINO,
     rigid_word, "N m/rad",
     "rotational stiffness k of each crease, a hinge whose energy depends on its turning angle "
     "alone, or rigid (stiffness_factor holds the angle); default rigid"},
    {"folds", "hinge_stiffness_left", CFG_TYPE_DOUBLE, OFF(fold_hinge_stiffness_left), 0.0, 1e6, MINO, NULL,
     "N m/rad", "the left crease's own hinge stiffness (compliant creases only); default hinge_stiffness"},
    {"folds", "hinge_stiffness_right", CFG_TYPE_DOUBLE, OFF(fold_hinge_stiffness_right), 0.0, 1e6, MINO, NULL,
     "N m/rad", "the right crease's own hinge stiffness (compliant creases only); default hinge_stiffness"},
    {"folds", "stiffness_factor", CFG_TYPE_DOUBLE, OFF(fold_stiffness_factor), 1.0, 1e12, REQ,
     NULL, "1",
     "rigid creases only (required with them, refused with a compliant hinge): multiplies the soft "
     "bending stiffness at a fold node (the paper gives none)"},

    {"imperfection", "fold_angle_rel", CFG_TYPE_DOUBLE, OFF(fold_angle_rel), -1.0, 1.0, 0, NULL,
     "1",
     "relative difference between the two crease angles that seeds symmetry breaking: phi (1 + rel/2) "
     "at Gamma, phi (1 - rel/2) at 1 - Gamma; default 1e-6"},

    {"mesh", "nodes", CFG_TYPE_INT, OFF(nodes), 5.0, 100001.0, REQ, NULL, "1",
     "N, total nodes including the two clamped edges"},

    {"protocol", "compression", CFG_TYPE_DOUBLE, OFF(compression), 0.0, 1.0, REQ | MAXO, NULL, "1",
     "Delta L = dl / l, held during the shear"},
    {"protocol", "shear_rate", CFG_TYPE_DOUBLE, OFF(shear_rate), 0.0, 100.0, REQ | MINO, NULL,
     "m/s", "speed of the shear clamp along y"},
    {"protocol", "shear_max", CFG_TYPE_DOUBLE, OFF(shear_max), 0.0, 10.0, REQ | MINO, NULL, "1",
     "Delta W = dw / l at which the protocol stops if no snap happened"},
    {"protocol", "route", CFG_TYPE_ENUM, OFF(route), 0.0, 0.0, 0, route_names, "-",
     "route to the upper state: compress-then-fold (compress flat with an upward bias, then ramp "
     "the creases) or together (ramp both at once); default compress-then-fold"},

    {"solver", "dt", CFG_TYPE_DOUBLE, OFF(dt), 0.0, 10.0, REQ | MINO, NULL, "s",
     "time step of the implicit Euler dynamics"},
    {"solver", "damping", CFG_TYPE_DOUBLE, OFF(damping), 0.0, 1e6, REQ, NULL, "1/s",
     "mass-proportional damping mu (C = mu M; the paper gives none); 0 is undamped"},
    {"solver", "tolerance", CFG_TYPE_DOUBLE, OFF(tolerance), 0.0, 1.0, REQ | MINO | MAXO, NULL,
     "1", "Newton tolerance on the force residual, relative to the force scale E I1 / l^2"},
    {"solver", "max_iterations", CFG_TYPE_INT, OFF(max_iterations), 1.0, 1000000.0, REQ, NULL,
     "1", "Newton iteration cap per solve"},

    {"snap", "speed", CFG_TYPE_DOUBLE, OFF(snap_speed), 0.0, 1e6, MINO, NULL, "1/s",
     "|d(Delta Z)/dt| above which the ribbon counts as snapping; default 1"},
    {"snap", "asym_threshold", CFG_TYPE_DOUBLE, OFF(asym_threshold), 0.0, 10.0, MINO, NULL, "rad",
     "peak |A| during the snap above which the snap is asymmetric; default 0.5 (docs/simulator.md \"The regime rule\")"},
};

#define N_KEYS (sizeof scene_keys / sizeof scene_keys[0])

static const char *const section_names[] = {"ribbon", "folds",    "imperfection", "mesh",
                                            "protocol", "solver", "snap"};
#define N_SECTIONS (sizeof section_names / sizeof section_names[0])

static const cfg_key_table key_table = CFG_KEY_TABLE(scene_keys, cfg_scene_key);

const cfg_scene_key *cfg_scene_keys(size_t *n)
{
    if (n) *n = N_KEYS;
    return scene_keys;
}

/* ---- helpers ------------------------------------------------------------------------------ */

static int find_section(const char *section)
{
    return cfg_names_find(section_names, N_SECTIONS, section);
}

static void key_dotted(const cfg_scene_key *k, char *buf, size_t len)
{
    snprintf(buf, len, "%s.%s", k->section, k->name);
}

/* Describe the allowed range of a numeric key, e.g. "(0, 100] m". */
static void range_text(const cfg_scene_key *k, char *buf, size_t len)
{
    cfg_range_text(buf, len, k->min, k->max, (k->flags & CFG_KEY_MIN_OPEN) != 0,
                   (k->flags & CFG_KEY_MAX_OPEN) != 0, k->unit);
}

static int in_range(const cfg_scene_key *k, double v)
{
    return cfg_in_range(v, k->min, k->max, (k->flags & CFG_KEY_MIN_OPEN) != 0,
                        (k->flags & CFG_KEY_MAX_OPEN) != 0);
}

/* Parse one finite number at *p (leading whitespace allowed), advancing *p past it.
 * Returns CFG_OK or CFG_ERR_VALUE with msg filled. */
static cfg_status parse_number(const char **p, double *out, char *msg, size_t msglen)
{
    char shown[64];
    const char *end;
    double v;
    cfg_number_status ns = cfg_number_scan(*p, &v, &end);
    if (ns) {
        const char *q = *p;
        size_t n = 0;
        while (q[n] && q[n] != ' ' && q[n] != '\t') n++;
        cfg_text_printable(shown, sizeof shown, q, n ? n : strlen(q));
        snprintf(msg, msglen, "'%s' %s", shown, cfg_number_why(ns));
        return CFG_ERR_VALUE;
    }
    *out = v;
    *p = end;
    return CFG_OK;
}

static const char *skip_space(const char *p)
{
    while (*p && isspace((unsigned char)*p)) p++;
    return p;
}

static cfg_status trailing_error(const char *rest, const char *value, char *msg, size_t msglen)
{
    char shown_rest[48], shown_value[64];
    cfg_text_printable(shown_rest, sizeof shown_rest, rest, strlen(rest));
    cfg_text_printable(shown_value, sizeof shown_value, value, strlen(value));
    snprintf(msg, msglen, "unexpected text '%s' after the value in '%s'", shown_rest, shown_value);
    return CFG_ERR_VALUE;
}

/* Parse `value` (already stripped of surrounding whitespace) for key k into the scene. */
static cfg_status value_apply(const cfg_scene_key *k, const char *value, rod_scene *s, char *msg,
                              size_t msglen)
{
    char range[96], shown[64];
    unsigned char *field = (unsigned char *)s + k->offset;
    if (value[0] == '\0') {
        snprintf(msg, msglen, "empty value (expected %s)",
                 k->type == CFG_TYPE_VEC3 ? "three numbers, e.g. \"0 0 -9.81\""
                 : k->type == CFG_TYPE_ENUM ? "a name"
                 : k->type == CFG_TYPE_INT  ? "an integer"
                 : k->type == CFG_TYPE_DOUBLE_OR_WORD ? "a number or rigid"
                                            : "a number");
        return CFG_ERR_VALUE;
    }
    switch (k->type) {
    case CFG_TYPE_DOUBLE_OR_WORD:
        if (k->names && strcmp(value, k->names[0]) == 0) {
            double inf = INFINITY;
            memcpy(field, &inf, sizeof inf);
            return CFG_OK;
        }
        __attribute__((fallthrough)); /* a number */
    case CFG_TYPE_DOUBLE: {
        const char *p = value;
        double v;
        cfg_status st = parse_number(&p, &v, msg, msglen);
        if (st && k->type == CFG_TYPE_DOUBLE_OR_WORD) {
            size_t used = strlen(msg);
            snprintf(msg + used, msglen - used, " (expected a number of %s or %s)", k->unit, k->names[0]);
        }
        if (st) return st;
        p = skip_space(p);
        if (*p) return trailing_error(p, value, msg, msglen);
        if (!in_range(k, v)) {
            range_text(k, range, sizeof range);
            snprintf(msg, msglen, "%.10g is out of range: allowed %s%s%s (%s)", v, range,
                     k->type == CFG_TYPE_DOUBLE_OR_WORD ? " or " : "",
                     k->type == CFG_TYPE_DOUBLE_OR_WORD ? k->names[0] : "", k->doc);
            return CFG_ERR_RANGE;
        }
        memcpy(field, &v, sizeof v);
        return CFG_OK;
    }
    case CFG_TYPE_INT: {
        const char *p = value;
        char *end;
        errno = 0;
        long long v = strtoll(p, &end, 10);
        if (end == p) {
            cfg_text_printable(shown, sizeof shown, value, strlen(value));
            snprintf(msg, msglen, "'%s' is not an integer", shown);
            return CFG_ERR_VALUE;
        }
        p = skip_space(end);
        if (*p == '.' || *p == 'e' || *p == 'E') {
            cfg_text_printable(shown, sizeof shown, value, strlen(value));
            snprintf(msg, msglen, "'%s' is not an integer (write whole numbers without '.' or 'e')",
                     shown);
            return CFG_ERR_VALUE;
        }
        if (*p) return trailing_error(p, value, msg, msglen);
        if (errno == ERANGE || !in_range(k, (double)v)) {
            range_text(k, range, sizeof range);
            cfg_text_printable(shown, sizeof shown, value, strlen(value));
            snprintf(msg, msglen, "%s is out of range: allowed %s (%s)", shown, range, k->doc);
            return CFG_ERR_RANGE;
        }
        int iv = (int)v;
        memcpy(field, &iv, sizeof iv);
        return CFG_OK;
    }
    case CFG_TYPE_VEC3: {
        /* Three numbers; separators are whitespace or one comma (with optional whitespace). */
        double v[3];
        const char *p = value;
        for (int i = 0; i < 3; i++) {
            if (i > 0) {
                p = skip_space(p);
                if (*p == ',') p = skip_space(p + 1);
                if (*p == '\0') {
                    snprintf(msg, msglen, "expected three numbers, found %d", i);
                    return CFG_ERR_VALUE;
                }
            }
            cfg_status st = parse_number(&p, &v[i], msg, msglen);
            if (st) return st;
        }
        p = skip_space(p);
        if (*p) return trailing_error(p, value, msg, msglen);
        for (int i = 0; i < 3; i++) {
            if (!in_range(k, v[i])) {
                range_text(k, range, sizeof range);
                snprintf(msg, msglen, "component %d (%.10g) is out of range: allowed %s each", i + 1,
                         v[i], range);
                return CFG_ERR_RANGE;
            }
        }
        memcpy(field, v, sizeof v);
        return CFG_OK;
    }
    case CFG_TYPE_ENUM: {
        for (int i = 0; k->names && k->names[i]; i++) {
            if (strcmp(value, k->names[i]) == 0) {
                memcpy(field, &i, sizeof i);
                return CFG_OK;
            }
        }
        char allowed[128];
        cfg_names_join(k->names, allowed, sizeof allowed);
        cfg_text_printable(shown, sizeof shown, value, strlen(value));
        snprintf(msg, msglen, "'%s' is not one of: %s", shown, allowed);
        return CFG_ERR_VALUE;
    }
    }
    snprintf(msg, msglen, "internal error: key has an unknown type");
    return CFG_ERR_VALUE;
}

/* ---- loading ------------------------------------------------------------------------------ */

/* Where each key's current value came from. */
typedef struct key_origin {
    int line;     /* line of the file that set it, 0 if the file did not */
    int override; /* 1 + index of the last override that set it, 0 if none did */
} key_origin;

typedef struct load_ctx {
    const char *name; /* file name for errors */
    int lines;        /* lines in the file */
    int section_line[N_SECTIONS]; /* first line of each [section], 0 if absent */
    rod_scene scene;
    key_origin origin[N_KEYS];
    cfg_error *err;
    int failed;
} load_ctx;

/* Record the first error, at line `line` of the file. Returns 1 (stop), as the reader wants. */
static int fail_line(load_ctx *c, int line, cfg_status st, const char *key, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static int fail_line(load_ctx *c, int line, cfg_status st, const char *key, const char *fmt, ...)
{
    if (c->failed) return 1;
    c->failed = 1;
    char msg[sizeof c->err->message];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cfg_error_set(c->err, st, CFG_ORIGIN_LINE, c->name, line, NULL, key, "%s", msg);
    return 1;
}

/* A [section] header (cfg_ini has checked its syntax): only the scene's sections exist. */
static int on_section(void *user, int line, const char *section)
{
    load_ctx *c = user;
    if (strlen(section) > 63)
        return fail_line(c, line, CFG_ERR_UNKNOWN, NULL, "unknown section (name too long)");
    int s = find_section(section);
    if (s < 0) {
        char shown[64];
        cfg_text_printable(shown, sizeof shown, section, strlen(section));
        return fail_line(c, line, CFG_ERR_UNKNOWN, NULL,
                         "unknown section [%s] (known: ribbon folds imperfection mesh protocol "
                         "solver snap)",
                         shown);
    }
    if (!c->section_line[s]) c->section_line[s] = line;
    return 0;
}

static int on_key(void *user, int line, const char *section, const char *name, const char *value)
{
    load_ctx *c = user;
    char dotted[128];
    snprintf(dotted, sizeof dotted, "%s.%s", section, name);
    if (find_section(section) < 0) /* on_section refused it already */
        return fail_line(c, line, CFG_ERR_UNKNOWN, dotted, "unknown section [%s]", section);
    int k = cfg_keys_find(&key_table, section, name);
    if (k < 0) {
        char known[256];
        cfg_keys_known(&key_table, section, known, sizeof known);
        return fail_line(c, line, CFG_ERR_UNKNOWN, dotted, "unknown key in [%s] (known: %s)",
                         section, known);
    }
    key_dotted(&scene_keys[k], dotted, sizeof dotted);
    if (c->origin[k].line)
        return fail_line(c, line, CFG_ERR_DUPLICATE, dotted, "set twice (first on line %d)",
                         c->origin[k].line);
    char msg[sizeof c->err->message];
    cfg_status st = value_apply(&scene_keys[k], value, &c->scene, msg, sizeof msg);
    if (st) return fail_line(c, line, st, dotted, "%s", msg);
    c->origin[k].line = line;
    return 0;
}

static void fail_override(load_ctx *c, cfg_status st, const char *ovr, const char *key,
                          const char *msg)
{
    c->failed = 1;
    cfg_error_from(c->err, st, NULL, 0, ovr ? ovr : "(null)", key, msg);
}

static void override_apply(load_ctx *c, const char *ovr, int index)
{
    char key[128], value[CFG_SCENE_MAX_LINE + 1], msg[sizeof c->err->message];
    if (!ovr) {
        fail_override(c, CFG_ERR_SYNTAX, NULL, NULL, "missing override text");
        return;
    }
    switch (cfg_override_split(ovr, key, sizeof key, value, sizeof value)) {
    case CFG_SPLIT_OK:
        break;
    case CFG_SPLIT_NO_EQUALS:
        fail_override(c, CFG_ERR_SYNTAX, ovr, NULL, "expected section.key=value");
        return;
    case CFG_SPLIT_KEY_TOO_LONG:
        fail_override(c, CFG_ERR_UNKNOWN, ovr, NULL, "unknown key (name too long)");
        return;
    case CFG_SPLIT_VALUE_TOO_LONG:
        fail_override(c, CFG_ERR_VALUE, ovr, key, "value too long");
        return;
    }
    int k = cfg_keys_find_dotted(&key_table, key);
    if (k < 0) {
        fail_override(c, CFG_ERR_UNKNOWN, ovr, key,
                      strchr(key, '.') ? "unknown key (see README, \"Scene files\")"
                                       : "expected section.key=value");
        return;
    }
    cfg_status st = value_apply(&scene_keys[k], value, &c->scene, msg, sizeof msg);
    if (st) {
        fail_override(c, st, ovr, key, msg);
        return;
    }
    c->origin[k].override = index + 1;
}

/* A required key the file did not set. Named at its section header if the section is there,
 * else at the last line of the file. */
static void check_required(load_ctx *c)
{
    int hinge = cfg_keys_find(&key_table, "folds", "hinge_stiffness");
    int factor = cfg_keys_find(&key_table, "folds", "stiffness_factor");
    int file_compliant = c->origin[hinge].line && isfinite(c->scene.fold_hinge_stiffness);
    for (size_t i = 0; i < N_KEYS && !c->failed; i++) {
        const cfg_scene_key *k = &scene_keys[i];
        if (!(k->flags & CFG_KEY_REQUIRED) || c->origin[i].line) continue;
        /* stiffness_factor is the rigid crease's penalty: not wanted with a compliant hinge. */
        if ((int)i == factor && file_compliant) continue;
        char dotted[128];
        key_dotted(k, dotted, sizeof dotted);
        int s = find_section(k->section);
        int line = (s >= 0 && c->section_line[s]) ? c->section_line[s] : c->lines;
        if (line > 0) {
            fail_line(c, line, CFG_ERR_MISSING, dotted, "required key missing%s (%s, %s)",
                      c->section_line[s] ? " from this section" : " (no such section)", k->unit,
                      k->doc);
        } else {
            cfg_error_set(c->err, CFG_ERR_MISSING, CFG_ORIGIN_FILE, c->name, 0, NULL, dotted,
                          "required key missing (the file is empty)");
            c->failed = 1;
        }
    }
}

/* folds.stiffness_factor belongs to rigid creases only. A compliant hinge refuses it when both
 * come from the same place (both in the file), or when stiffness_factor was given by an
 * override; an override of hinge_stiffness replaces the crease model of a file that sets
 * stiffness_factor for its rigid creases (so `--set folds.hinge_stiffness=K` works on the paper's
 * scenes). */
static void check_hinge_keys(load_ctx *c, const char *const *overrides)
{
    int hinge = cfg_keys_find(&key_table, "folds", "hinge_stiffness");
    int factor = cfg_keys_find(&key_table, "folds", "stiffness_factor");
    if (!isfinite(c->scene.fold_hinge_stiffness)) return;
    const key_origin *of = &c->origin[factor], *oh = &c->origin[hinge];
    int contradicts = of->override || (of->line && !oh->override);
    if (!contradicts) return;
    char msg[sizeof c->err->message];
    snprintf(msg, sizeof msg,
             "applies only to rigid creases, but folds.hinge_stiffness = %g N m/rad makes them "
             "compliant hinges: remove folds.stiffness_factor, or set folds.hinge_stiffness = rigid",
             c->scene.fold_hinge_stiffness);
    c->failed = 1;
    cfg_error_from(c->err, CFG_ERR_CHECK, c->name, of->override ? 0 : of->line,
                   of->override ? overrides[of->override - 1] : NULL, "folds.stiffness_factor", msg);
}

/* Cross-field checks, named where the blamed key was last set. */
static void check_scene(load_ctx *c, const char *const *overrides)
{
    char msg[sizeof c->err->message], key[96];
    msg[0] = key[0] = '\0';
    if (rod_scene_check(&c->scene, msg, sizeof msg, key, sizeof key) == 0) return;
    c->failed = 1;
    const char *why = msg[0] ? msg : "the scene is not usable";
    int k = cfg_keys_find_dotted(&key_table, key);
    if (k < 0) {
        cfg_error_set(c->err, CFG_ERR_CHECK, CFG_ORIGIN_FILE, c->name, 0, NULL, key, "%s", why);
        return;
    }
    const char *ovr = c->origin[k].override ? overrides[c->origin[k].override - 1] : NULL;
    cfg_error_from(c->err, CFG_ERR_CHECK, c->name, c->origin[k].line, ovr, key, why);
}

cfg_status cfg_scene_parse(const char *name, const char *text, size_t len,
                           const char *const *overrides, int n_overrides, rod_scene *out,
                           cfg_error *err)
{
    cfg_error local;
    if (!err) err = &local;
    cfg_error_clear(err);
    if (!name) name = "(scene)";
    load_ctx *c = calloc(1, sizeof *c);
    if (!c) return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, name, 0, NULL, NULL,
                                 "out of memory");
    c->name = name;
    c->scene = rod_scene_default();
    c->err = err;

    static const cfg_ini_handler h = {.section = on_section, .key = on_key,
                                      .max_line = CFG_SCENE_MAX_LINE, .name_keys = 1};
    if (cfg_ini_parse(name, text, len, &h, c, err)) c->failed = 1;
    c->lines = cfg_ini_count_lines(text ? text : "", text ? len : 0);
    if (!c->failed) check_required(c);
    if (!c->failed && n_overrides > 0 && !overrides)
        fail_override(c, CFG_ERR_SYNTAX, NULL, NULL, "missing override list");
    for (int i = 0; i < n_overrides && !c->failed; i++) override_apply(c, overrides[i], i);
    if (!c->failed) check_hinge_keys(c, overrides);
    if (!c->failed) check_scene(c, overrides);

    cfg_status st = c->failed ? err->status : CFG_OK;
    if (st == CFG_OK && out) *out = c->scene;
    free(c);
    return st;
}

cfg_status cfg_scene_apply(const rod_scene *base, const char *name, const char *const *overrides,
                           int n_overrides, rod_scene *out, cfg_error *err)
{
    cfg_error local;
    if (!err) err = &local;
    cfg_error_clear(err);
    if (!name) name = "(scene)";
    if (!base)
        return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, name, 0, NULL, NULL, "no base scene");
    load_ctx *c = calloc(1, sizeof *c);
    if (!c) return cfg_error_set(err, CFG_ERR_IO, CFG_ORIGIN_FILE, name, 0, NULL, NULL, "out of memory");
    c->name = name;
    c->scene = *base;
    c->err = err;
    if (n_overrides > 0 && !overrides) fail_override(c, CFG_ERR_SYNTAX, NULL, NULL, "missing override list");
    for (int i = 0; i < n_overrides && !c->failed; i++) override_apply(c, overrides[i], i);
    if (!c->failed) check_scene(c, overrides);
    cfg_status st = c->failed ? err->status : CFG_OK;
    if (st == CFG_OK && out) *out = c->scene;
    free(c);
    return st;
}

cfg_status cfg_scene_load(const char *path, const char *const *overrides, int n_overrides,
                          rod_scene *out, cfg_error *err)
{
    cfg_error local;
    if (!err) err = &local;
    cfg_error_clear(err);
    snprintf(err->file, sizeof err->file, "%s", path ? path : "(null)");
    err->origin = CFG_ORIGIN_FILE;
    if (!path) {
        err->status = CFG_ERR_IO;
        snprintf(err->message, sizeof err->message, "no scene file given");
        return err->status;
    }
    FILE *f = cfg_open_regular(path, err->message, sizeof err->message);
    if (!f) {
        err->status = CFG_ERR_IO;
        return err->status;
    }
    char *buf = malloc(CFG_SCENE_MAX_FILE_BYTES + 1);
    if (!buf) {
        fclose(f);
        err->status = CFG_ERR_IO;
        snprintf(err->message, sizeof err->message, "out of memory");
        return err->status;
    }
    size_t len = fread(buf, 1, CFG_SCENE_MAX_FILE_BYTES + 1, f);
    int read_error = ferror(f);
    fclose(f);
    if (read_error || len > CFG_SCENE_MAX_FILE_BYTES) {
        free(buf);
        err->status = CFG_ERR_IO;
        snprintf(err->message, sizeof err->message, "%s",
                 read_error ? "read error (is it a directory?)"
                            : "file larger than 1 MiB; not a scene file");
        return err->status;
    }
    cfg_status st = cfg_scene_parse(path, buf, len, overrides, n_overrides, out, err);
    free(buf);
    return st;
}
