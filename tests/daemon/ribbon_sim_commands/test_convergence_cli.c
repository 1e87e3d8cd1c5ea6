/* test_convergence_cli.c: `ribbon-sim convergence --json` (daemon/ribbon_sim_commands/sim_cmd_convergence.c)
 * called in-process on the paper's Gamma = 0.21 scene (about 3.5 s in Release): the ladder refines
 * N, dt and the fast mode's step targets together (N - 3 = 36 .. 288, dt and adapt_scale 8, 4, 2, 1
 * times the scene's), keeps the former JSON fields and adds the verdict, and estimates every
 * rung's error, the finest one's included (issue 31: it printed 0 for a rung compared with
 * itself): in the asymptotic range the finest rung's error is |s_fin - s_prev| / (r - 1) over the
 * extrapolated value. stdout and stderr are redirected to temporary files around the call. */
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

#define SCENE RIBBON_SOURCE_DIR "/config/scenes/paper-gamma021.ini"

static void slurp(FILE *f, char *buf, size_t len)
{
    rewind(f);
    size_t n = fread(buf, 1, len - 1, f);
    buf[n] = '\0';
}

static int run(char **argv, int argc, char *out, size_t out_len, char *err, size_t err_len)
{
    FILE *fo = tmpfile(), *fe = tmpfile();
    assert_non_null(fo);
    assert_non_null(fe);
    fflush(stdout);
    fflush(stderr);
    int saved_out = dup(STDOUT_FILENO), saved_err = dup(STDERR_FILENO);
    assert_true(saved_out >= 0 && saved_err >= 0);
    assert_true(dup2(fileno(fo), STDOUT_FILENO) >= 0);
    assert_true(dup2(fileno(fe), STDERR_FILENO) >= 0);
    int status = sim_cmd_convergence(argc, argv);
    fflush(stdout);
    fflush(stderr);
    assert_true(dup2(saved_out, STDOUT_FILENO) >= 0);
    assert_true(dup2(saved_err, STDERR_FILENO) >= 0);
    close(saved_out);
    close(saved_err);
    slurp(fo, out, out_len);
    slurp(fe, err, err_len);
    fclose(fo);
    fclose(fe);
    return status;
}

static double num(const json_t *o, const char *key)
{
    const json_t *v = json_object_get(o, key);
    if (!json_is_number(v)) fail_msg("no number \"%s\"", key);
    return json_number_value(v);
}

static void ladder_json(void **state)
{
    (void)state;
    char *argv[] = {"convergence", "--scene", SCENE, "--json", NULL};
    static char out[8192], err[4096];
    int status = run(argv, 4, out, sizeof out, err, sizeof err);
    printf("%s", out);
    if (status != 0) fail_msg("exit %d: %s", status, err);
    json_error_t je;
    json_t *j = json_loads(out, 0, &je);
    if (!j) fail_msg("not JSON: %s", je.text);
    const json_t *rungs = json_object_get(j, "rungs");
    assert_int_equal(json_array_size(rungs), 4);
    double dt0 = num(json_array_get(rungs, 3), "dt");
    double s[4], e[4];
    for (int k = 0; k < 4; k++) {
        const json_t *r = json_array_get(rungs, (size_t)k);
        assert_int_equal(json_integer_value(json_object_get(r, "nodes")), 36 * (1 << k) + 3);
        assert_float_equal(num(r, "dt"), dt0 * (double)(1 << (3 - k)), 1e-12);
        assert_float_equal(num(r, "adapt_scale"), (double)(1 << (3 - k)), 1e-12);
        assert_true(num(r, "wall_s") >= 0.0);
        s[k] = num(r, "snap_dw");
        e[k] = num(r, "rel_error");
        assert_true(e[k] > 0.0); /* the finest rung too: never 0 against itself */
    }
    double order = num(j, "observed_order"), ext = num(j, "extrapolated_snap_dw");
    const json_t *range = json_object_get(j, "expected_order");
    assert_float_equal(json_number_value(json_array_get(range, 0)), 0.7, 0);
    assert_float_equal(json_number_value(json_array_get(range, 1)), 2.3, 0);
    assert_float_equal(num(j, "estimate_order"), 1.0, 0);
    assert_true(json_is_boolean(json_object_get(j, "asymptotic")));
    assert_true(json_is_string(json_object_get(j, "note")));
    /* This scene's ladder is in the asymptotic range (order 0.85 measured): Richardson at order 1. */
    assert_true(json_is_true(json_object_get(j, "asymptotic")));
    assert_true(order >= 0.7 && order <= 2.3);
    assert_float_equal(num(j, "safety_factor"), 1.0, 0);
    assert_float_equal(ext, s[3] + (s[3] - s[2]), 1e-12);
    for (int k = 0; k < 4; k++) assert_float_equal(e[k], fabs(s[k] - ext) / fabs(ext), 1e-9);
    json_decref(j);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(ladder_json)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
