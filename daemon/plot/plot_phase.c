/*
 * plot_phase.c: the lab's main result (ribbonctl phase-report): the predicted (Gamma, phi) phase
 * diagram with every trial's measured regime on it. After the paper's figure 5c, with Gamma on x
 * and phi (deg) on y.
 *
 * The predicted sweep is a grid of points, not of cells: each point becomes a rectangle reaching
 * halfway to its neighbours (the outer half-cells mirror the inner spacing; a lone row or column
 * gets a nominal half-width of 2.5% of its value, at least 0.005 in Gamma and 1 deg in phi). The
 * rectangles are filled with plfill in pale regime colours: blue asymmetric, red symmetric, grey
 * no snap, yellow failed/unknown. Sweep points need not be evenly spaced.
 *
 * On top: the predicted boundary Gamma*(phi) as a dashed black line (NaN breaks it), then the
 * trials: filled dark-blue squares asymmetric, open dark-red circles symmetric, crosses no snap,
 * open diamonds unknown; a marker standing for several trials says how many ("x3"). Then the
 * experimental boundary (ribbonctl phase): a bluish-green bar per phi over its interval (dotted to
 * the axis where a side is open), a star at each estimate, the estimates joined. The legend only
 * lists what is present in the figure.
 */
#include "plot.h"

#include "plot_legend.h"
#include "plot_series.h"
#include "plot_session.h"
#include "plot_style.h"

#include <math.h>
#include <plplot.h>
#include <stdint.h>
#include <stdio.h>

#define VP_LEFT 0.10
#define VP_RIGHT 0.68
#define VP_BOTTOM 0.10
#define VP_TOP 0.90

void plot_phase_data_default(plot_phase_data *d)
{
    *d = (plot_phase_data){0};
}

static double lone_half_width(double v, double floor)
{
    return fmax(0.025 * fabs(v), floor);
}

/* Edges of the cell of point i along an axis of n increasing values. */
static void cell_edges(const double *v, size_t n, size_t i, double floor, double *lo, double *hi)
{
    if (n == 1) {
        double h = lone_half_width(v[0], floor);
        *lo = v[0] - h;
        *hi = v[0] + h;
        return;
    }
    double left = i > 0 ? 0.5 * (v[i] - v[i - 1]) : 0.5 * (v[1] - v[0]);
    double right = i + 1 < n ? 0.5 * (v[i + 1] - v[i]) : 0.5 * (v[n - 1] - v[n - 2]);
    *lo = v[i] - left;
    *hi = v[i] + right;
}

#define GAMMA_FLOOR 0.005
#define PHI_FLOOR 1.0

static int cell_color(plot_regime r)
{
    switch (r) {
    case PLOT_REGIME_ASYMMETRIC: return PLOT_COL_CELL_ASYM;
    case PLOT_REGIME_SYMMETRIC: return PLOT_COL_CELL_SYM;
    case PLOT_REGIME_NO_SNAP: return PLOT_COL_CELL_NOSNAP;
    case PLOT_REGIME_NO_UPPER: return PLOT_COL_CELL_NOUPPER;
    case PLOT_REGIME_UNKNOWN: break;
    }
    return PLOT_COL_CELL_UNKNOWN;
}

static void trial_style(plot_regime r, int *color, const char **glyph, double *scale)
{
    switch (r) {
    case PLOT_REGIME_ASYMMETRIC:
        *color = PLOT_COL_MARK_ASYM;
        *glyph = PLOT_GLYPH_SQUARE_FILLED;
        *scale = 1.2;
        return;
    case PLOT_REGIME_SYMMETRIC:
        *color = PLOT_COL_MARK_SYM;
        *glyph = PLOT_GLYPH_CIRCLE_OPEN;
        *scale = 1.5;
        return;
    case PLOT_REGIME_NO_SNAP:
        *color = PLOT_COL_MARK_OTHER;
        *glyph = PLOT_GLYPH_CROSS;
        *scale = 1.6;
        return;
    case PLOT_REGIME_NO_UPPER: /* measured trials are never this; drawn as unknown */
    case PLOT_REGIME_UNKNOWN: break;
    }
    *color = PLOT_COL_MARK_OTHER;
    *glyph = PLOT_GLYPH_DIAMOND_OPEN;
    *scale = 1.4;
}

