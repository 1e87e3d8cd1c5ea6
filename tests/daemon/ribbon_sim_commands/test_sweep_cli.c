/* test_sweep_cli: `ribbon-sim sweep` (daemon/sim_cmd_sweep.c) called in-process on a small
 * grid: the CSV has one point row per grid point and a boundary between the asymmetric and the
 * symmetric regime inside the bracketing grid cell; a rerun resumes (adds no row); a file that is
 * not a sweep file is refused; bad ranges are usage errors; two shards joined by sweep-merge hold
 * the same rows as one run; the upper states continued in Gamma classify like a route per point;
 * a point between two folds of the upper state is "no-upper" with them located.
 * N = 41 keeps it to seconds. (The MPI runs: test_sweep_mpi.sh.) */
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

#include "scene_file.h"
#include "sim_cmd.h"
#include "sim_sweep_row.h"
#include "sim_sweep_task.h"

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

/* sweep with the given grid and extra options (NULL-terminated) into out. */
static int run_grid(const char *phi, const char *gamma, const char *out, const char *x1, const char *x2)
{
    char scene[512];
    snprintf(scene, sizeof scene, "%s/config/scenes/paper-gamma013.ini", RIBBON_SOURCE_DIR);
    char *argv[] = {"sweep", "--scene", scene, "--set", "mesh.nodes=41", "--phi", (char *)phi, "--gamma",
                    (char *)gamma, "--out", (char *)out, "--jobs", "2", (char *)x1, (char *)x2, NULL};
    int argc = 13 + (x1 != NULL) + (x1 && x2);
    fflush(stdout);
    return sim_cmd_sweep(argc, argv);
}

