/* test_ribbond_check.c: ribbond's readiness checks (issue 34 E), through the daemon's own
 * operations in this process, in rig mode on config/rig-rehearsal.ini. With its GRBL port missing
 * the daemon still opens (before: it refused to start, so the lab saw nothing but a log line): its
 * status says not ready with the reasons, a trial is refused with 409 naming them, and once the
 * port is there (the GRBL simulator behind a link at the configured path) and the camera answers,
 * POST /checks opens the rails and the daemon is ready. In replay mode a replay start runs the
 * replay's checks (store writable, free disk where the store is) and is refused with 409 naming a
 * failed one. Then the real ribbond in mock mode runs them again on SIGHUP. No trial runs. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "grblsim_spawn.h"
#include "rig_daemon.h"
#include "test_dir.h"

static char dir[64];

static int good_camera(const rig_config *cfg, check_camera_facts *out)
{
    (void)cfg;
    memset(out, 0, sizeof *out);
    out->found = true;
    snprintf(out->fourcc, sizeof out->fourcc, "GREY");
    out->width_px = 640;
    out->height_px = 480;
    out->exposure = 1;
    snprintf(out->exposure_text, sizeof out->exposure_text, "settable (test)");
    return 0;
}

static json_t *status(rig_daemon *d)
{
    api_ops ops = rig_daemon_ops();
    json_t *out = NULL;
    char why[256];
    assert_int_equal(ops.status(d, &out, why, sizeof why), 0);
    char *s = json_dumps(json_object_get(out, "checks"), JSON_COMPACT);
    printf("status checks: %.600s...\n", s);
    free(s);
    return out;
}

static void test_not_ready_then_ready(void **state)
{
    (void)state;
    static rig_daemon d;
    char port[128], s_cport[160], s_sport[160], s_calib[160], s_store[160], s_video[160], calib[128];
    snprintf(port, sizeof port, "%s/grbl", dir);
    snprintf(calib, sizeof calib, "%s/camera.calib", dir);
    vis_calib c = vis_calib_default();
    vis_error ve;
    const double l[2] = {120.0, 300.0}, r[2] = {520.0, 300.0};
    assert_int_equal(vis_calib_from_clamps(&c, l, r, 100.0, &ve), VIS_OK);
    assert_int_equal(vis_calib_save(&c, calib, &ve), VIS_OK);
    snprintf(s_cport, sizeof s_cport, "rail.compress.port=%s", port);
    snprintf(s_sport, sizeof s_sport, "rail.shear.port=%s", port);
    snprintf(s_calib, sizeof s_calib, "camera.calibration=%s", calib);
    snprintf(s_store, sizeof s_store, "store.path=%s/rig.db", dir);
    snprintf(s_video, sizeof s_video, "camera.video_dir=%s/videos", dir);
    const char *ov[] = {s_cport, s_sport, s_calib, s_store, s_video, "api.port=0",
                        "camera.source=/dev/video-ribbon-test-none"};
    char why[1024] = "";
    int rc = rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/rig-rehearsal.ini", ov, 7, NULL, why, sizeof why);
    if (rc) fail_msg("a rig whose port is missing must still open (and say why it is not ready): %s", why);

    json_t *st = status(&d);
    assert_false(json_is_true(json_object_get(st, "ready")));
    json_t *ck = json_object_get(st, "checks");
    assert_false(json_is_true(json_object_get(ck, "ok")));
    assert_true(json_integer_value(json_object_get(ck, "fails")) >= 2);
    char *text = json_dumps(ck, JSON_COMPACT);
    assert_non_null(strstr(text, "does not exist"));
    free(text);
    json_decref(st);

    api_ops ops = rig_daemon_ops();
    json_error_t je;
    json_t *body = json_loads("{}", 0, &je), *out = NULL;
    int http = 201;
    assert_int_equal(ops.start(&d, body, &out, &http, why, sizeof why), -1);
    printf("start refused: %d %s\n", http, why);
    assert_int_equal(http, 409);
    assert_non_null(strstr(why, "not ready"));
    assert_non_null(strstr(why, "does not exist"));
    json_decref(out);
    out = NULL;

    /* The lab plugs the controller in (the simulator at the configured path) and the camera. */
    grbl_sim_params gp = grbl_sim_params_default();
    gp.start_mm[0] = 90.0;
    gp.start_mm[1] = 50.0;
    char pty[128];
    pid_t g = grblsim_spawn(&gp, pty, sizeof pty);
    assert_true(g > 0);
    assert_int_equal(symlink(pty, port), 0);
    d.check_hooks.camera_probe = good_camera;
    http = 200;
    assert_int_equal(ops.campaign(&d, "POST", "/checks", body, &out, &http, why, sizeof why), 0);
    assert_true(json_is_true(json_object_get(out, "ok")));
    json_decref(out);
    out = NULL;
    st = status(&d);
    assert_true(json_is_true(json_object_get(st, "ready")));
    assert_non_null(json_object_get(st, "rails"));
    json_decref(st);
    http = 200;
    assert_int_equal(ops.campaign(&d, "GET", "/checks", NULL, &out, &http, why, sizeof why), 0);
    assert_int_equal(json_integer_value(json_object_get(out, "fails")), 0);
    json_decref(out);
    json_decref(body);
    rig_daemon_close(&d, "test done");
    grblsim_kill(g);
}

