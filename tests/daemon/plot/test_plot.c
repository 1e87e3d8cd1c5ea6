/*
 * test_plot.c: the figures of daemon/plot.h, checked from the PNG files they write.
 *
 * Every figure is read back twice: its IHDR chunk by hand (signature, width, height) and its
 * pixels through cairo (cairo_image_surface_create_from_png, test-only), counting the exact RGB of
 * the palette entries a series is drawn in (plot_style.h), so a figure with nothing drawn fails.
 * Gaps are checked by comparison: the same curve with and without NaN, pixels counted in a strip
 * over the hole. Error paths: bad paths and input give a reason and leave no file behind; a
 * missing driver, a PLplot abort and a PLplot fatal error (plexit, which would end the process)
 * come back as errors and the next figure still works; repeated and concurrent calls leave no
 * PLplot stream behind.
 *
 * The PNGs go to a fresh directory under $TMPDIR (default /tmp), kept when RIBBON_PLOT_KEEP is set.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "plot.h"
#include "plot_session.h"
#include "plot_style.h"

#include <cairo.h>
#include <dirent.h>
#include <math.h>
#include <plplot.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* PLplot's own error entry points (declared in its private plplotP.h, exported by libplplot). */
void plexit(const char *errormsg);
void plabort(const char *errormsg);

static char g_dir[256];

/* A path in the test directory; a ring of buffers so that a test can hold a few at once. */
static const char *out_path(const char *name)
{
    static char ring[8][512];
    static int next;
    char *buf = ring[next++ % 8];
    snprintf(buf, 512, "%s/%s", g_dir, name);
    return buf;
}

static int count_dir_entries(void)
{
    DIR *d = opendir(g_dir);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
            n++;
    closedir(d);
    return n;
}

/* ---- reading the PNG back ---------------------------------------------------------------- */

static int png_size(const char *path, unsigned *w, unsigned *h)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    unsigned char b[24];
    FILE *f = fopen(path, "rb");
    if (!f)
        return -1;
    size_t got = fread(b, 1, sizeof b, f);
    fclose(f);
    if (got != sizeof b || memcmp(b, sig, 8) != 0 || memcmp(b + 12, "IHDR", 4) != 0)
        return -1;
    *w = (unsigned)b[16] << 24 | (unsigned)b[17] << 16 | (unsigned)b[18] << 8 | b[19];
    *h = (unsigned)b[20] << 24 | (unsigned)b[21] << 16 | (unsigned)b[22] << 8 | b[23];
    return 0;
}

/* A region as fractions of the image, y from the top. */
typedef struct region {
    double x0, x1, y0, y1;
} region;

static const region WHOLE = {0.0, 1.0, 0.0, 1.0};

#define COUNT_NOT_BACKGROUND (-1) /* pixels that are not the background */
#define COUNT_DARK (-2)           /* near-black grey pixels: black lines, antialiased included */

/* Pixels of exactly colour c inside region, or of a COUNT_* class. */
static long count_color(const char *path, int c, region rg)
{
    cairo_surface_t *s = cairo_image_surface_create_from_png(path);
    if (cairo_surface_status(s) != CAIRO_STATUS_SUCCESS) {
        cairo_surface_destroy(s);
        return -1;
    }
    int w = cairo_image_surface_get_width(s), h = cairo_image_surface_get_height(s);
    int stride = cairo_image_surface_get_stride(s);
    cairo_surface_flush(s);
    const unsigned char *data = cairo_image_surface_get_data(s);
    int r, g, b;
    plot_style_rgb(c < 0 ? PLOT_COL_BACKGROUND : (enum plot_color)c, &r, &g, &b);
    int xa = (int)(rg.x0 * w), xb = (int)(rg.x1 * w), ya = (int)(rg.y0 * h), yb = (int)(rg.y1 * h);
    long n = 0;
    for (int y = ya; y < yb; y++) {
        const uint32_t *row = (const uint32_t *)(data + (size_t)y * (size_t)stride);
        for (int x = xa; x < xb; x++) {
            uint32_t p = row[x];
            int pr = (int)(p >> 16 & 255), pg = (int)(p >> 8 & 255), pb = (int)(p & 255);
            bool same = pr == r && pg == g && pb == b;
            if (c == COUNT_NOT_BACKGROUND)
                n += !same;
            else if (c == COUNT_DARK)
                n += pr < 90 && pg < 90 && pb < 90 && abs(pr - pg) < 12 && abs(pg - pb) < 12;
            else
                n += same;
        }
    }
    cairo_surface_destroy(s);
    return n;
}

static void assert_png(const char *path, unsigned w, unsigned h)
{
    unsigned pw = 0, ph = 0;
    assert_int_equal(png_size(path, &pw, &ph), 0);
    assert_int_equal(pw, w);
    assert_int_equal(ph, h);
}

/* ---- synthetic data ------------------------------------------------------------------------ */

#define NM 400
#define NP 200

typedef struct trial_arrays {
    double mdw[NM], mdz[NM], ma[NM];
    double pdw[NP], pdz[NP], pa[NP];
} trial_arrays;

/* An upper state sinking with shear, snapping to the lower one at 0.43, A growing before it. */
static double fake_dz(double dw)
{
    return dw < 0.43 ? 0.35 - 0.5 * dw * dw : -0.30 - 0.1 * (dw - 0.43);
}

static double fake_a(double dw)
{
    return dw < 0.43 ? 0.02 * exp(12.0 * (dw - 0.43)) : 0.0;
}

