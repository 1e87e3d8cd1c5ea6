/* test_sweep_cli: `ribbon-sim sweep` (daemon/sim_cmd_sweep.c) called in-process on a small
 * grid: the CSV has one point row per grid point and a boundary between the asymmetric and the
 * symmetric regime inside the bracketing grid cell; a rerun resumes (adds no row); a file that is
 * not a sweep file is refused; bad ranges are usage errors. N = 41 keeps it to seconds. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <gsl/gsl_errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sim_cmd.h"

static char csv_path[256];

static int run(const char *gamma_range, const char *out)
{
    char scene[512];
    snprintf(scene, sizeof scene, "%s/config/scenes/paper-gamma013.ini", RIBBON_SOURCE_DIR);
    char *argv[] = {"sweep", "--scene", scene, "--set", "mesh.nodes=41", "--phi", "90:90:1", "--gamma",
                    (char *)gamma_range, "--out", (char *)out, "--jobs", "2", NULL};
    int argc = (int)(sizeof argv / sizeof argv[0]) - 1;
    fflush(stdout);
    return sim_cmd_sweep(argc, argv);
}

static int count_rows(const char *kind, double *gamma)
{
    FILE *f = fopen(csv_path, "r");
    assert_non_null(f);
    char line[1024];
    int n = 0;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, kind, strlen(kind)) && line[strlen(kind)] == ',') {
            n++;
            if (gamma) *gamma = strtod(strchr(strchr(line, ',') + 1, ',') + 1, NULL);
        }
    fclose(f);
    return n;
}

static void test_sweep_and_resume(void **state)
{
    (void)state;
    snprintf(csv_path, sizeof csv_path, "/tmp/test_sweep_cli_%d.csv", (int)getpid());
    unlink(csv_path);
    assert_int_equal(run("0.12:0.22:2", csv_path), 0);
    assert_int_equal(count_rows("point", NULL), 2);
    double gstar = 0.0;
    assert_int_equal(count_rows("boundary", &gstar), 1);
    print_message("Gamma* at phi = 90 deg, N = 41: %.4f\n", gstar);
    assert_true(gstar > 0.12 && gstar < 0.22);
    int probes = count_rows("probe", NULL);
    assert_true(probes >= 5); /* 0.1 / 2^k <= 1e-3 after 7 halvings */
    /* Resume: nothing new. */
    assert_int_equal(run("0.12:0.22:2", csv_path), 0);
    assert_int_equal(count_rows("point", NULL), 2);
    assert_int_equal(count_rows("boundary", NULL), 1);
    assert_int_equal(count_rows("probe", NULL), probes);
    unlink(csv_path);
}

/* --plot writes the figure through the plot module: a PNG file, not empty. */
static void test_sweep_plot(void **state)
{
    (void)state;
    char png[256], scene[512];
    snprintf(csv_path, sizeof csv_path, "/tmp/test_sweep_cli_plot_%d.csv", (int)getpid());
    snprintf(png, sizeof png, "/tmp/test_sweep_cli_plot_%d.png", (int)getpid());
    snprintf(scene, sizeof scene, "%s/config/scenes/paper-gamma013.ini", RIBBON_SOURCE_DIR);
    unlink(csv_path);
    unlink(png);
    char *argv[] = {"sweep", "--scene", scene, "--set", "mesh.nodes=41", "--phi", "90:90:1", "--gamma",
                    "0.12:0.22:2", "--out", csv_path, "--plot", png, "--jobs", "2", NULL};
    fflush(stdout);
    assert_int_equal(sim_cmd_sweep((int)(sizeof argv / sizeof argv[0]) - 1, argv), 0);
    FILE *f = fopen(png, "rb");
    assert_non_null(f);
    unsigned char sig[8] = {0};
    assert_int_equal(fread(sig, 1, 8, f), 8);
    fseek(f, 0, SEEK_END);
    assert_true(ftell(f) > 1000);
    fclose(f);
    assert_memory_equal(sig, "\x89PNG\r\n\x1a\n", 8);
    unlink(csv_path);
    unlink(png);
}

static void test_refuses_foreign_file_and_bad_ranges(void **state)
{
    (void)state;
    char path[256];
    snprintf(path, sizeof path, "/tmp/test_sweep_cli_foreign_%d.csv", (int)getpid());
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("not,a,sweep\n1,2,3\n", f);
    fclose(f);
    assert_int_equal(run("0.12:0.22:2", path), 1);
    f = fopen(path, "r");
    char buf[64] = "";
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    assert_string_equal(buf, "not,a,sweep\n1,2,3\n"); /* untouched */
    unlink(path);
    assert_int_equal(run("0.12:0.22", path), 2);
    assert_int_equal(run("0.12:nan:3", path), 2);
    assert_int_equal(run("0.12:0.2:0", path), 2);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sweep_and_resume),
        cmocka_unit_test(test_sweep_plot),
        cmocka_unit_test(test_refuses_foreign_file_and_bad_ranges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
