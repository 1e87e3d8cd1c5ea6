/* sim_plot_sweep.c: the figure of `ribbon-sim sweep --plot` (see sim_plot_sweep.h), drawn by the
 * plot module (plot.h: plot_sweep, which also contains PLplot's fatal errors). This file only
 * picks the sweep's rows inside the requested box and turns them into plain arrays: a marker per
 * point, and the boundaries, as vertical lines at Gamma* for one phi, or for several phi one line
 * per kind of boundary (the regimes either side, in the row's note) through its points in order
 * of phi, asymmetric/symmetric solid, the others dashed. */
#include "sim_plot_sweep.h"

#include "plot.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PAGE_W 900
#define PAGE_H 650

static int inside(double v, double a, double b) { return v >= fmin(a, b) - 1e-9 && v <= fmax(a, b) + 1e-9; }

static int by_phi(const void *a, const void *b)
{
    const sweep_row *x = a, *y = b;
    return x->phi < y->phi ? -1 : x->phi > y->phi;
}

static plot_regime regime_of(const char *s)
{
    return !strcmp(s, "asymmetric") ? PLOT_REGIME_ASYMMETRIC
           : !strcmp(s, "symmetric") ? PLOT_REGIME_SYMMETRIC
                                     : PLOT_REGIME_UNKNOWN;
}

int sim_plot_sweep(const char *path, const sweep_table *t, double phi_a, double phi_b, double gamma_a,
                   double gamma_b, char *err, size_t errlen)
{
    int line = phi_a == phi_b;
    size_t n = t->n ? t->n : 1;
    plot_sweep_point *pts = malloc(n * sizeof *pts);
    sweep_row *b = malloc(n * sizeof *b);
    plot_sweep_line *lines = malloc(n * sizeof *lines);
    double *lx = malloc(2 * n * sizeof *lx), *ly = malloc(2 * n * sizeof *ly);
    char *done = calloc(n, 1);
    int rc = -1;
    if (!pts || !b || !lines || !lx || !ly || !done) {
        snprintf(err, errlen, "out of memory drawing %s", path);
        goto out;
    }
    plot_sweep_data d;
    plot_sweep_data_default(&d);
    d.width_px = PAGE_W;
    d.height_px = PAGE_H;
    char title[128];
    if (line) {
        /* Gamma against the first instability's Delta W, over the Delta W the points reach. */
        d.x0 = gamma_a;
        d.x1 = gamma_b;
        double y0 = INFINITY, y1 = -INFINITY;
        for (size_t k = 0; k < t->n; k++) {
            const sweep_row *r = &t->rows[k];
            if (r->kind == 'b' || !inside(r->phi, phi_a, phi_b) || !inside(r->gamma, gamma_a, gamma_b)) continue;
            if (strcmp(r->first_type, "none") == 0) continue;
            y0 = fmin(y0, r->first_dw);
            y1 = fmax(y1, r->first_dw);
        }
        if (!(y1 > y0)) { y0 = 0.0; y1 = 1.0; }
        d.y0 = y0;
        d.y1 = y1;
        snprintf(title, sizeof title, "#gf = %g#uo#d: circle pitchfork first, square saddle-node first", phi_a);
        d.title = title;
        d.x_label = "#gG";
        d.y_label = "#gDW at the first instability";
    } else {
        d.x0 = phi_a;
        d.x1 = phi_b;
        d.y0 = gamma_a;
        d.y1 = gamma_b;
        d.title = "circle: pitchfork first (asymmetric), square: saddle-node first";
        d.x_label = "#gf (deg)";
        d.y_label = "#gG";
    }
    size_t np = 0;
    for (size_t k = 0; k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind != 'p' || !inside(r->phi, phi_a, phi_b) || !inside(r->gamma, gamma_a, gamma_b)) continue;
        plot_regime g = regime_of(r->regime);
        if (line && g == PLOT_REGIME_UNKNOWN) continue;
        pts[np++] = (plot_sweep_point){line ? r->gamma : r->phi, line ? r->first_dw : r->gamma, g};
    }
    d.points = pts;
    d.n_points = np;
    /* Boundaries. */
    size_t nb = 0, nl = 0, used = 0;
    for (size_t k = 0; k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind == 'b' && inside(r->phi, phi_a, phi_b) && inside(r->gamma, gamma_a, gamma_b)) b[nb++] = *r;
    }
    qsort(b, nb, sizeof *b, by_phi);
    if (line) {
        double y0 = d.y0 - 0.08 * (d.y1 - d.y0 > 0 ? d.y1 - d.y0 : 1.0);
        double y1 = d.y1 + 0.08 * (d.y1 - d.y0 > 0 ? d.y1 - d.y0 : 1.0);
        for (size_t k = 0; k < nb; k++) {
            lx[used] = lx[used + 1] = b[k].gamma;
            ly[used] = y0;
            ly[used + 1] = y1;
            lines[nl++] = (plot_sweep_line){&lx[used], &ly[used], 2, true, false};
            used += 2;
        }
    } else {
        for (size_t k = 0; k < nb; k++) {
            if (done[k]) continue;
            size_t m = 0;
            for (size_t q = k; q < nb; q++)
                if (!done[q] && !strcmp(b[q].note, b[k].note)) {
                    done[q] = 1;
                    lx[used + m] = b[q].phi;
                    ly[used + m] = b[q].gamma;
                    m++;
                }
            bool dashed = !strstr(b[k].note, "asymmetric below; symmetric above");
            lines[nl++] = (plot_sweep_line){&lx[used], &ly[used], m, dashed, true};
            used += m;
        }
    }
    d.lines = lines;
    d.n_lines = nl;
    if (plot_sweep(path, &d, err, errlen) == PLOT_OK)
        rc = 0;
out:
    free(pts);
    free(b);
    free(lines);
    free(lx);
    free(ly);
    free(done);
    return rc;
}