static sweep_table load_sorted(const char *path)
{
    sweep_table t;
    char err[256];
    assert_int_equal(sweep_table_load(path, &t, err, sizeof err), 0);
    qsort(t.rows, t.n, sizeof *t.rows, sweep_row_compare);
    return t;
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

static void test_shards_merge_to_the_same_rows(void **state)
{
    (void)state;
    char one[256], s0[256], s1[256], merged[256];
    int pid = (int)getpid();
    snprintf(one, sizeof one, "/tmp/test_sweep_one_%d.csv", pid);
    snprintf(s0, sizeof s0, "/tmp/test_sweep_s0_%d.csv", pid);
    snprintf(s1, sizeof s1, "/tmp/test_sweep_s1_%d.csv", pid);
    snprintf(merged, sizeof merged, "/tmp/test_sweep_merged_%d.csv", pid);
    unlink(one);
    unlink(s0);
    unlink(s1);
    unlink(merged);
    assert_int_equal(run_grid("80:100:2", "0.12:0.22:2", one, NULL, NULL), 0);
    assert_int_equal(run_grid("80:100:2", "0.12:0.22:2", s0, "--shard", "0/2"), 0);
    assert_int_equal(run_grid("80:100:2", "0.12:0.22:2", s1, "--shard", "1/2"), 0);
    char *margv[] = {"sweep-merge", "--out", merged, s0, s1, NULL};
    assert_int_equal(sim_cmd_sweep_merge(5, margv), 0);
    assert_int_equal(sim_cmd_sweep_merge(5, margv), 1); /* refuses to overwrite */
    sweep_table a = load_sorted(one), b = load_sorted(merged), c0 = load_sorted(s0), c1 = load_sorted(s1);
    assert_true(c0.n > 0 && c1.n > 0);      /* each shard did a part ... */
    assert_int_equal(c0.n + c1.n, a.n);     /* ... and no row twice */
    assert_int_equal(a.n, b.n);
    for (size_t k = 0; k < a.n; k++) {
        sweep_row x = a.rows[k], y = b.rows[k];
        assert_int_equal(x.kind, y.kind);
        assert_true(x.phi == y.phi && x.gamma == y.gamma && x.gamma_lo == y.gamma_lo && x.gamma_hi == y.gamma_hi);
        assert_true(x.dl == y.dl && x.first_dw == y.first_dw && x.first_dz == y.first_dz);
        assert_string_equal(x.regime, y.regime);
        assert_string_equal(x.note, y.note);
    }
    sweep_table_free(&a);
    sweep_table_free(&b);
    sweep_table_free(&c0);
    sweep_table_free(&c1);
    unlink(one);
    unlink(s0);
    unlink(s1);
    unlink(merged);
}

/* Continued upper states are the route's equilibria: the same regime and the first
 * instability's Delta W to the continuation's location accuracy (1e-5), at every grid point. */
static void test_continued_upper_states_classify_like_routes(void **state)
{
    (void)state;
    char cont[256], route[256];
    snprintf(cont, sizeof cont, "/tmp/test_sweep_cont_%d.csv", (int)getpid());
    snprintf(route, sizeof route, "/tmp/test_sweep_route_%d.csv", (int)getpid());
    unlink(cont);
    unlink(route);
    assert_int_equal(run_grid("100:100:1", "0.08:0.26:4", cont, "--gamma-tol", "0.05"), 0);
    assert_int_equal(run_grid("100:100:1", "0.08:0.26:4", route, "--seed", "route"), 0);
    sweep_table a = load_sorted(cont), b = load_sorted(route);
    int continued = 0, compared = 0;
    for (size_t k = 0; k < a.n; k++) {
        if (a.rows[k].kind != 'p') continue;
        continued += !strcmp(a.rows[k].upper, "continued");
        for (size_t m = 0; m < b.n; m++) {
            if (b.rows[m].kind != 'p' || b.rows[m].gamma != a.rows[k].gamma) continue;
            assert_string_equal(b.rows[m].upper, "route");
            assert_string_equal(a.rows[k].regime, b.rows[m].regime);
            assert_true(fabs(a.rows[k].first_dw - b.rows[m].first_dw) < 1e-5);
            compared++;
        }
    }
    assert_int_equal(compared, 4);
    assert_int_equal(continued, 3); /* all but the anchor */
    sweep_table_free(&a);
    sweep_table_free(&b);
    unlink(cont);
    unlink(route);
}

/* The README diagram's last cross, (phi 135 deg, Gamma 0.244): neither continuation from the
 * neighbours at Gamma 0.217 and 0.272 nor the route reaches an upper state there. The row says
 * "no-upper", with the two folds in Gamma (Delta W 0) that end the state coming from either
 * side, located directly (sim/rod_seed_fold.c): one between 0.217 and 0.244, one between 0.244
 * and 0.272, each with its even eigenvalue at zero to round-off. Without the location the row was
 * "failed" (Newton's cap). N = 41, a third of a second. */
static void test_no_upper_state_between_two_folds(void **state)
{
    (void)state;
    char out[256];
    snprintf(out, sizeof out, "/tmp/test_sweep_fold_%d.csv", (int)getpid());
    unlink(out);
    assert_int_equal(run_grid("135:135:1", "0.216666666666666667:0.272222222222222222:3", out, NULL, NULL), 0);
    sweep_table t = load_sorted(out);
    const sweep_row *mid = NULL;
    for (size_t k = 0; k < t.n; k++)
        if (t.rows[k].kind == 'p' && fabs(t.rows[k].gamma - 0.24444) < 1e-4) mid = &t.rows[k];
    assert_non_null(mid);
    assert_string_equal(mid->regime, "no-upper");
    double f1 = 0.0, f2 = 0.0, rel = 1.0;
    assert_int_equal(sscanf(mid->note, "fold at Gamma %lf and fold at Gamma %lf", &f1, &f2), 2);
    const char *ev = strstr(mid->note, "eigenvalue -> ");
    assert_non_null(ev);
    rel = strtod(ev + 14, NULL);
    assert_true(rel < 1e-12);
    double lo = fmin(f1, f2), hi = fmax(f1, f2);
    assert_true(lo > 0.2167 && lo < 0.2444);
    assert_true(hi > 0.2444 && hi < 0.2722);
    sweep_table_free(&t);
    unlink(out);
}

static void test_bad_axes_and_shards(void **state)
{
    (void)state;
    char path[256];
    snprintf(path, sizeof path, "/tmp/test_sweep_bad_%d.csv", (int)getpid());
    unlink(path);
    assert_int_equal(run_grid("90:90:1", "0.12:0.22:2", path, "--shard", "2/2"), 2);
    assert_int_equal(run_grid("90:90:1", "0.12:0.22:2", path, "--shard", "1"), 2);
    assert_int_equal(run_grid("90:90:1", "0.12:0.22:2", path, "--dl", "0:0.5:2"), 2);
    assert_int_equal(run_grid("90:90:1", "0.12:0.22:2", path, "--seed", "guess"), 2);
    assert_int_equal(run_grid("170:190:3", "0.12:0.22:2", path, NULL, NULL), 2);
    assert_int_equal(run_grid("90:90:1", "0.3:0.6:2", path, NULL, NULL), 2);
    assert_int_equal(access(path, F_OK), -1); /* nothing written */
}

/* Issue 33, item 9: a reversed range (high to low) once gave boundaries with inverted brackets and
 * no bisection; now every range option refuses it, before anything is written. */
static void test_reversed_ranges_refused(void **state)
{
    (void)state;
    char path[256];
    snprintf(path, sizeof path, "/tmp/test_sweep_reversed_%d.csv", (int)getpid());
    unlink(path);
    assert_int_equal(run_grid("90:90:1", "0.30:0.05:6", path, NULL, NULL), 2);
    assert_int_equal(run_grid("120:60:2", "0.12:0.22:2", path, NULL, NULL), 2);
    assert_int_equal(run_grid("90:90:1", "0.12:0.22:2", path, "--dl", "0.5:0.4:2"), 2);
    assert_int_equal(access(path, F_OK), -1); /* nothing written */
}

/* sweep at N nodes (mesh.nodes=N) on the grid phi x gamma into out. */
static int run_nodes(const char *nodes_set, const char *gamma, const char *out)
{
    char scene[512];
    snprintf(scene, sizeof scene, "%s/config/scenes/paper-gamma013.ini", RIBBON_SOURCE_DIR);
    char *argv[] = {"sweep", "--scene", scene, "--set", (char *)nodes_set, "--phi", "90:90:1", "--gamma",
                    (char *)gamma, "--out", (char *)out, "--jobs", "1", NULL};
    fflush(stdout);
    return sim_cmd_sweep((int)(sizeof argv / sizeof argv[0]) - 1, argv);
}

/* Issue 33, item 10: a Gamma the mesh cannot hold (a crease inside the clamp: closer than one
 * edge, 1/(N-3)) made every point of the row "failed" with "out of memory allocating the row
 * task". The grid is now refused before anything runs, naming the point; nothing is written. */
static void test_grid_point_inside_the_clamp_refused(void **state)
{
    (void)state;
    char path[256];
    snprintf(path, sizeof path, "/tmp/test_sweep_clamp_%d.csv", (int)getpid());
    unlink(path);
    assert_int_equal(run_nodes("mesh.nodes=21", "0.05:0.2:2", path), 2); /* 0.05 < 1/18 */
    assert_int_equal(run_nodes("mesh.nodes=61", "0.01:0.2:2", path), 2); /* 0.01 < 1/58 */
    assert_int_equal(access(path, F_OK), -1);
}

typedef struct collected {
    sweep_row rows[64];
    int n;
} collected;

static void collect(void *ctx, const sweep_row *row, int is_new)
{
    collected *c = ctx;
    (void)is_new;
    if (c->n < 64) c->rows[c->n++] = *row;
}

/* The row task itself (what a farm or shard runs): the point the mesh cannot hold fails alone
 * with rod_scene_check's reason; the other point of the row is classified. N = 21. */
static void test_row_task_fails_only_the_unfit_point(void **state)
{
    (void)state;
    char scene[512];
    snprintf(scene, sizeof scene, "%s/config/scenes/paper-gamma013.ini", RIBBON_SOURCE_DIR);
    const char *sets[] = {"mesh.nodes=21"};
    sweep_spec sp;
    memset(&sp, 0, sizeof sp);
    cfg_error ce;
    assert_int_equal(cfg_scene_load(scene, sets, 1, &sp.base, &ce), CFG_OK);
    const double gamma[] = {0.03, 0.15};
    sp.sign = sp.base.fold_angle_deg < 0.0 ? -1.0 : 1.0;
    sp.gamma = gamma;
    sp.ngamma = 2;
    sp.gamma_tol = 0.05;
    char why[512];
    const double phi = 90.0, dl = 0.5;
    assert_int_equal(sweep_grid_check(&sp, &phi, 1, &dl, 1, why, sizeof why), -1);
    print_message("refused: %s\n", why);
    assert_non_null(strstr(why, "Gamma 0.03"));
    assert_non_null(strstr(why, "inside the clamp"));
    collected c = {.n = 0};
    sweep_table known = {0};
    sweep_run_row(&sp, phi, dl, &known, collect, &c, NULL);
    int points = 0;
    for (int k = 0; k < c.n; k++) {
        if (c.rows[k].kind != 'p') continue;
        points++;
        print_message("Gamma %.2f: %s (%s)\n", c.rows[k].gamma, c.rows[k].regime, c.rows[k].note);
        if (c.rows[k].gamma == 0.03) {
            assert_string_equal(c.rows[k].regime, "failed");
            assert_non_null(strstr(c.rows[k].note, "inside the clamp"));
        } else {
            assert_true(sweep_is_regime(&c.rows[k]));
        }
        assert_null(strstr(c.rows[k].note, "out of memory"));
    }
    assert_int_equal(points, 2);
}

/* ---- issue 33, item 11: what made a shard, and rows that are not rows --------------------- */

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    return buf;
}

