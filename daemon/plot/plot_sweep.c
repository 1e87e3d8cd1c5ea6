/*
 * plot_sweep.c: the regime map of a parameter sweep (`ribbon-sim sweep --plot`): one marker per
 * classified point, circle where the pitchfork comes first (asymmetric snap), square where the
 * saddle-node does (symmetric), cross where the analysis failed or found no instability, and the
 * located boundaries as lines, solid or dashed, optionally with small diamonds at their points.
 * The caller decides what the axes are (phi and Gamma for a phase diagram, Gamma and the first
 * instability's Delta W for one phi) and passes plain arrays. Markers are outlined polygons in
 * data units (plot_marker.h), scaled by the page's aspect so they stay round.
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
#include <string.h>

void plot_sweep_data_default(plot_sweep_data *d)
{
    *d = (plot_sweep_data){0};
    d->x0 = d->y0 = 0.0;
    d->x1 = d->y1 = 1.0;
}

typedef struct sweep_ctx {
    const plot_sweep_data *d;
    double x0, x1, y0, y1; /* padded axis ranges */
    int w, h;              /* page, px */
} sweep_ctx;

static plot_status sweep_draw(void *vctx, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    const sweep_ctx *c = vctx;
    const plot_sweep_data *d = c->d;
    plcol0(PLOT_COL_INK);
    plwidth(PLOT_WIDTH_THIN);
    double rx = 0.012 * (c->x1 - c->x0);
    double ry = rx / (c->x1 - c->x0) * (c->y1 - c->y0) * c->w / c->h;
    if (d->legend) {
        /* Axes on the left half of the page, the legend right of them; markers stay round in
         * this viewport (0.45 of the width, 0.78 of the height). */
        pladv(0);
        plvpor(0.10, 0.55, 0.12, 0.90);
        plwind(c->x0, c->x1, c->y0, c->y1);
        plbox("bcnst", 0.0, 0, "bcnstv", 0.0, 0);
        rx = 0.016 * (c->x1 - c->x0);
        ry = rx / (c->x1 - c->x0) * (c->y1 - c->y0) * (0.45 * c->w) / (0.78 * c->h);
    } else {
        plenv(c->x0, c->x1, c->y0, c->y1, 0, 0);
    }
    pllab(d->x_label ? d->x_label : "", d->y_label ? d->y_label : "", d->title ? d->title : "");
    bool seen[5] = {false, false, false, false, false}, bars = false;
    /* Grey bars first, under the markers. */
    for (size_t k = 0; k < d->n_points; k++) {
        const plot_sweep_point *p = &d->points[k];
        if (!p->no_state || !isfinite(p->x) || !isfinite(p->y) || !isfinite(p->bar_to) || p->bar_to == p->y)
            continue;
        double from = isfinite(p->bar_from) && p->bar_from != 0.0 ? p->bar_from : p->y;
        PLFLT bx[4] = {p->x - 0.6 * rx, p->x + 0.6 * rx, p->x + 0.6 * rx, p->x - 0.6 * rx};
        PLFLT by[4] = {from, from, p->bar_to, p->bar_to};
        plcol0(PLOT_COL_CELL_NOSNAP);
        plpsty(0);
        plfill(4, bx, by);
        bars = true;
    }
    plwidth(1.5);
    plcol0(PLOT_COL_INK);
    for (size_t k = 0; k < d->n_points; k++) {
        const plot_sweep_point *p = &d->points[k];
        if (!isfinite(p->x) || !isfinite(p->y))
            continue;
        plcol0(PLOT_COL_INK);
        if (p->no_state) {
            PLFLT px[4] = {p->x - rx, p->x, p->x + rx, p->x}, py[4] = {p->y, p->y + ry, p->y, p->y - ry};
            plcol0(PLOT_COL_UNSTABLE);
            plpsty(0);
            plfill(4, px, py);
            plcol0(PLOT_COL_INK);
            plot_marker_polygon(p->x, p->y, rx, ry, 4, 0.0);
            seen[4] = true;
        } else if (p->regime == PLOT_REGIME_ASYMMETRIC)
            plot_marker_polygon(p->x, p->y, rx, ry, 36, 0.0);
        else if (p->regime == PLOT_REGIME_SYMMETRIC)
            plot_marker_polygon(p->x, p->y, rx * M_SQRT2, ry * M_SQRT2, 4, M_PI / 4);
        else if (p->regime == PLOT_REGIME_NO_SNAP)
            plot_marker_polygon(p->x, p->y, rx * 1.2, ry * 1.2, 3, M_PI / 2);
        else
            plot_marker_cross(p->x, p->y, rx, ry);
        if (!p->no_state) seen[p->regime] = true;
    }
    plcol0(PLOT_COL_MARK_OTHER);
    plwidth(2.0);
    for (size_t k = 0; k < d->n_lines; k++) {
        const plot_sweep_line *l = &d->lines[k];
        pllsty(l->dashed ? PLOT_LSTY_DOTTED : PLOT_LSTY_SOLID);
        if (l->n > 1)
            plot_series_line(l->x, l->y, l->n);
        for (size_t i = 0; l->marked && i < l->n; i++)
            if (isfinite(l->x[i]) && isfinite(l->y[i]))
                plot_marker_polygon(l->x[i], l->y[i], 0.4 * rx, 0.4 * ry, 4, 0.0);
    }
    pllsty(PLOT_LSTY_SOLID);
    plwidth(PLOT_WIDTH_THIN);
    if (d->legend) {
        plot_legend_entry e[PLOT_LEGEND_MAX];
        int n = 0;
        static const char *const mark_text[4] = {"analysis failed (reason in the CSV)",
                                                 "pitchfork first: asymmetric snap",
                                                 "saddle-node first: symmetric snap",
                                                 "no instability up to #gDW = 1: no snap"};
        static const char *const glyph[4] = {PLOT_GLYPH_CROSS, PLOT_GLYPH_CIRCLE_OPEN, PLOT_GLYPH_SQUARE_OPEN, "△"};
        static const plot_regime order[4] = {PLOT_REGIME_ASYMMETRIC, PLOT_REGIME_SYMMETRIC, PLOT_REGIME_NO_SNAP,
                                             PLOT_REGIME_UNKNOWN};
        for (int k = 0; k < 4; k++)
            if (seen[order[k]])
                e[n++] = (plot_legend_entry){mark_text[order[k]], PLOT_LEGEND_KIND_SYMBOL, PLOT_COL_INK, 0, 0,
                                             glyph[order[k]], 1.2};
        if (seen[4])
            e[n++] = (plot_legend_entry){"no stable upper state (evidence in the CSV)", PLOT_LEGEND_KIND_SYMBOL,
                                         PLOT_COL_UNSTABLE, 0, 0, "◆", 1.2};
        if (bars)
            e[n++] = (plot_legend_entry){"grey bar: to the fold or pitchfork that ends it", PLOT_LEGEND_KIND_BOX,
                                         PLOT_COL_CELL_NOSNAP, 0, 0, NULL, 0};
        bool marked = false;
        for (size_t k = 0; k < d->n_lines && n < PLOT_LEGEND_MAX - 1; k++) {
            const plot_sweep_line *l = &d->lines[k];
            marked = marked || l->marked;
            bool dup = !l->legend;
            for (size_t q = 0; !dup && q < k; q++)
                dup = d->lines[q].legend && !strcmp(d->lines[q].legend, l->legend);
            if (!dup)
                e[n++] = (plot_legend_entry){l->legend, PLOT_LEGEND_KIND_LINE, PLOT_COL_MARK_OTHER,
                                             l->dashed ? PLOT_LSTY_DOTTED : PLOT_LSTY_SOLID, 2.0, NULL, 0};
        }
        if (marked && n < PLOT_LEGEND_MAX)
            e[n++] = (plot_legend_entry){"boundary located by bisection", PLOT_LEGEND_KIND_SYMBOL, PLOT_COL_MARK_OTHER,
                                         0, 0, PLOT_GLYPH_DIAMOND_OPEN, 0.6};
        plschr(0.0, 0.6 * PLOT_CHAR_SCALE);
        plot_legend_draw(e, n, PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, 0.03, 0.0);
        plschr(0.0, PLOT_CHAR_SCALE);
    }
    return PLOT_OK;
}

