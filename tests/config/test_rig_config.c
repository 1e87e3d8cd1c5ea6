/* test_rig_config.c: the rig file loader (config/rig_config.c).
 *
 * Covers: every shipped rig file loads with the values it states (and the unit file says what the
 * README promises); each section's refusals (unknown key, bad value, duplicate, missing required
 * key per mode) name the file, the line (or the --set, or "default") and "section.key"; the mode
 * rules (virtual clock only in mock, mock rails only in mock, token off loopback, replay sources);
 * the cross-checks against the scene (minimum clamp gap, soft limits, speeds, crease orientation);
 * scene errors passed up unchanged; overrides of rig, rail and scene keys; the rail <-> Delta L,
 * Delta W conversions round-trip with the right signs; the calibration JSON; docs/config.md lists
 * every key; and a deterministic fuzz run over mutated shipped files never crashes.
 * Most cases edit one line of a small complete mock file (BASE) so the expected line is known. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rig_config.h"

#ifndef RIBBON_SOURCE_DIR
#error "RIBBON_SOURCE_DIR must be defined"
#endif

#define CONFIG_DIR RIBBON_SOURCE_DIR "/config"
#define NEAR(a, b) (fabs((a) - (b)) <= 1e-9 * (fabs(b) + 1.0))

/* A small complete mock-mode rig file. Line i + 1 is BASE[i]. */
static const char *const BASE[] = {
    "[rig]",                             /* 1 */
    "mode = mock",                       /* 2 */
    "scene = scenes/paper-gamma013.ini", /* 3 */
    "[rail.compress]",                   /* 4 */
    "driver = mock",                     /* 5 */
    "travel_mm = 700",                   /* 6 */
    "soft_max_mm = 650",                 /* 7 */
    "max_speed_mm_s = 50",               /* 8 */
    "[rail.shear]",                      /* 9 */
    "driver = mock",                     /* 10 */
    "travel_mm = 800",                   /* 11 */
    "soft_max_mm = 750",                 /* 12 */
    "max_speed_mm_s = 50",               /* 13 */
    "[calibration]",                     /* 14 */
    "compress_zero_mm = 50",             /* 15 */
    "shear_zero_mm = 50",                /* 16 */
    "compress_sign = +1",                /* 17 */
    "shear_sign = +1",                   /* 18 */
    "[specimen]",                        /* 19 */
    "min_clamp_gap_mm = 400",            /* 20 */
    "[trial]",                           /* 21 */
    "compress_speed_mm_s = 20",          /* 22 */
    "[camera]",                          /* 23 */
    "fps = 30",                          /* 24 */
    "[detect]",                          /* 25 */
    "dz_jump = 0.02",                    /* 26 */
    "[sim]",                             /* 27 */
    "target_error = 0.01",               /* 28 */
    "[store]",                           /* 29 */
    "path = test.db",                    /* 30 */
    "[api]",                             /* 31 */
    "port = 8377",                       /* 32 */
    "[replay]",                          /* 33 */
    "source_trial = 7",                  /* 34 */
};
#define BASE_N ((int)(sizeof BASE / sizeof BASE[0]))

/* What turns BASE into a rig-mode file (gcode rails, camera, specimen name). */
#define RIG_TAIL                                                                                \
    "[camera]\nsource = /dev/video0\ncalibration = camera.calib\n[specimen]\nname = S1\n"

typedef struct edit {
    int line;         /* 1-based line of BASE to replace, 0 = none */
    const char *text; /* NULL: the line becomes a comment (line numbers do not move) */
} edit;

/* BASE with edits applied and `tail` appended. Returns a static buffer. */
static const char *make(const edit *ed, int n_ed, const char *tail)
{
    static char buf[16384];
    size_t used = 0;
    for (int i = 0; i < BASE_N; i++) {
        const char *line = BASE[i];
        for (int j = 0; j < n_ed; j++)
            if (ed[j].line == i + 1) line = ed[j].text ? ed[j].text : "; (removed)";
        used += (size_t)snprintf(buf + used, sizeof buf - used, "%s\n", line);
    }
    if (tail) snprintf(buf + used, sizeof buf - used, "%s", tail);
    return buf;
}

static const char *make1(int line, const char *text)
{
    edit e = {line, text};
    return make(&e, 1, NULL);
}

/* BASE as a rig-mode file, with one more edit. */
static const char *make_rig(int line, const char *text)
{
    edit e[4] = {{2, "mode = rig"},
                 {5, "driver = gcode"},
                 {10, "driver = gcode"},
                 {line, text}};
    return make(e, line ? 4 : 3, RIG_TAIL);
}

static cfg_status parse_ovr(const char *text, const char *const *ovr, int n, rig_config *out,
                            cfg_error *err)
{
    return rig_config_parse("rig.ini", CONFIG_DIR, text, strlen(text), ovr, n, out, err);
}

static cfg_status parse(const char *text, rig_config *out, cfg_error *err)
{
    return parse_ovr(text, NULL, 0, out, err);
}

static rig_config cfg; /* large: kept out of the stack */

/* The error must have this status, come from this line of rig.ini and name this key. */
static void expect_line(const char *text, cfg_status st, int line, const char *key,
                        const char *needle)
{
    cfg_error err;
    cfg_status got = parse(text, &cfg, &err);
    char buf[1024];
    cfg_error_format(&err, buf, sizeof buf);
    if (got != st || err.origin != CFG_ORIGIN_LINE || err.line != line ||
        strcmp(err.key, key) != 0 || strcmp(err.file, "rig.ini") != 0 ||
        (needle && !strstr(err.message, needle))) {
        print_error("expected status %d at rig.ini:%d key %s (%s); got status %d: %s\n", st, line,
                    key, needle ? needle : "", got, buf);
        fail();
    }
}

static void expect_origin(const char *text, const char *const *ovr, int n, cfg_status st,
                          cfg_origin origin, const char *key, const char *needle)
{
    cfg_error err;
    cfg_status got = parse_ovr(text, ovr, n, &cfg, &err);
    char buf[1024];
    cfg_error_format(&err, buf, sizeof buf);
    if (got != st || err.origin != origin || strcmp(err.key, key) != 0 ||
        (needle && !strstr(buf, needle))) {
        print_error("expected status %d origin %d key %s (%s); got status %d: %s\n", st, origin,
                    key, needle ? needle : "", got, buf);
        fail();
    }
}

/* ---- shipped files ------------------------------------------------------------------------ */

static void load_ok(const char *file, const char *const *ovr, int n)
{
    cfg_error err;
    char path[1024], buf[1024];
    snprintf(path, sizeof path, "%s/%s", CONFIG_DIR, file);
    cfg_status st = rig_config_load(path, ovr, n, &cfg, &err);
    if (st) {
        print_error("%s: %s\n", file, cfg_error_format(&err, buf, sizeof buf));
        fail();
    }
}

