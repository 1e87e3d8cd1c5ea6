/*
 * plot_trial.c: the report of one trial (ribbonctl report, GET /trials/{id}/report.png).
 *
 * Layout, after the paper's dynamic-simulation panels (figures 3c and 4c):
 *
 *   +------------------------------------------+  title
 *   |  Delta Z = dz/l   (top panel)            |  legend
 *   |------------------------------------------|  (outside, right)
 *   |  A (rad)          (bottom panel)         |
 *   +------------------------------------------+
 *                 Delta W = dw/l  (shared axis, numbers on the bottom panel only)
 *
 * Measured: blue solid line with sample dots (at most PLOT_TRIAL_MAX_MARKS of them, evenly
 * strided, so a long video does not turn the line into a smear); predicted: vermilion dashed line.
 * Each snap is a vertical line in both panels in its curve's colour, a triangle at the top of the
 * upper panel and its value written beside it (measured above predicted, so two close snaps stay
 * readable). The calibrated prediction's snap (issue 32 B) is a bluish green line with its 1-sigma
 * band shaded pale green behind the grid and the curves. The A axis spans at least +-PLOT_TRIAL_A_MIN rad: a symmetric snap, whose A stays near
 * zero, then reads as flat instead of as magnified noise.
 */
#include "plot.h"

#include "plot_legend.h"
#include "plot_series.h"
#include "plot_session.h"
#include "plot_style.h"

#include <math.h>
#include <plplot.h>
#include <stdio.h>

#define PLOT_TRIAL_MAX_MARKS 150
#define PLOT_TRIAL_A_MIN 0.1 /* rad */

/* Viewport of each panel in normalised page units: x from left to right, y from bottom to top. */
#define VP_LEFT 0.11
#define VP_RIGHT 0.67
#define VP_TOP_BOTTOM 0.51
#define VP_TOP_TOP 0.88
#define VP_BOT_BOTTOM 0.10
#define VP_BOT_TOP 0.49

void plot_trial_data_default(plot_trial_data *d)
{
    *d = (plot_trial_data){0};
    d->snap_dw_measured = NAN;
    d->snap_dw_predicted = NAN;
    d->snap_dw_calibrated = NAN;
    d->snap_sd_calibrated = NAN;
}

/* The calibrated snap's 1-sigma band, shaded over the panel's height (behind the curves). */
static void draw_band(double x, double sd, double y0, double y1)
{
    if (!isfinite(x) || !isfinite(sd) || !(sd > 0.0)) return;
    PLFLT bx[4] = {x - sd, x + sd, x + sd, x - sd}, by[4] = {y0, y0, y1, y1};
    plcol0(PLOT_COL_CALIBRATED_BAND);
    plfill(4, bx, by);
    plcol0(PLOT_COL_INK);
}

static plot_status check_curve(const char *name, const plot_curve *c, char *why, size_t why_len)
{
    char field[64];
    plot_status st;
    if (c->n > 0 && (!c->dw || !c->dz))
        return plot_fail(PLOT_ERR_ARG, why, why_len, "%s has %zu points but no dw or dz array", name, c->n);
    snprintf(field, sizeof field, "%s.dw", name);
    if ((st = plot_series_check(field, c->dw, c->n, why, why_len)) != PLOT_OK)
        return st;
    snprintf(field, sizeof field, "%s.dz", name);
    if ((st = plot_series_check(field, c->dz, c->n, why, why_len)) != PLOT_OK)
        return st;
    snprintf(field, sizeof field, "%s.a", name);
    if (c->a && (st = plot_series_check(field, c->a, c->n, why, why_len)) != PLOT_OK)
        return st;
    return PLOT_OK;
}

typedef struct trial_ctx {
    const plot_trial_data *d;
    double x0, x1; /* shared Delta W axis */
} trial_ctx;

