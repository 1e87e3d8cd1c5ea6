/*
 * plot_boundary.c: the figures of a two-parameter continuation (`ribbon-sim boundary --plot`):
 * the traced regime boundary Gamma*(phi), one coloured line per Delta L, over a sweep's
 * classified points; or the saddle-node and pitchfork curves in (Gamma, Delta W) with the
 * codimension-2 point where they meet. The caller names the curves and the axes and passes plain
 * arrays (see plot.h). Sweep points are grey outlined polygons in data units (plot_marker.h), as
 * in plot_sweep, so the curves stay readable over them; the legend says what every line and
 * marker is.
 */
#include "plot.h"

#include "plot_legend.h"
#include "plot_marker.h"
#include "plot_series.h"
#include "plot_session.h"
#include "plot_style.h"

#include <math.h>
#include <plplot.h>
#include <stdio.h>

/* The axes' box on the page, leaving room for the labels below and left. */
#define VP_LEFT 0.11
#define VP_RIGHT 0.96
#define VP_BOTTOM 0.13
#define VP_TOP 0.92

static const int curve_color[PLOT_BOUNDARY_CURVES_MAX] = {PLOT_COL_SERIES_1, PLOT_COL_SERIES_2, PLOT_COL_SERIES_3,
                                                          PLOT_COL_SERIES_4, PLOT_COL_SERIES_5, PLOT_COL_SERIES_6};

void plot_boundary_data_default(plot_boundary_data *d)
{
    *d = (plot_boundary_data){0};
    d->star_x = d->star_y = NAN;
}

typedef struct boundary_ctx {
    const plot_boundary_data *d;
    double x0, x1, y0, y1; /* axis ranges */
    int w, h;              /* page, px */
    bool any[4];           /* sweep points of each marker kind: asymmetric, symmetric, other, no state */
    bool star;             /* the special point is drawn */
} boundary_ctx;

/* The sweep markers' kind: 0 circle (asymmetric), 1 square (symmetric), 2 cross, 3 diamond (no
 * stable upper state). */
static int point_kind(const plot_sweep_point *p)
{
    if (p->no_state) return 3;
    return p->regime == PLOT_REGIME_ASYMMETRIC ? 0 : p->regime == PLOT_REGIME_SYMMETRIC ? 1 : 2;
}

static void marker(int kind, double x, double y, double rx, double ry)
{
    if (kind == 0)
        plot_marker_polygon(x, y, rx, ry, 36, 0.0);
    else if (kind == 1)
        plot_marker_polygon(x, y, rx * M_SQRT2, ry * M_SQRT2, 4, M_PI / 4);
    else if (kind == 3)
        plot_marker_polygon(x, y, rx, ry, 4, 0.0);
    else
        plot_marker_cross(x, y, rx, ry);
}

/* The legend's entries in order: curves, sweep point kinds present, the special point, the note. */
static int legend_entries(const boundary_ctx *c, plot_legend_entry *e)
{
    const plot_boundary_data *d = c->d;
    int n = 0;
    for (size_t k = 0; k < d->n_curves; k++) {
        const plot_boundary_curve *cv = &d->curves[k];
        bool marked = cv->mark != PLOT_CURVE_MARK_NONE;
        e[n++] = (plot_legend_entry){cv->label ? cv->label : "",
                                     marked ? PLOT_LEGEND_KIND_LINE_SYMBOL : PLOT_LEGEND_KIND_LINE,
                                     curve_color[k],
                                     PLOT_LSTY_SOLID,
                                     PLOT_WIDTH_DATA,
                                     cv->mark == PLOT_CURVE_MARK_SQUARE ? PLOT_GLYPH_SQUARE_OPEN : PLOT_GLYPH_CIRCLE_OPEN,
                                     1.3};
    }
    static const char *point_text[4] = {"sweep point: pitchfork first (asymmetric snap)",
                                        "sweep point: saddle-node first (symmetric snap)",
                                        "sweep point: failed or no instability",
                                        "sweep point: no stable upper state"};
    static const char *point_glyph[4] = {PLOT_GLYPH_CIRCLE_OPEN, PLOT_GLYPH_SQUARE_OPEN, PLOT_GLYPH_CROSS,
                                         PLOT_GLYPH_DIAMOND_OPEN};
    for (int k = 0; k < 4; k++)
        if (c->any[k])
            e[n++] = (plot_legend_entry){point_text[k], PLOT_LEGEND_KIND_SYMBOL, PLOT_COL_UNSTABLE, 0, 0,
                                         point_glyph[k], 1.3};
    if (c->star)
        e[n++] = (plot_legend_entry){d->star_label ? d->star_label : "", PLOT_LEGEND_KIND_LINE_SYMBOL, PLOT_COL_INK,
                                     PLOT_LSTY_DASHED, PLOT_WIDTH_THIN, PLOT_GLYPH_STAR, 1.5};
    if (d->note && *d->note)
        e[n++] = (plot_legend_entry){d->note, PLOT_LEGEND_KIND_NONE, PLOT_COL_INK, 0, 0, NULL, 0};
    return n;
}