static void test_mock_ini(void **state)
{
    (void)state;
    load_ok("mock.ini", NULL, 0);
    assert_int_equal(cfg.mode, RIG_MODE_MOCK);
    assert_int_equal(cfg.clock, RIG_CLOCK_VIRTUAL);
    assert_true(cfg.has_rails);
    assert_string_equal(cfg.compress.driver, "mock");
    assert_true(NEAR(cfg.scene.length, 0.2));
    assert_true(NEAR(cfg.scene.compression, 0.5));
    /* Gap model from the calibration: gap = 250 - x; specimen minimum pushed into the rail. */
    assert_true(NEAR(cfg.compress.params.gap_at_zero_mm, 250.0));
    assert_true(cfg.compress.params.gap_per_mm == -1.0);
    assert_true(NEAR(cfg.compress.params.min_gap_mm, 90.0));
    assert_true(NEAR(cfg.trial.compress_target_mm, 150.0));
    assert_true(NEAR(cfg.trial.shear_end_mm, 170.0));
    assert_true(NEAR(cfg.trial.shear_speed_mm_s, 10.0));
    assert_int_equal(cfg.camera.source, RIG_SOURCE_SYNTHETIC);
    assert_int_equal(cfg.camera.calibration[0], '\0');
    assert_int_equal(cfg.specimen.crease_orientation, RIG_CREASE_DOWN);
    assert_true(isnan(cfg.specimen.crease_angle_left_deg));
    assert_int_equal(cfg.sim.n_ladder, 3);
    assert_int_equal(cfg.sim.ladder_nodes[2], 121);
    assert_false(cfg.sim.explicit_resolution);
    assert_true(cfg.api.loopback);
    assert_int_equal(cfg.api.port, 8377);
    /* Outputs in the working directory, inputs beside the rig file. */
    char cwd[1024], want[1200];
    assert_non_null(getcwd(cwd, sizeof cwd));
    snprintf(want, sizeof want, "%s/ribbon-mock.db", cwd);
    assert_string_equal(cfg.store_path, want);
    snprintf(want, sizeof want, "%s/ribbon-mock-videos", cwd);
    assert_string_equal(cfg.camera.video_dir, want);
    assert_string_equal(cfg.scene_path, CONFIG_DIR "/scenes/mock-gamma013.ini");
    assert_string_equal(cfg.path, CONFIG_DIR "/mock.ini");
    assert_string_equal(cfg.dir, CONFIG_DIR);
    /* The twin is a different strip from the scene: relaxed, unequal creases, a finer mesh and
     * step than the scene's (and the prediction's). */
    assert_true(cfg.twin.present);
    assert_true(NEAR(cfg.scene.fold_angle_deg, -90.0));
    assert_true(NEAR(cfg.twin.scene.fold_angle_deg, -86.0));
    assert_true(fabs(cfg.twin.scene.fold_angle_rel) >= 0.02 && fabs(cfg.twin.scene.fold_angle_rel) <= 0.03);
    assert_true(cfg.twin.scene.nodes > cfg.scene.nodes);
    assert_true(cfg.twin.scene.dt < cfg.scene.dt);
}

/* The rehearsal files' twin (ribbon-rigsim's) differs from their scene the same way. */
static void test_rehearsal_twins(void **state)
{
    (void)state;
    const char *files[] = {"rig-rehearsal.ini", "rig-rehearsal-modbus.ini"};
    for (int i = 0; i < 2; i++) {
        load_ok(files[i], NULL, 0);
        assert_int_equal(cfg.mode, RIG_MODE_RIG);
        assert_true(cfg.twin.present);
        assert_true(NEAR(cfg.twin.scene.fold_angle_deg, -86.0));
        assert_true(NEAR(cfg.twin.scene.fold_angle_rel, 0.025));
        assert_int_equal(cfg.twin.scene.nodes, 91);
        assert_true(cfg.twin.scene.nodes > cfg.sim.nodes && cfg.twin.scene.dt < cfg.sim.dt);
    }
}

static void test_rig_gcode_ini(void **state)
{
    (void)state;
    load_ok("rig-gcode.ini", NULL, 0);
    assert_int_equal(cfg.mode, RIG_MODE_RIG);
    assert_int_equal(cfg.clock, RIG_CLOCK_REAL);
    assert_string_equal(cfg.compress.driver, "gcode");
    assert_int_equal(cfg.compress.gcode.axis, 'X');
    assert_int_equal(cfg.shear.gcode.axis, 'Y');
    assert_true(NEAR(cfg.scene.length, 0.2));
    assert_true(NEAR(cfg.trial.compress_target_mm, 72.5));
    assert_true(NEAR(cfg.trial.shear_end_mm, 120.0));
    assert_true(NEAR(cfg.trial.shear_speed_mm_s, 1.0));
    assert_true(NEAR(cfg.compress.params.min_gap_mm, 120.0));      /* specimen > rail's 60 */
    assert_true(NEAR(cfg.compress.params.gap_at_zero_mm, 212.5));
    assert_int_equal(cfg.camera.source, RIG_SOURCE_DEVICE);
    assert_string_equal(cfg.camera.device, "/dev/video0");
    assert_string_equal(cfg.camera.calibration, CONFIG_DIR "/camera.calib");
    assert_string_equal(cfg.store_path, "/var/lib/ribbon/ribbon.db");
    assert_string_equal(cfg.specimen.name, "PET-200x5 #1");
    assert_true(NEAR(cfg.specimen.crease_angle_left_deg, 88.0));
    assert_true(NEAR(cfg.sim.target_error, 0.005));
}

static void test_rig_modbus_ini(void **state)
{
    (void)state;
    load_ok("rig-modbus.ini", NULL, 0);
    assert_int_equal(cfg.mode, RIG_MODE_RIG);
    assert_string_equal(cfg.shear.driver, "modbus");
    assert_string_equal(cfg.shear.modbus.address, "127.0.0.1:1503");
    assert_int_equal(cfg.camera.source, RIG_SOURCE_INDEX);
    assert_int_equal(cfg.camera.index, 0);
    assert_int_equal(cfg.camera.roi, RIG_ROI_RECT);
    assert_int_equal(cfg.camera.roi_w, 1080);
    assert_int_equal(cfg.calib.camera_side, RIG_CAMERA_BACK);
    assert_true(cfg.sim.explicit_resolution);
    assert_int_equal(cfg.sim.nodes, 101);
    assert_true(NEAR(cfg.sim.dt, 2e-3));
    /* The documented way onto the lab network: a token makes it acceptable. */
    const char *ovr[] = {"api.listen=0.0.0.0", "api.token=0123456789abcdef0123"};
    load_ok("rig-modbus.ini", ovr, 2);
    assert_false(cfg.api.loopback);
    cfg_error err;
    assert_int_equal(rig_config_load(CONFIG_DIR "/rig-modbus.ini", ovr, 1, &cfg, &err),
                     CFG_ERR_MISSING);
    assert_string_equal(err.key, "api.token");
}

static void test_replay_ini(void **state)
{
    (void)state;
    load_ok("replay.ini", NULL, 0);
    assert_int_equal(cfg.mode, RIG_MODE_REPLAY);
    assert_int_equal(cfg.clock, RIG_CLOCK_REAL);
    assert_false(cfg.has_rails);
    assert_int_equal(cfg.camera.source, RIG_SOURCE_NONE);
    assert_true(cfg.replay.source_trial == 1);
    assert_int_equal(cfg.replay.video[0], '\0');
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    static char buf[1 << 20]; /* the docs page may be larger than 64 KiB */
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    return buf;
}

static void test_service_unit(void **state)
{
    (void)state;
    const char *u = slurp(CONFIG_DIR "/ribbond.service");
    assert_non_null(u);
    assert_non_null(strstr(u, "\nType=notify\n"));
    assert_non_null(strstr(u, "\nExecStart=/usr/local/bin/ribbond --config /etc/ribbon/rig.ini\n"));
    assert_non_null(strstr(u, "\nKillSignal=SIGTERM\n"));
    assert_non_null(strstr(u, "\nRestart=on-failure\n"));
    assert_non_null(strstr(u, "NEVER resumes motion"));
}

/* ---- the file format and the key table ------------------------------------------------------ */

static void test_base_loads(void **state)
{
    (void)state;
    cfg_error err;
    char buf[1024];
    cfg_status st = parse(make(NULL, 0, NULL), &cfg, &err);
    if (st) print_error("%s\n", cfg_error_format(&err, buf, sizeof buf));
    assert_int_equal(st, CFG_OK);
    /* Defaults. */
    assert_true(NEAR(cfg.trial.hold_s, 2.0));
    assert_true(NEAR(cfg.trial.return_speed_mm_s, 5.0));
    assert_int_equal(cfg.camera.roi, RIG_ROI_AUTO);
    assert_int_equal(cfg.camera.frozen_frames, 12);
    assert_true(NEAR(cfg.camera.frozen_move_mm, 0.05));
    assert_string_equal(cfg.api.listen, "127.0.0.1");
    assert_string_equal(cfg.specimen.name, "paper-gamma013"); /* the scene file's name */
    assert_string_equal(cfg.camera.video_dir, CONFIG_DIR "/videos");
    assert_string_equal(cfg.store_path, CONFIG_DIR "/test.db");
    st = parse(make_rig(0, NULL), &cfg, &err);
    if (st) print_error("%s\n", cfg_error_format(&err, buf, sizeof buf));
    assert_int_equal(st, CFG_OK);
    assert_int_equal(cfg.clock, RIG_CLOCK_REAL);
}