static plot_status check_sweep(const plot_sweep_data *d, char *why, size_t why_len)
{
    if (!isfinite(d->x0) || !isfinite(d->x1) || !isfinite(d->y0) || !isfinite(d->y1))
        return plot_fail(PLOT_ERR_ARG, why, why_len, "the swept span is not finite");
    if (d->n_points > 0 && !d->points)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "points is NULL but n_points = %zu", d->n_points);
    for (size_t k = 0; k < d->n_points; k++)
        if (isinf(d->points[k].x) || isinf(d->points[k].y))
            return plot_fail(PLOT_ERR_ARG, why, why_len, "points[%zu] has an infinite coordinate", k);
    if (d->n_lines > 0 && !d->lines)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "lines is NULL but n_lines = %zu", d->n_lines);
    for (size_t k = 0; k < d->n_lines; k++) {
        char field[48];
        plot_status st;
        snprintf(field, sizeof field, "lines[%zu].x", k);
        if ((st = plot_series_check(field, d->lines[k].x, d->lines[k].n, why, why_len)) != PLOT_OK)
            return st;
        snprintf(field, sizeof field, "lines[%zu].y", k);
        if ((st = plot_series_check(field, d->lines[k].y, d->lines[k].n, why, why_len)) != PLOT_OK)
            return st;
    }
    return PLOT_OK;
}

plot_status plot_sweep(const char *png_path, const plot_sweep_data *d, char *why, size_t why_len)
{
    if (why && why_len)
        why[0] = '\0';
    if (!d)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "plot_sweep: no data");
    plot_status st;
    sweep_ctx c = {.d = d};
    if ((st = plot_size_resolve(d->width_px, PLOT_WIDTH_DEFAULT, "width", &c.w, why, why_len)) != PLOT_OK ||
        (st = plot_size_resolve(d->height_px, PLOT_HEIGHT_DEFAULT, "height", &c.h, why, why_len)) != PLOT_OK ||
        (st = check_sweep(d, why, why_len)) != PLOT_OK)
        return st;
    /* The swept span, padded by 6% in x and 8% in y (of 1 when the span is empty). */
    double x0 = fmin(d->x0, d->x1), x1 = fmax(d->x0, d->x1);
    double y0 = fmin(d->y0, d->y1), y1 = fmax(d->y0, d->y1);
    double mx = 0.06 * (x1 - x0 > 0 ? x1 - x0 : 1.0), my = 0.08 * (y1 - y0 > 0 ? y1 - y0 : 1.0);
    c.x0 = x0 - mx;
    c.x1 = x1 + mx;
    c.y0 = y0 - my;
    c.y1 = y1 + my;
    return plot_session_run(PLOT_DEVICE, png_path, c.w, c.h, sweep_draw, &c, why, why_len);
}
