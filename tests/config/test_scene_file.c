/* test_scene_file.c: the scene file loader (config/scene_file.c).
 *
 * Covers: the shipped scenes load with the paper's and the lab's values; every refusal the docs
 * list names the right file, line (or override, or "default") and "section.key"; overrides
 * apply and bad ones are refused; the physics checks (fold inside a clamp, phi = 180, stiff
 * creases at tiny Delta L) fire at load; docs/config.md documents every key of the table; and a
 * deterministic fuzz run over mutated shipped scenes never crashes and always ends in either a
 * finite, checked scene or an error with a message. Most cases mutate one line of a small complete
 * scene (BASE below) so the expected line number is known. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>

#include "scene_file.h"

#ifndef RIBBON_SOURCE_DIR
#error "RIBBON_SOURCE_DIR must be defined"
#endif

#define REL_CLOSE(a, b) (fabs((a) - (b)) <= 1e-12 * fabs(b) + 1e-300)

/* A minimal complete scene: every required key, no optional one. Line i + 1 is BASE[i]. */
static const char *const BASE[] = {
    "[ribbon]",               /* 1 */
    "length = 1.0",           /* 2 */
    "width = 0.2",            /* 3 */
    "thickness = 1e-3",       /* 4 */
    "youngs_modulus = 1e9",   /* 5 */
    "shear_modulus = 3.3e8",  /* 6 */
    "density = 1000",         /* 7 */
    "[folds]",                /* 8 */
    "angle_deg = 90",         /* 9 */
    "position = 0.21",        /* 10 */
    "stiffness_factor = 1e4", /* 11 */
    "[mesh]",                 /* 12 */
    "nodes = 101",            /* 13 */
    "[protocol]",             /* 14 */
    "compression = 0.5",      /* 15 */
    "shear_rate = 0.01",      /* 16 */
    "shear_max = 0.5",        /* 17 */
    "[solver]",               /* 18 */
    "dt = 1e-3",              /* 19 */
    "damping = 0.5",          /* 20 */
    "tolerance = 1e-8",       /* 21 */
    "max_iterations = 50",    /* 22 */
};
#define BASE_N ((int)(sizeof BASE / sizeof BASE[0]))

/* BASE with up to two lines replaced (line numbers 1-based; 0 = none; text NULL = a comment, so
 * that later line numbers do not move) and `tail` appended. Returns a static buffer. */
static const char *scene_edit2(int l1, const char *t1, int l2, const char *t2, const char *tail)
{
    static char buf[8192];
    size_t used = 0;
    for (int i = 0; i < BASE_N; i++) {
        const char *line = BASE[i];
        if (i + 1 == l1) line = t1 ? t1 : "; (removed)";
        if (i + 1 == l2) line = t2 ? t2 : "; (removed)";
        used += (size_t)snprintf(buf + used, sizeof buf - used, "%s\n", line);
    }
    if (tail) snprintf(buf + used, sizeof buf - used, "%s", tail);
    return buf;
}

static const char *scene_edit(int line, const char *text)
{
    return scene_edit2(line, text, 0, NULL, NULL);
}

static cfg_status parse(const char *text, const char *const *ovr, int n, rod_scene *out,
                        cfg_error *err)
{
    return cfg_scene_parse("test.ini", text, strlen(text), ovr, n, out, err);
}

/* Expect a refusal with this status, at this line of test.ini, naming this key, and with
 * `part` in the message. Also checks the formatted one-liner. */
static void expect_line_error(const char *text, cfg_status status, int line, const char *key,
                              const char *part)
{
    rod_scene s;
    cfg_error err;
    cfg_status st = parse(text, NULL, 0, &s, &err);
    char shown[1024];
    cfg_error_format(&err, shown, sizeof shown);
    print_message("  refused: %s\n", shown);
    assert_int_equal(st, status);
    assert_int_equal(err.status, status);
    assert_int_equal(err.origin, CFG_ORIGIN_LINE);
    assert_string_equal(err.file, "test.ini");
    assert_int_equal(err.line, line);
    assert_string_equal(err.key, key);
    if (part) assert_non_null(strstr(err.message, part));
    char prefix[256];
    if (key[0])
        snprintf(prefix, sizeof prefix, "test.ini:%d: %s: ", line, key);
    else
        snprintf(prefix, sizeof prefix, "test.ini:%d: ", line);
    assert_memory_equal(shown, prefix, strlen(prefix));
}

static void expect_override_error(const char *ovr, cfg_status status, const char *key,
                                  const char *part)
{
    rod_scene s;
    cfg_error err;
    const char *list[] = {"mesh.nodes=51", ovr};
    cfg_status st = parse(scene_edit(0, NULL), list, 2, &s, &err);
    char shown[1024], prefix[256];
    cfg_error_format(&err, shown, sizeof shown);
    print_message("  refused: %s\n", shown);
    assert_int_equal(st, status);
    assert_int_equal(err.origin, CFG_ORIGIN_OVERRIDE);
    assert_string_equal(err.file, "--set");
    assert_string_equal(err.where, ovr);
    assert_string_equal(err.key, key);
    if (part) assert_non_null(strstr(err.message, part));
    snprintf(prefix, sizeof prefix, "--set %s: ", ovr);
    assert_memory_equal(shown, prefix, strlen(prefix));
}

static char *file_read(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = malloc(1 << 20);
    if (!buf) {
        fclose(f);
        return NULL;
    }
    *len = fread(buf, 1, (1 << 20) - 1, f);
    buf[*len] = '\0';
    fclose(f);
    return buf;
}

/* ---- shipped scenes ---------------------------------------------------------------------- */