static void fill_trial(trial_arrays *t, plot_trial_data *d)
{
    for (int i = 0; i < NM; i++) {
        double dw = 0.5 * i / (NM - 1);
        t->mdw[i] = dw;
        t->mdz[i] = fake_dz(dw + 0.002) + 0.003 * sin(37.0 * i);
        t->ma[i] = fake_a(dw + 0.002) * 5.0;
    }
    for (int i = 0; i < NP; i++) {
        double dw = 0.5 * i / (NP - 1);
        t->pdw[i] = dw;
        t->pdz[i] = fake_dz(dw);
        t->pa[i] = fake_a(dw) * 4.0;
    }
    plot_trial_data_default(d);
    d->title = "trial 7: #gf = 90°, #gG = 0.13, #gDL = 0.5 (mock)";
    d->measured = (plot_curve){t->mdw, t->mdz, t->ma, NM};
    d->predicted = (plot_curve){t->pdw, t->pdz, t->pa, NP};
    d->snap_dw_measured = 0.4281;
    d->snap_dw_predicted = 0.4300;
    d->regime_measured = "asymmetric";
    d->regime_predicted = "asymmetric";
}

/* ---- trial report -------------------------------------------------------------------------- */

static void test_trial_report_draws_both_curves(void **state)
{
    (void)state;
    static trial_arrays t;
    plot_trial_data d;
    fill_trial(&t, &d);
    char why[256];
    const char *p = out_path("trial.png");
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_OK);
    assert_png(p, PLOT_WIDTH_DEFAULT, PLOT_HEIGHT_DEFAULT);

    /* both panels (upper: Delta Z, lower: A) hold measured and predicted pixels */
    region top = {0.11, 0.67, 0.12, 0.49}, bottom = {0.11, 0.67, 0.51, 0.90};
    assert_true(count_color(p, PLOT_COL_MEASURED, top) > 1000);
    assert_true(count_color(p, PLOT_COL_PREDICTED, top) > 300);
    assert_true(count_color(p, PLOT_COL_MEASURED, bottom) > 300);
    assert_true(count_color(p, PLOT_COL_PREDICTED, bottom) > 100);
    /* axes and labels in black, a legend on the right */
    assert_true(count_color(p, PLOT_COL_INK, WHOLE) > 2000);
    assert_true(count_color(p, COUNT_NOT_BACKGROUND, (region){0.70, 1.0, 0.1, 0.5}) > 500);
}

/* The calibrated prediction (issue 32 B): its snap line and its 1-sigma band in both panels, at
 * the band's place on the Delta W axis; none of either without it. */
static void test_trial_report_calibrated_band(void **state)
{
    (void)state;
    static trial_arrays t;
    plot_trial_data d;
    fill_trial(&t, &d);
    char why[256];
    const char *none = out_path("trial-nocal.png");
    assert_int_equal(plot_trial_report(none, &d, why, sizeof why), PLOT_OK);
    assert_int_equal(count_color(none, PLOT_COL_CALIBRATED_BAND, WHOLE), 0);
    assert_int_equal(count_color(none, PLOT_COL_CALIBRATED, WHOLE), 0);
    d.snap_dw_calibrated = 0.30;
    d.snap_sd_calibrated = 0.02;
    d.regime_calibrated = "asymmetric";
    const char *p = out_path("trial-cal.png");
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_OK);
    region top = {0.11, 0.67, 0.12, 0.49}, bottom = {0.11, 0.67, 0.51, 0.90};
    long band_top = count_color(p, PLOT_COL_CALIBRATED_BAND, top), band_bot = count_color(p, PLOT_COL_CALIBRATED_BAND, bottom);
    long line = count_color(p, PLOT_COL_CALIBRATED, WHOLE);
    /* The x axis spans about 0 .. 0.5 over 0.56 of the page: the band (0.28 .. 0.32) sits near 0.11
     * + 0.56 * 0.6 of the width, and nothing of it right of 0.11 + 0.56 * 0.7. */
    long right = count_color(p, PLOT_COL_CALIBRATED_BAND, (region){0.11 + 0.56 * 0.72, 0.67, 0.12, 0.90});
    printf("calibrated band: %ld px (top), %ld px (bottom), %ld right of it; line and legend %ld px\n", band_top,
           band_bot, right, line);
    assert_true(band_top > 1000 && band_bot > 1000);
    assert_int_equal(right, 0);
    assert_true(line > 100);
    d.snap_sd_calibrated = INFINITY;
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "snap_sd_calibrated"));
}

static void test_trial_report_custom_size_and_defaults(void **state)
{
    (void)state;
    static trial_arrays t;
    plot_trial_data d;
    fill_trial(&t, &d);
    d.width_px = 800;
    d.height_px = 600;
    d.title = NULL;
    d.regime_measured = NULL;
    d.snap_dw_measured = NAN; /* no measured snap: no line, no note */
    char why[256];
    const char *p = out_path("trial-800.png");
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_OK);
    assert_png(p, 800, 600);
    assert_true(count_color(p, PLOT_COL_MEASURED, WHOLE) > 300);
}

/* Pixels of the measured colour in a thin vertical strip at the middle of the Delta W axis. */
static long strip_measured(const char *path)
{
    /* the x axis spans the data symmetrically, so dw = 0.25 of [0, 0.5] sits at the viewport's
     * middle: 0.11 + 0.5 * (0.67 - 0.11) = 0.39 of the width */
    return count_color(path, PLOT_COL_MEASURED, (region){0.38, 0.40, 0.0, 1.0});
}

