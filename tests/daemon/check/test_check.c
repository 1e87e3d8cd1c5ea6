/* test_check.c: the rig's readiness checks (daemon/check/) against the simulators, one fault at a
 * time: a good rig (GRBL simulator on a pty, a camera whose answer is given, a fresh store) has no
 * fail; then GRBL in inches ($13=1), a controller that resets when the port opens, a wrong
 * acceleration, a missing port, a camera of the wrong size, a camera without a settable exposure,
 * a store the service user cannot write, a full disk and a disk short of 50 trials, a rail a
 * running daemon holds, a compression target closer than the specimen's minimum gap. Each fault
 * must give its own line at its level and no other fail. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <cmocka.h>

#include "check.h"
#include "grblsim_spawn.h"
#include "mbsim_spawn.h"
#include "rail_lock.h"
#include "test_dir.h"
#include "vision.h"

static char g_dir[256];   /* the test's temporary directory */
static char g_calib[320]; /* a calibration for 640 x 480 frames */

/* The camera's answer (check_env.camera_probe). */
static check_camera_facts g_cam;
static int fake_camera(const rig_config *cfg, check_camera_facts *out)
{
    (void)cfg;
    *out = g_cam;
    return 0;
}

static double g_free_bytes;
static int fake_statvfs(const char *path, struct statvfs *out)
{
    (void)path;
    memset(out, 0, sizeof *out);
    out->f_frsize = 4096;
    out->f_bsize = 4096;
    out->f_bavail = (fsblkcnt_t)(g_free_bytes / 4096.0);
    out->f_blocks = out->f_bavail + 1000;
    return 0;
}

static void good_camera(void)
{
    memset(&g_cam, 0, sizeof g_cam);
    g_cam.found = true;
    snprintf(g_cam.fourcc, sizeof g_cam.fourcc, "GREY");
    g_cam.width_px = 640;
    g_cam.height_px = 480;
    g_cam.exposure = 1;
    snprintf(g_cam.exposure_text, sizeof g_cam.exposure_text, "exposure_time_absolute settable, auto exposure off");
}

static check_env env_for_tests(void)
{
    check_env e = check_env_default();
    e.camera_probe = fake_camera;
    e.statvfs_fn = fake_statvfs;
    g_free_bytes = 1e12; /* 1 TB: room for every campaign */
    return e;
}

/* config/rig-rehearsal.ini (two GRBL axes on one port, a camera of 640 x 480) pointed at port,
 * the test's calibration, store and video directory, with extra overrides. */
static void load_rig(rig_config *cfg, const char *port, const char *const *extra, int n_extra)
{
    static char ov[16][400];
    const char *p[16];
    int n = 0;
    snprintf(ov[n], sizeof ov[n], "rail.compress.port=%s", port), n++;
    snprintf(ov[n], sizeof ov[n], "rail.shear.port=%s", port), n++;
    snprintf(ov[n], sizeof ov[n], "store.path=%s/rig.db", g_dir), n++;
    snprintf(ov[n], sizeof ov[n], "camera.calibration=%s", g_calib), n++;
    snprintf(ov[n], sizeof ov[n], "camera.video_dir=%s/videos", g_dir), n++;
    for (int k = 0; k < n_extra; k++) snprintf(ov[n], sizeof ov[n], "%s", extra[k]), n++;
    for (int k = 0; k < n; k++) p[k] = ov[k];
    cfg_error ce;
    cfg_status st = rig_config_load(RIBBON_SOURCE_DIR "/config/rig-rehearsal.ini", p, n, cfg, &ce);
    if (st != CFG_OK) {
        char m[600];
        print_error("rig file: %s\n", cfg_error_format(&ce, m, sizeof m));
    }
    assert_int_equal(st, CFG_OK);
}

static void show(const char *title, const check_report *r)
{
    printf("--- %s\n", title);
    check_report_print(r, stdout);
}

/* The one line of part/what, or NULL. */
static const check_item *find(const check_report *r, const char *part, const char *what)
{
    for (int i = 0; i < r->n; i++)
        if (!strcmp(r->items[i].part, part) && !strcmp(r->items[i].what, what)) return &r->items[i];
    return NULL;
}