/* An unknown key in every section, a duplicate, an unknown section, syntax. */
static void test_unknown_and_duplicate(void **state)
{
    (void)state;
    static const struct {
        int line; /* a section header of BASE */
        const char *key;
    } sect[] = {{1, "rig.bogus"},           {4, "rail.compress.bogus"}, {9, "rail.shear.bogus"},
                {14, "calibration.bogus"},  {19, "specimen.bogus"},      {21, "trial.bogus"},
                {23, "camera.bogus"},       {25, "detect.bogus"},        {27, "sim.bogus"},
                {29, "store.bogus"},        {31, "api.bogus"},           {33, "replay.bogus"}};
    for (size_t i = 0; i < sizeof sect / sizeof sect[0]; i++) {
        char line[96];
        snprintf(line, sizeof line, "%s\nbogus = 1", BASE[sect[i].line - 1]);
        /* The header keeps its line; "bogus" lands on the next one. */
        expect_line(make1(sect[i].line, line), CFG_ERR_UNKNOWN, sect[i].line + 1, sect[i].key,
                    "unknown key");
    }
    expect_line(make1(24, "fps = 30\nfps = 25"), CFG_ERR_DUPLICATE, 25, "camera.fps",
                "first on line 24");
    expect_line(make1(8, "max_speed_mm_s = 50\nmax_speed_mm_s = 40"), CFG_ERR_DUPLICATE, 9,
                "rail.compress.max_speed_mm_s", "first on line 8");
    expect_line(make1(33, "[replays]"), CFG_ERR_UNKNOWN, 33, "", "unknown section [replays]");
    expect_line(make1(26, "dz_jump: 0.02"), CFG_ERR_SYNTAX, 26, "", "'=' not ':'");
    expect_line(make1(26, "dz_jump"), CFG_ERR_SYNTAX, 26, "", "key = value");
    expect_line(make1(25, "[detect] x"), CFG_ERR_SYNTAX, 25, "", "after the section header");
}

/* A retired key (documented once, read by nothing) is refused, never silently ignored: the
 * refusal names its line (or --set) and says why it went and what to use instead. */
static void test_retired_keys(void **state)
{
    (void)state;
    expect_line(make1(26, "dz_jump = 0.02\njump_fraction = 0.3"), CFG_ERR_UNKNOWN, 27,
                "detect.jump_fraction", "retired");
    expect_line(make1(26, "dz_jump = 0.02\njump_fraction = 0.3"), CFG_ERR_UNKNOWN, 27,
                "detect.jump_fraction", "detect.dz_jump");
    const char *ovr[] = {"detect.jump_fraction=0.5"};
    expect_origin(make(NULL, 0, NULL), ovr, 1, CFG_ERR_UNKNOWN, CFG_ORIGIN_OVERRIDE,
                  "detect.jump_fraction", "retired");
    /* No shipped file sets it. */
    const char *files[] = {"mock.ini", "rig-gcode.ini", "rig-modbus.ini", "replay.ini",
                           "rig-rehearsal.ini", "rig-rehearsal-modbus.ini"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", CONFIG_DIR, files[i]);
        const char *text = slurp(path);
        assert_non_null(text);
        if (strstr(text, "jump_fraction")) {
            print_error("%s still sets detect.jump_fraction\n", files[i]);
            fail();
        }
    }
}

/* A bad value of every type, in every section. */
static void test_bad_values(void **state)
{
    (void)state;
    expect_line(make1(2, "mode = simulate"), CFG_ERR_VALUE, 2, "rig.mode", "rig | mock | replay");
    expect_line(make1(3, "scene = ~/s.ini"), CFG_ERR_VALUE, 3, "rig.scene", "'~'");
    expect_line(make1(8, "max_speed_mm_s = fast"), CFG_ERR_VALUE, 8,
                "rail.compress.max_speed_mm_s", "not a number");
    expect_line(make1(12, "soft_max_mm = 1e7"), CFG_ERR_VALUE, 12, "rail.shear.soft_max_mm",
                "outside");
    expect_line(make1(15, "compress_zero_mm = 50 mm"), CFG_ERR_VALUE, 15,
                "calibration.compress_zero_mm", "no unit");
    expect_line(make1(17, "compress_sign = 2"), CFG_ERR_VALUE, 17, "calibration.compress_sign",
                "+1 or -1");
    expect_line(make1(18, "shear_sign = nan"), CFG_ERR_VALUE, 18, "calibration.shear_sign", NULL);
    expect_line(make1(20, "min_clamp_gap_mm = -1"), CFG_ERR_RANGE, 20,
                "specimen.min_clamp_gap_mm", "out of range");
    expect_line(make1(20, "crease_orientation = sideways"), CFG_ERR_VALUE, 20,
                "specimen.crease_orientation", "up | down");
    expect_line(make1(20, "crease_angle_left_deg = 180"), CFG_ERR_RANGE, 20,
                "specimen.crease_angle_left_deg", "[0, 180) deg");
    expect_line(make1(22, "compress_speed_mm_s = 0"), CFG_ERR_RANGE, 22,
                "trial.compress_speed_mm_s", "(0, 1000] mm/s");
    expect_line(make1(22, "hold_s = inf"), CFG_ERR_VALUE, 22, "trial.hold_s", "not a finite");
    /* One number grammar (cfg_number.h): plain decimal, no hex floats (issue 17, defect 11). */
    expect_line(make1(22, "hold_s = 0x1p1"), CFG_ERR_VALUE, 22, "trial.hold_s", "plain decimal");
    expect_line(make1(22, "hold_s = 0X2"), CFG_ERR_VALUE, 22, "trial.hold_s", "plain decimal");
    expect_line(make1(22, "hold_s = infinity"), CFG_ERR_VALUE, 22, "trial.hold_s", "not a finite");
    expect_line(make1(24, "fps = "), CFG_ERR_VALUE, 24, "camera.fps", "empty value");
    expect_line(make1(24, "width_px = 640.5"), CFG_ERR_VALUE, 24, "camera.width_px",
                "not an integer");
    expect_line(make1(24, "roi = 1,2,3"), CFG_ERR_VALUE, 24, "camera.roi", "x,y,w,h");
    expect_line(make1(24, "roi = 0,0,0,10"), CFG_ERR_RANGE, 24, "camera.roi", NULL);
    expect_line(make1(24, "source = webcam"), CFG_ERR_VALUE, 24, "camera.source", "device index");
    /* the frozen-image rule: at least 2 frames, a motion above 0 */
    expect_line(make1(24, "frozen_frames = 1"), CFG_ERR_RANGE, 24, "camera.frozen_frames", "[2, 100000]");
    expect_line(make1(24, "frozen_frames = 12.5"), CFG_ERR_VALUE, 24, "camera.frozen_frames", "not an integer");
    expect_line(make1(24, "frozen_move_mm = 0"), CFG_ERR_RANGE, 24, "camera.frozen_move_mm", "(0, 1000] mm");
    expect_line(make1(26, "torque_witness = yes"), CFG_ERR_VALUE, 26, "detect.torque_witness",
                "off | on");
    expect_line(make1(26, "min_quality = 1.5"), CFG_ERR_RANGE, 26, "detect.min_quality", NULL);
    expect_line(make1(28, "ladder_nodes = 31,61,61"), CFG_ERR_VALUE, 28, "sim.ladder_nodes",
                "not larger");
    expect_line(make1(28, "ladder_nodes = 3,61"), CFG_ERR_RANGE, 28, "sim.ladder_nodes", NULL);
    expect_line(make1(28, "nodes = 0"), CFG_ERR_RANGE, 28, "sim.nodes", NULL);
    expect_line(make1(30, "path = "), CFG_ERR_VALUE, 30, "store.path", "empty");
    expect_line(make1(32, "port = 70000"), CFG_ERR_RANGE, 32, "api.port", NULL);
    expect_line(make1(32, "token = short"), CFG_ERR_RANGE, 32, "api.token", "16 to 127");
    expect_line(make1(32, "listen = example.org"), CFG_ERR_VALUE, 32, "api.listen",
                "not an IPv4");
    expect_line(make1(34, "source_trial = 0"), CFG_ERR_RANGE, 34, "replay.source_trial", NULL);
}

