/* test_fit_cli.c: `ribbon-sim fit` (daemon/ribbon_sim_commands/sim_cmd_fit.c, issue 32 C) called
 * in-process on the PET scene at N = 31: samples of a different strip (creases 86 and 89.5 deg,
 * hinge 2.5e-3 N m/rad) written as a CSV with extra columns and a skipped row, fitted (text and
 * --json), the fitted strip written with --out-scene and read back by the loader to the fitted
 * values, and its snap printed with a band; the column contract (the four columns in any order
 * among others, CRLF, rows in any order, --dl-min cutting a row); bad input named: no --csv, a
 * missing column, a key that is not a parameter, a rigid scene asked for the hinge, too few
 * samples, data no parameter set fits. stdout and stderr are redirected to temporary files around each call. */
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

#include "rod_fit.h"
#include "scene_file.h"
#include "sim_cmd.h"

#define SCENE RIBBON_SOURCE_DIR "/config/scenes/pet-200x5.ini"

typedef struct cli_run {
    int status;
    char out[16384];
    char err[4096];
} cli_run;

static char dir[64];

static void slurp(FILE *f, char *buf, size_t len)
{
    rewind(f);
    size_t n = fread(buf, 1, len - 1, f);
    buf[n] = '\0';
}

static void run(cli_run *r, int argc, char **argv)
{
    fflush(stdout);
    fflush(stderr);
    FILE *fo = tmpfile(), *fe = tmpfile();
    int so = dup(1), se = dup(2);
    dup2(fileno(fo), 1);
    dup2(fileno(fe), 2);
    r->status = sim_cmd_fit(argc, argv);
    fflush(stdout);
    fflush(stderr);
    dup2(so, 1);
    dup2(se, 2);
    close(so);
    close(se);
    slurp(fo, r->out, sizeof r->out);
    slurp(fe, r->err, sizeof r->err);
    fclose(fo);
    fclose(fe);
    printf("exit %d\n--- stdout\n%s--- stderr\n%s", r->status, r->out, r->err);
}

/* The truth strip's samples (camera observables) at Delta L 0.25 .. 0.3 and along the shear to
   0.15, with `shift` added to Delta Z on the shear, written as a CSV like ribbonctl export's. */
static void write_samples(const char *path, int n_c, int n_s, double shift)
{
    cfg_error err;
    rod_scene t;
    const char *sets[] = {"mesh.nodes=31", "folds.angle_left_deg=-86", "folds.angle_right_deg=-89.5",
                          "folds.hinge_stiffness=2.5e-3"};
    assert_int_equal(cfg_scene_load(SCENE, sets, 4, &t, &err), 0);
    rod_fit_obs obs[64];
    int n = 0;
    for (int k = 0; k < n_c; k++) obs[n++] = (rod_fit_obs){0.25 + 0.05 * k / (n_c > 1 ? n_c - 1 : 1), 0.0, 0, 0};
    for (int k = 1; k <= n_s; k++) obs[n++] = (rod_fit_obs){0.3, 0.15 * k / n_s, 0, 0};
    rod_fit_model *m = NULL;
    char why[256];
    assert_int_equal(rod_fit_model_alloc(&t, obs, n, 0, &m, why, sizeof why), ROD_OK);
    double u[ROD_FIT_NKEYS], y[128];
    rod_fit_scene_values(&t, u);
    assert_int_equal(rod_fit_model_eval(m, u, NULL, y, NULL, why, sizeof why), ROD_OK);
    rod_fit_model_free(m);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "seq,t_s,kind,dl,dw,dz,a,quality\n");
    fprintf(f, "0,0.0,event,,,,,\n");
    for (int k = 0; k < n; k++)
        fprintf(f, "%d,%.3f,frame,%.17g,%.17g,%.17g,%.17g,1\n", k + 1, 0.1 * k, obs[k].dl, obs[k].dw,
                y[2 * k] + (obs[k].dw > 0 ? shift : 0.0), y[2 * k + 1]);
    fclose(f);
}

