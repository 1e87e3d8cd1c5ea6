/* test_equilibrium_cli.c: `ribbon-sim equilibrium` (daemon/ribbon_sim_commands/sim_cmd_equilibrium.c)
 * called in-process on thicknesses at the edge of the numbers (issue 17, item 12: a denormal
 * thickness exited 0 and printed JSON without "residual"). The documented behaviour: a subnormal
 * thickness is refused by the scene loader, named (key, value, "subnormal"), exit 2, nothing on
 * stdout, whether it comes from --set or from the scene file; a tiny but normal thickness either
 * fails with a reason (exit non-zero, nothing on stdout) or prints JSON with a finite residual;
 * never exit 0 without one. stdout and stderr are redirected to temporary files around each call. */
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

#include "sim_cmd.h"

#define SCENE RIBBON_SOURCE_DIR "/config/scenes/paper-gamma013.ini"

typedef struct cli_run {
    int status;
    char out[8192];
    char err[4096];
} cli_run;

static void slurp(FILE *f, char *buf, size_t len)
{
    rewind(f);
    size_t n = fread(buf, 1, len - 1, f);
    buf[n] = '\0';
}

static void run_equilibrium(cli_run *r, const char *scene, const char *set)
{
    char *argv[12];
    int argc = 0;
    argv[argc++] = "equilibrium";
    argv[argc++] = "--scene";
    argv[argc++] = (char *)scene;
    argv[argc++] = "--dl";
    argv[argc++] = "0.3";
    argv[argc++] = "--dw";
    argv[argc++] = "0";
    if (set) {
        argv[argc++] = "--set";
        argv[argc++] = (char *)set;
    }
    argv[argc++] = "--json";
    argv[argc] = NULL;
    FILE *fo = tmpfile(), *fe = tmpfile();
    assert_non_null(fo);
    assert_non_null(fe);
    fflush(stdout);
    fflush(stderr);
    int saved_out = dup(STDOUT_FILENO), saved_err = dup(STDERR_FILENO);
    assert_true(saved_out >= 0 && saved_err >= 0);
    assert_true(dup2(fileno(fo), STDOUT_FILENO) >= 0);
    assert_true(dup2(fileno(fe), STDERR_FILENO) >= 0);
    r->status = sim_cmd_equilibrium(argc, argv);
    fflush(stdout);
    fflush(stderr);
    assert_true(dup2(saved_out, STDOUT_FILENO) >= 0);
    assert_true(dup2(saved_err, STDERR_FILENO) >= 0);
    close(saved_out);
    close(saved_err);
    slurp(fo, r->out, sizeof r->out);
    slurp(fe, r->err, sizeof r->err);
    fclose(fo);
    fclose(fe);
}

/* Exit 0 means one JSON object on stdout with a finite "residual"; anything else means a reason
 * on stderr and nothing on stdout. */
static void expect_result_or_reason(const cli_run *r)
{
    if (r->status == 0) {
        json_error_t jerr;
        json_t *o = json_loads(r->out, 0, &jerr);
        assert_non_null(o);
        json_t *res = json_object_get(o, "residual");
        assert_non_null(res);
        assert_true(json_is_number(res));
        assert_true(isfinite(json_number_value(res)) && json_number_value(res) >= 0.0);
        json_decref(o);
    } else {
        assert_string_equal(r->out, "");
        assert_non_null(strstr(r->err, "ribbon-sim"));
    }
}

static void test_paper_thickness_has_residual(void **state)
{
    (void)state;
    cli_run r;
    run_equilibrium(&r, SCENE, NULL);
    assert_int_equal(r.status, 0);
    expect_result_or_reason(&r);
}

static void test_subnormal_thickness_set_refused(void **state)
{
    (void)state;
    cli_run r;
    run_equilibrium(&r, SCENE, "ribbon.thickness=1e-310");
    assert_int_equal(r.status, 2);
    assert_string_equal(r.out, "");
    assert_non_null(strstr(r.err, "ribbon.thickness"));
    assert_non_null(strstr(r.err, "1e-310"));
    assert_non_null(strstr(r.err, "subnormal"));
}

static void test_subnormal_thickness_in_scene_file_refused(void **state)
{
    (void)state;
    FILE *in = fopen(SCENE, "r");
    assert_non_null(in);
    char path[] = "/tmp/test_equilibrium_cli_XXXXXX";
    int fd = mkstemp(path);
    assert_true(fd >= 0);
    FILE *out = fdopen(fd, "w");
    assert_non_null(out);
    char line[1024];
    int replaced = 0;
    while (fgets(line, sizeof line, in)) {
        if (strncmp(line, "thickness", 9) == 0) {
            fputs("thickness = 1e-310\n", out);
            replaced++;
        } else {
            fputs(line, out);
        }
    }
    fclose(in);
    fclose(out);
    assert_int_equal(replaced, 1);
    cli_run r;
    run_equilibrium(&r, path, NULL);
    unlink(path);
    assert_int_equal(r.status, 2);
    assert_string_equal(r.out, "");
    assert_non_null(strstr(r.err, path));
    assert_non_null(strstr(r.err, "ribbon.thickness"));
    assert_non_null(strstr(r.err, "subnormal"));
}

/* The smallest normal doubles and a merely tiny thickness load (the key's range is (0, 1] m):
 * whatever the solver makes of them, never exit 0 without a finite residual. */
static void test_tiny_normal_thickness_result_or_reason(void **state)
{
    (void)state;
    const char *sets[] = {"ribbon.thickness=2.3e-308", "ribbon.thickness=1e-300", "ribbon.thickness=1e-20"};
    for (size_t i = 0; i < sizeof sets / sizeof sets[0]; i++) {
        cli_run r;
        run_equilibrium(&r, SCENE, sets[i]);
        expect_result_or_reason(&r);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_paper_thickness_has_residual),
        cmocka_unit_test(test_subnormal_thickness_set_refused),
        cmocka_unit_test(test_subnormal_thickness_in_scene_file_refused),
        cmocka_unit_test(test_tiny_normal_thickness_result_or_reason),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
