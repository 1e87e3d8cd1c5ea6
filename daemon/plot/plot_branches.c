/*
 * plot_branches.c: continuation diagrams (`ribbon-sim continue --plot`: Delta Z and A against
 * Delta W, two panels side by side), after the paper's figures 3a and 4a: stable branches black
 * and solid, unstable ones grey and dashed, circles at pitchforks, squares at saddle-nodes,
 * diamonds at other located events. The caller chooses what is on the axes and names them; each
 * panel is one plot_branch_data, drawn in its own slice of the page.
 *
 * Stability belongs to points, lines join points: the piece between points i and i+1 is stable
 * only when both ends are, so the grey starts exactly at the last stable point. Consecutive pieces
 * of one kind go to PLplot as one polyline (a dashed pattern then runs on smoothly instead of
 * restarting at every point). Unstable pieces are drawn first, stable ones over them, events last.
 */
#include "plot.h"

#include "plot_legend.h"
#include "plot_series.h"
#include "plot_session.h"
#include "plot_style.h"

#include <math.h>
#include <plplot.h>
#include <stdio.h>

#define VP_LEFT 0.10
#define VP_RIGHT 0.76
#define VP_BOTTOM 0.10
#define VP_TOP 0.90
/* Several panels: they share [0, VP_PANELS_RIGHT] of the page, each with room for its y label
 * on the left and a gap on the right; the bottom leaves room for the x label on a wide page. */
#define VP_PANELS_RIGHT 0.83
#define VP_PANEL_LEFT 0.09
#define VP_PANEL_GAP 0.02
#define VP_PANEL_BOTTOM 0.14

void plot_branch_data_default(plot_branch_data *d)
{
    *d = (plot_branch_data){0};
}

static bool point_ok(const plot_branch *b, size_t i)
{
    return isfinite(b->x[i]) && isfinite(b->y[i]);
}

static bool point_stable(const plot_branch *b, size_t i)
{
    return !b->stable || b->stable[i];
}

/* Draws the pieces of branch b whose stability is `stable`. */
static void draw_pieces(const plot_branch *b, bool stable)
{
    size_t i = 0;
    while (i + 1 < b->n) {
        bool seg_ok = point_ok(b, i) && point_ok(b, i + 1);
        bool seg_stable = point_stable(b, i) && point_stable(b, i + 1);
        if (!seg_ok || seg_stable != stable) {
            i++;
            continue;
        }
        size_t j = i + 1; /* last point of the run */
        while (j + 1 < b->n && point_ok(b, j + 1) && (point_stable(b, j) && point_stable(b, j + 1)) == stable)
            j++;
        plline((PLINT)(j - i + 1), &b->x[i], &b->y[i]);
        i = j;
    }
}

/* A finite point with no finite neighbour has no piece: show it as a dot of its kind. */
static void draw_lone_points(const plot_branch *b)
{
    for (size_t i = 0; i < b->n; i++) {
        if (!point_ok(b, i))
            continue;
        bool prev = i > 0 && point_ok(b, i - 1);
        bool next = i + 1 < b->n && point_ok(b, i + 1);
        if (prev || next)
            continue;
        plcol0(point_stable(b, i) ? PLOT_COL_INK : PLOT_COL_UNSTABLE);
        plstring(1, &b->x[i], &b->y[i], PLOT_GLYPH_DOT);
    }
}

/* One panel: its data and axis ranges. */
typedef struct branch_panel {
    const plot_branch_data *d;
    double x0, x1, y0, y1;
} branch_panel;

typedef struct branch_ctx {
    branch_panel panel[PLOT_PANELS_MAX];
    size_t n;
} branch_ctx;

/* Panel k of n takes the k-th vertical slice of the page. One panel has the whole page, its
 * legend on the right; several share the page left of the legend, which only the last draws. */