static void test_trial_report_nan_is_a_gap(void **state)
{
    (void)state;
    static trial_arrays t;
    plot_trial_data d;
    fill_trial(&t, &d);
    d.predicted.n = 0; /* measured only, no snaps: nothing else in the strip */
    d.snap_dw_measured = NAN;
    d.snap_dw_predicted = NAN;
    char why[256];
    const char *full = out_path("trial-nogap.png");
    assert_int_equal(plot_trial_report(full, &d, why, sizeof why), PLOT_OK);

    /* the tracker lost the ribbon for 0.2 < dw < 0.3; dz lost alone before that, a alone after */
    for (int i = 0; i < NM; i++) {
        if (t.mdw[i] > 0.2 && t.mdw[i] < 0.3) {
            t.mdz[i] = NAN;
            t.ma[i] = NAN;
        }
    }
    t.mdz[10] = NAN;
    t.ma[300] = NAN;
    t.mdw[350] = NAN;
    const char *gap = out_path("trial-gap.png");
    assert_int_equal(plot_trial_report(gap, &d, why, sizeof why), PLOT_OK);
    assert_png(gap, PLOT_WIDTH_DEFAULT, PLOT_HEIGHT_DEFAULT);

    assert_true(strip_measured(full) > 20);
    assert_int_equal(strip_measured(gap), 0);
    assert_true(count_color(gap, PLOT_COL_MEASURED, WHOLE) > 1000);
}

/* A long recording (20000 frames): drawn in full as a line, its sample dots thinned out. */
static void test_trial_report_long_series(void **state)
{
    (void)state;
    enum { N = 20000 };
    static double dw[N], dz[N], a[N];
    for (int i = 0; i < N; i++) {
        dw[i] = 0.5 * i / (N - 1);
        dz[i] = fake_dz(dw[i]);
        a[i] = i % 997 == 0 ? NAN : fake_a(dw[i]);
    }
    plot_trial_data d;
    plot_trial_data_default(&d);
    d.measured = (plot_curve){dw, dz, a, N};
    d.snap_dw_measured = 0.43;
    d.regime_measured = "symmetric";
    char why[256];
    const char *p = out_path("trial-long.png");
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_OK);
    assert_true(count_color(p, PLOT_COL_MEASURED, (region){0.11, 0.67, 0.12, 0.90}) > 1000);
}

static void test_trial_report_all_nan_and_empty(void **state)
{
    (void)state;
    static double nan3[3] = {NAN, NAN, NAN};
    plot_trial_data d;
    plot_trial_data_default(&d);
    d.measured = (plot_curve){nan3, nan3, nan3, 3};
    char why[256];
    const char *p = out_path("trial-empty.png");
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_OK);
    assert_png(p, PLOT_WIDTH_DEFAULT, PLOT_HEIGHT_DEFAULT);
    /* nothing measured in the panels (the legend, right of them, still shows the style) */
    assert_int_equal(count_color(p, PLOT_COL_MEASURED, (region){0.0, 0.68, 0.0, 1.0}), 0);
    assert_true(count_color(p, PLOT_COL_INK, WHOLE) > 500); /* axes still there */

    plot_trial_data_default(&d); /* nothing at all */
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_OK);
}