/* dst = src with the first `from` replaced by `to` (which must be there). */
static void copy_edit(const char *src, const char *dst, const char *from, const char *to)
{
    const char *text = slurp(src);
    const char *at = strstr(text, from);
    if (!at) fail_msg("'%s' not in %s", from, src);
    FILE *f = fopen(dst, "wb");
    assert_non_null(f);
    fwrite(text, 1, (size_t)(at - text), f);
    fputs(to, f);
    fputs(at + strlen(from), f);
    fclose(f);
}

static int merge2(const char *out, const char *a, const char *b)
{
    char *argv[] = {"sweep-merge", "--out", (char *)out, (char *)a, (char *)b, NULL};
    unlink(out);
    fflush(stdout);
    return sim_cmd_sweep_merge(b ? 5 : 4, argv);
}

static char shard[256], other[256], merged_out[256];

/* One small sweep (N = 41, Gamma 0.12 and 0.22, --gamma-tol 0.05): the file the cases edit. */
static int sweep_file_setup(void **state)
{
    (void)state;
    int pid = (int)getpid();
    snprintf(shard, sizeof shard, "/tmp/test_sweep_origin_a_%d.csv", pid);
    snprintf(other, sizeof other, "/tmp/test_sweep_origin_b_%d.csv", pid);
    snprintf(merged_out, sizeof merged_out, "/tmp/test_sweep_origin_m_%d.csv", pid);
    unlink(shard);
    return run_grid("90:90:1", "0.12:0.22:2", shard, "--gamma-tol", "0.05");
}