static void panel_draw(const branch_panel *c, size_t slice, size_t n_slices)
{
    const plot_branch_data *d = c->d;
    bool legend = slice + 1 == n_slices;
    if (n_slices == 1) {
        plvpor(VP_LEFT, VP_RIGHT, VP_BOTTOM, VP_TOP);
    } else {
        double w = VP_PANELS_RIGHT / (double)n_slices;
        plvpor(w * (double)slice + VP_PANEL_LEFT, w * (double)(slice + 1) - VP_PANEL_GAP,
               VP_PANEL_BOTTOM, VP_TOP);
    }
    plwind(c->x0, c->x1, c->y0, c->y1);
    plwidth(PLOT_WIDTH_THIN);
    plcol0(PLOT_COL_GRID);
    plbox("g", 0.0, 0, "g", 0.0, 0);
    plcol0(PLOT_COL_INK);
    plbox("bcnst", 0.0, 0, "bcnstv", 0.0, 0);
    plmtex("b", 3.0, 0.5, 0.5, d->x_label ? d->x_label : "");
    plmtex("l", 5.0, 0.5, 0.5, d->y_label ? d->y_label : "");
    if (d->title && *d->title)
        plmtex("t", 1.5, 0.5, 0.5, d->title);

    bool any_stable = false, any_unstable = false;
    plwidth(PLOT_WIDTH_DATA);
    plcol0(PLOT_COL_UNSTABLE);
    pllsty(PLOT_LSTY_DASHED);
    for (size_t k = 0; k < d->n_branches; k++)
        draw_pieces(&d->branches[k], false);
    plcol0(PLOT_COL_INK);
    pllsty(PLOT_LSTY_SOLID);
    for (size_t k = 0; k < d->n_branches; k++)
        draw_pieces(&d->branches[k], true);
    for (size_t k = 0; k < d->n_branches; k++) {
        const plot_branch *b = &d->branches[k];
        draw_lone_points(b);
        for (size_t i = 0; i < b->n; i++) {
            if (!point_ok(b, i))
                continue;
            if (point_stable(b, i))
                any_stable = true;
            else
                any_unstable = true;
        }
    }

    /* branch labels beside each branch's last finite point */
    plcol0(PLOT_COL_INK);
    for (size_t k = 0; k < d->n_branches; k++) {
        const plot_branch *b = &d->branches[k];
        if (!b->label || !*b->label)
            continue;
        for (size_t i = b->n; i-- > 0;) {
            if (point_ok(b, i)) {
                /* right of the end, or left of it when the end is near the right edge */
                bool left = b->x[i] > c->x0 + 0.85 * (c->x1 - c->x0);
                double dx = 0.012 * (c->x1 - c->x0);
                plptex(left ? b->x[i] - dx : b->x[i] + dx, b->y[i], 1.0, 0.0, left ? 1.0 : 0.0, b->label);
                break;
            }
        }
    }

    bool any_pf = false, any_sn = false, any_other = false;
    plcol0(PLOT_COL_INK);
    plschr(0.0, 1.8);
    for (size_t i = 0; i < d->n_events; i++) {
        const plot_event *e = &d->events[i];
        if (!isfinite(e->x) || !isfinite(e->y))
            continue;
        PLFLT x = e->x, y = e->y;
        bool pf = e->kind == PLOT_EVENT_PITCHFORK, sn = e->kind == PLOT_EVENT_SADDLE_NODE;
        plstring(1, &x, &y,
                 pf ? PLOT_GLYPH_CIRCLE_OPEN : sn ? PLOT_GLYPH_SQUARE_OPEN : PLOT_GLYPH_DIAMOND_OPEN);
        any_pf |= pf;
        any_sn |= sn;
        any_other |= !pf && !sn;
    }
    plschr(0.0, PLOT_CHAR_SCALE);

    plot_legend_entry e[5];
    int n = 0;
    if (any_stable)
        e[n++] = (plot_legend_entry){"stable", PLOT_LEGEND_KIND_LINE, PLOT_COL_INK, PLOT_LSTY_SOLID, PLOT_WIDTH_DATA,
                                     NULL, 0};
    if (any_unstable)
        e[n++] = (plot_legend_entry){"unstable", PLOT_LEGEND_KIND_LINE, PLOT_COL_UNSTABLE, PLOT_LSTY_DASHED,
                                     PLOT_WIDTH_DATA, NULL, 0};
    if (any_pf)
        e[n++] = (plot_legend_entry){"pitchfork", PLOT_LEGEND_KIND_SYMBOL, PLOT_COL_INK, 0, 0,
                                     PLOT_GLYPH_CIRCLE_OPEN, 1.5};
    if (any_sn)
        e[n++] = (plot_legend_entry){"saddle-node", PLOT_LEGEND_KIND_SYMBOL, PLOT_COL_INK, 0, 0,
                                     PLOT_GLYPH_SQUARE_OPEN, 1.5};
    if (any_other)
        e[n++] = (plot_legend_entry){"other event", PLOT_LEGEND_KIND_SYMBOL, PLOT_COL_INK, 0, 0,
                                     PLOT_GLYPH_DIAMOND_OPEN, 1.5};
    if (legend)
        plot_legend_draw(e, n, PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, 0.02,
                         0.0);

    if (!any_stable && !any_unstable && !any_pf && !any_sn && !any_other) {
        plcol0(PLOT_COL_UNSTABLE);
        plptex(0.5 * (c->x0 + c->x1), 0.5 * (c->y0 + c->y1), 1.0, 0.0, 0.5, "no data");
    }
}

