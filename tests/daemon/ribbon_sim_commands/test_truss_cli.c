/* test_truss_cli.c: `ribbon-sim truss` (daemon/sim_cmd_truss.c) called in-process: --json prints
 * one JSON object with the documented keys, bad options and impossible models exit non-zero
 * with a message naming the cause, --help exits 0. stdout and stderr are redirected to
 * temporary files around each call. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <gsl/gsl_errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim_cmd.h"

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

static void run_cli(cli_run *r, int argc, char **argv)
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
    r->status = sim_cmd_truss(argc, argv);
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

static double jget(json_t *o, const char *key)
{
    json_t *v = json_object_get(o, key);
    assert_non_null(v);
    assert_true(json_is_number(v));
    double d = json_number_value(v);
    assert_true(isfinite(d));
    return d;
}

static void test_truss_cli_events_json(void **state)
{
    (void)state;
    char *argv[] = {"truss", "--lambda", "0.1", "--alpha", "0.1", "--l2", "0.8", "--json", NULL};
    cli_run r;
    run_cli(&r, 8, argv);
    assert_int_equal(r.status, 0);
    json_error_t jerr;
    json_t *o = json_loads(r.out, 0, &jerr); /* exactly one JSON value on stdout */
    assert_non_null(o);
    assert_string_equal(json_string_value(json_object_get(o, "first_bifurcation")), "pitchfork");
    assert_string_equal(json_string_value(json_object_get(o, "regime")), "asymmetric");
    json_t *sn = json_object_get(o, "saddle_node"), *pf = json_object_get(o, "pitchfork");
    assert_true(json_is_object(sn) && json_is_object(pf));
    assert_true(fabs(jget(sn, "psi_s") - 0.369) < 1e-3);
    assert_true(fabs(jget(pf, "psi_s") - 0.5597) < 1e-3);
    assert_true(jget(pf, "mu") > jget(sn, "mu"));
    json_t *an = json_object_get(o, "small_angle");
    assert_true(fabs(jget(an, "l2_star") - 0.5728) < 1e-4);
    json_decref(o);
}

static void test_truss_cli_switch_json(void **state)
{
    (void)state;
    char *argv[] = {"truss", "--find-switch", "--json", NULL};
    cli_run r;
    run_cli(&r, 3, argv);
    assert_int_equal(r.status, 0);
    json_error_t jerr;
    json_t *o = json_loads(r.out, 0, &jerr);
    assert_non_null(o);
    double sw = jget(o, "l2_switch"), star = jget(o, "l2_star");
    assert_true(fabs(sw - star) < 0.01);
    assert_true(fabs(star - 0.5728) < 1e-4);
    json_decref(o);
}

static void test_truss_cli_errors(void **state)
{
    (void)state;
    cli_run r;
    char *bad_num[] = {"truss", "--l2", "abc", NULL};
    run_cli(&r, 3, bad_num);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "--l2"));
    assert_string_equal(r.out, "");

    char *missing[] = {"truss", "--alpha", NULL};
    run_cli(&r, 2, missing);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "--alpha"));

    char *range[] = {"truss", "--lambda", "-1", NULL};
    run_cli(&r, 3, range);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "lambda"));

    char *unknown[] = {"truss", "--frobnicate", NULL};
    run_cli(&r, 2, unknown);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "--frobnicate"));

    /* a model without a stable upper state: a computation failure, named */
    char *printed[] = {"truss", "--printed-signs", "--l2", "0.8", "--json", NULL};
    run_cli(&r, 5, printed);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "no stable upper state"));
    assert_string_equal(r.out, "");

    /* more compression than the model allows */
    char *big[] = {"truss", "--mu-start", "200", NULL};
    run_cli(&r, 3, big);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "compression"));

    char *help[] = {"truss", "--help", NULL};
    run_cli(&r, 2, help);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "--find-switch"));
    assert_non_null(strstr(r.out, "--dynamics"));
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_truss_cli_events_json),
        cmocka_unit_test(test_truss_cli_switch_json),
        cmocka_unit_test(test_truss_cli_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