static bool regime_valid(plot_regime r)
{
    return r == PLOT_REGIME_UNKNOWN || r == PLOT_REGIME_ASYMMETRIC || r == PLOT_REGIME_SYMMETRIC ||
           r == PLOT_REGIME_NO_SNAP || r == PLOT_REGIME_NO_UPPER;
}

static plot_status check_axis(const char *name, const double *v, size_t n, char *why, size_t why_len)
{
    if (n == 0)
        return PLOT_OK;
    if (!v)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "%s is NULL but n_%s = %zu", name, name, n);
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(v[i]))
            return plot_fail(PLOT_ERR_ARG, why, why_len, "%s[%zu] is not finite (sweep values cannot be gaps)", name,
                             i);
        if (i > 0 && !(v[i] > v[i - 1]))
            return plot_fail(PLOT_ERR_ARG, why, why_len, "%s must increase strictly: %s[%zu] = %g after %g", name,
                             name, i, v[i], v[i - 1]);
    }
    return PLOT_OK;
}

static plot_status check_phase(const plot_phase_data *d, char *why, size_t why_len)
{
    plot_status st;
    if ((d->n_gamma == 0) != (d->n_phi == 0))
        return plot_fail(PLOT_ERR_ARG, why, why_len, "the predicted grid needs both axes: n_gamma = %zu, n_phi = %zu",
                         d->n_gamma, d->n_phi);
    if ((st = check_axis("gamma", d->gamma, d->n_gamma, why, why_len)) != PLOT_OK ||
        (st = check_axis("phi_deg", d->phi_deg, d->n_phi, why, why_len)) != PLOT_OK)
        return st;
    if (d->n_gamma > 0) {
        if (d->n_gamma > SIZE_MAX / d->n_phi)
            return plot_fail(PLOT_ERR_ARG, why, why_len, "grid of %zu x %zu is too large", d->n_phi, d->n_gamma);
        if (!d->grid)
            return plot_fail(PLOT_ERR_ARG, why, why_len, "grid is NULL for a %zu x %zu sweep", d->n_phi, d->n_gamma);
        for (size_t k = 0; k < d->n_gamma * d->n_phi; k++)
            if (!regime_valid(d->grid[k]))
                return plot_fail(PLOT_ERR_ARG, why, why_len, "grid[%zu] (phi %zu, gamma %zu) is not a regime code (%d)",
                                 k, k / d->n_gamma, k % d->n_gamma, (int)d->grid[k]);
    }
    if ((st = plot_series_check("boundary_gamma", d->boundary_gamma, d->n_boundary, why, why_len)) != PLOT_OK ||
        (st = plot_series_check("boundary_phi_deg", d->boundary_phi_deg, d->n_boundary, why, why_len)) != PLOT_OK)
        return st;
    if (d->n_edges > 0 && !d->edges)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "edges is NULL but n_edges = %zu", d->n_edges);
    for (size_t i = 0; i < d->n_edges; i++) {
        const plot_phase_edge *e = &d->edges[i];
        if (!isfinite(e->phi_deg) || isinf(e->gamma) || isinf(e->lo) || isinf(e->hi))
            return plot_fail(PLOT_ERR_ARG, why, why_len, "edges[%zu] has an infinite coordinate or no phi", i);
    }
    if (d->n_trials > 0 && !d->trials)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "trials is NULL but n_trials = %zu", d->n_trials);
    for (size_t i = 0; i < d->n_trials; i++) {
        const plot_phase_trial *t = &d->trials[i];
        if (isinf(t->gamma) || isinf(t->phi_deg))
            return plot_fail(PLOT_ERR_ARG, why, why_len, "trials[%zu] has an infinite coordinate", i);
        if (!regime_valid(t->regime))
            return plot_fail(PLOT_ERR_ARG, why, why_len, "trials[%zu].regime is not a regime code (%d)", i,
                             (int)t->regime);
    }
    return PLOT_OK;
}

typedef struct phase_ctx {
    const plot_phase_data *d;
    double x0, x1, y0, y1;
} phase_ctx;