static void expect(const check_report *r, const char *part, const char *what, check_level l, const char *text)
{
    const check_item *it = find(r, part, what);
    if (!it) print_error("no line '%s %s'\n", part, what);
    assert_non_null(it);
    if (it->level != l || (text && !strstr(it->text, text)))
        print_error("'%s %s': %s '%s', wanted %s with '%s'\n", part, what, check_level_name(it->level), it->text,
                    check_level_name(l), text ? text : "");
    assert_int_equal(it->level, l);
    if (text) assert_non_null(strstr(it->text, text));
}

static rig_config *g_cfg;
static check_report *g_rep;

/* Runs the checks of a rig on a GRBL simulator with params gp; overrides extra. */
static void run_on_grbl(const grbl_sim_params *gp, const char *const *extra, int n_extra, const check_env *env,
                        const char *title)
{
    char path[128];
    pid_t g = grblsim_spawn(gp, path, sizeof path);
    assert_true(g > 0);
    load_rig(g_cfg, path, extra, n_extra);
    check_report_init(g_rep);
    check_rig_run(g_cfg, env, g_rep);
    grblsim_kill(g);
    show(title, g_rep);
}

static grbl_sim_params grbl_good(void)
{
    grbl_sim_params gp = grbl_sim_params_default();
    gp.accel_mm_s2 = 200.0; /* the rig file's accel_mm_s2 */
    gp.start_mm[0] = 90.0;
    gp.start_mm[1] = 50.0;
    return gp;
}

static void run_good(const char *const *extra, int n_extra, const check_env *env, const char *title)
{
    grbl_sim_params gp = grbl_good();
    run_on_grbl(&gp, extra, n_extra, env, title);
}

static void test_good_rig(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    grbl_sim_params gp = grbl_good();
    run_on_grbl(&gp, NULL, 0, &env, "good rig");
    assert_int_equal(g_rep->fails, 0);
    expect(g_rep, "rail compress", "port", CHECK_OK, "exists, writable");
    expect(g_rep, "rail compress", "state", CHECK_OK, "idle at 90.000 mm");
    expect(g_rep, "rail shear", "state", CHECK_OK, "idle at 50.000 mm");
    expect(g_rep, "camera", "size", CHECK_OK, "640 x 480");
    expect(g_rep, "camera", "exposure", CHECK_OK, NULL);
    expect(g_rep, "store", "writable", CHECK_OK, NULL);
    expect(g_rep, "disk", "free", CHECK_OK, "50 trials");
    expect(g_rep, "rails", "limits", CHECK_OK, NULL);
}

static void test_grbl_inches(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    grbl_sim_params gp = grbl_good();
    snprintf(gp.settings, sizeof gp.settings, "$13=1");
    run_on_grbl(&gp, NULL, 0, &env, "GRBL in inches");
    expect(g_rep, "rails", "open", CHECK_FAIL, "$13=1");
    assert_int_equal(g_rep->fails, 1);
}

static void test_grbl_reset_on_open(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    grbl_sim_params gp = grbl_good();
    gp.reset_on_open = true;
    gp.reset_delay_s = 0.3;
    run_on_grbl(&gp, NULL, 0, &env, "GRBL resets when the port opens");
    expect(g_rep, "rail compress", "state", CHECK_FAIL, "confirm-zero");
    expect(g_rep, "rail shear", "state", CHECK_FAIL, "not trusted");
    assert_int_equal(g_rep->fails, 2);
}

/* Homing enabled ($22=1) and not homed: GRBL starts locked in alarm. */
static void test_grbl_not_homed(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    grbl_sim_params gp = grbl_good();
    gp.start_in_alarm = true;
    run_on_grbl(&gp, NULL, 0, &env, "GRBL with homing enabled, not homed");
    expect(g_rep, "rail compress", "state", CHECK_FAIL, "alarm at");
    expect(g_rep, "rail shear", "state", CHECK_FAIL, "home --confirm");
    assert_int_equal(g_rep->fails, 2);
}

static void test_grbl_wrong_accel(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    grbl_sim_params gp = grbl_good();
    gp.accel_mm_s2 = 50.0; /* the rig file says 200 mm/s^2 */
    run_on_grbl(&gp, NULL, 0, &env, "GRBL's acceleration is not the rig file's");
    expect(g_rep, "rail compress", "settings", CHECK_WARN, "$120=50");
    expect(g_rep, "rail shear", "settings", CHECK_WARN, "$121=50");
    assert_int_equal(g_rep->fails, 0);
}