static void check_paper_common(const rod_scene *s)
{
    assert_true(REL_CLOSE(s->length, 1.0));
    assert_true(REL_CLOSE(s->width, 0.2));
    assert_true(REL_CLOSE(s->thickness, 1e-3));
    assert_true(REL_CLOSE(s->youngs_modulus, 1e9));
    assert_true(REL_CLOSE(s->shear_modulus, 1e9 / 3.0));
    assert_true(REL_CLOSE(s->density, 1000.0));
    for (int i = 0; i < 3; i++) assert_true(s->gravity[i] == 0.0);
    assert_true(REL_CLOSE(s->fold_angle_deg, -90.0));
    assert_int_equal(s->nodes, 201);
    assert_true(REL_CLOSE(s->dt, 1e-3));
    assert_true(REL_CLOSE(s->shear_rate, 0.01));
    assert_true(REL_CLOSE(s->compression, 0.5));
    /* The values the paper does not give are the documented defaults. */
    rod_scene d = rod_scene_default();
    assert_true(REL_CLOSE(s->fold_stiffness_factor, d.fold_stiffness_factor));
    assert_true(REL_CLOSE(s->fold_angle_rel, d.fold_angle_rel));
    assert_true(REL_CLOSE(s->shear_max, d.shear_max));
    assert_int_equal(s->route, d.route);
    assert_true(REL_CLOSE(s->damping, d.damping));
    assert_true(REL_CLOSE(s->tolerance, d.tolerance));
    assert_int_equal(s->max_iterations, d.max_iterations);
    assert_true(REL_CLOSE(s->snap_speed, d.snap_speed));
    assert_true(REL_CLOSE(s->asym_threshold, d.asym_threshold));
}

static void test_paper_scenes_load(void **state)
{
    (void)state;
    rod_scene s;
    cfg_error err;
    char buf[1024];
    cfg_status st = cfg_scene_load(RIBBON_SOURCE_DIR "/config/scenes/paper-gamma013.ini", NULL, 0,
                                   &s, &err);
    if (st) print_error("%s\n", cfg_error_format(&err, buf, sizeof buf));
    assert_int_equal(st, CFG_OK);
    check_paper_common(&s);
    assert_true(REL_CLOSE(s.fold_position, 0.13));

    st = cfg_scene_load(RIBBON_SOURCE_DIR "/config/scenes/paper-gamma021.ini", NULL, 0, &s, &err);
    if (st) print_error("%s\n", cfg_error_format(&err, buf, sizeof buf));
    assert_int_equal(st, CFG_OK);
    check_paper_common(&s);
    assert_true(REL_CLOSE(s.fold_position, 0.21));
}

static void test_pet_scene_loads(void **state)
{
    (void)state;
    rod_scene s;
    cfg_error err;
    char buf[1024];
    cfg_status st =
        cfg_scene_load(RIBBON_SOURCE_DIR "/config/scenes/pet-200x5.ini", NULL, 0, &s, &err);
    if (st) print_error("%s\n", cfg_error_format(&err, buf, sizeof buf));
    assert_int_equal(st, CFG_OK);
    assert_true(REL_CLOSE(s.length, 0.2));
    assert_true(REL_CLOSE(s.width, 5e-3));
    assert_true(REL_CLOSE(s.thickness, 0.25e-3));
    assert_true(REL_CLOSE(s.youngs_modulus, 4e9));
    assert_true(REL_CLOSE(s.shear_modulus, 4e9 / (2.0 * 1.38)));
    assert_true(REL_CLOSE(s.density, 1380.0));
    assert_true(s.gravity[0] == 0.0 && s.gravity[1] == 0.0);
    assert_true(REL_CLOSE(s.gravity[2], -9.81));
    assert_true(REL_CLOSE(s.fold_angle_deg, -90.0));
    assert_true(REL_CLOSE(s.fold_position, 0.21));
    assert_true(REL_CLOSE(s.compression, 0.3));
    assert_true(REL_CLOSE(s.shear_rate, 1e-3));
    assert_true(REL_CLOSE(s.shear_max, 0.5));
    assert_int_equal(s.nodes, 101);
    assert_true(REL_CLOSE(s.dt, 1e-3));
    /* Compliant creases: k = E I1 / L*, L* = 30 b (the scene file's comment gives the source). */
    assert_true(REL_CLOSE(s.fold_hinge_stiffness, 3.5e-3));
}

/* The base scene sets only required keys: the optional ones keep their documented defaults. */
static void test_optional_keys_default(void **state)
{
    (void)state;
    rod_scene s;
    cfg_error err;
    assert_int_equal(parse(scene_edit(0, NULL), NULL, 0, &s, &err), CFG_OK);
    rod_scene d = rod_scene_default();
    for (int i = 0; i < 3; i++) assert_true(s.gravity[i] == 0.0);
    assert_true(s.fold_angle_rel == d.fold_angle_rel);
    assert_int_equal(s.route, ROD_ROUTE_COMPRESS_THEN_FOLD);
    assert_true(s.snap_speed == d.snap_speed);
    assert_true(s.asym_threshold == d.asym_threshold);
    assert_int_equal(s.nodes, 101);
    assert_true(s.shear_modulus == 3.3e8);
}

static void test_file_format_tolerances(void **state)
{
    (void)state;
    rod_scene s;
    cfg_error err;
    /* CRLF line ends, a BOM, indentation, inline comments, blank lines, '#' comments. */
    char text[8192];
    size_t used = (size_t)snprintf(text, sizeof text, "\xEF\xBB\xBF# scene\r\n\r\n");
    for (int i = 0; i < BASE_N; i++)
        used += (size_t)snprintf(text + used, sizeof text - used, "   %s   ; note\r\n", BASE[i]);
    snprintf(text + used, sizeof text - used,
             "[ribbon]\n\tgravity = 0, 0,-9.81\n[protocol]\nroute = together\n");
    cfg_status st = parse(text, NULL, 0, &s, &err);
    char buf[1024];
    if (st) print_error("%s\n", cfg_error_format(&err, buf, sizeof buf));
    assert_int_equal(st, CFG_OK);
    assert_true(s.gravity[2] == -9.81 && s.gravity[0] == 0.0 && s.gravity[1] == 0.0);
    assert_int_equal(s.route, ROD_ROUTE_TOGETHER);
    assert_true(s.length == 1.0);

    const char *forms[] = {"0 0 -9.81", "0,0,-9.81", "0, 0, -9.81", " 0 ,0 , -9.81"};
    for (size_t i = 0; i < sizeof forms / sizeof forms[0]; i++) {
        char tail[64];
        snprintf(tail, sizeof tail, "[ribbon]\ngravity = %s\n", forms[i]);
        s.gravity[2] = 0.0;
        assert_int_equal(parse(scene_edit2(0, NULL, 0, NULL, tail), NULL, 0, &s, &err), CFG_OK);
        assert_true(s.gravity[2] == -9.81);
    }
}

/* ---- refusals in the file ---------------------------------------------------------------- */