/* The experimental boundary: bars, stars, the line through the estimates. True when drawn. */
static bool draw_edges(const phase_ctx *c)
{
    const plot_phase_data *d = c->d;
    bool any = false;
    plcol0(PLOT_COL_SERIES_3);
    for (size_t i = 0; i < d->n_edges; i++) {
        const plot_phase_edge *e = &d->edges[i];
        if (isnan(e->lo) && isnan(e->hi)) continue;
        any = true;
        PLFLT y[2] = {e->phi_deg, e->phi_deg};
        PLFLT lo = isnan(e->lo) ? c->x0 : e->lo, hi = isnan(e->hi) ? c->x1 : e->hi;
        plwidth(2 * PLOT_WIDTH_DATA);
        PLFLT x[2] = {isnan(e->lo) ? e->hi : lo, isnan(e->hi) ? e->lo : hi};
        if (!isnan(e->lo) && !isnan(e->hi)) {
            pllsty(PLOT_LSTY_SOLID);
            plline(2, x, y);
        } else {
            PLFLT xo[2] = {isnan(e->lo) ? lo : x[1], isnan(e->hi) ? hi : x[0]};
            pllsty(PLOT_LSTY_DOTTED);
            plline(2, xo, y);
            pllsty(PLOT_LSTY_SOLID);
        }
        plwidth(PLOT_WIDTH_THIN);
        for (int s = 0; s < 2; s++) { /* end ticks at the closed sides */
            double v = s ? e->hi : e->lo;
            if (isnan(v)) continue;
            PLFLT tx[2] = {v, v}, ty[2] = {e->phi_deg - 0.012 * (c->y1 - c->y0), e->phi_deg + 0.012 * (c->y1 - c->y0)};
            plline(2, tx, ty);
        }
        if (isfinite(e->gamma)) {
            PLFLT gx = e->gamma, gy = e->phi_deg;
            plschr(0.0, 1.4 * PLOT_CHAR_SCALE);
            plstring(1, &gx, &gy, PLOT_GLYPH_STAR);
            plschr(0.0, PLOT_CHAR_SCALE);
        }
    }
    /* the estimates joined, in phi order (edges come sorted by phi) */
    plwidth(PLOT_WIDTH_DATA);
    for (size_t i = 0; i + 1 < d->n_edges; i++) {
        size_t j = i + 1;
        if (!isfinite(d->edges[i].gamma)) continue;
        while (j < d->n_edges && !isfinite(d->edges[j].gamma)) j++;
        if (j >= d->n_edges) break;
        PLFLT x[2] = {d->edges[i].gamma, d->edges[j].gamma}, y[2] = {d->edges[i].phi_deg, d->edges[j].phi_deg};
        plline(2, x, y);
    }
    plwidth(PLOT_WIDTH_THIN);
    return any;
}

static void draw_cells(const plot_phase_data *d, bool present[4])
{
    for (size_t j = 0; j < d->n_phi; j++) {
        double ylo, yhi;
        cell_edges(d->phi_deg, d->n_phi, j, PHI_FLOOR, &ylo, &yhi);
        for (size_t i = 0; i < d->n_gamma; i++) {
            double xlo, xhi;
            cell_edges(d->gamma, d->n_gamma, i, GAMMA_FLOOR, &xlo, &xhi);
            plot_regime r = d->grid[j * d->n_gamma + i];
            present[r] = true;
            PLFLT xs[4] = {xlo, xhi, xhi, xlo}, ys[4] = {ylo, ylo, yhi, yhi};
            plcol0(cell_color(r));
            plpsty(0);
            plfill(4, xs, ys);
        }
    }
}