static plot_status boundary_draw(void *vctx, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    const boundary_ctx *c = vctx;
    const plot_boundary_data *d = c->d;
    pladv(0);
    plvpor(VP_LEFT, VP_RIGHT, VP_BOTTOM, VP_TOP);
    plwind(c->x0, c->x1, c->y0, c->y1);
    plcol0(PLOT_COL_INK);
    plwidth(PLOT_WIDTH_THIN);
    plbox("bcnst", 0.0, 0, "bcnstv", 0.0, 0);
    plmtex("b", 2.6, 0.5, 0.5, d->x_label ? d->x_label : "");
    plmtex("l", 4.2, 0.5, 0.5, d->y_label ? d->y_label : "");
    plmtex("t", 1.4, 0.5, 0.5, d->title ? d->title : "");
    double rx = 0.008 * (c->x1 - c->x0);
    double ry = rx / (c->x1 - c->x0) * (c->y1 - c->y0) * c->w / c->h;
    plcol0(PLOT_COL_UNSTABLE);
    plwidth(1.5);
    for (size_t k = 0; k < d->n_points; k++) {
        const plot_sweep_point *p = &d->points[k];
        if (isfinite(p->x) && isfinite(p->y))
            marker(point_kind(p), p->x, p->y, rx, ry);
    }
    if (c->star) {
        PLFLT vx[2] = {d->star_x, d->star_x}, vy[2] = {c->y0, c->y1};
        plcol0(PLOT_COL_INK);
        plwidth(PLOT_WIDTH_THIN);
        pllsty(PLOT_LSTY_DASHED);
        plline(2, vx, vy);
        pllsty(PLOT_LSTY_SOLID);
    }
    for (size_t k = 0; k < d->n_curves; k++) {
        const plot_boundary_curve *cv = &d->curves[k];
        plcol0(curve_color[k]);
        plwidth(PLOT_WIDTH_DATA);
        plot_series_line(cv->x, cv->y, cv->n);
        plwidth(1.5);
        for (size_t i = 0; cv->mark != PLOT_CURVE_MARK_NONE && i < cv->n; i++)
            if (isfinite(cv->x[i]) && isfinite(cv->y[i]))
                marker(cv->mark == PLOT_CURVE_MARK_CIRCLE ? 0 : 1, cv->x[i], cv->y[i], rx, ry);
    }
    if (c->star) {
        PLFLT x = d->star_x, y = d->star_y;
        plcol0(PLOT_COL_INK);
        plschr(0.0, 2.0);
        plstring(1, &x, &y, PLOT_GLYPH_STAR);
        plschr(0.0, PLOT_CHAR_SCALE);
    }
    plot_legend_entry e[PLOT_LEGEND_MAX];
    int n = legend_entries(c, e);
    plot_legend_draw(e, n, PL_POSITION_LEFT | PL_POSITION_TOP | PL_POSITION_INSIDE | PL_POSITION_VIEWPORT, 0.02,
                     0.02);
    plwidth(PLOT_WIDTH_THIN);
    return PLOT_OK;
}