static void test_refuses_unknown(void **state)
{
    (void)state;
    expect_line_error(scene_edit(3, "widht = 0.2"), CFG_ERR_UNKNOWN, 3, "ribbon.widht", "width");
    expect_line_error(scene_edit(12, "[meshes]"), CFG_ERR_UNKNOWN, 12, "", "[meshes]");
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[extra]\n"), CFG_ERR_UNKNOWN, 23, "",
                      "[extra]");
    expect_line_error(scene_edit(12, "[Mesh]"), CFG_ERR_UNKNOWN, 12, "", "[Mesh]");
    /* A key of another section. */
    expect_line_error(scene_edit(13, "dt = 1e-3"), CFG_ERR_UNKNOWN, 13, "mesh.dt", NULL);
}

static void test_refuses_duplicate(void **state)
{
    (void)state;
    expect_line_error(scene_edit(3, "length = 2"), CFG_ERR_DUPLICATE, 3, "ribbon.length",
                      "line 2");
    /* Twice across two [ribbon] blocks. */
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[ribbon]\ndensity = 900\n"),
                      CFG_ERR_DUPLICATE, 24, "ribbon.density", "line 7");
}

static void test_refuses_malformed_lines(void **state)
{
    (void)state;
    expect_line_error(scene_edit(4, "thickness 1e-3"), CFG_ERR_SYNTAX, 4, "", "key = value");
    expect_line_error(scene_edit(4, "thickness: 1e-3"), CFG_ERR_SYNTAX, 4, "", "':'");
    expect_line_error(scene_edit(8, "[folds"), CFG_ERR_SYNTAX, 8, "", "']'");
    expect_line_error(scene_edit(8, "[folds] x"), CFG_ERR_SYNTAX, 8, "", "after the section");
    expect_line_error(scene_edit(4, "= 1e-3"), CFG_ERR_SYNTAX, 4, "ribbon.", "empty key");
    /* A key before any section. */
    char text[8192 + 16];
    snprintf(text, sizeof text, "length = 1\n%s", scene_edit(0, NULL));
    expect_line_error(text, CFG_ERR_SYNTAX, 1, "length", "before any [section]");
    /* A line longer than the limit. */
    char longline[400];
    memset(longline, '1', sizeof longline);
    memcpy(longline, "width = 0.", 10);
    longline[sizeof longline - 1] = '\0';
    expect_line_error(scene_edit(3, longline), CFG_ERR_SYNTAX, 3, "", "longer than");
    /* A NUL byte inside line 5. */
    const char *base = scene_edit(0, NULL);
    size_t len = strlen(base);
    char *copy = malloc(len);
    assert_non_null(copy);
    memcpy(copy, base, len);
    char *l5 = strstr(copy, "youngs_modulus");
    assert_non_null(l5);
    l5[3] = '\0';
    rod_scene s;
    cfg_error err;
    assert_int_equal(cfg_scene_parse("test.ini", copy, len, NULL, 0, &s, &err), CFG_ERR_SYNTAX);
    assert_int_equal(err.line, 5);
    assert_non_null(strstr(err.message, "NUL"));
    free(copy);
}

static void test_refuses_bad_values(void **state)
{
    (void)state;
    expect_line_error(scene_edit(3, "width ="), CFG_ERR_VALUE, 3, "ribbon.width", "empty");
    expect_line_error(scene_edit(3, "width =   ; comment only"), CFG_ERR_VALUE, 3, "ribbon.width",
                      "empty");
    expect_line_error(scene_edit(2, "length = 1.0abc"), CFG_ERR_VALUE, 2, "ribbon.length",
                      "'abc'");
    expect_line_error(scene_edit(2, "length = 1.0 m"), CFG_ERR_VALUE, 2, "ribbon.length", "'m'");
    expect_line_error(scene_edit(2, "length = 1;x"), CFG_ERR_VALUE, 2, "ribbon.length", NULL);
    expect_line_error(scene_edit(2, "length = one"), CFG_ERR_VALUE, 2, "ribbon.length",
                      "not a number");
    expect_line_error(scene_edit(2, "length = nan"), CFG_ERR_VALUE, 2, "ribbon.length", "finite");
    expect_line_error(scene_edit(2, "length = inf"), CFG_ERR_VALUE, 2, "ribbon.length", "finite");
    expect_line_error(scene_edit(5, "youngs_modulus = -infinity"), CFG_ERR_VALUE, 5,
                      "ribbon.youngs_modulus", "finite");
    expect_line_error(scene_edit(7, "density = 1e999"), CFG_ERR_VALUE, 7, "ribbon.density",
                      "finite");
    expect_line_error(scene_edit(13, "nodes = 101.5"), CFG_ERR_VALUE, 13, "mesh.nodes",
                      "integer");
    expect_line_error(scene_edit(13, "nodes = 1e2"), CFG_ERR_VALUE, 13, "mesh.nodes", "integer");
    expect_line_error(scene_edit(13, "nodes = 101x"), CFG_ERR_VALUE, 13, "mesh.nodes", NULL);
    expect_line_error(scene_edit(22, "max_iterations = many"), CFG_ERR_VALUE, 22,
                      "solver.max_iterations", "integer");
    /* Vectors. */
    expect_line_error(scene_edit(7, "gravity = 0 0"), CFG_ERR_VALUE, 7, "ribbon.gravity", "three");
    expect_line_error(scene_edit(7, "gravity = 0 0 -9.81 1"), CFG_ERR_VALUE, 7, "ribbon.gravity",
                      NULL);
    expect_line_error(scene_edit(7, "gravity = 0,,0,-9.81"), CFG_ERR_VALUE, 7, "ribbon.gravity",
                      NULL);
    expect_line_error(scene_edit(7, "gravity = 0 0 nan"), CFG_ERR_VALUE, 7, "ribbon.gravity",
                      "finite");
    expect_line_error(scene_edit(7, "gravity = 0 0 -1e4"), CFG_ERR_RANGE, 7, "ribbon.gravity",
                      "component 3");
    /* Enum. */
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[protocol]\nroute = sideways\n"),
                      CFG_ERR_VALUE, 24, "protocol.route", "compress-then-fold | together");
}