/* Required keys depend on the mode; a missing key is named at its section header. */
static void test_missing_per_mode(void **state)
{
    (void)state;
    expect_line(make1(2, NULL), CFG_ERR_MISSING, 1, "rig.mode", "required key missing");
    expect_line(make1(3, NULL), CFG_ERR_MISSING, 1, "rig.scene", "mock mode");
    expect_line(make1(15, NULL), CFG_ERR_MISSING, 14, "calibration.compress_zero_mm", NULL);
    expect_line(make1(17, NULL), CFG_ERR_MISSING, 14, "calibration.compress_sign", NULL);
    expect_line(make1(30, NULL), CFG_ERR_MISSING, 29, "store.path", NULL);
    expect_line(make1(5, NULL), CFG_ERR_MISSING, 4, "rail.compress.driver", "moves the rails");
    /* A whole rail section missing: named at the last line. */
    edit no_shear[] = {{9, NULL}, {10, NULL}, {11, NULL}, {12, NULL}, {13, NULL}};
    expect_line(make(no_shear, 5, NULL), CFG_ERR_MISSING, BASE_N, "rail.shear.driver",
                "no such section");
    /* Mock needs no camera source, calibration or specimen name; rig mode does. */
    edit rig[] = {{2, "mode = rig"}, {5, "driver = gcode"}, {10, "driver = gcode"}};
    expect_line(make(rig, 3, "[specimen]\nname = S\n[camera]\ncalibration = c.calib\n"),
                CFG_ERR_MISSING, 23, "camera.source", "rig mode");
    expect_line(make(rig, 3, "[specimen]\nname = S\n[camera]\nsource = 0\n"), CFG_ERR_MISSING,
                23, "camera.calibration", "rig mode");
    expect_line(make(rig, 3, "[camera]\nsource = 0\ncalibration = c.calib\n"), CFG_ERR_MISSING,
                19, "specimen.name", "rig mode");
    expect_line(make_rig(20, "; no minimum gap"), CFG_ERR_MISSING, 19, "specimen.min_clamp_gap_mm",
                "rig mode");
    /* Replay needs no rails, but a source: a stored trial, or video + rails + calibration. */
    edit replay[] = {{2, "mode = replay"}, {5, NULL}, {10, NULL}, {34, "video = v.mkv"}};
    expect_line(make(replay, 4, NULL), CFG_ERR_MISSING, 23, "camera.calibration",
                "without source_trial");
    expect_line(make(replay, 4, "[camera]\ncalibration = c.calib\n"), CFG_ERR_MISSING, 33,
                "replay.rails", "t_s,compress_mm,shear_mm");
    cfg_error err;
    edit replay_ok[] = {{2, "mode = replay"}, {4, NULL}, {5, NULL}, {6, NULL}, {7, NULL},
                        {8, NULL}, {9, NULL}, {10, NULL}, {11, NULL}, {12, NULL}, {13, NULL}};
    assert_int_equal(parse(make(replay_ok, 11, NULL), &cfg, &err), CFG_OK);
    assert_false(cfg.has_rails);
    /* Replay with rail sections: validated all the same. */
    assert_int_equal(parse(make(replay, 2, NULL), &cfg, &err), CFG_OK);
    assert_true(cfg.has_rails);
    edit replay_bad[] = {{2, "mode = replay"}, {8, "max_speed_mm_s = x"}};
    expect_line(make(replay_bad, 2, NULL), CFG_ERR_VALUE, 8, "rail.compress.max_speed_mm_s",
                NULL);
    /* An empty file. */
    assert_int_equal(parse("", &cfg, &err), CFG_ERR_MISSING);
    assert_string_equal(err.key, "rig.mode");
    assert_int_equal(err.origin, CFG_ORIGIN_FILE);
}

/* Mode rules: clock, drivers, camera source, token, torque witness. */
static void test_mode_rules(void **state)
{
    (void)state;
    expect_line(make_rig(3, "scene = scenes/paper-gamma013.ini\nclock = virtual"), CFG_ERR_CHECK,
                4, "rig.clock", "mock mode only");
    edit virt_replay[] = {{2, "mode = replay"}, {1, "[rig]\nclock = virtual"}};
    expect_line(make(virt_replay, 2, NULL), CFG_ERR_CHECK, 2, "rig.clock", "mock mode only");
    expect_line(make1(10, "driver = gcode"), CFG_ERR_CHECK, 10, "rail.shear.driver",
                "mock mode uses mock rails");
    expect_line(make_rig(5, "driver = mock"), CFG_ERR_CHECK, 5, "rail.compress.driver",
                "rig mode drives real rails");
    expect_line(make1(24, "source = /dev/video0"), CFG_ERR_CHECK, 24, "camera.source",
                "never opens a camera");
}

/* The same rule checks with exact lines (make_rig appends a [camera] with its own source). */
static void test_mode_rules_exact(void **state)
{
    (void)state;
    edit rig_synth[] = {{2, "mode = rig"}, {5, "driver = gcode"}, {10, "driver = gcode"},
                        {24, "source = synthetic"}};
    expect_line(make(rig_synth, 4, "[camera]\ncalibration = c.calib\n[specimen]\nname = S\n"),
                CFG_ERR_CHECK, 24, "camera.source", "rig mode needs a camera");
    edit replay_src[] = {{2, "mode = replay"}, {24, "source = 0"}};
    expect_line(make(replay_src, 2, NULL), CFG_ERR_CHECK, 24, "camera.source",
                "replay mode reads its frames");
    /* Off loopback, a token is required; named at the [api] header. */
    expect_line(make1(32, "listen = 0.0.0.0"), CFG_ERR_MISSING, 31, "api.token",
                "not a loopback address");
    expect_line(make1(32, "listen = 192.168.1.5"), CFG_ERR_MISSING, 31, "api.token", "line 32");
    cfg_error err;
    const char *loop[] = {"127.0.0.1", "127.1.2.3", "::1", "localhost", "::ffff:127.0.0.1"};
    for (size_t i = 0; i < sizeof loop / sizeof loop[0]; i++) {
        char line[64];
        snprintf(line, sizeof line, "listen = %s", loop[i]);
        assert_int_equal(parse(make1(32, line), &cfg, &err), CFG_OK);
        assert_true(cfg.api.loopback);
    }
    assert_int_equal(parse(make1(32, "listen = ::\ntoken = abcdefghijklmnopq"), &cfg, &err),
                     CFG_OK);
    assert_false(cfg.api.loopback);
    /* The load witness: a mock shear rail (the twin's shear force) is accepted, GRBL is refused
     * with the reason, a Modbus rail needs a load register. */
    assert_int_equal(parse(make1(26, "torque_witness = on\nload_jump = 0.8"), &cfg, &err), CFG_OK);
    assert_true(cfg.detect.torque_witness);
    assert_true(NEAR(cfg.detect.load_jump, 0.8));
    assert_int_equal(parse(make1(26, "dz_jump = 0.02"), &cfg, &err), CFG_OK);
    assert_true(NEAR(cfg.detect.load_jump, 0.5));
    expect_line(make1(26, "load_jump = 0"), CFG_ERR_RANGE, 26, "detect.load_jump", "(0, 10]");
    assert_int_equal(parse(make_rig(26, "torque_witness = on"), &cfg, &err), CFG_ERR_CHECK);
    assert_string_equal(err.key, "detect.torque_witness");
    assert_non_null(strstr(err.message, "GRBL reports no torque"));
    const char *ovr[] = {"detect.torque_witness=on", "rail.shear.reg_load=18", "rail.shear.load_scale=0.1"};
    assert_int_equal(rig_config_load(CONFIG_DIR "/rig-modbus.ini", ovr, 1, &cfg, &err), CFG_ERR_CHECK);
    assert_string_equal(err.key, "detect.torque_witness");
    assert_non_null(strstr(err.message, "reg_load"));
    assert_int_equal(rig_config_load(CONFIG_DIR "/rig-modbus.ini", ovr, 3, &cfg, &err), CFG_OK);
    assert_int_equal(cfg.shear.modbus.map.load.addr, 18);
    assert_true(NEAR(cfg.shear.modbus.map.load_scale, 0.1));
}

