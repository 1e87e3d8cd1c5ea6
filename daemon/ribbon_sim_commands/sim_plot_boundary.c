/* sim_plot_boundary.c: the boundary figures (see sim_plot_boundary.h), drawn by the plot module
 * (plot.h: plot_boundary, which also contains PLplot's fatal errors). This file only turns the
 * traced points, the sweep's classified points and the critical curves into plain arrays and
 * names them for the legend. */
#include "sim_plot_boundary.h"

#include "plot.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PAGE_W 1000
#define PAGE_H 700

static plot_regime regime_of(const char *s)
{
    return !strcmp(s, "asymmetric") ? PLOT_REGIME_ASYMMETRIC
           : !strcmp(s, "symmetric") ? PLOT_REGIME_SYMMETRIC
                                     : PLOT_REGIME_UNKNOWN;
}

int sim_plot_boundary(const char *path, const rod_boundary_curve *curves, const double *dl, int ncurves,
                      const sweep_table *sweep, char *why, size_t why_len)
{
    if (ncurves > PLOT_BOUNDARY_CURVES_MAX) {
        snprintf(why, why_len, "--plot draws at most %d Delta L (%d given)", PLOT_BOUNDARY_CURVES_MAX, ncurves);
        return -1;
    }
    size_t npts = 0, nsw = sweep ? sweep->n : 0;
    for (int c = 0; c < ncurves; c++) npts += curves[c].n;
    double *xy = malloc((2 * npts + 1) * sizeof *xy);
    plot_sweep_point *pts = malloc((nsw + 1) * sizeof *pts);
    int rc = -1;
    if (!xy || !pts) {
        snprintf(why, why_len, "out of memory drawing %s", path);
        goto out;
    }
    plot_boundary_curve cv[PLOT_BOUNDARY_CURVES_MAX];
    char label[PLOT_BOUNDARY_CURVES_MAX][64];
    size_t used = 0;
    for (int c = 0; c < ncurves; c++) {
        double *x = xy + used, *y = xy + npts + used;
        for (size_t k = 0; k < curves[c].n; k++) {
            x[k] = curves[c].pts[k].phi_deg;
            y[k] = curves[c].pts[k].gamma;
        }
        used += curves[c].n;
        snprintf(label[c], sizeof label[c], "#gG*(#gf) traced at #gDL = %g", dl[c]);
        cv[c] = (plot_boundary_curve){x, y, curves[c].n, PLOT_CURVE_MARK_NONE, label[c]};
    }
    size_t np = 0;
    for (size_t k = 0; k < nsw; k++) {
        const sweep_row *r = &sweep->rows[k];
        if (r->kind == 'p')
            pts[np++] = (plot_sweep_point){r->phi, r->gamma, regime_of(r->regime), !strcmp(r->regime, "no-upper"), NAN, 0.0};
    }
    plot_boundary_data d;
    plot_boundary_data_default(&d);
    d.title = "regime boundary #gG*(#gf): pitchfork and saddle-node coincide";
    d.x_label = "#gf (deg)";
    d.y_label = "#gG";
    d.curves = cv;
    d.n_curves = (size_t)ncurves;
    d.points = pts;
    d.n_points = np;
    d.width_px = PAGE_W;
    d.height_px = PAGE_H;
    if (plot_boundary(path, &d, why, why_len) == PLOT_OK) rc = 0;
out:
    free(xy);
    free(pts);
    return rc;
}

int sim_plot_boundary_curves(const char *path, const rod_crit_curve *fold, const rod_crit_curve *pitchfork,
                             const rod_codim2_point *star, char *why, size_t why_len)
{
    const rod_crit_curve *cs[2] = {fold, pitchfork};
    double *x[2] = {NULL, NULL}, *y[2] = {NULL, NULL};
    int rc = -1;
    for (int c = 0; c < 2; c++) {
        x[c] = malloc((cs[c]->n + 1) * sizeof *x[c]);
        y[c] = malloc((cs[c]->n + 1) * sizeof *y[c]);
        if (!x[c] || !y[c]) {
            snprintf(why, why_len, "out of memory drawing %s", path);
            goto out;
        }
        for (size_t k = 0; k < cs[c]->n; k++) {
            x[c][k] = cs[c]->pts[k].gamma;
            y[c][k] = cs[c]->pts[k].dw;
        }
    }
    plot_boundary_curve cv[2] = {
        {x[0], y[0], fold->n, PLOT_CURVE_MARK_SQUARE, "saddle-node (fold in #gDW, even mode)"},
        {x[1], y[1], pitchfork->n, PLOT_CURVE_MARK_CIRCLE, "pitchfork (odd mode)"},
    };
    char title[128], star_label[128];
    snprintf(title, sizeof title, "#gf = %g#uo#d, #gDL = %g: bifurcations of the upper symmetric branch",
             star->phi_deg, star->dl);
    snprintf(star_label, sizeof star_label, "codim-2 point, both critical: #gG* = %.4f, #gDW = %.4f", star->gamma,
             star->dw);
    plot_boundary_data d;
    plot_boundary_data_default(&d);
    d.title = title;
    d.x_label = "#gG";
    d.y_label = "#gDW";
    d.curves = cv;
    d.n_curves = 2;
    d.star_x = star->gamma;
    d.star_y = star->dw;
    d.star_label = star_label;
    d.note = "left of #gG*: pitchfork first (asymmetric); right: saddle-node first";
    d.width_px = PAGE_W;
    d.height_px = PAGE_H;
    if (plot_boundary(path, &d, why, why_len) == PLOT_OK) rc = 0;
out:
    for (int c = 0; c < 2; c++) {
        free(x[c]);
        free(y[c]);
    }
    return rc;
}