static void test_refuses_out_of_range(void **state)
{
    (void)state;
    struct {
        int line;
        const char *text;
        const char *key;
    } cases[] = {
        {2, "length = -1", "ribbon.length"},
        {2, "length = 0", "ribbon.length"},
        {2, "length = 1e6", "ribbon.length"},
        {3, "width = 0", "ribbon.width"},
        {4, "thickness = -1e-3", "ribbon.thickness"},
        {5, "youngs_modulus = -1e9", "ribbon.youngs_modulus"},
        {6, "shear_modulus = 0", "ribbon.shear_modulus"},
        {7, "density = 0", "ribbon.density"},
        {9, "angle_deg = 180", "folds.angle_deg"},
        {9, "angle_deg = -180", "folds.angle_deg"},
        {9, "angle_deg = 270", "folds.angle_deg"},
        {10, "position = 0", "folds.position"},
        {10, "position = 0.5", "folds.position"},
        {10, "position = 0.6", "folds.position"},
        {10, "position = -0.1", "folds.position"},
        {11, "stiffness_factor = 0.5", "folds.stiffness_factor"},
        {13, "nodes = 4", "mesh.nodes"},
        {13, "nodes = -5", "mesh.nodes"},
        {13, "nodes = 100002", "mesh.nodes"},
        {13, "nodes = 99999999999999999999", "mesh.nodes"},
        {15, "compression = 1", "protocol.compression"},
        {15, "compression = -0.1", "protocol.compression"},
        {16, "shear_rate = 0", "protocol.shear_rate"},
        {17, "shear_max = -0.5", "protocol.shear_max"},
        {19, "dt = 0", "solver.dt"},
        {19, "dt = -1e-3", "solver.dt"},
        {20, "damping = -1", "solver.damping"},
        {21, "tolerance = 0", "solver.tolerance"},
        {21, "tolerance = -1e-8", "solver.tolerance"},
        {22, "max_iterations = 0", "solver.max_iterations"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        expect_line_error(scene_edit(cases[i].line, cases[i].text), CFG_ERR_RANGE, cases[i].line,
                          cases[i].key, "out of range");
    /* The bounds themselves, where allowed, are accepted. */
    rod_scene s;
    cfg_error err;
    assert_int_equal(parse(scene_edit(13, "nodes = 100001"), NULL, 0, &s, &err), CFG_OK);
    assert_int_equal(parse(scene_edit(20, "damping = 0"), NULL, 0, &s, &err), CFG_OK);
    assert_int_equal(parse(scene_edit(22, "max_iterations = 1"), NULL, 0, &s, &err), CFG_OK);
    assert_int_equal(parse(scene_edit(9, "angle_deg = 0"), NULL, 0, &s, &err), CFG_OK);
    /* 180 deg names its reason. */
    expect_line_error(scene_edit(9, "angle_deg = 180"), CFG_ERR_RANGE, 9, "folds.angle_deg",
                      "flat onto itself");
}

static void test_refuses_missing(void **state)
{
    (void)state;
    /* A key missing from its section: named at the section header. */
    expect_line_error(scene_edit(7, NULL), CFG_ERR_MISSING, 1, "ribbon.density", "missing");
    expect_line_error(scene_edit(19, NULL), CFG_ERR_MISSING, 18, "solver.dt", "missing");
    expect_line_error(scene_edit(10, NULL), CFG_ERR_MISSING, 8, "folds.position", "missing");
    /* A whole section missing: named at the end of the file. */
    expect_line_error(scene_edit2(12, NULL, 13, NULL, NULL), CFG_ERR_MISSING, BASE_N,
                      "mesh.nodes", "no such section");
    /* An empty file. */
    rod_scene s;
    cfg_error err;
    assert_int_equal(parse("", NULL, 0, &s, &err), CFG_ERR_MISSING);
    assert_string_equal(err.key, "ribbon.length");
    assert_int_equal(err.origin, CFG_ORIGIN_FILE);
    /* Every required key of the table is enforced. */
    size_t n;
    const cfg_scene_key *keys = cfg_scene_keys(&n);
    int required = 0;
    for (int line = 1; line <= BASE_N; line++) {
        if (BASE[line - 1][0] == '[') continue;
        assert_int_equal(parse(scene_edit(line, NULL), NULL, 0, &s, &err), CFG_ERR_MISSING);
        required++;
    }
    int table_required = 0;
    for (size_t i = 0; i < n; i++)
        if (keys[i].flags & CFG_KEY_REQUIRED) table_required++;
    assert_int_equal(required, table_required);
}

/* ---- physics checks at load --------------------------------------------------------------- */

static void test_refuses_impossible_scenes(void **state)
{
    (void)state;
    /* A fold inside the clamp: N = 21 gives edges of 1/18 of l; Gamma = 0.02 is inside. */
    expect_line_error(scene_edit2(13, "nodes = 21", 10, "position = 0.02", NULL), CFG_ERR_CHECK,
                      10, "folds.position", "inside the clamp");
    /* Stiff 175 deg creases on a nearly uncompressed ribbon. */
    expect_line_error(scene_edit2(9, "angle_deg = 175", 15, "compression = 0.01", NULL),
                      CFG_ERR_CHECK, 15, "protocol.compression", "cannot be clamped");
    /* A cross-field error on a key the file did not set is named "default". */
    rod_scene s;
    cfg_error err;
    char shown[1024];
    assert_int_equal(parse(scene_edit(9, "angle_deg = 179.99995"), NULL, 0, &s, &err),
                     CFG_ERR_CHECK);
    cfg_error_format(&err, shown, sizeof shown);
    print_message("  refused: %s\n", shown);
    assert_int_equal(err.origin, CFG_ORIGIN_DEFAULT);
    assert_string_equal(err.key, "imperfection.fold_angle_rel");
    assert_non_null(strstr(shown, "test.ini:default: imperfection.fold_angle_rel: "));
    /* ... and "--set" when an override set it last. */
    const char *ovr[] = {"folds.position=0.02", "mesh.nodes=21"};
    assert_int_equal(parse(scene_edit(0, NULL), ovr, 2, &s, &err), CFG_ERR_CHECK);
    cfg_error_format(&err, shown, sizeof shown);
    print_message("  refused: %s\n", shown);
    assert_int_equal(err.origin, CFG_ORIGIN_OVERRIDE);
    assert_string_equal(err.where, "folds.position=0.02");
    assert_non_null(strstr(shown, "--set folds.position=0.02: folds.position: "));
}

/* ---- overrides ---------------------------------------------------------------------------- */

static void test_overrides_apply(void **state)
{
    (void)state;
    rod_scene s;
    cfg_error err;
    const char *ovr[] = {"mesh.nodes=51", " ribbon.gravity = 0,0,-9.81 ", "protocol.route=together",
                         "imperfection.fold_angle_rel=1e-8", "mesh.nodes=61", "snap.speed=2"};
    assert_int_equal(parse(scene_edit(0, NULL), ovr, 6, &s, &err), CFG_OK);
    assert_int_equal(s.nodes, 61); /* the later override wins */
    assert_true(s.gravity[2] == -9.81);
    assert_int_equal(s.route, ROD_ROUTE_TOGETHER);
    assert_true(s.fold_angle_rel == 1e-8);
    assert_true(s.snap_speed == 2.0);

    /* The shipped scene with the brief's overrides. */
    const char *ovr2[] = {"folds.position=0.21", "solver.dt=2e-3"};
    assert_int_equal(cfg_scene_load(RIBBON_SOURCE_DIR "/config/scenes/paper-gamma013.ini", ovr2,
                                    2, &s, &err),
                     CFG_OK);
    assert_true(s.fold_position == 0.21 && s.dt == 2e-3);
}

/* cfg_scene_apply: overrides on a scene already loaded, with the loader's rules; a refused one
 * leaves *out untouched and names the override. */
static void test_apply_to_loaded_scene(void **state)
{
    (void)state;
    rod_scene base, s;
    cfg_error err;
    assert_int_equal(cfg_scene_load(RIBBON_SOURCE_DIR "/config/scenes/paper-gamma013.ini", NULL, 0, &base, &err),
                     CFG_OK);
    const char *ovr[] = {"folds.angle_deg=-86", "mesh.nodes = 121", "folds.angle_deg=-85"};
    assert_int_equal(cfg_scene_apply(&base, "twin", ovr, 3, &s, &err), CFG_OK);
    assert_true(REL_CLOSE(s.fold_angle_deg, -85.0));
    assert_int_equal(s.nodes, 121);
    assert_true(REL_CLOSE(s.length, base.length));
    assert_true(REL_CLOSE(base.fold_angle_deg, -90.0));
    rod_scene keep = s;
    const char *bad[] = {"mesh.nodes=61", "folds.nope=1"};
    assert_int_equal(cfg_scene_apply(&base, "twin", bad, 2, &s, &err), CFG_ERR_UNKNOWN);
    assert_int_equal(err.origin, CFG_ORIGIN_OVERRIDE);
    assert_string_equal(err.where, "folds.nope=1");
    assert_int_equal(s.nodes, keep.nodes);
    assert_true(REL_CLOSE(s.fold_angle_deg, keep.fold_angle_deg));
    const char *clamp[] = {"folds.position=0.001"};
    assert_int_equal(cfg_scene_apply(&base, "twin", clamp, 1, &s, &err), CFG_ERR_CHECK);
    assert_string_equal(err.key, "folds.position");
    assert_string_equal(err.where, "folds.position=0.001");
    const char *coarse[] = {"mesh.nodes=9"}; /* blames folds.position, which base set */
    assert_int_equal(cfg_scene_apply(&base, "twin", coarse, 1, &s, &err), CFG_ERR_CHECK);
    assert_string_equal(err.key, "folds.position");
    assert_int_equal(cfg_scene_apply(&base, "twin", NULL, 0, &s, &err), CFG_OK);
    assert_int_equal(s.nodes, base.nodes);
    assert_true(REL_CLOSE(s.fold_angle_deg, base.fold_angle_deg));
}

static void test_overrides_refused(void **state)
{
    (void)state;
    expect_override_error("mesh.nodez=5", CFG_ERR_UNKNOWN, "mesh.nodez", "unknown key");
    expect_override_error("nodes=5", CFG_ERR_UNKNOWN, "nodes", NULL);
    expect_override_error("meshnodes", CFG_ERR_SYNTAX, "", "section.key=value");
    expect_override_error("mesh.nodes=", CFG_ERR_VALUE, "mesh.nodes", "empty");
    expect_override_error("mesh.nodes=abc", CFG_ERR_VALUE, "mesh.nodes", "integer");
    expect_override_error("mesh.nodes=4", CFG_ERR_RANGE, "mesh.nodes", "out of range");
    expect_override_error("ribbon.length=nan", CFG_ERR_VALUE, "ribbon.length", "finite");
    expect_override_error("ribbon.length=2m", CFG_ERR_VALUE, "ribbon.length", "'m'");
    /* One number grammar (cfg_number.h): plain decimal, no hex floats (issue 17, defect 11). */
    expect_override_error("protocol.compression=0x1p-1", CFG_ERR_VALUE, "protocol.compression",
                          "plain decimal");
    expect_override_error("ribbon.length=0x1", CFG_ERR_VALUE, "ribbon.length", "plain decimal");
    expect_override_error("ribbon.length=-inf", CFG_ERR_VALUE, "ribbon.length", "finite");
    /* A subnormal thickness (issue 17, item 12: `equilibrium` exited 0 and omitted residual). */
    expect_override_error("ribbon.thickness=1e-310", CFG_ERR_VALUE, "ribbon.thickness", "subnormal");
    expect_override_error("protocol.route=back", CFG_ERR_VALUE, "protocol.route", "together");
    /* A failed load leaves the caller's scene untouched. */
    rod_scene s;
    memset(&s, 0x5a, sizeof s);
    rod_scene before = s;
    cfg_error err;
    const char *ovr[] = {"mesh.nodes=4"};
    assert_int_not_equal(parse(scene_edit(0, NULL), ovr, 1, &s, &err), CFG_OK);
    assert_memory_equal(&s, &before, sizeof s);
}

static void test_io_errors(void **state)
{
    (void)state;
    rod_scene s;
    cfg_error err;
    char shown[1024];
    assert_int_equal(cfg_scene_load("/nonexistent/scene.ini", NULL, 0, &s, &err), CFG_ERR_IO);
    cfg_error_format(&err, shown, sizeof shown);
    assert_non_null(strstr(shown, "/nonexistent/scene.ini: cannot open"));
    assert_int_equal(cfg_scene_load(RIBBON_SOURCE_DIR "/config", NULL, 0, &s, &err), CFG_ERR_IO);
    assert_int_equal(cfg_scene_load(NULL, NULL, 0, &s, &err), CFG_ERR_IO);
    /* A NULL error pointer is allowed. */
    assert_int_equal(cfg_scene_load("/nonexistent/scene.ini", NULL, 0, &s, NULL), CFG_ERR_IO);
}

/* Only regular files are read (issue 17, defect 9): a FIFO with no writer used to block the
 * open for ever; a directory and a device are named as what they are. alarm() turns a hang into
 * a failure. */
static void test_only_regular_files(void **state)
{
    (void)state;
    rod_scene s;
    cfg_error err;
    char dir[] = "/tmp/ribbon-scene-fifo-XXXXXX", fifo[64];
    assert_non_null(mkdtemp(dir));
    snprintf(fifo, sizeof fifo, "%s/scene.ini", dir);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    alarm(10);
    assert_int_equal(cfg_scene_load(fifo, NULL, 0, &s, &err), CFG_ERR_IO);
    alarm(0);
    assert_non_null(strstr(err.message, "not a regular file (a FIFO)"));
    assert_int_equal(cfg_scene_load(dir, NULL, 0, &s, &err), CFG_ERR_IO);
    assert_non_null(strstr(err.message, "not a regular file (a directory)"));
    assert_int_equal(cfg_scene_load("/dev/zero", NULL, 0, &s, &err), CFG_ERR_IO);
    assert_non_null(strstr(err.message, "not a regular file (a character device)"));
    unlink(fifo);
    rmdir(dir);
}

/* The "Scene files" table of docs/config.md (the reference the README points to) documents every key of the table. */
static void test_readme_documents_every_key(void **state)
{
    (void)state;
    size_t len;
    char *readme = file_read(RIBBON_SOURCE_DIR "/docs/config.md", &len);
    assert_non_null(readme);
    const char *sec = strstr(readme, "## Scene files");
    assert_non_null(sec);
    size_t n;
    const cfg_scene_key *keys = cfg_scene_keys(&n);
    for (size_t i = 0; i < n; i++) {
        char row[128];
        snprintf(row, sizeof row, "| %s | %s |", keys[i].section, keys[i].name);
        if (!strstr(sec, row)) print_error("docs/config.md lacks the row '%s'\n", row);
        assert_non_null(strstr(sec, row));
    }
    free(readme);
}


/* ---- per-crease keys and hinges (issue 31) ------------------------------------------------ */

static void test_crease_keys(void **state)
{
    (void)state;
    rod_scene s;
    cfg_error err;
    char shown[1024];
    /* Unset per-crease keys follow the pair; a compliant hinge needs no stiffness_factor. */
    assert_int_equal(parse(scene_edit(0, NULL), NULL, 0, &s, &err), CFG_OK);
    assert_true(rod_scene_hinge_rigid(&s));
    assert_true(rod_scene_crease_angle_deg(&s, 0) == 90.0 && rod_scene_crease_angle_deg(&s, 1) == 90.0);
    assert_true(rod_scene_crease_position(&s, 0) == 0.21 && rod_scene_crease_position(&s, 1) == 1.0 - 0.21);
    assert_int_equal(parse(scene_edit2(11, "hinge_stiffness = 2.5e-3", 0, NULL,
                                       "[folds]\nangle_left_deg = 88\nangle_right_deg = 91\n"
                                       "position_left = 0.2\nposition_right = 0.81\n"),
                           NULL, 0, &s, &err),
                     CFG_OK);
    assert_true(s.fold_hinge_stiffness == 2.5e-3 && !rod_scene_hinge_rigid(&s));
    assert_true(rod_scene_crease_angle_deg(&s, 0) == 88.0 && rod_scene_crease_angle_deg(&s, 1) == 91.0);
    assert_true(rod_scene_crease_position(&s, 0) == 0.2 && rod_scene_crease_position(&s, 1) == 0.81);
    /* `rigid` by name; without it the file's rigid creases need stiffness_factor. */
    assert_int_equal(parse(scene_edit(0, "x"), NULL, 0, &s, &err), CFG_OK);
    assert_int_equal(parse(scene_edit2(0, NULL, 0, NULL, "[folds]\nhinge_stiffness = rigid\n"), NULL, 0, &s, &err),
                     CFG_OK);
    assert_true(rod_scene_hinge_rigid(&s));
    expect_line_error(scene_edit2(11, NULL, 0, NULL, "[folds]\nhinge_stiffness = rigid\n"), CFG_ERR_MISSING, 8,
                      "folds.stiffness_factor", "required");
    /* Bad hinge stiffnesses, named. */
    expect_line_error(scene_edit(11, "hinge_stiffness = 0"), CFG_ERR_RANGE, 11, "folds.hinge_stiffness",
                      "or rigid");
    expect_line_error(scene_edit(11, "hinge_stiffness = -1e-3"), CFG_ERR_RANGE, 11, "folds.hinge_stiffness",
                      "out of range");
    expect_line_error(scene_edit(11, "hinge_stiffness = nan"), CFG_ERR_VALUE, 11, "folds.hinge_stiffness",
                      "or rigid");
    expect_line_error(scene_edit(11, "hinge_stiffness = rigidd"), CFG_ERR_VALUE, 11, "folds.hinge_stiffness",
                      NULL);
    expect_override_error("folds.hinge_stiffness=0", CFG_ERR_RANGE, "folds.hinge_stiffness", "out of range");
    expect_override_error("folds.hinge_stiffness=-2", CFG_ERR_RANGE, "folds.hinge_stiffness", NULL);
    expect_override_error("folds.hinge_stiffness=NaN", CFG_ERR_VALUE, "folds.hinge_stiffness", NULL);
    /* Contradictory keys: stiffness_factor with a compliant hinge in the same file, or by --set. */
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nhinge_stiffness = 1e-3\n"), CFG_ERR_CHECK, 11,
                      "folds.stiffness_factor", "applies only to rigid creases");
    {
        const char *list[] = {"folds.stiffness_factor=10"};
        assert_int_equal(parse(scene_edit(11, "hinge_stiffness = 1e-3"), list, 1, &s, &err), CFG_ERR_CHECK);
        cfg_error_format(&err, shown, sizeof shown);
        print_message("  refused: %s\n", shown);
        assert_string_equal(err.key, "folds.stiffness_factor");
        assert_int_equal(err.origin, CFG_ORIGIN_OVERRIDE);
    }
    /* Each crease's own hinge (issue 32): read, defaulting to the pair's; refused beside rigid
       creases and when not positive. */
    {
        const char *list[] = {"folds.hinge_stiffness=1e-3", "folds.hinge_stiffness_right=2e-3"};
        assert_int_equal(parse(scene_edit(0, NULL), list, 2, &s, &err), CFG_OK);
        assert_true(rod_scene_hinge_k(&s, 0) == 1e-3 && rod_scene_hinge_k(&s, 1) == 2e-3);
        const char *rigid[] = {"folds.hinge_stiffness_left=2e-3"};
        assert_int_equal(parse(scene_edit(0, NULL), rigid, 1, &s, &err), CFG_ERR_CHECK);
        cfg_error_format(&err, shown, sizeof shown);
        print_message("  refused: %s\n", shown);
        assert_string_equal(err.key, "folds.hinge_stiffness_left");
        assert_non_null(strstr(err.message, "needs compliant creases"));
    }
    expect_override_error("folds.hinge_stiffness_left=0", CFG_ERR_RANGE, "folds.hinge_stiffness_left", "out of range");
    /* ... while --set hinge_stiffness over a rigid file replaces the crease model. */
    {
        const char *list[] = {"folds.hinge_stiffness=1e-3"};
        assert_int_equal(parse(scene_edit(0, NULL), list, 1, &s, &err), CFG_OK);
        assert_true(s.fold_hinge_stiffness == 1e-3);
    }
    /* Per-crease angles: range, opposite ways, 180 through the imperfection, the clamp rule with
     * each crease's own angle (a pair of 10 deg creases clamps at Delta L = 0.05, one of 170 deg
     * beside a 10 deg one does not). */
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nangle_left_deg = 180\n"), CFG_ERR_RANGE, 24,
                      "folds.angle_left_deg", "out of range");
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nangle_right_deg = -90\n"), CFG_ERR_CHECK, 24,
                      "folds.angle_right_deg", "opposite ways");
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nangle_right_deg = 179.99\n[imperfection]\nfold_angle_rel = -0.01\n"),
                      CFG_ERR_CHECK, 26, "imperfection.fold_angle_rel", "180");
    assert_int_equal(parse(scene_edit2(9, "angle_deg = 10", 15, "compression = 0.05", NULL), NULL, 0, &s, &err),
                     CFG_OK);
    expect_line_error(scene_edit2(9, "angle_deg = 10", 15, "compression = 0.05", "[folds]\nangle_right_deg = 170\n"),
                      CFG_ERR_CHECK, 15, "protocol.compression", "creases of 10 and 170 deg cannot be clamped");
    /* Positions: outside (0, 1), crossing, inside a clamp, closer than one edge. */
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nposition_right = 1\n"), CFG_ERR_RANGE, 24,
                      "folds.position_right", "out of range");
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nposition_left = 0.6\nposition_right = 0.4\n"),
                      CFG_ERR_CHECK, 25, "folds.position_right", "cross");
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nposition_left = 0.8\n"), CFG_ERR_CHECK, 24,
                      "folds.position_left", "cross");
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nposition_left = 0.005\n"), CFG_ERR_CHECK, 24,
                      "folds.position_left", "inside the clamp");
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nposition_right = 0.995\n"), CFG_ERR_CHECK, 24,
                      "folds.position_right", "inside the clamp");
    expect_line_error(scene_edit2(0, NULL, 0, NULL, "[folds]\nposition_left = 0.5\nposition_right = 0.505\n"),
                      CFG_ERR_CHECK, 25, "folds.position_right", "closer than one edge");
    /* A scene built by hand gets the same refusals from rod_scene_check, NaN included. */
    rod_scene h = rod_scene_default();
    char msg[256], key[64];
    const double bad_k[] = {0.0, -1.0, NAN};
    for (int i = 0; i < 3; i++) {
        h.fold_hinge_stiffness = bad_k[i];
        assert_int_equal(rod_scene_check(&h, msg, sizeof msg, key, sizeof key), 1);
        print_message("  rod_scene_check: %s: %s\n", key, msg);
        assert_string_equal(key, "folds.hinge_stiffness");
    }
    h = rod_scene_default();
    h.fold_angle_left_deg = INFINITY;
    assert_int_equal(rod_scene_check(&h, msg, sizeof msg, key, sizeof key), 1);
    assert_string_equal(key, "folds.angle_left_deg");
    h = rod_scene_default();
    h.fold_position_left = 0.9;
    h.fold_position_right = 0.1;
    assert_int_equal(rod_scene_check(&h, msg, sizeof msg, key, sizeof key), 1);
    assert_string_equal(key, "folds.position_right");
}