/* Cross-checks with the scene: minimum gap, soft limits, speeds, crease orientation. */
static void test_cross_checks(void **state)
{
    (void)state;
    /* The scene's Delta L = 0.5 needs a 500 mm gap. */
    expect_line(make1(20, "min_clamp_gap_mm = 600"), CFG_ERR_CHECK, 20,
                "specimen.min_clamp_gap_mm", "gap of 500 mm");
    expect_line(make1(8, "max_speed_mm_s = 50\nmin_gap_mm = 501"), CFG_ERR_CHECK, 9,
                "rail.compress.min_gap_mm", "rail's minimum");
    /* Target at 550 mm: outside [0, 500]. */
    expect_line(make1(7, "soft_max_mm = 500"), CFG_ERR_CHECK, 7, "rail.compress.soft_max_mm",
                "rail position 550 mm");
    /* The compression zero moved so the target (zero + 500) leaves the soft limits below. */
    expect_line(make1(17, "compress_sign = -1"), CFG_ERR_CHECK, 4, "rail.compress.soft_min_mm",
                "-450");
    /* The shear range 50 .. 550 must fit. */
    expect_line(make1(12, "soft_max_mm = 540"), CFG_ERR_CHECK, 12, "rail.shear.soft_max_mm",
                "protocol.shear_max");
    expect_line(make1(18, "shear_sign = -1"), CFG_ERR_CHECK, 9, "rail.shear.soft_min_mm",
                "-450");
    /* Speeds: the shear speed comes from the scene (0.01 m/s = 10 mm/s). */
    expect_line(make1(13, "max_speed_mm_s = 5"), CFG_ERR_CHECK, 13, "rail.shear.max_speed_mm_s",
                "protocol.shear_rate");
    expect_line(make1(22, "compress_speed_mm_s = 60"), CFG_ERR_CHECK, 22,
                "trial.compress_speed_mm_s", "max_speed_mm_s = 50");
    expect_line(make1(22, "return_speed_mm_s = 60"), CFG_ERR_CHECK, 22, "trial.return_speed_mm_s",
                NULL);
    /* A default blamed: the default return speed (5 mm/s) above a slow rail. */
    edit slow[] = {{8, "max_speed_mm_s = 4"}, {22, "compress_speed_mm_s = 1"}};
    expect_origin(make(slow, 2, NULL), NULL, 0, CFG_ERR_CHECK, CFG_ORIGIN_DEFAULT,
                  "trial.return_speed_mm_s", "rig.ini:default: trial.return_speed_mm_s: 5 mm/s");
    /* Crease orientation against the scene's negative angle. */
    expect_line(make1(20, "min_clamp_gap_mm = 400\ncrease_orientation = up"), CFG_ERR_CHECK, 21,
                "specimen.crease_orientation", "folds.angle_deg = -90");
    /* ... and against each crease's own angle: mock.ini's creases down, the scene's per-crease
     * angles up while its folds.angle_deg stays -90. */
    const char *own_up[] = {"folds.angle_left_deg=88", "folds.angle_right_deg=91"};
    cfg_error oerr;
    assert_int_equal(rig_config_load(CONFIG_DIR "/mock.ini", own_up, 2, &cfg, &oerr), CFG_ERR_CHECK);
    printf("per-crease angles up, specimen down: %s: %s\n", oerr.key, oerr.message);
    assert_string_equal(oerr.key, "specimen.crease_orientation");
    assert_non_null(strstr(oerr.message, "folds.angle_left_deg = 88"));
    const char *own_down[] = {"folds.angle_left_deg=-88", "folds.angle_right_deg=-91"};
    assert_int_equal(rig_config_load(CONFIG_DIR "/mock.ini", own_down, 2, &cfg, &oerr), CFG_OK);
    /* Mock rails: soft limits within the simulated travel. */
    expect_line(make1(6, "travel_mm = 600"), CFG_ERR_CHECK, 7, "rail.compress.soft_max_mm",
                "travel");
    /* The derived gap model may be stated, but must agree. */
    expect_line(make1(8, "max_speed_mm_s = 50\ngap_at_zero_mm = 1000"), CFG_ERR_CHECK, 9,
                "rail.compress.gap_at_zero_mm", "1050");
    expect_line(make1(8, "max_speed_mm_s = 50\ngap_per_mm = 1"), CFG_ERR_CHECK, 9,
                "rail.compress.gap_per_mm", "compress_sign");
    cfg_error err;
    assert_int_equal(parse(make1(8, "max_speed_mm_s = 50\ngap_at_zero_mm = 1050"), &cfg, &err),
                     CFG_OK);
    /* Driver checks come back named: soft_min above soft_max. */
    expect_line(make1(12, "soft_max_mm = 750\nsoft_min_mm = 800"), CFG_ERR_CHECK, 13,
                "rail.shear.soft_min_mm", "below soft_max_mm");
}

static void test_scene_errors_unchanged(void **state)
{
    (void)state;
    cfg_error err;
    assert_int_equal(parse(make1(3, "scene = scenes/none.ini"), &cfg, &err), CFG_ERR_IO);
    assert_string_equal(err.file, CONFIG_DIR "/scenes/none.ini");
    assert_non_null(strstr(err.message, "cannot open"));
    /* A scene override that the scene refuses: the scene loader's own error. */
    const char *ovr[] = {"mesh.nodes=4"};
    expect_origin(make(NULL, 0, NULL), ovr, 1, CFG_ERR_RANGE, CFG_ORIGIN_OVERRIDE, "mesh.nodes",
                  "--set mesh.nodes=4: mesh.nodes:");
}

/* Issue 31: the specimen's own measurements. folded_at is an ISO 8601 date-time with a zone
 * (checked against closed forms: seconds since the epoch counted by hand), not in the future;
 * crease positions in (0, 1) and in order; each may come from --set specimen.* as from the file. */
