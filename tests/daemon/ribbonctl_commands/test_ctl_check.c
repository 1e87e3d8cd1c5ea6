/* test_ctl_check.c: `ribbonctl check` as a user runs it: a mock rig file is ready (exit 0, "ready:"),
 * a rig file whose port and camera are missing is not (exit 1, one fail line each, "NOT READY"),
 * --json carries the same, a usage error or a rig file that does not load exits 2. The checks
 * themselves, fault by fault, are test_check's. */
#include <jansson.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

static char g_dir[64];

/* Run ribbonctl with args (stderr folded in); returns the exit status. */
static int run(const char *args, char *out, size_t n)
{
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "%s %s 2>&1", RIBBONCTL_PATH, args);
    fflush(NULL);
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    size_t k = fread(out, 1, n - 1, p);
    out[k] = 0;
    int st = pclose(p);
    printf("$ ribbonctl %s\n%s", args, out);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static void test_mock_ready(void **s)
{
    (void)s;
    char args[1024], out[16384];
    snprintf(args, sizeof args,
             "check --config %s/config/mock.ini --set store.path=%s/mock.db --set camera.video_dir=%s/videos",
             RIBBON_SOURCE_DIR, g_dir, g_dir);
    assert_int_equal(run(args, out, sizeof out), 0);
    assert_non_null(strstr(out, "\nready: "));
    assert_null(strstr(out, "fail "));
    strcat(args, " --json");
    assert_int_equal(run(args, out, sizeof out), 0);
    json_error_t err;
    json_t *o = json_loads(out, JSON_DISABLE_EOF_CHECK, &err);
    assert_non_null(o);
    assert_true(json_is_true(json_object_get(o, "ok")));
    assert_int_equal(json_integer_value(json_object_get(o, "fails")), 0);
    assert_true(json_array_size(json_object_get(o, "checks")) >= 6);
    json_decref(o);
}

static void test_rig_broken(void **s)
{
    (void)s;
    char args[1024], out[16384];
    snprintf(args, sizeof args,
             "check --config %s/config/rig-rehearsal.ini --set rail.compress.port=%s/no-port "
             "--set rail.shear.port=%s/no-port --set camera.source=/dev/video-ribbon-test-none --set store.path=%s/rig.db "
             "--set camera.video_dir=%s/videos",
             RIBBON_SOURCE_DIR, g_dir, g_dir, g_dir, g_dir);
    assert_int_equal(run(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "fail  rail compress  port      port "));
    assert_non_null(strstr(out, "no-port does not exist"));
    assert_non_null(strstr(out, "fail  camera         found"));
    assert_non_null(strstr(out, "NOT READY: 4 fails"));
    strcat(args, " --json");
    assert_int_equal(run(args, out, sizeof out), 1);
    json_error_t err;
    json_t *o = json_loads(out, JSON_DISABLE_EOF_CHECK, &err);
    assert_non_null(o);
    assert_false(json_is_true(json_object_get(o, "ok")));
    assert_int_equal(json_integer_value(json_object_get(o, "fails")), 4);
    json_decref(o);
}

static void test_usage(void **s)
{
    (void)s;
    char out[4096], args[512];
    assert_int_equal(run("check", out, sizeof out), 2);
    assert_int_equal(run("check --config", out, sizeof out), 2);
    snprintf(args, sizeof args, "check --config %s/nothing.ini", g_dir);
    assert_int_equal(run(args, out, sizeof out), 2);
    assert_int_equal(run("check --help", out, sizeof out), 0);
    assert_non_null(strstr(out, "usage: ribbonctl check --config RIG.ini"));
}

int main(void)
{
    snprintf(g_dir, sizeof g_dir, "/tmp/ribbon-ctl-check-XXXXXX");
    if (!mkdtemp(g_dir)) return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mock_ready),
        cmocka_unit_test(test_rig_broken),
        cmocka_unit_test(test_usage),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", g_dir);
    if (system(cmd) != 0) rc = 1;
    return rc;
}