/* ---- fuzz --------------------------------------------------------------------------------- */

static uint64_t rng_next(uint64_t *x)
{
    /* xorshift64*: deterministic across platforms, good enough to pick mutations. */
    *x ^= *x >> 12;
    *x ^= *x << 25;
    *x ^= *x >> 27;
    return *x * 2685821657736338717ull;
}

static size_t rng_below(uint64_t *x, size_t n)
{
    return n ? (size_t)(rng_next(x) % n) : 0;
}

static const char *const FRAGMENTS[] = {
    "[ribbon]", "[folds]", "[mesh]", "[snap]", "[", "]", "=", "nodes = 5", "nodes = 100001",
    "position = 0.499999", "angle_deg = 179.9", "compression = 0.999", "gravity = 1e3 -1e3 0",
    "dt = 1e-300", "length = 1e-300", "route = together", "tolerance = 0.999999",
    "nan", "inf", "1e308", "-0", "0x1p-3", ";", "#", "\t", "\r", "\xEF\xBB\xBF", "\xff\xfe",
    "length = 1 ; =", "width = 0.2 0.3", "[ribbon] ; c", "fold_angle_rel = -1",
};
#define N_FRAGMENTS (sizeof FRAGMENTS / sizeof FRAGMENTS[0])

/* One mutation of src (len bytes) into dst (capacity cap); returns the new length. */
static size_t mutate(uint64_t *rng, const char *src, size_t len, char *dst, size_t cap)
{
    size_t n = len < cap ? len : cap;
    memcpy(dst, src, n);
    int kind = (int)rng_below(rng, 6);
    switch (kind) {
    case 0: { /* flip a few bytes to random values */
        int flips = 1 + (int)rng_below(rng, 4);
        for (int i = 0; i < flips && n; i++) dst[rng_below(rng, n)] = (char)rng_below(rng, 256);
        break;
    }
    case 1: /* truncate */
        n = rng_below(rng, n + 1);
        break;
    case 2: { /* delete a range */
        size_t a = rng_below(rng, n + 1), b = a + rng_below(rng, 64);
        if (b > n) b = n;
        memmove(dst + a, dst + b, n - b);
        n -= b - a;
        break;
    }
    case 3:   /* insert a fragment, maybe as its own line */
    case 4: {
        const char *f = FRAGMENTS[rng_below(rng, N_FRAGMENTS)];
        size_t fl = strlen(f), at = rng_below(rng, n + 1);
        int line = kind == 4;
        size_t add = fl + (line ? 1 : 0);
        if (n + add > cap) break;
        memmove(dst + at + add, dst + at, n - at);
        memcpy(dst + at, f, fl);
        if (line) dst[at + fl] = '\n';
        n += add;
        break;
    }
    default: { /* duplicate a random chunk at another place */
        size_t a = rng_below(rng, n + 1), l = rng_below(rng, 80), at = rng_below(rng, n + 1);
        if (a + l > n) l = n - a;
        if (n + l > cap) break;
        char tmp[80];
        memcpy(tmp, dst + a, l);
        memmove(dst + at + l, dst + at, n - at);
        memcpy(dst + at, tmp, l);
        n += l;
        break;
    }
    }
    return n;
}

