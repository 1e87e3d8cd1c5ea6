/* test_boundary_cli: `ribbon-sim boundary` (daemon/ribbon_sim_commands/sim_cmd_boundary.c) in-process against
 * `ribbon-sim sweep` at the same N (61) and on the same mesh (10 outer edges: Gamma 0.164-0.181):
 * at phi = 90 deg, Delta L = 0.5 the traced Gamma* agrees with the sweep's bisected boundary
 * within 2e-3 (issue 16 D); a phi range crossing 180 deg is traced to 179 deg and stops with
 * exit 1, the points before kept; bad --dl and --phi are usage errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim_cmd.h"

static char scene[512];

static int run_boundary(const char *phi, const char *csv)
{
    char *argv[] = {"boundary", "--scene", scene, "--set", "mesh.nodes=61", "--set", "folds.position=0.172", "--phi",
                    (char *)phi, "--csv", (char *)csv, NULL};
    int argc = (int)(sizeof argv / sizeof argv[0]) - 1;
    fflush(stdout);
    return sim_cmd_boundary(argc, argv);
}

/* Gamma and phi of the boundary rows of a boundary CSV; returns the count. */
static int read_boundary(const char *path, double *phi, double *gamma, int max)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char line[1024];
    int n = 0;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, "boundary,", 9) && n < max) {
            double dl;
            assert_int_equal(sscanf(line + 9, "%lf,%lf,%lf", &dl, &phi[n], &gamma[n]), 3);
            assert_true(isfinite(phi[n]) && isfinite(gamma[n]));
            n++;
        }
    fclose(f);
    return n;
}

static void test_traced_matches_sweep(void **state)
{
    (void)state;
    char sweep_csv[256], bcsv[256];
    snprintf(sweep_csv, sizeof sweep_csv, "/tmp/test_boundary_cli_sweep_%d.csv", (int)getpid());
    snprintf(bcsv, sizeof bcsv, "/tmp/test_boundary_cli_%d.csv", (int)getpid());
    unlink(sweep_csv);
    char *argv[] = {"sweep", "--scene", scene, "--set", "mesh.nodes=61", "--phi", "90:90:1", "--gamma", "0.168:0.179:2",
                    "--gamma-tol", "2e-4", "--out", sweep_csv, "--jobs", "2", NULL};
    fflush(stdout);
    assert_int_equal(sim_cmd_sweep((int)(sizeof argv / sizeof argv[0]) - 1, argv), 0);
    FILE *f = fopen(sweep_csv, "r");
    assert_non_null(f);
    char line[1024];
    double gs = NAN;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, "boundary,", 9)) gs = strtod(strchr(line + 9, ',') + 1, NULL);
    fclose(f);
    assert_true(isfinite(gs));
    assert_int_equal(run_boundary("90:90", bcsv), 0);
    double phi[8], gamma[8];
    assert_int_equal(read_boundary(bcsv, phi, gamma, 8), 1);
    print_message("phi 90, N 61: traced Gamma* %.6f, sweep's bisected boundary %.6f (|diff| %.2e)\n", gamma[0], gs,
                  fabs(gamma[0] - gs));
    assert_true(fabs(phi[0] - 90.0) < 1e-9);
    assert_true(fabs(gamma[0] - gs) <= 2e-3);
    unlink(sweep_csv);
    unlink(bcsv);
}

static void test_phi_range_crossing_180(void **state)
{
    (void)state;
    char bcsv[256];
    snprintf(bcsv, sizeof bcsv, "/tmp/test_boundary_cli_180_%d.csv", (int)getpid());
    int rc = run_boundary("150:185", bcsv);
    assert_int_equal(rc, 1);
    double phi[512], gamma[512];
    int n = read_boundary(bcsv, phi, gamma, 512);
    print_message("%d points kept, last phi %.3f, Gamma* %.4f\n", n, n ? phi[n - 1] : -1.0, n ? gamma[n - 1] : -1.0);
    assert_true(n >= 1);
    for (int k = 0; k < n; k++) assert_true(phi[k] > 0.0 && phi[k] <= 179.0 + 1e-9);
    unlink(bcsv);
}

static void test_usage_errors(void **state)
{
    (void)state;
    char *a1[] = {"boundary", "--scene", scene, "--dl", "0.5,1.5", NULL};
    assert_int_equal(sim_cmd_boundary(5, a1), 2);
    char *a2[] = {"boundary", "--scene", scene, "--phi", "90", NULL};
    assert_int_equal(sim_cmd_boundary(5, a2), 2);
    char *a3[] = {"boundary", "--phi", "80:90", NULL};
    assert_int_equal(sim_cmd_boundary(3, a3), 2);
}

int main(void)
{
    gsl_set_error_handler_off();
    snprintf(scene, sizeof scene, "%s/config/scenes/paper-gamma013.ini", RIBBON_SOURCE_DIR);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_traced_matches_sweep),
        cmocka_unit_test(test_phi_range_crossing_180),
        cmocka_unit_test(test_usage_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