static void test_missing_port(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    char port[320];
    snprintf(port, sizeof port, "%s/no-such-port", g_dir);
    load_rig(g_cfg, port, NULL, 0);
    check_report_init(g_rep);
    check_rig_run(g_cfg, &env, g_rep);
    show("missing port", g_rep);
    expect(g_rep, "rail compress", "port", CHECK_FAIL, "does not exist");
    expect(g_rep, "rail shear", "port", CHECK_FAIL, "does not exist");
    expect(g_rep, "rails", "open", CHECK_FAIL, "not opened");
    assert_int_equal(g_rep->fails, 3);
}

/* The camera: wrong size against the calibration; a size the rig file asks for and does not get;
 * no settable exposure; no camera at all. Mock rails (no simulator needed). */
static void test_camera_faults(void **s)
{
    (void)s;
    check_env env = env_for_tests();
    good_camera();
    g_cam.width_px = 320;
    g_cam.height_px = 240;
    run_good(NULL, 0, &env, "camera of the wrong size");
    expect(g_rep, "camera", "size", CHECK_FAIL, "the camera gives 320 x 240");
    expect(g_rep, "camera", "calib", CHECK_FAIL, "left clamp point (120.0, 300.0) px is outside them");
    assert_int_equal(g_rep->fails, 2);

    const char *any_size[] = {"camera.width_px=0", "camera.height_px=0"};
    run_good(any_size, 2, &env, "camera of the wrong size, no size asked");
    expect(g_rep, "camera", "calib", CHECK_FAIL, "320 x 240 frames: its left clamp point");
    assert_int_equal(g_rep->fails, 1);

    good_camera();
    g_cam.exposure = 0;
    snprintf(g_cam.exposure_text, sizeof g_cam.exposure_text, "no settable exposure control (auto exposure only)");
    run_good(NULL, 0, &env, "camera without a settable exposure");
    expect(g_rep, "camera", "exposure", CHECK_FAIL, "cannot hold");
    assert_int_equal(g_rep->fails, 1);

    memset(&g_cam, 0, sizeof g_cam);
    snprintf(g_cam.why, sizeof g_cam.why, "/dev/video0: No such file or directory");
    run_good(NULL, 0, &env, "no camera");
    expect(g_rep, "camera", "found", CHECK_FAIL, "No such file");
    assert_int_equal(g_rep->fails, 1);
}

/* A store the service user cannot write (the file, then its directory), judged for user nobody
 * from the mode bits, so that it fails for root too. */
static void test_store_not_writable(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    env.service_user = "nobody";
    char db[400];
    snprintf(db, sizeof db, "%s/rig.db", g_dir);
    FILE *f = fopen(db, "w");
    assert_non_null(f);
    fclose(f);
    assert_int_equal(chmod(db, 0444), 0);
    assert_int_equal(chmod(g_dir, 0777), 0);
    load_rig(g_cfg, "/dev/null", NULL, 0);
    check_report_init(g_rep);
    check_store(g_cfg, &env, g_rep);
    show("read-only store (for user nobody)", g_rep);
    expect(g_rep, "store", "writable", CHECK_FAIL, "not writable by user nobody (mode 0444");
    assert_int_equal(g_rep->fails, 1);
    assert_int_equal(chmod(db, 0666), 0);
    check_report_init(g_rep);
    check_store(g_cfg, &env, g_rep);
    expect(g_rep, "store", "writable", CHECK_OK, "writable by nobody");
    assert_int_equal(g_rep->fails, 0);
    assert_int_equal(chmod(g_dir, 0755), 0);
    check_report_init(g_rep);
    check_store(g_cfg, &env, g_rep);
    expect(g_rep, "store", "writable", CHECK_FAIL, "its -wal and -shm files");
    /* The port as well: the simulator's pty is root's (0620), not nobody's. */
    check_report_init(g_rep);
    run_good(NULL, 0, &env, "ports and store for user nobody");
    expect(g_rep, "rail compress", "port", CHECK_FAIL, "not writable by user nobody");
    assert_int_equal(chmod(g_dir, 0700), 0);
    unlink(db);
}

/* A full disk, and one with room for fewer than 50 trials: the estimate is 640 x 480 at 60 fps
 * over the protocol's duration, worked out here from the rig file's numbers. */