static void scene_assert_sane(const rod_scene *s)
{
    const double *d[] = {&s->length, &s->width, &s->thickness, &s->youngs_modulus,
                         &s->shear_modulus, &s->density, &s->gravity[0], &s->gravity[1],
                         &s->gravity[2], &s->fold_angle_deg, &s->fold_position,
                         &s->fold_stiffness_factor, &s->fold_angle_rel, &s->compression,
                         &s->shear_rate, &s->shear_max, &s->dt, &s->damping, &s->tolerance,
                         &s->snap_speed, &s->asym_threshold};
    for (size_t i = 0; i < sizeof d / sizeof d[0]; i++) assert_true(isfinite(*d[i]));
    /* The per-crease keys are unset (NaN) or finite; the hinge finite and positive, or rigid. */
    const double *o[] = {&s->fold_angle_left_deg, &s->fold_angle_right_deg, &s->fold_position_left,
                         &s->fold_position_right};
    for (size_t i = 0; i < sizeof o / sizeof o[0]; i++) assert_true(isnan(*o[i]) || isfinite(*o[i]));
    assert_true(rod_scene_hinge_rigid(s) || (isfinite(s->fold_hinge_stiffness) && s->fold_hinge_stiffness > 0));
    assert_true(s->nodes >= 5 && s->nodes <= 100001);
    assert_true(s->max_iterations >= 1);
    assert_true(s->length > 0 && s->width > 0 && s->thickness > 0 && s->dt > 0);
    assert_true(s->route == ROD_ROUTE_COMPRESS_THEN_FOLD || s->route == ROD_ROUTE_TOGETHER);
    assert_int_equal(rod_scene_check(s, NULL, 0, NULL, 0), 0);
}