static void draw_grid(const char *xopt_numbers)
{
    plcol0(PLOT_COL_GRID);
    plwidth(PLOT_WIDTH_THIN);
    plbox("ga", 0.0, 0, "ga", 0.0, 0);
    plcol0(PLOT_COL_INK);
    plbox(xopt_numbers, 0.0, 0, "bcnstv", 0.0, 0);
}

static void draw_snap_line(double x, double y0, double y1, int color)
{
    if (!isfinite(x))
        return;
    PLFLT xs[2] = {x, x}, ys[2] = {y0, y1};
    plcol0(color);
    plwidth(1.5);
    pllsty(PLOT_LSTY_DOTTED);
    plline(2, xs, ys);
    pllsty(PLOT_LSTY_SOLID);
}

/* Triangle at the top of the panel and the value beside it, on row (0 = highest). */
static void draw_snap_note(const trial_ctx *c, double x, double y0, double y1, int row, int color, const char *who)
{
    if (!isfinite(x))
        return;
    double h = y1 - y0;
    PLFLT tx = x, ty = y1 - 0.035 * h;
    plcol0(color);
    plstring(1, &tx, &ty, PLOT_GLYPH_TRIANGLE_DOWN);
    char text[96];
    snprintf(text, sizeof text, "%s snap %.4f", who, x);
    /* write on the side of the line with more room */
    bool left = (x - c->x0) > 0.65 * (c->x1 - c->x0);
    double dx = 0.01 * (c->x1 - c->x0);
    plschr(0.0, 0.9);
    plptex(left ? x - dx : x + dx, y1 - (0.09 + 0.07 * row) * h, 1.0, 0.0, left ? 1.0 : 0.0, text);
    plschr(0.0, PLOT_CHAR_SCALE);
}

static void draw_curve(const plot_curve *cv, const double *y, int color, int style, bool marks)
{
    if (!y || cv->n == 0)
        return;
    plcol0(color);
    plwidth(PLOT_WIDTH_DATA);
    pllsty(style);
    plot_series_line(cv->dw, y, cv->n);
    pllsty(PLOT_LSTY_SOLID);
    if (marks) {
        size_t k = plot_series_finite(cv->dw, y, cv->n);
        size_t stride = k > PLOT_TRIAL_MAX_MARKS ? (cv->n + PLOT_TRIAL_MAX_MARKS - 1) / PLOT_TRIAL_MAX_MARKS : 1;
        plschr(0.0, 0.8);
        plot_series_points(cv->dw, y, cv->n, PLOT_GLYPH_DOT, stride);
        plschr(0.0, PLOT_CHAR_SCALE);
    }
}