static void test_disk(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    load_rig(g_cfg, "/dev/null", NULL, 0);
    double secs = 0.0;
    double per = check_trial_video_bytes(g_cfg, 640, 480, &secs);
    /* rig-rehearsal.ini on mock-gamma013.ini: from Delta L = 0 to 0.5 of 200 mm (100 mm) at 1 mm/s,
       hold 3 s, shear to Delta W 0.6 (120 mm) at the scene's 0.01 m/s, 2 s after the snap. */
    double want = 100.0 / 1.0 + 3.0 + 120.0 / 10.0 + 2.0;
    printf("one trial: %.1f s, %.3f GB\n", secs, per / 1e9);
    assert_true(fabs(secs - want) < 1e-9);
    assert_true(fabs(per - 640.0 * 480.0 * 60.0 * want) < 1.0);

    g_free_bytes = 0.5 * per; /* less than one trial */
    check_report_init(g_rep);
    check_disk(g_cfg, &env, g_rep);
    show("full disk", g_rep);
    expect(g_rep, "disk", "free", CHECK_FAIL, "a trial needs");
    assert_int_equal(g_rep->fails, 1);

    g_free_bytes = 10.5 * per; /* ten trials */
    check_report_init(g_rep);
    check_disk(g_cfg, &env, g_rep);
    expect(g_rep, "disk", "free", CHECK_WARN, "room for 10 trials, not 50");
    assert_int_equal(g_rep->fails, 0);

    g_free_bytes = 50.0 * per + 4096.0 * 2;
    check_report_init(g_rep);
    check_disk(g_cfg, &env, g_rep);
    expect(g_rep, "disk", "free", CHECK_OK, "50 trials");
}

/* A rail a running daemon holds is reported and not opened (nothing is sent to its port). */
static void test_rail_held(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    char locks[320];
    snprintf(locks, sizeof locks, "%s/locks", g_dir);
    mkdir(locks, 0700);
    setenv("RIBBON_LOCK_DIR", locks, 1);
    char port[320];
    snprintf(port, sizeof port, "%s/held-port", g_dir);
    load_rig(g_cfg, port, NULL, 0);
    FILE *f = fopen(port, "w"); /* a "port" that exists: the check must not open it */
    assert_non_null(f);
    fclose(f);
    rail_locks *held = NULL;
    char why[600];
    assert_int_equal(rail_locks_take(&g_cfg->compress, &g_cfg->shear, "ribbond on test.ini", &held, why, sizeof why),
                     RAIL_OK);
    check_report_init(g_rep);
    check_rig_run(g_cfg, &env, g_rep);
    show("rails held by a daemon", g_rep);
    expect(g_rep, "rails", "lock", CHECK_WARN, "ribbond on test.ini");
    assert_null(find(g_rep, "rail compress", "state"));
    assert_int_equal(g_rep->fails, 0);
    rail_locks_release(held);
    unsetenv("RIBBON_LOCK_DIR");
    unlink(port);
}

/* The specimen's minimum clamp gap above the gap at the compression target, and a target outside
 * the soft limits. The rig loader refuses both already (a file that says so does not load); the
 * check says them again from the struct, so a struct changed after loading is caught too. */
static void test_limits(void **s)
{
    (void)s;
    load_rig(g_cfg, "/dev/null", NULL, 0);
    check_report_init(g_rep);
    check_rail_limits(g_cfg, g_rep);
    expect(g_rep, "rails", "limits", CHECK_OK, "gap there 100.000 mm (minimum 90.000)");
    g_cfg->specimen.min_clamp_gap_mm = 120.0;
    g_cfg->shear.params.soft_max_mm = 150.0;
    check_report_init(g_rep);
    check_rail_limits(g_cfg, g_rep);
    show("minimum gap above the target's, shear end beyond the soft limit", g_rep);
    expect(g_rep, "rail compress", "limits", CHECK_FAIL, "below the specimen's minimum 120.000 mm");
    expect(g_rep, "rail shear", "limits", CHECK_FAIL, "the shear's end 170.000 mm");
    assert_int_equal(g_rep->fails, 2);
}

/* Two Modbus TCP drives (config/rig-rehearsal-modbus.ini on two simulators): every register of
 * each map read once; then the shear drive's alarm register mapped to an address the drive does
 * not have, as a map copied from the wrong manual would: the probe names it and the rails do not
 * open; a drive that does not answer at all. */