static void test_fuzz_mutated_scenes(void **state)
{
    (void)state;
    const char *files[] = {RIBBON_SOURCE_DIR "/config/scenes/paper-gamma013.ini",
                           RIBBON_SOURCE_DIR "/config/scenes/paper-gamma021.ini",
                           RIBBON_SOURCE_DIR "/config/scenes/pet-200x5.ini"};
    enum { CASES = 6000, CAP = 8192 };
    uint64_t rng = 0x9E3779B97F4A7C15ull;
    int ok = 0, refused = 0;
    for (size_t f = 0; f < 3; f++) {
        size_t len;
        char *src = file_read(files[f], &len);
        assert_non_null(src);
        assert_true(len < CAP);
        char work[CAP];
        for (int c = 0; c < CASES / 3; c++) {
            size_t n = len;
            memcpy(work, src, len);
            int rounds = 1 + (int)rng_below(&rng, 3);
            for (int r = 0; r < rounds; r++) {
                char tmp[CAP];
                n = mutate(&rng, work, n, tmp, CAP);
                memcpy(work, tmp, n);
            }
            /* An exact-size heap copy, so that ASan sees any read past the end. */
            char *text = malloc(n ? n : 1);
            assert_non_null(text);
            memcpy(text, work, n);
            rod_scene s;
            memset(&s, 0, sizeof s);
            cfg_error err;
            cfg_status st = cfg_scene_parse("fuzz.ini", text, n, NULL, 0, &s, &err);
            if (st == CFG_OK) {
                scene_assert_sane(&s);
                ok++;
            } else {
                assert_int_equal(err.status, st);
                assert_true(err.message[0] != '\0');
                assert_string_equal(err.origin == CFG_ORIGIN_OVERRIDE ? "fuzz.ini" : err.file,
                                    "fuzz.ini");
                char shown[1024];
                cfg_error_format(&err, shown, sizeof shown);
                assert_true(strlen(shown) > strlen("fuzz.ini: "));
                refused++;
            }
            free(text);
        }
        free(src);
    }
    print_message("  fuzz: %d loaded, %d refused\n", ok, refused);
    /* Both outcomes must occur, or the mutations are not exercising the loader. */
    assert_true(ok > 50);
    assert_true(refused > 500);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_paper_scenes_load),
        cmocka_unit_test(test_pet_scene_loads),
        cmocka_unit_test(test_optional_keys_default),
        cmocka_unit_test(test_file_format_tolerances),
        cmocka_unit_test(test_refuses_unknown),
        cmocka_unit_test(test_refuses_duplicate),
        cmocka_unit_test(test_refuses_malformed_lines),
        cmocka_unit_test(test_refuses_bad_values),
        cmocka_unit_test(test_refuses_out_of_range),
        cmocka_unit_test(test_refuses_missing),
        cmocka_unit_test(test_refuses_impossible_scenes),
        cmocka_unit_test(test_overrides_apply),
        cmocka_unit_test(test_overrides_refused),
        cmocka_unit_test(test_apply_to_loaded_scene),
        cmocka_unit_test(test_io_errors),
        cmocka_unit_test(test_only_regular_files),
        cmocka_unit_test(test_readme_documents_every_key),
        cmocka_unit_test(test_crease_keys),
        cmocka_unit_test(test_fuzz_mutated_scenes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