static int sweep_file_teardown(void **state)
{
    (void)state;
    unlink(shard);
    unlink(other);
    unlink(merged_out);
    return 0;
}

/* The file says what made it, and the merge refuses shards of another N, another grid, or none. */
static void test_merge_refuses_shards_of_different_sweeps(void **state)
{
    (void)state;
    const char *text = slurp(shard);
    const char *made = strstr(text, "\n# made by: ribbon-sim ");
    assert_non_null(made);
    print_message("%.200s\n", made + 1);
    assert_non_null(strstr(made, "; nodes 41; phi 90:90:1; gamma 0.12:0.22:2; dl 0.5:0.5:1; gamma-tol 0.05; seed continue"));
    copy_edit(shard, other, "; nodes 41;", "; nodes 61;");
    assert_int_equal(merge2(merged_out, shard, other), 1);
    assert_int_equal(access(merged_out, F_OK), -1);
    copy_edit(shard, other, "; gamma 0.12:0.22:2;", "; gamma 0.12:0.22:3;");
    assert_int_equal(merge2(merged_out, shard, other), 1);
    copy_edit(shard, other, "; scene ", "; scene 0");
    assert_int_equal(merge2(merged_out, shard, other), 1);
    const char *t = slurp(shard);
    const char *nl = strchr(strstr(t, "# made by:"), '\n');
    char line2[600];
    snprintf(line2, sizeof line2, "%.*s", (int)(nl - strstr(t, "# made by:") + 1), strstr(t, "# made by:"));
    copy_edit(shard, other, line2, ""); /* an earlier ribbon-sim's file */
    assert_int_equal(merge2(merged_out, other, NULL), 1);
    /* The same file twice: rows that agree are kept once. */
    assert_int_equal(merge2(merged_out, shard, shard), 0);
    sweep_table a = load_sorted(shard), m = load_sorted(merged_out);
    assert_int_equal(a.n, m.n);
    assert_string_equal(a.origin, m.origin);
    sweep_table_free(&a);
    sweep_table_free(&m);
}

/* Two rows at one place that differ are an error naming the row; so is a row with nan, in the
 * merge and in a resume (it was dropped: "0 rows from 1 files", exit 0). */