static plot_status check_boundary(const plot_boundary_data *d, char *why, size_t why_len)
{
    if (d->n_curves > PLOT_BOUNDARY_CURVES_MAX)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "plot_boundary: %zu curves (at most %d)", d->n_curves,
                         PLOT_BOUNDARY_CURVES_MAX);
    if (d->n_curves > 0 && !d->curves)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "curves is NULL but n_curves = %zu", d->n_curves);
    for (size_t k = 0; k < d->n_curves; k++) {
        char field[48];
        plot_status st;
        snprintf(field, sizeof field, "curves[%zu].x", k);
        if ((st = plot_series_check(field, d->curves[k].x, d->curves[k].n, why, why_len)) != PLOT_OK)
            return st;
        snprintf(field, sizeof field, "curves[%zu].y", k);
        if ((st = plot_series_check(field, d->curves[k].y, d->curves[k].n, why, why_len)) != PLOT_OK)
            return st;
    }
    if (d->n_points > 0 && !d->points)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "points is NULL but n_points = %zu", d->n_points);
    for (size_t k = 0; k < d->n_points; k++)
        if (isinf(d->points[k].x) || isinf(d->points[k].y))
            return plot_fail(PLOT_ERR_ARG, why, why_len, "points[%zu] has an infinite coordinate", k);
    plot_status st;
    if ((st = plot_value_check("star_x", d->star_x, why, why_len)) != PLOT_OK ||
        (st = plot_value_check("star_y", d->star_y, why, why_len)) != PLOT_OK)
        return st;
    return PLOT_OK;
}

plot_status plot_boundary(const char *png_path, const plot_boundary_data *d, char *why, size_t why_len)
{
    if (why && why_len)
        why[0] = '\0';
    if (!d)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "plot_boundary: no data");
    plot_status st;
    boundary_ctx c = {.d = d};
    if ((st = plot_size_resolve(d->width_px, PLOT_WIDTH_DEFAULT, "width", &c.w, why, why_len)) != PLOT_OK ||
        (st = plot_size_resolve(d->height_px, PLOT_HEIGHT_DEFAULT, "height", &c.h, why, why_len)) != PLOT_OK ||
        (st = check_boundary(d, why, why_len)) != PLOT_OK)
        return st;
    plot_range rx, ry;
    plot_range_init(&rx);
    plot_range_init(&ry);
    for (size_t k = 0; k < d->n_curves; k++)
        for (size_t i = 0; i < d->curves[k].n; i++)
            if (isfinite(d->curves[k].x[i]) && isfinite(d->curves[k].y[i])) {
                plot_range_add1(&rx, d->curves[k].x[i]);
                plot_range_add1(&ry, d->curves[k].y[i]);
            }
    for (size_t k = 0; k < d->n_points; k++)
        if (isfinite(d->points[k].x) && isfinite(d->points[k].y)) {
            plot_range_add1(&rx, d->points[k].x);
            plot_range_add1(&ry, d->points[k].y);
            c.any[point_kind(&d->points[k])] = true;
        }
    c.star = isfinite(d->star_x) && isfinite(d->star_y);
    if (c.star) {
        plot_range_add1(&rx, d->star_x);
        plot_range_add1(&ry, d->star_y);
    }
    plot_range_axis(&rx, 0.06, 0.0, 1.0, &c.x0, &c.x1);
    plot_range_axis(&ry, 0.08, 0.0, 1.0, &c.y0, &c.y1);
    /* Room for the legend above the data: about 4.5% of the axis height per entry at the default
     * character size, so the top fraction f of the axis is the legend's. */
    plot_legend_entry e[PLOT_LEGEND_MAX];
    int n = legend_entries(&c, e);
    double f = fmin(0.6, 0.045 * n * (double)PLOT_HEIGHT_DEFAULT / c.h + 0.03);
    c.y1 += (c.y1 - c.y0) * f / (1.0 - f);
    return plot_session_run(PLOT_DEVICE, png_path, c.w, c.h, boundary_draw, &c, why, why_len);
}