static void test_trial_report_bad_input(void **state)
{
    (void)state;
    static trial_arrays t;
    plot_trial_data d;
    char why[256];
    const char *p = out_path("bad.png");
    int before = count_dir_entries();

    assert_int_equal(plot_trial_report(p, NULL, why, sizeof why), PLOT_ERR_ARG);
    assert_true(strlen(why) > 0);

    fill_trial(&t, &d);
    t.mdz[3] = INFINITY;
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "measured.dz[3]"));
    t.mdz[3] = 0.0;

    d.predicted.dw = NULL;
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "predicted"));

    fill_trial(&t, &d);
    d.snap_dw_predicted = -INFINITY;
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "snap_dw_predicted"));

    fill_trial(&t, &d);
    d.width_px = 50;
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "width"));

    fill_trial(&t, &d);
    assert_int_equal(plot_trial_report(NULL, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_int_equal(plot_trial_report("", &d, why, sizeof why), PLOT_ERR_ARG);
    /* a NULL or empty reason buffer is allowed */
    assert_int_equal(plot_trial_report("", &d, NULL, 0), PLOT_ERR_ARG);

    assert_int_equal(count_dir_entries(), before);
}

static void test_trial_report_bad_path(void **state)
{
    (void)state;
    static trial_arrays t;
    plot_trial_data d;
    fill_trial(&t, &d);
    char why[256];
    int before = count_dir_entries();

    assert_int_equal(plot_trial_report("/nonexistent-ribbon-dir/r.png", &d, why, sizeof why), PLOT_ERR_IO);
    assert_non_null(strstr(why, "/nonexistent-ribbon-dir/r.png"));
    assert_non_null(strstr(why, "No such file or directory"));

    /* the target is a directory: drawn, then the rename is refused; no temporary file is left */
    char sub[300];
    snprintf(sub, sizeof sub, "%s/adir", g_dir);
    assert_int_equal(mkdir(sub, 0755), 0);
    assert_int_equal(plot_trial_report(sub, &d, why, sizeof why), PLOT_ERR_IO);
    assert_non_null(strstr(why, "rename"));
    assert_int_equal(count_dir_entries(), before + 1);
    rmdir(sub);

    /* and the process is fine: the next figure works */
    assert_int_equal(plot_trial_report(out_path("after-bad-path.png"), &d, why, sizeof why), PLOT_OK);
    unlink(out_path("after-bad-path.png"));
}

/* ---- phase diagram ------------------------------------------------------------------------- */

#define NG 6
#define NPHI 5

static double g_gamma[NG] = {0.05, 0.10, 0.15, 0.20, 0.25, 0.30};
static double g_phi[NPHI] = {30.0, 60.0, 90.0, 120.0, 150.0};
static plot_regime g_grid[NPHI * NG];
static double g_bg[NPHI + 1], g_bphi[NPHI + 1];
static plot_phase_trial g_trials[8];

static void fill_phase(plot_phase_data *d)
{
    /* the boundary Gamma*(phi) = 0.12 + 0.0006 phi; one failed cell, one no-snap corner */
    for (int j = 0; j < NPHI; j++)
        for (int i = 0; i < NG; i++)
            g_grid[j * NG + i] = g_gamma[i] < 0.12 + 0.0006 * g_phi[j] ? PLOT_REGIME_ASYMMETRIC : PLOT_REGIME_SYMMETRIC;
    g_grid[2 * NG + 5] = PLOT_REGIME_UNKNOWN;
    g_grid[0 * NG + 5] = PLOT_REGIME_NO_SNAP;
    for (int j = 0; j < NPHI; j++) {
        g_bphi[j] = g_phi[j];
        g_bg[j] = 0.12 + 0.0006 * g_phi[j];
    }
    g_bphi[NPHI] = NAN; /* a gap at the end is fine */
    g_bg[NPHI] = NAN;
    g_trials[0] = (plot_phase_trial){0.13, 90.0, PLOT_REGIME_ASYMMETRIC};
    g_trials[1] = (plot_phase_trial){0.21, 90.0, PLOT_REGIME_SYMMETRIC};
    g_trials[2] = (plot_phase_trial){0.08, 60.0, PLOT_REGIME_ASYMMETRIC};
    g_trials[3] = (plot_phase_trial){0.26, 130.0, PLOT_REGIME_SYMMETRIC};
    g_trials[4] = (plot_phase_trial){0.29, 30.0, PLOT_REGIME_NO_SNAP};
    g_trials[5] = (plot_phase_trial){0.18, 140.0, PLOT_REGIME_UNKNOWN};
    g_trials[6] = (plot_phase_trial){NAN, 90.0, PLOT_REGIME_SYMMETRIC}; /* skipped */
    g_trials[7] = (plot_phase_trial){0.17, 70.0, PLOT_REGIME_SYMMETRIC};
    plot_phase_data_default(d);
    d->title = "Phase diagram: predicted (cells), measured (markers)";
    d->gamma = g_gamma;
    d->n_gamma = NG;
    d->phi_deg = g_phi;
    d->n_phi = NPHI;
    d->grid = g_grid;
    d->boundary_gamma = g_bg;
    d->boundary_phi_deg = g_bphi;
    d->n_boundary = NPHI + 1;
    d->trials = g_trials;
    d->n_trials = 8;
}

static void test_phase_report_draws_cells_boundary_and_trials(void **state)
{
    (void)state;
    plot_phase_data d;
    fill_phase(&d);
    char why[256];
    const char *p = out_path("phase.png");
    assert_int_equal(plot_phase_report(p, &d, why, sizeof why), PLOT_OK);
    assert_png(p, PLOT_WIDTH_DEFAULT, PLOT_HEIGHT_DEFAULT);

    region plot = {0.10, 0.68, 0.10, 0.90};
    long asym = count_color(p, PLOT_COL_CELL_ASYM, plot), sym = count_color(p, PLOT_COL_CELL_SYM, plot);
    assert_true(asym > 20000);
    assert_true(sym > 20000);
    assert_true(count_color(p, PLOT_COL_CELL_NOSNAP, plot) > 5000);
    assert_true(count_color(p, PLOT_COL_CELL_UNKNOWN, plot) > 5000);
    assert_true(count_color(p, PLOT_COL_MARK_ASYM, plot) > 100);
    assert_true(count_color(p, PLOT_COL_MARK_SYM, plot) > 50);
    assert_true(count_color(p, PLOT_COL_MARK_OTHER, plot) > 30);
    /* the dashed boundary: compare with the same figure without it */
    d.n_boundary = 0;
    const char *q = out_path("phase-noboundary.png");
    assert_int_equal(plot_phase_report(q, &d, why, sizeof why), PLOT_OK);
    region inner = {0.12, 0.66, 0.12, 0.88};
    assert_true(count_color(p, COUNT_DARK, inner) > count_color(q, COUNT_DARK, inner) + 300);
    /* legend boxes of both regimes sit right of the plot */
    assert_true(count_color(p, PLOT_COL_CELL_ASYM, (region){0.69, 1.0, 0.0, 1.0}) > 50);
    assert_true(count_color(p, PLOT_COL_CELL_SYM, (region){0.69, 1.0, 0.0, 1.0}) > 50);
}

static void test_phase_report_trials_only_and_bad_input(void **state)
{
    (void)state;
    plot_phase_data d;
    fill_phase(&d);
    char why[256];
    /* no prediction yet: trials alone still make a figure */
    d.n_gamma = d.n_phi = 0;
    d.grid = NULL;
    d.n_boundary = 0;
    const char *p = out_path("phase-trials.png");
    assert_int_equal(plot_phase_report(p, &d, why, sizeof why), PLOT_OK);
    assert_int_equal(count_color(p, PLOT_COL_CELL_ASYM, (region){0.10, 0.68, 0.10, 0.90}), 0);
    assert_true(count_color(p, PLOT_COL_MARK_ASYM, WHOLE) > 100);

    fill_phase(&d);
    double unsorted[NG] = {0.05, 0.10, 0.10, 0.20, 0.25, 0.30};
    d.gamma = unsorted;
    assert_int_equal(plot_phase_report(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "gamma"));

    fill_phase(&d);
    g_grid[4] = (plot_regime)17;
    assert_int_equal(plot_phase_report(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "grid[4]"));

    fill_phase(&d);
    d.n_phi = 0;
    assert_int_equal(plot_phase_report(p, &d, why, sizeof why), PLOT_ERR_ARG);

    fill_phase(&d);
    g_trials[2].phi_deg = INFINITY;
    assert_int_equal(plot_phase_report(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "trials[2]"));
}

static void test_regime_names(void **state)
{
    (void)state;
    assert_int_equal(plot_regime_parse("asymmetric"), PLOT_REGIME_ASYMMETRIC);
    assert_int_equal(plot_regime_parse("Symmetric"), PLOT_REGIME_SYMMETRIC);
    assert_int_equal(plot_regime_parse("none"), PLOT_REGIME_NO_SNAP);
    assert_int_equal(plot_regime_parse("no snap"), PLOT_REGIME_NO_SNAP);
    assert_int_equal(plot_regime_parse("diverged"), PLOT_REGIME_UNKNOWN);
    assert_int_equal(plot_regime_parse(NULL), PLOT_REGIME_UNKNOWN);
    assert_string_equal(plot_regime_name(PLOT_REGIME_NO_SNAP), "no snap");
    assert_int_equal(plot_regime_parse("no-upper"), PLOT_REGIME_NO_UPPER);
    assert_string_equal(plot_regime_name(PLOT_REGIME_NO_UPPER), "no-upper");
    assert_string_equal(plot_regime_name((plot_regime)99), "unknown");
}

/* ---- branches ------------------------------------------------------------------------------ */

#define NB 120

static double b_up_x[NB], b_up_y[NB], b_as_x[NB], b_as_y[NB], b_lo_x[NB], b_lo_y[NB];
static bool b_up_s[NB], b_as_s[NB], b_lo_s[NB];
static plot_branch g_branches[3];
static plot_event g_events[2];

/* The paper's figure 3a in caricature: the plus branch loses stability at a pitchfork (0.40),
 * folds back at a saddle-node (0.45); an unstable asymmetric branch leaves the pitchfork; the
 * minus branch is stable throughout. */
static void fill_branches(plot_branch_data *d)
{
    for (int i = 0; i < NB; i++) {
        double s = (double)i / (NB - 1);
        /* plus branch: parametrised by s through the fold */
        double u = 0.9 * s;
        b_up_x[i] = 0.45 - (u - 0.45) * (u - 0.45) / 0.45;
        b_up_y[i] = 0.35 - 0.5 * u;
        b_up_s[i] = u < 0.25;
        double u_pf = 0.9 * 33.0 / (NB - 1); /* the pitchfork is point 33 of the plus branch */
        b_as_x[i] = 0.45 - (u_pf - 0.45) * (u_pf - 0.45) / 0.45 - 0.15 * s;
        b_as_y[i] = 0.35 - 0.5 * u_pf - 0.3 * s * s;
        b_as_s[i] = false;
        b_lo_x[i] = 0.5 * s;
        b_lo_y[i] = -0.3 - 0.05 * s;
        b_lo_s[i] = true;
    }
    b_lo_y[60] = NAN; /* a gap */
    g_branches[0] = (plot_branch){b_up_x, b_up_y, b_up_s, NB, "C#uP#d"};
    g_branches[1] = (plot_branch){b_as_x, b_as_y, b_as_s, NB, "C#uA#d"};
    g_branches[2] = (plot_branch){b_lo_x, b_lo_y, b_lo_s, NB, "C#uM#d"};
    g_events[0] = (plot_event){b_up_x[33], b_up_y[33], PLOT_EVENT_PITCHFORK};
    g_events[1] = (plot_event){0.45, 0.35 - 0.5 * 0.45, PLOT_EVENT_SADDLE_NODE};
    plot_branch_data_default(d);
    d->title = "Continuation, #gG = 0.13, #gf = 90°";
    d->x_label = "#gDW = dw/l";
    d->y_label = "#gDZ = dz/l";
    d->branches = g_branches;
    d->n_branches = 3;
    d->events = g_events;
    d->n_events = 2;
}

static void test_branches_stable_black_unstable_grey(void **state)
{
    (void)state;
    plot_branch_data d;
    fill_branches(&d);
    char why[256];
    const char *p = out_path("branches.png");
    assert_int_equal(plot_branches(p, &d, why, sizeof why), PLOT_OK);
    assert_png(p, PLOT_WIDTH_DEFAULT, PLOT_HEIGHT_DEFAULT);
    region plot = {0.11, 0.75, 0.11, 0.89};
    assert_true(count_color(p, PLOT_COL_UNSTABLE, plot) > 500);
    assert_true(count_color(p, PLOT_COL_INK, plot) > 1500);

    /* all unstable: no black inside the plot apart from the event markers and labels */
    for (int i = 0; i < NB; i++)
        b_up_s[i] = b_lo_s[i] = false;
    d.n_events = 0;
    for (int k = 0; k < 3; k++)
        g_branches[k].label = NULL;
    const char *q = out_path("branches-unstable.png");
    assert_int_equal(plot_branches(q, &d, why, sizeof why), PLOT_OK);
    assert_true(count_color(q, PLOT_COL_UNSTABLE, plot) > count_color(p, PLOT_COL_UNSTABLE, plot));
    assert_true(count_color(q, PLOT_COL_INK, (region){0.12, 0.74, 0.12, 0.88}) < 100);

    /* bad input */
    fill_branches(&d);
    b_as_y[5] = INFINITY;
    assert_int_equal(plot_branches(q, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "branches[1].y[5]"));
    fill_branches(&d);
    g_events[1].kind = (plot_event_kind)7;
    assert_int_equal(plot_branches(q, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "events[1]"));
}

/* Two panels on one page (ribbon-sim continue --plot): each slice has its own branches; a panel
 * with only unstable branches has grey but no stable black line in its slice; other events are
 * accepted; too many panels are refused. */
static void test_branch_panels_side_by_side(void **state)
{
    (void)state;
    plot_branch_data panels[2];
    fill_branches(&panels[0]);
    fill_branches(&panels[1]);
    panels[1].n_events = 0;
    panels[1].n_branches = 1; /* the asymmetric branch only */
    g_events[0].kind = PLOT_EVENT_OTHER;
    char why[256];
    const char *p = out_path("panels.png");
    assert_int_equal(plot_branches_panels(p, panels, 2, 1400, 600, why, sizeof why), PLOT_OK);
    assert_png(p, 1400, 600);
    region left = {0.10, 0.40, 0.15, 0.89}, right = {0.51, 0.81, 0.15, 0.89};
    assert_true(count_color(p, PLOT_COL_INK, left) > 500);
    assert_true(count_color(p, PLOT_COL_UNSTABLE, right) > 200);
    assert_true(count_color(p, PLOT_COL_UNSTABLE, left) > 200);
    assert_int_equal(plot_branches_panels(p, panels, PLOT_PANELS_MAX + 1, 0, 0, why, sizeof why),
                     PLOT_ERR_ARG);
    assert_int_equal(plot_branches_panels(p, NULL, 1, 0, 0, why, sizeof why), PLOT_ERR_ARG);
    g_events[0].kind = PLOT_EVENT_PITCHFORK;
}

/* A sweep's regime map: markers and a boundary line are drawn; bad input is refused. */
static void test_sweep_map(void **state)
{
    (void)state;
    plot_sweep_point pts[6];
    for (int i = 0; i < 6; i++)
        pts[i] = (plot_sweep_point){60.0 + 10.0 * (i % 3), i < 3 ? 0.1 : 0.3,
                                    i < 3 ? PLOT_REGIME_ASYMMETRIC : PLOT_REGIME_SYMMETRIC, false, NAN, 0.0};
    double bx[3] = {60, 70, 80}, by[3] = {0.2, 0.21, 0.22};
    plot_sweep_line line = {bx, by, 3, false, true, NULL};
    plot_sweep_data d;
    plot_sweep_data_default(&d);
    d.x0 = 60;
    d.x1 = 80;
    d.y0 = 0.1;
    d.y1 = 0.3;
    d.points = pts;
    d.n_points = 6;
    d.lines = &line;
    d.n_lines = 1;
    d.width_px = 900;
    d.height_px = 650;
    char why[256];
    const char *p = out_path("sweep.png");
    assert_int_equal(plot_sweep(p, &d, why, sizeof why), PLOT_OK);
    assert_png(p, 900, 650);
    assert_true(count_color(p, COUNT_DARK, (region){0.15, 0.9, 0.15, 0.85}) > 300);
    assert_true(count_color(p, PLOT_COL_MARK_OTHER, (region){0.15, 0.9, 0.15, 0.85}) > 100);
    /* No stable state at one point: a grey diamond and a grey bar up to bar_to; and the legend on
     * the right, which a map without it does not have. */
    long right_dark = count_color(p, COUNT_DARK, (region){0.93, 1.0, 0.1, 0.9});
    pts[0].no_state = true;
    pts[0].bar_to = 0.2;
    line.legend = "boundary";
    d.legend = true;
    assert_int_equal(plot_sweep(p, &d, why, sizeof why), PLOT_OK);
    assert_true(count_color(p, PLOT_COL_CELL_NOSNAP, (region){0.0, 0.65, 0.0, 1.0}) > 50);
    assert_true(count_color(p, PLOT_COL_UNSTABLE, (region){0.0, 0.65, 0.0, 1.0}) > 20);
    print_message("dark pixels right of the axes: %ld without the legend, %ld with it\n", right_dark,
                  count_color(p, COUNT_DARK, (region){0.93, 1.0, 0.1, 0.9}));
    assert_true(count_color(p, COUNT_DARK, (region){0.93, 1.0, 0.1, 0.9}) > right_dark + 100);
    pts[2].y = INFINITY;
    assert_int_equal(plot_sweep(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "points[2]"));
}

/* A two-parameter continuation's curves: each in its own colour (none in a colour no curve has),
 * the special point's dashed line and star add dark pixels in a strip around it, grey sweep
 * points under the curves; too many curves, Inf and a NULL array are refused with a reason. */
static void test_boundary_curves(void **state)
{
    (void)state;
    double x[2][20], y[2][20];
    for (int i = 0; i < 20; i++) {
        x[0][i] = x[1][i] = 0.1 + 0.01 * i;
        y[0][i] = 0.5 - 0.002 * i;
        y[1][i] = 0.3 + 0.004 * i;
    }
    y[1][10] = NAN; /* a gap */
    plot_boundary_curve cv[2] = {{x[0], y[0], 20, PLOT_CURVE_MARK_SQUARE, "fold"},
                                 {x[1], y[1], 20, PLOT_CURVE_MARK_CIRCLE, "pitchfork"}};
    plot_sweep_point pts[2] = {{0.12, 0.35, PLOT_REGIME_ASYMMETRIC, false, NAN, 0.0}, {0.27, 0.45, PLOT_REGIME_SYMMETRIC, false, NAN, 0.0}};
    plot_boundary_data d;
    plot_boundary_data_default(&d);
    assert_true(isnan(d.star_x) && isnan(d.star_y));
    d.curves = cv;
    d.n_curves = 2;
    d.points = pts;
    d.n_points = 2;
    d.width_px = 1000;
    d.height_px = 700;
    char why[256];
    const char *p = out_path("boundary.png"), *q = out_path("boundary-star.png");
    assert_int_equal(plot_boundary(p, &d, why, sizeof why), PLOT_OK);
    assert_png(p, 1000, 700);
    region plot_area = {0.12, 0.9, 0.12, 0.88};
    assert_true(count_color(p, PLOT_COL_SERIES_1, plot_area) > 500);
    assert_true(count_color(p, PLOT_COL_SERIES_2, plot_area) > 500);
    assert_int_equal(count_color(p, PLOT_COL_SERIES_3, WHOLE), 0);
    assert_true(count_color(p, PLOT_COL_UNSTABLE, plot_area) > 50);
    d.star_x = 0.2;
    d.star_y = 0.4;
    d.star_label = "codim-2 point";
    d.note = "a note";
    assert_int_equal(plot_boundary(q, &d, why, sizeof why), PLOT_OK);
    /* the star sits at x = 0.2, halfway along the data's x span: a strip around the page's middle */
    region strip = {0.45, 0.6, 0.3, 0.95};
    assert_true(count_color(q, COUNT_DARK, strip) > count_color(p, COUNT_DARK, strip) + 100);
    plot_boundary_curve many[PLOT_BOUNDARY_CURVES_MAX + 1];
    for (int k = 0; k <= PLOT_BOUNDARY_CURVES_MAX; k++) many[k] = cv[0];
    d.curves = many;
    d.n_curves = PLOT_BOUNDARY_CURVES_MAX + 1;
    assert_int_equal(plot_boundary(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "curves"));
    d.curves = cv;
    d.n_curves = 2;
    y[0][3] = INFINITY;
    assert_int_equal(plot_boundary(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "curves[0].y"));
    y[0][3] = 0.4;
    d.star_y = -INFINITY;
    assert_int_equal(plot_boundary(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_non_null(strstr(why, "star_y"));
    d.star_y = 0.4;
    d.points = NULL;
    assert_int_equal(plot_boundary(p, &d, why, sizeof why), PLOT_ERR_ARG);
    assert_int_equal(plot_boundary(p, NULL, why, sizeof why), PLOT_ERR_ARG);
    unlink(p);
    unlink(q);
}

/* ---- PLplot containment -------------------------------------------------------------------- */

static plot_status draw_nothing(void *ctx, char *why, size_t why_len)
{
    (void)ctx;
    (void)why;
    (void)why_len;
    pladv(0);
    return PLOT_OK;
}

static plot_status draw_then_exit(void *ctx, char *why, size_t why_len)
{
    (void)ctx;
    (void)why;
    (void)why_len;
    pladv(0);
    plvpor(0.1, 0.9, 0.1, 0.9);
    plwind(0, 1, 0, 1);
    plexit("test: a fatal PLplot error");
    return PLOT_OK; /* not reached */
}

static plot_status draw_then_abort(void *ctx, char *why, size_t why_len)
{
    (void)ctx;
    (void)why;
    (void)why_len;
    pladv(0);
    plabort("test: an aborted PLplot operation");
    return PLOT_OK;
}

static plot_status draw_own_error(void *ctx, char *why, size_t why_len)
{
    (void)ctx;
    return plot_fail(PLOT_ERR_ARG, why, why_len, "drawing refused: %s", "test");
}

static void assert_next_figure_works(void)
{
    static trial_arrays t;
    plot_trial_data d;
    fill_trial(&t, &d);
    char why[256];
    const char *p = out_path("after.png");
    assert_int_equal(plot_trial_report(p, &d, why, sizeof why), PLOT_OK);
    assert_true(count_color(p, PLOT_COL_MEASURED, WHOLE) > 1000);
    unlink(p);
}

static void test_missing_driver_is_an_error(void **state)
{
    (void)state;
    char why[256];
    int before = count_dir_entries();
    assert_int_equal(plot_session_run("nosuchdevice", out_path("x.png"), 400, 300, draw_nothing, NULL, why, sizeof why),
                     PLOT_ERR_DEVICE);
    assert_non_null(strstr(why, "nosuchdevice"));
    assert_int_equal(count_dir_entries(), before);
    assert_next_figure_works();
}

static void test_fatal_error_does_not_exit(void **state)
{
    (void)state;
    char why[256];
    int before = count_dir_entries();
    assert_int_equal(plot_session_run(PLOT_DEVICE, out_path("x.png"), 400, 300, draw_then_exit, NULL, why, sizeof why),
                     PLOT_ERR_PLPLOT);
    assert_non_null(strstr(why, "test: a fatal PLplot error"));
    assert_int_equal(count_dir_entries(), before);
    PLINT cur = -1;
    plgstrm(&cur);
    assert_int_equal(cur, 0);
    assert_next_figure_works();
}

static void test_abort_and_draw_errors_are_reported(void **state)
{
    (void)state;
    char why[256];
    int before = count_dir_entries();
    assert_int_equal(plot_session_run(PLOT_DEVICE, out_path("x.png"), 400, 300, draw_then_abort, NULL, why, sizeof why),
                     PLOT_ERR_PLPLOT);
    assert_non_null(strstr(why, "test: an aborted PLplot operation"));
    assert_int_equal(plot_session_run(PLOT_DEVICE, out_path("x.png"), 400, 300, draw_own_error, NULL, why, sizeof why),
                     PLOT_ERR_ARG);
    assert_string_equal(why, "drawing refused: test");
    assert_int_equal(count_dir_entries(), before);
    assert_next_figure_works();
}

/* Every figure ends its stream: after many, the next new stream PLplot hands out is still 1. */
static void test_repeated_calls_leave_no_stream(void **state)
{
    (void)state;
    static trial_arrays t;
    plot_trial_data td;
    plot_phase_data pd;
    plot_branch_data bd;
    char why[256];
    for (int k = 0; k < 12; k++) {
        fill_trial(&t, &td);
        fill_phase(&pd);
        fill_branches(&bd);
        td.width_px = pd.width_px = bd.width_px = 400 + 10 * k;
        td.height_px = pd.height_px = bd.height_px = 300;
        assert_int_equal(plot_trial_report(out_path("rep-t.png"), &td, why, sizeof why), PLOT_OK);
        assert_int_equal(plot_phase_report(out_path("rep-p.png"), &pd, why, sizeof why), PLOT_OK);
        assert_int_equal(plot_branches(out_path("rep-b.png"), &bd, why, sizeof why), PLOT_OK);
        assert_png(out_path("rep-t.png"), (unsigned)td.width_px, 300);
    }
    /* the caller's current stream is left as it was */
    PLINT cur = -1, s = -1;
    plgstrm(&cur);
    assert_int_equal(cur, 0);
    plmkstrm(&s);
    assert_int_equal(s, 1);
    plend1();
    plsstrm(0);
    unlink(out_path("rep-t.png"));
    unlink(out_path("rep-p.png"));
    unlink(out_path("rep-b.png"));
}

typedef struct thread_job {
    int id;
    int failures;
} thread_job;

static void *thread_main(void *arg)
{
    thread_job *j = arg;
    static trial_arrays t[2]; /* one per thread (id 0, 1), read only after filling */
    plot_trial_data d;
    fill_trial(&t[j->id], &d);
    d.width_px = 500;
    d.height_px = 400;
    char name[64], why[256];
    snprintf(name, sizeof name, "thread-%d.png", j->id);
    char path[512];
    snprintf(path, sizeof path, "%s/%s", g_dir, name);
    for (int k = 0; k < 4; k++) {
        if (plot_trial_report(path, &d, why, sizeof why) != PLOT_OK) {
            j->failures++;
            continue;
        }
        unsigned w, h;
        if (png_size(path, &w, &h) != 0 || w != 500 || h != 400)
            j->failures++;
    }
    unlink(path);
    return NULL;
}

static void test_concurrent_calls(void **state)
{
    (void)state;
    pthread_t th[2];
    thread_job jobs[2] = {{0, 0}, {1, 0}};
    for (int i = 0; i < 2; i++)
        assert_int_equal(pthread_create(&th[i], NULL, thread_main, &jobs[i]), 0);
    for (int i = 0; i < 2; i++)
        pthread_join(th[i], NULL);
    assert_int_equal(jobs[0].failures, 0);
    assert_int_equal(jobs[1].failures, 0);
}

/* ---- main ---------------------------------------------------------------------------------- */

static int remove_dir(void)
{
    DIR *d = opendir(g_dir);
    if (!d)
        return 0;
    struct dirent *e;
    char p[600];
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        snprintf(p, sizeof p, "%s/%s", g_dir, e->d_name);
        unlink(p);
    }
    closedir(d);
    return rmdir(g_dir);
}

int main(void)
{
    /* PLplot must find its drivers in its installed location, without help from the environment */
    unsetenv("PLPLOT_DRV_DIR");
    unsetenv("PLPLOT_LIB");
    unsetenv("PLPLOT_HOME");

    const char *tmp = getenv("TMPDIR");
    snprintf(g_dir, sizeof g_dir, "%s/ribbon-plot-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(g_dir)) {
        perror("mkdtemp");
        return 1;
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_trial_report_draws_both_curves),
        cmocka_unit_test(test_trial_report_calibrated_band),
        cmocka_unit_test(test_trial_report_custom_size_and_defaults),
        cmocka_unit_test(test_trial_report_nan_is_a_gap),
        cmocka_unit_test(test_trial_report_long_series),
        cmocka_unit_test(test_trial_report_all_nan_and_empty),
        cmocka_unit_test(test_trial_report_bad_input),
        cmocka_unit_test(test_trial_report_bad_path),
        cmocka_unit_test(test_phase_report_draws_cells_boundary_and_trials),
        cmocka_unit_test(test_phase_report_trials_only_and_bad_input),
        cmocka_unit_test(test_regime_names),
        cmocka_unit_test(test_branches_stable_black_unstable_grey),
        cmocka_unit_test(test_branch_panels_side_by_side),
        cmocka_unit_test(test_sweep_map),
        cmocka_unit_test(test_boundary_curves),
        cmocka_unit_test(test_missing_driver_is_an_error),
        cmocka_unit_test(test_fatal_error_does_not_exit),
        cmocka_unit_test(test_abort_and_draw_errors_are_reported),
        cmocka_unit_test(test_repeated_calls_leave_no_stream),
        cmocka_unit_test(test_concurrent_calls),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    if (getenv("RIBBON_PLOT_KEEP"))
        fprintf(stderr, "figures kept in %s\n", g_dir);
    else
        remove_dir();
    return rc;
}