/* Replay mode: a replay start consults the checks a replay needs, as a trial start does (409 naming
 * the failed check, nothing started): the store's directory writable (judged here for the user
 * nobody, who may not write the test's 0700 directory) and free disk where the store is (all a
 * replay writes; statvfs faked to 1 MB). Healthy again, the start gets past the checks to the
 * replay itself (400: this store has no trial 1 to replay). */
static int tiny_statvfs(const char *path, struct statvfs *out)
{
    (void)path;
    memset(out, 0, sizeof *out);
    out->f_frsize = out->f_bsize = 4096;
    out->f_bavail = 256; /* 1 MB */
    out->f_blocks = 100000;
    return 0;
}

static void test_replay_consults_checks(void **state)
{
    (void)state;
    static rig_daemon d;
    char s_store[160], why[1024] = "";
    snprintf(s_store, sizeof s_store, "store.path=%s/replay.db", dir);
    const char *ov[] = {s_store, "api.port=0"};
    if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/replay.ini", ov, 2, NULL, why, sizeof why))
        fail_msg("replay daemon: %s", why);
    api_ops ops = rig_daemon_ops();
    json_error_t je;
    json_t *body = json_loads("{}", 0, &je), *out = NULL;
    int http = 0;

    d.check_hooks.statvfs_fn = tiny_statvfs;
    assert_int_equal(ops.start(&d, body, &out, &http, why, sizeof why), -1);
    printf("replay, disk full: %d %s\n", http, why);
    assert_int_equal(http, 409);
    assert_non_null(strstr(why, "not ready"));
    assert_non_null(strstr(why, "disk free"));
    assert_non_null(strstr(why, "trial.min_free_disk_mb"));
    d.check_hooks.statvfs_fn = NULL;

    d.check_hooks.service_user = "nobody";
    assert_int_equal(ops.start(&d, body, &out, &http, why, sizeof why), -1);
    printf("replay, store not writable: %d %s\n", http, why);
    assert_int_equal(http, 409);
    assert_non_null(strstr(why, "store writable"));
    d.check_hooks.service_user = NULL;

    assert_int_equal(ops.start(&d, body, &out, &http, why, sizeof why), -1);
    printf("replay, ready: %d %s\n", http, why);
    assert_int_equal(http, 400);
    assert_null(strstr(why, "not ready"));
    json_t *st = status(&d);
    assert_true(json_is_true(json_object_get(json_object_get(st, "checks"), "ok")));
    json_decref(st);
    json_decref(body);
    rig_daemon_close(&d, "test done");
}

/* The real ribbond (mock mode): the checks at start are logged once, SIGHUP runs them again (a
 * second "checks:" line), SIGTERM still stops it with status 0. */
static int count_lines(const char *path, const char *what)
{
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    char line[2048];
    int n = 0;
    while (fgets(line, sizeof line, f))
        if (strstr(line, what)) n++;
    fclose(f);
    return n;
}

static int wait_lines(const char *path, const char *what, int n)
{
    for (int i = 0; i < 300; i++) { /* 30 s at most */
        if (count_lines(path, what) >= n) return 1;
        usleep(100000);
    }
    return 0;
}

static void test_sighup(void **state)
{
    (void)state;
    char log[128], s_store[160], s_video[160];
    snprintf(log, sizeof log, "%s/ribbond.log", dir);
    snprintf(s_store, sizeof s_store, "store.path=%s/mock.db", dir);
    snprintf(s_video, sizeof s_video, "camera.video_dir=%s/mock-videos", dir);
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        FILE *f = freopen(log, "w", stderr);
        (void)f;
        execl(RIBBON_BIN_DIR "/ribbond", "ribbond", "--config", RIBBON_SOURCE_DIR "/config/mock.ini", "--set", s_store,
              "--set", s_video, "--set", "api.port=0", (char *)NULL);
        _exit(127);
    }
    int up = wait_lines(log, "listening on", 1);
    if (up) {
        assert_int_equal(count_lines(log, "checks: ready"), 1);
        kill(pid, SIGHUP);
        up = wait_lines(log, "checks: ready", 2);
    }
    kill(pid, SIGTERM);
    int st = 0;
    waitpid(pid, &st, 0);
    char cmd[200];
    snprintf(cmd, sizeof cmd, "cat %s", log);
    if (!up && system(cmd) != 0) fail_msg("no log");
    assert_true(up);
    assert_true(WIFEXITED(st) && WEXITSTATUS(st) == 0);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/ribbond-check-XXXXXX");
    if (!mkdtemp(dir)) return 1;
    char locks[128];
    snprintf(locks, sizeof locks, "%s/locks", dir);
    mkdir(locks, 0700);
    setenv("RIBBON_LOCK_DIR", locks, 1);
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_not_ready_then_ready),
                                       cmocka_unit_test(test_replay_consults_checks), cmocka_unit_test(test_sighup)};
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    test_dir_done(dir, rc == 0, "ribbond check");
    return rc;
}