static plot_status phase_draw(void *vctx, char *why, size_t why_len)
{
    (void)why;
    (void)why_len;
    phase_ctx *c = vctx;
    const plot_phase_data *d = c->d;

    pladv(0);
    plvpor(VP_LEFT, VP_RIGHT, VP_BOTTOM, VP_TOP);
    plwind(c->x0, c->x1, c->y0, c->y1);

    bool cells[5] = {false, false, false, false, false};
    draw_cells(d, cells);

    plcol0(PLOT_COL_INK);
    plwidth(PLOT_WIDTH_THIN);
    plbox("bcnst", 0.0, 0, "bcnstv", 0.0, 0);
    plmtex("b", 3.0, 0.5, 0.5, "#gG (crease position, fraction of l)");
    plmtex("l", 5.0, 0.5, 0.5, "#gf (crease angle, deg)");
    if (d->title && *d->title)
        plmtex("t", 1.5, 0.5, 0.5, d->title);

    bool have_boundary = plot_series_finite(d->boundary_gamma, d->boundary_phi_deg, d->n_boundary) > 0;
    if (have_boundary) {
        plcol0(PLOT_COL_INK);
        plwidth(PLOT_WIDTH_DATA);
        pllsty(PLOT_LSTY_DASHED);
        plot_series_line(d->boundary_gamma, d->boundary_phi_deg, d->n_boundary);
        pllsty(PLOT_LSTY_SOLID);
    }

    bool marks[5] = {false, false, false, false, false};
    for (size_t i = 0; i < d->n_trials; i++) {
        const plot_phase_trial *t = &d->trials[i];
        if (!isfinite(t->gamma) || !isfinite(t->phi_deg))
            continue;
        int color;
        const char *glyph;
        double scale;
        trial_style(t->regime, &color, &glyph, &scale);
        marks[t->regime] = true;
        PLFLT x = t->gamma, y = t->phi_deg;
        plcol0(color);
        plschr(0.0, PLOT_CHAR_SCALE * scale);
        plstring(1, &x, &y, glyph);
        plschr(0.0, PLOT_CHAR_SCALE);
        if (d->trial_counts && d->trial_counts[i] > 1) {
            char txt[32];
            snprintf(txt, sizeof txt, "×%d", d->trial_counts[i]);
            plschr(0.0, 0.8 * PLOT_CHAR_SCALE);
            plptex(x + 0.012 * (c->x1 - c->x0), y + 0.02 * (c->y1 - c->y0), 1.0, 0.0, 0.0, txt);
            plschr(0.0, PLOT_CHAR_SCALE);
        }
    }
    bool have_edges = draw_edges(c);

    plot_legend_entry e[PLOT_LEGEND_MAX];
    int n = 0;
    static const plot_regime order[5] = {PLOT_REGIME_ASYMMETRIC, PLOT_REGIME_SYMMETRIC, PLOT_REGIME_NO_SNAP,
                                         PLOT_REGIME_NO_UPPER, PLOT_REGIME_UNKNOWN};
    static const char *cell_text[5] = {
        [PLOT_REGIME_ASYMMETRIC] = "predicted asymmetric",
        [PLOT_REGIME_SYMMETRIC] = "predicted symmetric",
        [PLOT_REGIME_NO_SNAP] = "predicted no snap",
        [PLOT_REGIME_NO_UPPER] = "no stable upper state",
        [PLOT_REGIME_UNKNOWN] = "prediction failed",
    };
    static const char *mark_text[5] = {
        [PLOT_REGIME_ASYMMETRIC] = "measured asymmetric",
        [PLOT_REGIME_SYMMETRIC] = "measured symmetric",
        [PLOT_REGIME_NO_SNAP] = "measured no snap",
        [PLOT_REGIME_NO_UPPER] = "measured unknown",
        [PLOT_REGIME_UNKNOWN] = "measured unknown",
    };
    for (int k = 0; k < 5; k++)
        if (cells[order[k]])
            e[n++] = (plot_legend_entry){cell_text[order[k]], PLOT_LEGEND_KIND_BOX, cell_color(order[k]), 0, 0, NULL,
                                         0};
    if (have_boundary)
        e[n++] = (plot_legend_entry){"predicted boundary", PLOT_LEGEND_KIND_LINE, PLOT_COL_INK, PLOT_LSTY_DASHED,
                                     PLOT_WIDTH_DATA, NULL, 0};
    if (have_edges)
        e[n++] = (plot_legend_entry){"experimental boundary", PLOT_LEGEND_KIND_SYMBOL, PLOT_COL_SERIES_3, 0, 0,
                                     PLOT_GLYPH_STAR, 1.4};
    for (int k = 0; k < 5; k++) {
        if (order[k] == PLOT_REGIME_NO_UPPER || !marks[order[k]])
            continue;
        int color;
        const char *glyph;
        double scale;
        trial_style(order[k], &color, &glyph, &scale);
        e[n++] = (plot_legend_entry){mark_text[order[k]], PLOT_LEGEND_KIND_SYMBOL, color, 0, 0, glyph, scale};
    }
    plot_legend_draw(e, n, PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT, 0.02, 0.0);

    if (d->n_gamma == 0 && plot_series_finite(d->boundary_gamma, d->boundary_phi_deg, d->n_boundary) == 0 &&
        d->n_trials == 0 && d->n_edges == 0) {
        plcol0(PLOT_COL_UNSTABLE);
        plptex(0.5 * (c->x0 + c->x1), 0.5 * (c->y0 + c->y1), 1.0, 0.0, 0.5, "no data");
    }
    return PLOT_OK;
}