static void test_specimen_measurements(void **state)
{
    (void)state;
    cfg_error err;
    /* Closed forms: 2000-03-01 is day 11017 after 1970-01-01 (30 years, 7 of them leap, plus
     * Jan and the 29 days of the leap February 2000); an offset moves the instant the other way. */
    struct {
        const char *text;
        double want;
    } good[] = {{"1970-01-01T00:00Z", 0.0},
                {"2000-03-01T00:00:00Z", 11017.0 * 86400.0},
                {"2000-02-29T23:59:59.5Z", 11017.0 * 86400.0 - 0.5},
                {"2000-03-01T01:30+01:30", 11017.0 * 86400.0},
                {"2000-02-29 22:00-02:00", 11017.0 * 86400.0},
                {"1969-12-31T23:00Z", -3600.0}};
    for (size_t k = 0; k < sizeof good / sizeof good[0]; k++) {
        char line[96];
        snprintf(line, sizeof line, "folded_at = %s", good[k].text);
        assert_int_equal(parse(make1(20, line), &cfg, &err), CFG_OK);
        if (cfg.specimen.folded_at_s != good[k].want) {
            print_error("%s: %.3f s, expected %.3f s\n", good[k].text, cfg.specimen.folded_at_s, good[k].want);
            fail();
        }
        assert_string_equal(cfg.specimen.folded_at, good[k].text);
    }
    assert_int_equal(parse(make(NULL, 0, NULL), &cfg, &err), CFG_OK);
    assert_true(isnan(cfg.specimen.folded_at_s));
    assert_true(isnan(cfg.specimen.crease_position_left) && isnan(cfg.specimen.crease_position_right));
    expect_line(make1(20, "folded_at = 2026-11-30"), CFG_ERR_VALUE, 20, "specimen.folded_at", "without a time");
    expect_line(make1(20, "folded_at = 2026-11-30T14:05"), CFG_ERR_VALUE, 20, "specimen.folded_at", "no time zone");
    expect_line(make1(20, "folded_at = yesterday"), CFG_ERR_VALUE, 20, "specimen.folded_at",
                "not an ISO 8601 date-time");
    expect_line(make1(20, "folded_at = 2026-02-29T10:00Z"), CFG_ERR_VALUE, 20, "specimen.folded_at",
                "out of range");
    expect_line(make1(20, "folded_at = 2026-11-30T24:00Z"), CFG_ERR_VALUE, 20, "specimen.folded_at",
                "out of range");
    expect_line(make1(20, "folded_at = 2026-11-30T10:00Zoo"), CFG_ERR_VALUE, 20, "specimen.folded_at",
                "text after");
    expect_line(make1(20, "folded_at = 2999-01-01T00:00Z"), CFG_ERR_CHECK, 20, "specimen.folded_at",
                "lies in the future");
    expect_line(make1(20, "crease_position_left = 0"), CFG_ERR_RANGE, 20, "specimen.crease_position_left", NULL);
    expect_line(make1(20, "crease_position_right = 1"), CFG_ERR_RANGE, 20, "specimen.crease_position_right",
                NULL);
    /* --set specimen.* as from the file; crossing creases named at the override that set them. */
    const char *ok[] = {"specimen.crease_angle_left_deg=88", "specimen.crease_angle_right_deg=91",
                        "specimen.crease_position_left=0.12", "specimen.crease_position_right=0.88",
                        "specimen.folded_at=2026-11-30T14:05+01:00"};
    assert_int_equal(parse_ovr(make(NULL, 0, NULL), ok, 5, &cfg, &err), CFG_OK);
    assert_true(cfg.specimen.crease_angle_left_deg == 88.0 && cfg.specimen.crease_angle_right_deg == 91.0);
    assert_true(cfg.specimen.crease_position_left == 0.12 && cfg.specimen.crease_position_right == 0.88);
    /* 2026-11-30 is day 20787 of the epoch; 14:05 at +01:00 is 13:05 UTC. */
    assert_true(cfg.specimen.folded_at_s == 20787.0 * 86400.0 + 13.0 * 3600.0 + 5.0 * 60.0);
    const char *cross[] = {"specimen.crease_position_left=0.6", "specimen.crease_position_right=0.4"};
    expect_origin(make(NULL, 0, NULL), cross, 2, CFG_ERR_CHECK, CFG_ORIGIN_OVERRIDE, "specimen.crease_position_right",
                  "the creases cross");
    const char *future[] = {"specimen.folded_at=2999-01-01T00:00Z"};
    expect_origin(make(NULL, 0, NULL), future, 1, CFG_ERR_CHECK, CFG_ORIGIN_OVERRIDE, "specimen.folded_at",
                  "future");
}

static void test_overrides(void **state)
{
    (void)state;
    cfg_error err;
    const char *ovr[] = {"trial.hold_s=5",
                         "rail.shear.soft_max_mm = 760",
                         "protocol.compression=0.4",
                         "camera.roi=10,20,300,200",
                         "trial.hold_s=6",
                         "rig.outputs=cwd"};
    assert_int_equal(parse_ovr(make(NULL, 0, NULL), ovr, 6, &cfg, &err), CFG_OK);
    assert_true(NEAR(cfg.trial.hold_s, 6.0)); /* the later one wins */
    assert_true(NEAR(cfg.shear.params.soft_max_mm, 760.0));
    assert_true(NEAR(cfg.scene.compression, 0.4));
    assert_true(NEAR(cfg.trial.compress_target_mm, 450.0));
    assert_int_equal(cfg.camera.roi, RIG_ROI_RECT);
    assert_int_equal(cfg.camera.roi_h, 200);
    char cwd[1024], want[1200];
    assert_non_null(getcwd(cwd, sizeof cwd));
    snprintf(want, sizeof want, "%s/test.db", cwd);
    assert_string_equal(cfg.store_path, want);
    /* A V4L2 camera's gain, in its control's own units: -1 (the camera's own) unless set. */
    assert_true(NEAR(cfg.camera.v4l2_gain, -1.0));
    const char *ovr_gain[] = {"camera.v4l2_gain=40"};
    assert_int_equal(parse_ovr(make(NULL, 0, NULL), ovr_gain, 1, &cfg, &err), CFG_OK);
    assert_true(NEAR(cfg.camera.v4l2_gain, 40.0));

    const char *bad1[] = {"trial.hold_s=-1"};
    expect_origin(make(NULL, 0, NULL), bad1, 1, CFG_ERR_RANGE, CFG_ORIGIN_OVERRIDE, "trial.hold_s",
                  "--set trial.hold_s=-1: trial.hold_s:");
    const char *bad2[] = {"trial.hodl_s=1"};
    expect_origin(make(NULL, 0, NULL), bad2, 1, CFG_ERR_UNKNOWN, CFG_ORIGIN_OVERRIDE,
                  "trial.hodl_s", "unknown key");
    const char *bad3[] = {"hold_s"};
    expect_origin(make(NULL, 0, NULL), bad3, 1, CFG_ERR_SYNTAX, CFG_ORIGIN_OVERRIDE, "",
                  "section.key=value");
    const char *bad4[] = {"rail.compress.speeed=3"};
    expect_origin(make(NULL, 0, NULL), bad4, 1, CFG_ERR_UNKNOWN, CFG_ORIGIN_OVERRIDE,
                  "rail.compress.speeed", NULL);
    /* A cross-check blames the override that set the key. */
    const char *bad5[] = {"specimen.min_clamp_gap_mm=700"};
    expect_origin(make(NULL, 0, NULL), bad5, 1, CFG_ERR_CHECK, CFG_ORIGIN_OVERRIDE,
                  "specimen.min_clamp_gap_mm", "--set specimen.min_clamp_gap_mm=700");
    const char *bad6[] = {"rail.compress.soft_max_mm=500"};
    expect_origin(make(NULL, 0, NULL), bad6, 1, CFG_ERR_CHECK, CFG_ORIGIN_OVERRIDE,
                  "rail.compress.soft_max_mm", "--set rail.compress.soft_max_mm=500");
    /* An override cannot stand in for a required key missing from the file. */
    const char *ovr_path[] = {"store.path=x.db"};
    expect_origin(make1(30, NULL), ovr_path, 1, CFG_ERR_MISSING, CFG_ORIGIN_LINE, "store.path",
                  NULL);
    /* Overriding the mode to rig brings rig mode's requirements. */
    const char *ovr_mode[] = {"rig.mode=rig"};
    expect_origin(make(NULL, 0, NULL), ovr_mode, 1, CFG_ERR_MISSING, CFG_ORIGIN_LINE,
                  "specimen.name", "rig mode");
}

/* ---- [twin] ------------------------------------------------------------------------------------ */

/* BASE ends on line 34; the [twin] tail starts at line 35. */
#define TWIN_TAIL                                                                                  \
    "[twin]\n"                            /* 35 */                                                 \
    "folds.angle_deg = -86\n"             /* 36 */                                                 \
    "imperfection.fold_angle_rel = 0.03\n" /* 37 */                                                \
    "mesh.nodes = 121\n"                  /* 38 */                                                 \
    "solver.dt = 1e-3\n"                  /* 39 */

/* The twin is the trial's scene with the [twin] keys applied through the scene loader: every
 * scene key, in order (file, then --set twin.*, a later one wins), checked as a scene; the trial's
 * own scene is untouched; errors name "twin.section.key" at its line or --set; replay mode refuses
 * it, rig mode keeps it for ribbon-rigsim. */
