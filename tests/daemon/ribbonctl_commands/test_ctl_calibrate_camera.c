/* test_ctl_calibrate_camera.c: `ribbonctl calibrate-camera`'s refusals, each named and with its
 * exit status: a rig file whose camera is not live (mock.ini's synthetic one) exits 1 and writes
 * nothing; a missing --out, a --dl outside [0, 0.99] and a rig file that does not load exit 2. The
 * calibration itself, against ribbon-rigsim's live camera and its exact file, is test_rig_rehearsal's
 * (heavy, real time). */
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

#define MOCK RIBBON_SOURCE_DIR "/config/mock.ini"

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

static void test_not_a_live_camera(void **s)
{
    (void)s;
    char dir[] = "/tmp/test_calcam.XXXXXX", args[512], out[4096], path[128];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/lab.calib", dir);
    snprintf(args, sizeof args, "calibrate-camera --config " MOCK " --out %s", path);
    assert_int_equal(run(args, out, sizeof out), 1);
    assert_non_null(strstr(out, "not a live camera"));
    assert_int_equal(access(path, F_OK), -1); /* nothing written */
    rmdir(dir);
}

static void test_usage_errors(void **s)
{
    (void)s;
    char out[4096];
    assert_int_equal(run("calibrate-camera --config " MOCK, out, sizeof out), 2);
    assert_non_null(strstr(out, "usage: ribbonctl calibrate-camera"));
    assert_int_equal(run("calibrate-camera --config " MOCK " --out /tmp/x.calib --dl 1.5", out, sizeof out), 2);
    assert_non_null(strstr(out, "--dl needs a number in [0, 0.99]"));
    assert_int_equal(run("calibrate-camera --config /nonexistent/rig.ini --out /tmp/x.calib", out, sizeof out), 2);
    assert_non_null(strstr(out, "ribbonctl calibrate-camera: "));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_not_a_live_camera),
        cmocka_unit_test(test_usage_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