/* One panel: which = 0 for Delta Z, 1 for A. */
static void draw_panel(const trial_ctx *c, int which)
{
    const plot_trial_data *d = c->d;
    const double *ym = which == 0 ? d->measured.dz : d->measured.a;
    const double *yp = which == 0 ? d->predicted.dz : d->predicted.a;

    plot_range r;
    plot_range_init(&r);
    plot_range_add(&r, ym, ym ? d->measured.n : 0);
    plot_range_add(&r, yp, yp ? d->predicted.n : 0);
    double y0, y1;
    if (which == 0) {
        plot_range_axis(&r, 0.08, -0.5, 0.5, &y0, &y1);
    } else {
        plot_range_axis(&r, 0.08, -PLOT_TRIAL_A_MIN, PLOT_TRIAL_A_MIN, &y0, &y1);
        y0 = fmin(y0, -PLOT_TRIAL_A_MIN);
        y1 = fmax(y1, PLOT_TRIAL_A_MIN);
    }
    /* room at the top of the upper panel for the snap notes */
    if (which == 0)
        y1 += 0.25 * (y1 - y0);

    if (which == 0)
        plvpor(VP_LEFT, VP_RIGHT, VP_TOP_BOTTOM, VP_TOP_TOP);
    else
        plvpor(VP_LEFT, VP_RIGHT, VP_BOT_BOTTOM, VP_BOT_TOP);
    plwind(c->x0, c->x1, y0, y1);
    draw_band(d->snap_dw_calibrated, d->snap_sd_calibrated, y0, y1); /* behind the grid and curves */
    draw_grid(which == 0 ? "bcst" : "bcnst");

    plcol0(PLOT_COL_INK);
    if (which == 0) {
        plmtex("l", 5.0, 0.5, 0.5, "#gDZ = dz/l");
    } else {
        plmtex("l", 5.0, 0.5, 0.5, "A (rad)");
        plmtex("b", 3.0, 0.5, 0.5, "#gDW = dw/l");
    }

    draw_snap_line(d->snap_dw_calibrated, y0, y1, PLOT_COL_CALIBRATED);
    draw_snap_line(d->snap_dw_measured, y0, y1, PLOT_COL_MEASURED);
    draw_snap_line(d->snap_dw_predicted, y0, y1, PLOT_COL_PREDICTED);
    draw_curve(&d->predicted, yp, PLOT_COL_PREDICTED, PLOT_LSTY_DASHED, false);
    draw_curve(&d->measured, ym, PLOT_COL_MEASURED, PLOT_LSTY_SOLID, true);
    if (which == 0) {
        draw_snap_note(c, d->snap_dw_measured, y0, y1, 0, PLOT_COL_MEASURED, "measured");
        draw_snap_note(c, d->snap_dw_predicted, y0, y1, 1, PLOT_COL_PREDICTED, "predicted");
    }

    if (plot_series_finite(d->measured.dw, ym, ym ? d->measured.n : 0) == 0 &&
        plot_series_finite(d->predicted.dw, yp, yp ? d->predicted.n : 0) == 0) {
        plcol0(PLOT_COL_UNSTABLE);
        plptex(0.5 * (c->x0 + c->x1), 0.5 * (y0 + y1), 1.0, 0.0, 0.5, "no data");
    }
    plcol0(PLOT_COL_INK);
}

static plot_status trial_draw(void *vctx, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    trial_ctx *c = vctx;
    const plot_trial_data *d = c->d;

    pladv(0);
    draw_panel(c, 0);
    plcol0(PLOT_COL_INK);
    if (d->title && *d->title)
        plmtex("t", 1.5, 0.5, 0.5, d->title);

    /* legend beside the top panel */
    char lm[64], lp[64], lsm[64], lsp[64], lsc[96];
    snprintf(lm, sizeof lm, "measured (%.24s)", d->regime_measured ? d->regime_measured : "unknown");
    snprintf(lp, sizeof lp, "predicted (%.24s)", d->regime_predicted ? d->regime_predicted : "unknown");
    snprintf(lsm, sizeof lsm, "measured snap %.4f", d->snap_dw_measured);
    snprintf(lsp, sizeof lsp, "predicted snap %.4f", d->snap_dw_predicted);
    if (isfinite(d->snap_sd_calibrated))
        snprintf(lsc, sizeof lsc, "calibrated %.4f +- %.4f (%.16s)", d->snap_dw_calibrated, d->snap_sd_calibrated,
                 d->regime_calibrated ? d->regime_calibrated : "unknown");
    else
        snprintf(lsc, sizeof lsc, "calibrated %.4f (%.16s)", d->snap_dw_calibrated,
                 d->regime_calibrated ? d->regime_calibrated : "unknown");
    plot_legend_entry e[7];
    int n = 0;
    if (plot_series_finite(d->measured.dw, d->measured.dz, d->measured.n) > 0)
        e[n++] = (plot_legend_entry){lm, PLOT_LEGEND_KIND_LINE_SYMBOL, PLOT_COL_MEASURED, PLOT_LSTY_SOLID,
                                     PLOT_WIDTH_DATA, PLOT_GLYPH_DOT, 0.8};
    else
        e[n++] = (plot_legend_entry){"no measured curve", PLOT_LEGEND_KIND_NONE, PLOT_COL_MEASURED, 0, 0, NULL, 0};
    if (plot_series_finite(d->predicted.dw, d->predicted.dz, d->predicted.n) > 0)
        e[n++] = (plot_legend_entry){lp, PLOT_LEGEND_KIND_LINE, PLOT_COL_PREDICTED, PLOT_LSTY_DASHED,
                                     PLOT_WIDTH_DATA, NULL, 0};
    else
        e[n++] = (plot_legend_entry){"no predicted curve", PLOT_LEGEND_KIND_NONE, PLOT_COL_PREDICTED, 0, 0, NULL, 0};
    if (isfinite(d->snap_dw_measured))
        e[n++] = (plot_legend_entry){lsm, PLOT_LEGEND_KIND_LINE_SYMBOL, PLOT_COL_MEASURED, PLOT_LSTY_DOTTED, 1.5,
                                     PLOT_GLYPH_TRIANGLE_DOWN, 0.8};
    if (isfinite(d->snap_dw_predicted))
        e[n++] = (plot_legend_entry){lsp, PLOT_LEGEND_KIND_LINE_SYMBOL, PLOT_COL_PREDICTED, PLOT_LSTY_DOTTED, 1.5,
                                     PLOT_GLYPH_TRIANGLE_DOWN, 0.8};
    if (isfinite(d->snap_dw_calibrated))
        e[n++] = (plot_legend_entry){lsc, PLOT_LEGEND_KIND_LINE, PLOT_COL_CALIBRATED, PLOT_LSTY_DOTTED, 1.5, NULL, 0};
    if (!isfinite(d->snap_dw_measured))
        e[n++] = (plot_legend_entry){"no measured snap", PLOT_LEGEND_KIND_NONE, PLOT_COL_MEASURED, 0, 0, NULL, 0};
    if (!isfinite(d->snap_dw_predicted))
        e[n++] = (plot_legend_entry){"no predicted snap", PLOT_LEGEND_KIND_NONE, PLOT_COL_PREDICTED, 0, 0, NULL, 0};
    plot_legend_draw(e, n, PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, 0.02, 0.0);

    draw_panel(c, 1);
    return PLOT_OK;
}