static void fits_and_writes_the_scene(void **state)
{
    (void)state;
    char csv[128], out[128];
    snprintf(csv, sizeof csv, "%s/samples.csv", dir);
    snprintf(out, sizeof out, "%s/fitted.ini", dir);
    write_samples(csv, 6, 12, 0.0);
    char *argv[] = {"fit", "--scene", SCENE, "--set", "mesh.nodes=31", "--csv", csv, "--out-scene", out, "--sigma-dz",
                    "1e-4", "--sigma-a", "1e-3"};
    cli_run r;
    run(&r, 13, argv);
    assert_int_equal(r.status, 0);
    assert_non_null(strstr(r.out, "folds.angle_left_deg"));
    assert_non_null(strstr(r.out, "(1 skipped)"));
    assert_non_null(strstr(r.out, "snap         Delta W"));
    /* the fitted scene reads back to the truth's crease angles and hinge */
    cfg_error err;
    rod_scene f;
    cfg_status cs = cfg_scene_load(out, NULL, 0, &f, &err);
    if (cs) printf("%s: %s\n", out, err.message);
    assert_int_equal(cs, 0);
    printf("fitted scene: %.6f %.6f deg, k %.6g\n", f.fold_angle_left_deg, f.fold_angle_right_deg, f.fold_hinge_stiffness);
    assert_true(fabs(f.fold_angle_left_deg + 86.0) < 1e-3);
    assert_true(fabs(f.fold_angle_right_deg + 89.5) < 1e-3);
    assert_true(fabs(f.fold_hinge_stiffness / 2.5e-3 - 1.0) < 1e-4);
    assert_int_equal(f.nodes, 31);

    char *jv[] = {"fit", "--scene", SCENE, "--set", "mesh.nodes=31", "--csv", csv, "--json", "--no-snap",
                  "--fit", "folds.angle_left_deg,ribbon.youngs_modulus", "--bound", "ribbon.youngs_modulus=1e9:2e10",
                  "--prior", "folds.angle_left_deg=30"};
    run(&r, 15, jv);
    assert_int_equal(r.status, 0);
    json_error_t je;
    json_t *j = json_loads(r.out, 0, &je);
    assert_non_null(j);
    assert_int_equal(json_integer_value(json_object_get(j, "samples")), 18);
    json_t *ps = json_object_get(j, "parameters");
    assert_int_equal(json_array_size(ps), 2);
    for (size_t i = 0; i < 2; i++) {
        json_t *p = json_array_get(ps, i);
        /* a parameter the data do not determine has a null error, never a number */
        assert_true(json_is_true(json_object_get(p, "determined")) ? json_is_real(json_object_get(p, "se"))
                                                                   : json_is_null(json_object_get(p, "se")));
    }
    json_decref(j);
}

/* The column contract: the four columns in any order among others, rows in any order, a row
   below --dl-min (here one no upper state could explain) left out. */