plot_status plot_phase_report(const char *png_path, const plot_phase_data *d, char *why, size_t why_len)
{
    if (why && why_len)
        why[0] = '\0';
    if (!d)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "plot_phase_report: no data");
    plot_status st;
    int w, h;
    if ((st = plot_size_resolve(d->width_px, PLOT_WIDTH_DEFAULT, "width", &w, why, why_len)) != PLOT_OK ||
        (st = plot_size_resolve(d->height_px, PLOT_HEIGHT_DEFAULT, "height", &h, why, why_len)) != PLOT_OK ||
        (st = check_phase(d, why, why_len)) != PLOT_OK)
        return st;

    /* axis ranges: the cells exactly, widened (and padded) only where boundary points or trials
     * lie outside them */
    phase_ctx c = {.d = d};
    plot_range cx, cy, ax, ay;
    plot_range_init(&cx);
    plot_range_init(&cy);
    if (d->n_gamma > 0) {
        double lo, hi;
        cell_edges(d->gamma, d->n_gamma, 0, GAMMA_FLOOR, &lo, &hi);
        plot_range_add1(&cx, lo);
        cell_edges(d->gamma, d->n_gamma, d->n_gamma - 1, GAMMA_FLOOR, &lo, &hi);
        plot_range_add1(&cx, hi);
        cell_edges(d->phi_deg, d->n_phi, 0, PHI_FLOOR, &lo, &hi);
        plot_range_add1(&cy, lo);
        cell_edges(d->phi_deg, d->n_phi, d->n_phi - 1, PHI_FLOOR, &lo, &hi);
        plot_range_add1(&cy, hi);
    }
    ax = cx;
    ay = cy;
    for (size_t i = 0; i < d->n_boundary; i++) {
        if (isfinite(d->boundary_gamma[i]) && isfinite(d->boundary_phi_deg[i])) {
            plot_range_add1(&ax, d->boundary_gamma[i]);
            plot_range_add1(&ay, d->boundary_phi_deg[i]);
        }
    }
    for (size_t i = 0; i < d->n_trials; i++) {
        if (isfinite(d->trials[i].gamma) && isfinite(d->trials[i].phi_deg)) {
            plot_range_add1(&ax, d->trials[i].gamma);
            plot_range_add1(&ay, d->trials[i].phi_deg);
        }
    }
    for (size_t i = 0; i < d->n_edges; i++) {
        const plot_phase_edge *e = &d->edges[i];
        if (isnan(e->lo) && isnan(e->hi)) continue;
        plot_range_add1(&ay, e->phi_deg);
        if (isfinite(e->lo)) plot_range_add1(&ax, e->lo);
        if (isfinite(e->hi)) plot_range_add1(&ax, e->hi);
    }
    bool inside_x = cx.n > 0 && ax.lo >= cx.lo && ax.hi <= cx.hi;
    bool inside_y = cy.n > 0 && ay.lo >= cy.lo && ay.hi <= cy.hi;
    plot_range_axis(&ax, inside_x ? 0.0 : 0.06, 0.0, 0.5, &c.x0, &c.x1);
    plot_range_axis(&ay, inside_y ? 0.0 : 0.06, 0.0, 180.0, &c.y0, &c.y1);
    return plot_session_run(PLOT_DEVICE, png_path, w, h, phase_draw, &c, why, why_len);
}