static void test_twin_section(void **state)
{
    (void)state;
    cfg_error err;
    char buf[1024];
    /* Without [twin] there is no twin of its own. */
    assert_int_equal(parse(make(NULL, 0, NULL), &cfg, &err), CFG_OK);
    assert_false(cfg.twin.present);
    assert_int_equal(cfg.twin.n, 0);

    cfg_status st = parse(make(NULL, 0, TWIN_TAIL), &cfg, &err);
    if (st) print_error("%s\n", cfg_error_format(&err, buf, sizeof buf));
    assert_int_equal(st, CFG_OK);
    assert_true(cfg.twin.present);
    assert_int_equal(cfg.twin.n, 4);
    assert_string_equal(cfg.twin.keys[0], "folds.angle_deg=-86");
    assert_string_equal(cfg.twin.keys[3], "solver.dt=1e-3");
    assert_true(NEAR(cfg.twin.scene.fold_angle_deg, -86.0));
    assert_true(NEAR(cfg.twin.scene.fold_angle_rel, 0.03));
    assert_int_equal(cfg.twin.scene.nodes, 121);
    assert_true(NEAR(cfg.twin.scene.dt, 1e-3));
    /* What [twin] does not set is the trial's scene's; the trial's scene is untouched. */
    assert_true(NEAR(cfg.scene.fold_angle_deg, -90.0));
    assert_int_equal(cfg.scene.nodes, 201);
    assert_true(NEAR(cfg.twin.scene.fold_position, cfg.scene.fold_position));
    assert_true(NEAR(cfg.twin.scene.length, cfg.scene.length));
    assert_true(NEAR(cfg.twin.scene.damping, cfg.scene.damping));

    /* --set twin.SECTION.KEY wins over the file; a scene --set reaches the twin too (it is a copy
     * of the trial's scene); a twin.* --set alone makes a twin. */
    const char *ovr[] = {"twin.folds.angle_deg=-84", "protocol.compression=0.4", "twin.ribbon.gravity=0 0 -9.81",
                         "twin.solver.damping = 2"};
    st = parse_ovr(make(NULL, 0, TWIN_TAIL), ovr, 4, &cfg, &err);
    if (st) print_error("%s\n", cfg_error_format(&err, buf, sizeof buf));
    assert_int_equal(st, CFG_OK);
    assert_true(NEAR(cfg.twin.scene.fold_angle_deg, -84.0));
    assert_true(NEAR(cfg.twin.scene.compression, 0.4));
    assert_true(NEAR(cfg.scene.compression, 0.4));
    assert_true(NEAR(cfg.twin.scene.gravity[2], -9.81));
    assert_true(NEAR(cfg.scene.gravity[2], 0.0));
    assert_true(NEAR(cfg.twin.scene.damping, 2.0));
    assert_int_equal(cfg.twin.n, 7);
    assert_int_equal(parse_ovr(make(NULL, 0, NULL), ovr, 1, &cfg, &err), CFG_OK);
    assert_true(cfg.twin.present);
    assert_true(NEAR(cfg.twin.scene.fold_angle_deg, -84.0));

    /* Named errors. A key that is not a scene key, at its line. */
    expect_line(make(NULL, 0, "[twin]\nfolds.angel_deg = -86\n"), CFG_ERR_UNKNOWN, 36,
                "twin.folds.angel_deg", "not a scene key");
    expect_line(make(NULL, 0, "[twin]\nangle_deg = -86\n"), CFG_ERR_UNKNOWN, 36, "twin.angle_deg",
                "not a scene key");
    expect_line(make(NULL, 0, "[twin]\ncamera.fps = 60\n"), CFG_ERR_UNKNOWN, 36, "twin.camera.fps",
                "not a scene key");
    expect_line(make(NULL, 0, "[twin]\nribbon.length = 0.21\n"), CFG_ERR_CHECK, 36, "twin.ribbon.length",
                "free length is the trial's");
    expect_line(make(NULL, 0, "[twin]\nprotocol.shear_rate = 0.02\n"), CFG_ERR_CHECK, 36,
                "twin.protocol.shear_rate", "the rails drive the twin");
    expect_line(make(NULL, 0, TWIN_TAIL "mesh.nodes = 61\n"), CFG_ERR_DUPLICATE, 40, "twin.mesh.nodes",
                "first on line 38");
    /* A value the scene loader refuses, at its line, with the scene loader's reason. */
    expect_line(make(NULL, 0, "[twin]\nfolds.angle_deg = -86\nmesh.nodes = 2\n"), CFG_ERR_RANGE, 37,
                "twin.mesh.nodes", "out of range");
    expect_line(make(NULL, 0, "[twin]\nsolver.dt = fast\n"), CFG_ERR_VALUE, 36, "twin.solver.dt", NULL);
    /* A cross-field check blaming a key the twin set: at its line. */
    expect_line(make(NULL, 0, "[twin]\nmesh.nodes = 121\nfolds.position = 0.005\n"), CFG_ERR_CHECK, 37,
                "twin.folds.position", "inside the clamp");
    /* ... blaming a value the twin took from the scene: at the [twin] header, saying so. */
    expect_line(make(NULL, 0, "[twin]\nmesh.nodes = 9\n"), CFG_ERR_CHECK, 35, "twin.folds.position",
                "the twin's scene");
    /* Overrides: an unknown key and a bad value name the --set. */
    const char *bad1[] = {"twin.folds.bogus=1"};
    expect_origin(make(NULL, 0, TWIN_TAIL), bad1, 1, CFG_ERR_UNKNOWN, CFG_ORIGIN_OVERRIDE, "twin.folds.bogus",
                  "--set twin.folds.bogus=1");
    const char *bad2[] = {"twin.solver.dt=-1"};
    expect_origin(make(NULL, 0, TWIN_TAIL), bad2, 1, CFG_ERR_RANGE, CFG_ORIGIN_OVERRIDE, "twin.solver.dt",
                  "--set twin.solver.dt=-1");
    /* Replay mode films no twin; rig mode keeps it (ribbon-rigsim reads the same file). */
    edit rep[2] = {{2, "mode = replay"}, {3, "scene = scenes/paper-gamma013.ini"}};
    expect_line(make(rep, 1, TWIN_TAIL), CFG_ERR_CHECK, 36, "twin", "replay mode films no twin");
    edit rig[3] = {{2, "mode = rig"}, {5, "driver = gcode"}, {10, "driver = gcode"}};
    st = parse(make(rig, 3, TWIN_TAIL RIG_TAIL), &cfg, &err);
    if (st) print_error("%s\n", cfg_error_format(&err, buf, sizeof buf));
    assert_int_equal(st, CFG_OK);
    assert_true(cfg.twin.present);
    assert_int_equal(cfg.twin.scene.nodes, 121);
}

/* ---- conversions and the calibration record ---------------------------------------------------- */

static void test_conversions(void **state)
{
    (void)state;
    cfg_error err;
    assert_int_equal(parse(make(NULL, 0, NULL), &cfg, &err), CFG_OK);
    /* +1: the compression rail at zero + 500 mm is Delta L = 0.5, gap 500 mm. */
    double dl, dw, x, y;
    rig_config_rails_to_norm(&cfg, 550.0, 300.0, &dl, &dw);
    assert_true(NEAR(dl, 0.5));
    assert_true(NEAR(dw, 0.25));
    assert_true(NEAR(rig_calib_gap_mm(&cfg.calib, cfg.scene.length, 550.0), 500.0));
    /* The drivers' gap model gives the same gap. */
    assert_true(NEAR(cfg.compress.params.gap_at_zero_mm + cfg.compress.params.gap_per_mm * 550.0,
                     500.0));
    /* Compressing means the clamps get closer: more Delta L, less gap. */
    assert_true(rig_calib_gap_mm(&cfg.calib, 1.0, 560.0) < rig_calib_gap_mm(&cfg.calib, 1.0, 550.0));
    /* Round trips with both signs. */
    for (int sc = -1; sc <= 1; sc += 2) {
        for (int ss = -1; ss <= 1; ss += 2) {
            cfg.calib.compress_sign = sc;
            cfg.calib.shear_sign = ss;
            for (double v = -0.3; v <= 0.9; v += 0.15) {
                rig_config_norm_to_rails(&cfg, v, 0.5 * v, &x, &y);
                rig_config_rails_to_norm(&cfg, x, y, &dl, &dw);
                assert_true(NEAR(dl, v));
                assert_true(NEAR(dw, 0.5 * v));
                double g0, gp;
                rig_calib_gap_model(&cfg.calib, cfg.scene.length, &g0, &gp);
                assert_true(NEAR(g0 + gp * x, 1000.0 * (1.0 - v)));
            }
            rig_config_norm_to_rails(&cfg, 0.1, 0.1, &x, &y);
            assert_true(NEAR(x - cfg.calib.compress_zero_mm, sc * 100.0));
            assert_true(NEAR(y - cfg.calib.shear_zero_mm, ss * 100.0));
        }
    }
    /* A PET-size free length: 1 mm = 0.005. */
    rig_calibration c = {12.5, 20.0, 1, -1, RIG_CAMERA_BACK, 0.0};
    assert_true(NEAR(rig_calib_dl(&c, 0.2, 13.5), 0.005));
    assert_true(NEAR(rig_calib_dw(&c, 0.2, 19.0), 0.005));
    assert_true(rig_calib_a_sign(&c) == -1.0);
    c.camera_side = RIG_CAMERA_FRONT;
    assert_true(rig_calib_a_sign(&c) == 1.0);
}