static void test_modbus(void **s)
{
    (void)s;
    good_camera();
    check_env env = env_for_tests();
    mb_sim_params mp = mb_sim_params_default();
    int pc = 0, ps = 0;
    mp.start_mm = 90.0;
    pid_t c = mbsim_spawn(mp, &pc);
    mp.start_mm = 50.0;
    pid_t h = mbsim_spawn(mp, &ps);
    assert_true(c > 0 && h > 0);
    char ov[6][400];
    snprintf(ov[0], sizeof ov[0], "rail.compress.address=127.0.0.1:%d", pc);
    snprintf(ov[1], sizeof ov[1], "rail.shear.address=127.0.0.1:%d", ps);
    snprintf(ov[2], sizeof ov[2], "store.path=%s/rig.db", g_dir);
    snprintf(ov[3], sizeof ov[3], "camera.calibration=%s", g_calib);
    snprintf(ov[4], sizeof ov[4], "camera.video_dir=%s/videos", g_dir);
    snprintf(ov[5], sizeof ov[5], "rail.shear.reg_alarm=9000");
    const char *p[6] = {ov[0], ov[1], ov[2], ov[3], ov[4], ov[5]};
    cfg_error ce;
    assert_int_equal(rig_config_load(RIBBON_SOURCE_DIR "/config/rig-rehearsal-modbus.ini", p, 5, g_cfg, &ce), CFG_OK);
    check_report_init(g_rep);
    check_rig_run(g_cfg, &env, g_rep);
    show("two Modbus drives", g_rep);
    expect(g_rep, "rail compress", "map", CHECK_OK, "registers read");
    expect(g_rep, "rail shear", "map", CHECK_OK, "registers read");
    expect(g_rep, "rail compress", "state", CHECK_OK, "idle at 90.000 mm");
    assert_int_equal(g_rep->fails, 0);

    assert_int_equal(rig_config_load(RIBBON_SOURCE_DIR "/config/rig-rehearsal-modbus.ini", p, 6, g_cfg, &ce), CFG_OK);
    check_report_init(g_rep);
    check_rig_run(g_cfg, &env, g_rep);
    show("the shear drive's alarm register at an address it does not have", g_rep);
    expect(g_rep, "rail shear", "map", CHECK_FAIL, "alarm at 9000");
    expect(g_rep, "rail compress", "map", CHECK_OK, NULL);
    mbsim_kill(h);
    mbsim_kill(c);

    check_report_init(g_rep);
    check_rig_run(g_cfg, &env, g_rep);
    show("no drive answers", g_rep);
    expect(g_rep, "rail compress", "map", CHECK_FAIL, NULL);
    expect(g_rep, "rails", "open", CHECK_FAIL, NULL);
}

static int setup(void **s)
{
    (void)s;
    snprintf(g_dir, sizeof g_dir, "/tmp/ribbon-test-check-XXXXXX");
    assert_non_null(mkdtemp(g_dir));
    snprintf(g_calib, sizeof g_calib, "%s/camera.calib", g_dir);
    vis_calib c = vis_calib_default();
    vis_error ve;
    const double l[2] = {120.0, 300.0}, r[2] = {520.0, 300.0};
    assert_int_equal(vis_calib_from_clamps(&c, l, r, 100.0, &ve), VIS_OK);
    assert_int_equal(vis_calib_save(&c, g_calib, &ve), VIS_OK);
    g_cfg = malloc(sizeof *g_cfg);
    g_rep = malloc(sizeof *g_rep);
    return g_cfg && g_rep ? 0 : -1;
}

static int teardown(void **s)
{
    (void)s;
    free(g_cfg);
    free(g_rep);
    test_dir_done(g_dir, 1, "check"); /* a failed check leaves its lines on stdout, not files */
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_good_rig),         cmocka_unit_test(test_grbl_inches),
        cmocka_unit_test(test_grbl_reset_on_open), cmocka_unit_test(test_grbl_not_homed), cmocka_unit_test(test_grbl_wrong_accel),
        cmocka_unit_test(test_missing_port),     cmocka_unit_test(test_camera_faults),
        cmocka_unit_test(test_store_not_writable), cmocka_unit_test(test_disk),
        cmocka_unit_test(test_rail_held), cmocka_unit_test(test_modbus),        cmocka_unit_test(test_limits),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