static void test_merge_refuses_conflicts_and_rows_that_are_not_rows(void **state)
{
    (void)state;
    const char *text = slurp(shard);
    const char *p = strstr(text, "\npoint,");
    assert_non_null(p);
    char row[1100];
    snprintf(row, sizeof row, "%.*s", (int)(strchr(p + 1, '\n') - p), p);
    /* The same point, another regime. */
    char changed[1100];
    snprintf(changed, sizeof changed, "%s", row);
    char *reg = strstr(changed, ",asymmetric,") ? strstr(changed, ",asymmetric,") : strstr(changed, ",symmetric,");
    assert_non_null(reg);
    const char *swap = strstr(changed, ",asymmetric,") ? ",symmetric," : ",asymmetric,";
    char rebuilt[1100];
    snprintf(rebuilt, sizeof rebuilt, "%.*s%s%s", (int)(reg - changed), changed, swap,
             reg + (strstr(changed, ",asymmetric,") ? strlen(",asymmetric,") : strlen(",symmetric,")));
    copy_edit(shard, other, row, rebuilt);
    assert_int_equal(merge2(merged_out, shard, other), 1);
    assert_int_equal(access(merged_out, F_OK), -1);
    /* A nan in the row's first_dw (field 9). */
    char *f = rebuilt;
    snprintf(rebuilt, sizeof rebuilt, "%s", row);
    for (int k = 0; k < 8; k++) f = strchr(f + 1, ',');
    char *end = strchr(f + 1, ',');
    char nanrow[1100];
    snprintf(nanrow, sizeof nanrow, "%.*s,nan%s", (int)(f - rebuilt), rebuilt, end);
    copy_edit(shard, other, row, nanrow);
    assert_int_equal(merge2(merged_out, other, NULL), 1);
    sweep_table t;
    char err[512];
    assert_int_equal(sweep_table_load(other, &t, err, sizeof err), -1);
    print_message("%s\n", err);
    assert_non_null(strstr(err, "line 3"));
    assert_non_null(strstr(err, "first_dw 'nan'"));
    assert_int_equal(run_grid("90:90:1", "0.12:0.22:2", other, "--gamma-tol", "0.05"), 1); /* no resume over it */
}

/* A resume refuses a file another sweep made (another N); one of its Delta L's alone is fine. A
 * last row cut by a kill is cut off the file on resume, not left as a broken line. */
static void test_resume_checks_origin_and_cuts_a_cut_row(void **state)
{
    (void)state;
    char scene[512];
    snprintf(scene, sizeof scene, "%s/config/scenes/paper-gamma013.ini", RIBBON_SOURCE_DIR);
    char *argv[] = {"sweep", "--scene", scene, "--set", "mesh.nodes=31", "--phi", "90:90:1", "--gamma", "0.12:0.22:2",
                    "--gamma-tol", "0.05", "--out", shard, NULL};
    fflush(stdout);
    assert_int_equal(sim_cmd_sweep((int)(sizeof argv / sizeof argv[0]) - 1, argv), 1); /* N 31 on an N 41 file */
    assert_int_equal(run_grid("90:90:1", "0.12:0.22:2", shard, "--gamma-tol", "0.05"), 0); /* the same: resumes */
    sweep_table before = load_sorted(shard);
    FILE *f = fopen(shard, "ab");
    assert_non_null(f);
    fputs("point,90,0.17,0.17,0.17,0.5,asym", f); /* a row cut by a kill */
    fclose(f);
    sweep_table cut;
    char err[512];
    assert_int_equal(sweep_table_load(shard, &cut, err, sizeof err), 0);
    assert_int_equal(cut.n, before.n);
    assert_true(cut.cut_line > 0);
    sweep_table_free(&cut);
    assert_int_equal(run_grid("90:90:1", "0.12:0.22:2", shard, "--gamma-tol", "0.05"), 0);
    const char *text = slurp(shard);
    assert_null(strstr(text, "asym\n"));
    assert_int_equal(text[strlen(text) - 1], '\n');
    sweep_table after = load_sorted(shard);
    assert_int_equal(after.n, before.n);
    assert_int_equal(after.cut_line, 0);
    sweep_table_free(&before);
    sweep_table_free(&after);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sweep_and_resume),
        cmocka_unit_test(test_sweep_plot),
        cmocka_unit_test(test_refuses_foreign_file_and_bad_ranges),
        cmocka_unit_test(test_shards_merge_to_the_same_rows),
        cmocka_unit_test(test_continued_upper_states_classify_like_routes),
        cmocka_unit_test(test_no_upper_state_between_two_folds),
        cmocka_unit_test(test_bad_axes_and_shards),
        cmocka_unit_test(test_reversed_ranges_refused),
        cmocka_unit_test(test_grid_point_inside_the_clamp_refused),
        cmocka_unit_test(test_row_task_fails_only_the_unfit_point),
        cmocka_unit_test_setup_teardown(test_merge_refuses_shards_of_different_sweeps, sweep_file_setup,
                                        sweep_file_teardown),
        cmocka_unit_test_setup_teardown(test_merge_refuses_conflicts_and_rows_that_are_not_rows, sweep_file_setup,
                                        sweep_file_teardown),
        cmocka_unit_test_setup_teardown(test_resume_checks_origin_and_cuts_a_cut_row, sweep_file_setup,
                                        sweep_file_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