static void columns_in_any_order_and_cuts(void **state)
{
    (void)state;
    char csv[128], re[128];
    snprintf(csv, sizeof csv, "%s/samples.csv", dir);
    snprintf(re, sizeof re, "%s/reordered.csv", dir);
    write_samples(csv, 6, 12, 0.0);
    FILE *in = fopen(csv, "r"), *out = fopen(re, "w");
    assert_non_null(in);
    assert_non_null(out);
    char line[512];
    assert_non_null(fgets(line, sizeof line, in));
    fprintf(out, "quality, a ,note,dz,dw,dl\r\n");
    fprintf(out, "1,0.9,early,0.01,0,0.05\r\n"); /* below --dl-min */
    char rows[32][256];
    int n = 0;
    while (fgets(line, sizeof line, in) && n < 32) {
        int seq;
        double t, dl, dw, dz, a, q;
        char kind[16];
        if (sscanf(line, "%d,%lf,%15[^,],%lf,%lf,%lf,%lf,%lf", &seq, &t, kind, &dl, &dw, &dz, &a, &q) != 8) continue;
        snprintf(rows[n++], sizeof rows[0], "%g,%.17g,x,%.17g,%.17g,%.17g", q, a, dz, dw, dl);
    }
    for (int k = n - 1; k >= 0; k--) fprintf(out, "%s\r\n", rows[k]); /* reversed */
    fclose(in);
    fclose(out);
    assert_int_equal(n, 18);
    char *argv[] = {"fit", "--scene", SCENE, "--set", "mesh.nodes=31", "--csv", re, "--dl-min", "0.2", "--json",
                    "--no-snap", "--sigma-dz", "1e-4", "--sigma-a", "1e-3"};
    cli_run r;
    run(&r, 15, argv);
    assert_int_equal(r.status, 0);
    json_t *j = json_loads(r.out, 0, NULL);
    assert_non_null(j);
    assert_int_equal(json_integer_value(json_object_get(j, "samples")), 18);
    json_t *p0 = json_array_get(json_object_get(j, "parameters"), 0);
    assert_true(fabs(json_real_value(json_object_get(p0, "fitted")) + 86.0) < 1e-3);
    json_decref(j);
}

static void bad_input_is_named(void **state)
{
    (void)state;
    char csv[128], bad[128], few[128];
    snprintf(csv, sizeof csv, "%s/samples.csv", dir);
    snprintf(bad, sizeof bad, "%s/bad.csv", dir);
    snprintf(few, sizeof few, "%s/few.csv", dir);
    write_samples(csv, 3, 3, 0.0);
    cli_run r;
    char *a1[] = {"fit", "--scene", SCENE};
    run(&r, 3, a1);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "--csv is required"));
    FILE *f = fopen(bad, "w");
    fprintf(f, "dl,dw,dz\n0.3,0,0.2\n");
    fclose(f);
    char *a2[] = {"fit", "--scene", SCENE, "--csv", bad};
    run(&r, 5, a2);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "no column \"a\""));
    char *a3[] = {"fit", "--scene", SCENE, "--csv", csv, "--fit", "ribbon.width"};
    run(&r, 7, a3);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "ribbon.width: not a fit parameter"));
    char *a4[] = {"fit", "--scene", SCENE, "--set", "folds.hinge_stiffness=rigid", "--csv", csv, "--fit",
                  "folds.hinge_stiffness"};
    run(&r, 9, a4);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "creases are rigid"));
    char *a7[] = {"fit", "--scene", SCENE, "--csv", csv, "--bound", "folds.angle_left_deg=-80:-70"};
    run(&r, 7, a7);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "do not hold the scene's value"));
    char *a8[] = {"fit", "--scene", SCENE, "--csv", csv, "--prior", "folds.hinge_stiffness=-1"};
    run(&r, 7, a8);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "must be positive"));
    write_samples(few, 2, 0, 0.0);
    char *a5[] = {"fit", "--scene", SCENE, "--set", "mesh.nodes=31", "--csv", few};
    run(&r, 7, a5);
    assert_int_equal(r.status, 2);
    assert_non_null(strstr(r.err, "too few observations"));
    write_samples(csv, 4, 6, 0.1);
    char *a6[] = {"fit", "--scene", SCENE, "--set", "mesh.nodes=31", "--csv", csv};
    run(&r, 7, a6);
    assert_int_equal(r.status, 1);
    assert_non_null(strstr(r.err, "no parameter set fits these data"));
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/test_fit_cli.XXXXXX");
    if (!mkdtemp(dir)) return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(fits_and_writes_the_scene),
        cmocka_unit_test(columns_in_any_order_and_cuts),
        cmocka_unit_test(bad_input_is_named),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd)) rc = rc ? rc : 1;
    return rc;
}