static void test_calibration_json(void **state)
{
    (void)state;
    load_ok("rig-modbus.ini", NULL, 0);
    char *s = rig_calibration_json(&cfg);
    assert_non_null(s);
    json_error_t jerr;
    json_t *o = json_loads(s, 0, &jerr);
    assert_non_null(o);
    assert_true(NEAR(json_number_value(json_object_get(o, "compress_zero_mm")), 12.5));
    assert_true(NEAR(json_number_value(json_object_get(o, "shear_zero_mm")), 20.0));
    assert_int_equal(json_integer_value(json_object_get(o, "compress_sign")), 1);
    assert_int_equal(json_integer_value(json_object_get(o, "shear_sign")), 1);
    assert_string_equal(json_string_value(json_object_get(o, "camera_side")), "back");
    assert_true(NEAR(json_number_value(json_object_get(o, "camera_time_offset_s")), -0.012));
    assert_true(NEAR(json_number_value(json_object_get(o, "free_length_mm")), 200.0));
    assert_true(NEAR(json_number_value(json_object_get(o, "gap_at_zero_mm")), 212.5));
    json_decref(o);
    free(s);

    s = rig_specimen_json(&cfg);
    assert_non_null(s);
    o = json_loads(s, 0, &jerr);
    assert_non_null(o);
    assert_string_equal(json_string_value(json_object_get(o, "name")), "PET-200x5 #2");
    assert_string_equal(json_string_value(json_object_get(o, "crease_orientation")), "down");
    assert_true(NEAR(json_number_value(json_object_get(o, "crease_angle_right_deg")), 89.0));
    assert_true(NEAR(json_number_value(json_object_get(o, "length_m")), 0.2));
    json_decref(o);
    free(s);

    load_ok("mock.ini", NULL, 0); /* angles not measured: null, never NaN */
    s = rig_specimen_json(&cfg);
    assert_non_null(s);
    o = json_loads(s, 0, &jerr);
    assert_non_null(o);
    assert_true(json_is_null(json_object_get(o, "crease_angle_left_deg")));
    json_decref(o);
    free(s);
}

/* ---- documentation ------------------------------------------------------------------------------ */

static void test_readme_documents_every_key(void **state)
{
    (void)state;
    const char *readme = slurp(RIBBON_SOURCE_DIR "/docs/config.md");
    assert_non_null(readme);
    const char *sec = strstr(readme, "\n## Rig files\n");
    assert_non_null(sec);
    const char *end = strstr(sec + 1, "\n## ");
    size_t len = end ? (size_t)(end - sec) : strlen(sec);
    char *part = malloc(len + 1);
    assert_non_null(part);
    memcpy(part, sec, len);
    part[len] = '\0';
    size_t n;
    const rig_key *k = rig_config_keys(&n);
    int missing = 0;
    for (size_t i = 0; i < n; i++) {
        char row[128];
        snprintf(row, sizeof row, "| %s | %s |", k[i].section, k[i].name);
        if (!strstr(part, row)) {
            print_error("docs/config.md \"Rig files\" has no row '%s'\n", row);
            missing++;
        }
    }
    /* Every rail key appears, in backquotes, somewhere in docs/config.md. */
    for (size_t i = 0; rail_config_key_name(i); i++) {
        const char *name = rail_config_key_name(i);
        char word[64];
        size_t m = strlen(name);
        const char *p = readme;
        int found = 0;
        while ((p = strstr(p, name)) != NULL) {
            char before = p == readme ? ' ' : p[-1], after = p[m];
            if ((before == ' ' || before == '`' || before == '\n') &&
                (after == ' ' || after == '`' || after == ',' || after == '\n')) {
                found = 1;
                break;
            }
            p += m;
        }
        snprintf(word, sizeof word, "%s", name);
        if (!found) {
            print_error("docs/config.md does not mention the rail key %s\n", word);
            missing++;
        }
    }
    /* Every shipped file is listed. */
    const char *files[] = {"mock.ini", "rig-gcode.ini", "rig-modbus.ini", "replay.ini",
                           "ribbond.service"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        if (!strstr(part, files[i])) {
            print_error("docs/config.md \"Rig files\" does not list %s\n", files[i]);
            missing++;
        }
    }
    free(part);
    assert_int_equal(missing, 0);
}

/* ---- fuzz ----------------------------------------------------------------------------------------- */

static uint64_t rng_next(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static void test_fuzz_shipped(void **state)
{
    (void)state;
    const char *files[] = {"mock.ini", "rig-gcode.ini", "rig-modbus.ini", "replay.ini"};
    static const char junk[] = "=:;[]# \t\r\n\0x9-+.e,/~";
    uint64_t seed = 0x9E3779B97F4A7C15ull;
    int ok = 0, refused = 0;
    for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", CONFIG_DIR, files[f]);
        const char *orig = slurp(path);
        assert_non_null(orig);
        size_t len = strlen(orig);
        char *buf = malloc(len + 64);
        assert_non_null(buf);
        for (int round = 0; round < 150; round++) {
            memcpy(buf, orig, len);
            size_t n = len;
            int muts = 1 + (int)(rng_next(&seed) % 4);
            for (int m = 0; m < muts; m++) {
                size_t at = (size_t)(rng_next(&seed) % n);
                switch (rng_next(&seed) % 3) {
                case 0: buf[at] = junk[rng_next(&seed) % (sizeof junk - 1)]; break;
                case 1: memmove(buf + at, buf + at + 1, n - at - 1), n--; break;
                default:
                    memmove(buf + at + 1, buf + at, n - at);
                    buf[at] = junk[rng_next(&seed) % (sizeof junk - 1)];
                    n++;
                }
            }
            cfg_error err;
            cfg_status st = rig_config_parse(files[f], CONFIG_DIR, buf, n, NULL, 0, &cfg, &err);
            if (st == CFG_OK) {
                ok++;
                assert_true(isfinite(cfg.scene.length) && cfg.scene.length > 0);
            } else {
                refused++;
                assert_true(err.message[0] != '\0');
            }
        }
        free(buf);
    }
    assert_true(ok > 0 && refused > 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mock_ini),
        cmocka_unit_test(test_rig_gcode_ini),
        cmocka_unit_test(test_rig_modbus_ini),
        cmocka_unit_test(test_replay_ini),
        cmocka_unit_test(test_service_unit),
        cmocka_unit_test(test_base_loads),
        cmocka_unit_test(test_unknown_and_duplicate),
        cmocka_unit_test(test_retired_keys),
        cmocka_unit_test(test_bad_values),
        cmocka_unit_test(test_missing_per_mode),
        cmocka_unit_test(test_mode_rules),
        cmocka_unit_test(test_mode_rules_exact),
        cmocka_unit_test(test_cross_checks),
        cmocka_unit_test(test_scene_errors_unchanged),
        cmocka_unit_test(test_specimen_measurements),
        cmocka_unit_test(test_overrides),
        cmocka_unit_test(test_twin_section),
        cmocka_unit_test(test_rehearsal_twins),
        cmocka_unit_test(test_conversions),
        cmocka_unit_test(test_calibration_json),
        cmocka_unit_test(test_readme_documents_every_key),
        cmocka_unit_test(test_fuzz_shipped),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