plot_status plot_trial_report(const char *png_path, const plot_trial_data *d, char *why, size_t why_len)
{
    if (why && why_len)
        why[0] = '\0';
    if (!d)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "plot_trial_report: no data");
    plot_status st;
    int w, h;
    if ((st = plot_size_resolve(d->width_px, PLOT_WIDTH_DEFAULT, "width", &w, why, why_len)) != PLOT_OK ||
        (st = plot_size_resolve(d->height_px, PLOT_HEIGHT_DEFAULT, "height", &h, why, why_len)) != PLOT_OK ||
        (st = check_curve("measured", &d->measured, why, why_len)) != PLOT_OK ||
        (st = check_curve("predicted", &d->predicted, why, why_len)) != PLOT_OK ||
        (st = plot_value_check("snap_dw_measured", d->snap_dw_measured, why, why_len)) != PLOT_OK ||
        (st = plot_value_check("snap_dw_predicted", d->snap_dw_predicted, why, why_len)) != PLOT_OK ||
        (st = plot_value_check("snap_dw_calibrated", d->snap_dw_calibrated, why, why_len)) != PLOT_OK ||
        (st = plot_value_check("snap_sd_calibrated", d->snap_sd_calibrated, why, why_len)) != PLOT_OK)
        return st;

    trial_ctx c = {.d = d};
    plot_range r;
    plot_range_init(&r);
    plot_range_add(&r, d->measured.dw, d->measured.n);
    plot_range_add(&r, d->predicted.dw, d->predicted.n);
    plot_range_add1(&r, d->snap_dw_measured);
    plot_range_add1(&r, d->snap_dw_predicted);
    plot_range_add1(&r, d->snap_dw_calibrated);
    plot_range_axis(&r, 0.03, 0.0, 1.0, &c.x0, &c.x1);
    return plot_session_run(PLOT_DEVICE, png_path, w, h, trial_draw, &c, why, why_len);
}