static plot_status branches_draw(void *vctx, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    const branch_ctx *c = vctx;
    pladv(0);
    for (size_t k = 0; k < c->n; k++)
        panel_draw(&c->panel[k], k, c->n);
    return PLOT_OK;
}

static plot_status check_branches(const plot_branch_data *d, char *why, size_t why_len)
{
    if (d->n_branches > 0 && !d->branches)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "branches is NULL but n_branches = %zu", d->n_branches);
    for (size_t k = 0; k < d->n_branches; k++) {
        const plot_branch *b = &d->branches[k];
        char field[48];
        plot_status st;
        snprintf(field, sizeof field, "branches[%zu].x", k);
        if ((st = plot_series_check(field, b->x, b->n, why, why_len)) != PLOT_OK)
            return st;
        snprintf(field, sizeof field, "branches[%zu].y", k);
        if ((st = plot_series_check(field, b->y, b->n, why, why_len)) != PLOT_OK)
            return st;
    }
    if (d->n_events > 0 && !d->events)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "events is NULL but n_events = %zu", d->n_events);
    for (size_t i = 0; i < d->n_events; i++) {
        const plot_event *e = &d->events[i];
        if (isinf(e->x) || isinf(e->y))
            return plot_fail(PLOT_ERR_ARG, why, why_len, "events[%zu] has an infinite coordinate", i);
        if (e->kind != PLOT_EVENT_PITCHFORK && e->kind != PLOT_EVENT_SADDLE_NODE &&
            e->kind != PLOT_EVENT_OTHER)
            return plot_fail(PLOT_ERR_ARG, why, why_len, "events[%zu].kind is not an event kind (%d)", i,
                             (int)e->kind);
    }
    return PLOT_OK;
}

/* The axis ranges of one panel: every finite point and event, padded. */
static void panel_ranges(branch_panel *c)
{
    const plot_branch_data *d = c->d;
    plot_range rx, ry;
    plot_range_init(&rx);
    plot_range_init(&ry);
    for (size_t k = 0; k < d->n_branches; k++) {
        const plot_branch *b = &d->branches[k];
        for (size_t i = 0; i < b->n; i++) {
            if (point_ok(b, i)) {
                plot_range_add1(&rx, b->x[i]);
                plot_range_add1(&ry, b->y[i]);
            }
        }
    }
    for (size_t i = 0; i < d->n_events; i++) {
        if (isfinite(d->events[i].x) && isfinite(d->events[i].y)) {
            plot_range_add1(&rx, d->events[i].x);
            plot_range_add1(&ry, d->events[i].y);
        }
    }
    plot_range_axis(&rx, 0.04, 0.0, 1.0, &c->x0, &c->x1);
    plot_range_axis(&ry, 0.06, -1.0, 1.0, &c->y0, &c->y1);
}

plot_status plot_branches_panels(const char *png_path, const plot_branch_data *panels,
                                 size_t n_panels, int width_px, int height_px, char *why,
                                 size_t why_len)
{
    if (why && why_len)
        why[0] = '\0';
    if (!panels || n_panels == 0)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "plot_branches: no data");
    if (n_panels > PLOT_PANELS_MAX)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "plot_branches: %zu panels (at most %d)",
                         n_panels, PLOT_PANELS_MAX);
    plot_status st;
    int w, h;
    if ((st = plot_size_resolve(width_px, PLOT_WIDTH_DEFAULT, "width", &w, why, why_len)) != PLOT_OK ||
        (st = plot_size_resolve(height_px, PLOT_HEIGHT_DEFAULT, "height", &h, why, why_len)) != PLOT_OK)
        return st;
    branch_ctx c = {.n = n_panels};
    for (size_t k = 0; k < n_panels; k++) {
        if ((st = check_branches(&panels[k], why, why_len)) != PLOT_OK)
            return st;
        c.panel[k].d = &panels[k];
        panel_ranges(&c.panel[k]);
    }
    return plot_session_run(PLOT_DEVICE, png_path, w, h, branches_draw, &c, why, why_len);
}

plot_status plot_branches(const char *png_path, const plot_branch_data *d, char *why, size_t why_len)
{
    if (!d) {
        if (why && why_len)
            why[0] = '\0';
        return plot_fail(PLOT_ERR_ARG, why, why_len, "plot_branches: no data");
    }
    return plot_branches_panels(png_path, d, 1, d->width_px, d->height_px, why, why_len);
}
