/* sim_plot_sweep.c: the figure of `ribbon-sim sweep --plot` (see sim_plot_sweep.h), drawn by the
 * plot module (plot.h: plot_sweep, which also contains PLplot's fatal errors). This file only
 * picks the sweep's rows inside the requested box (and of one Delta L) and turns them into plain
 * arrays: a marker per point (no-upper points with a bar up to the Gamma where continuation lost
 * the upper state, read from the row's note), and the boundaries, as vertical lines at Gamma* for one phi, or for several phi one line
 * per kind of boundary (the regimes either side, in the row's note) through its points in order
 * of phi, asymmetric/symmetric solid, the others dashed. */
#include "sim_plot_sweep.h"

#include "plot.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PAGE_W 1250
#define PAGE_H 650

static int inside(double v, double a, double b) { return v >= fmin(a, b) - 1e-9 && v <= fmax(a, b) + 1e-9; }

static int by_phi(const void *a, const void *b)
{
    const sweep_row *x = a, *y = b;
    if (x->phi != y->phi) return x->phi < y->phi ? -1 : 1;
    return x->gamma < y->gamma ? -1 : x->gamma > y->gamma;
}

/* A regime as the legend names it, short enough for its width. */
static const char *short_regime(const char *r)
{
    return !strcmp(r, "none") ? "no snap" : !strcmp(r, "asymmetric") ? "asym." : !strcmp(r, "symmetric") ? "sym." : r;
}

static int same_dl(double a, double b) { return fabs(a - b) <= 1e-9 * fmax(1.0, fabs(a)); }

int sim_plot_sweep(const char *path, const sweep_table *t, double phi_a, double phi_b, double gamma_a,
                   double gamma_b, double dl, char *why, size_t why_len)
{
    int line = phi_a == phi_b;
    size_t n = t->n ? t->n : 1;
    plot_sweep_point *pts = malloc(n * sizeof *pts);
    sweep_row *b = malloc(n * sizeof *b);
    plot_sweep_line *lines = malloc(n * sizeof *lines);
    double *lx = malloc(2 * n * sizeof *lx), *ly = malloc(2 * n * sizeof *ly);
    char *done = calloc(n, 1);
    char (*texts)[96] = malloc(n * sizeof *texts); /* the legend's text of each line */
    int rc = -1;
    if (!pts || !b || !lines || !lx || !ly || !done || !texts) {
        snprintf(why, why_len, "out of memory drawing %s", path);
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
            if (r->kind == 'b' || !inside(r->phi, phi_a, phi_b) || !inside(r->gamma, gamma_a, gamma_b) ||
                !same_dl(r->dl, dl))
                continue;
            if (strcmp(r->first_type, "none") == 0) continue;
            y0 = fmin(y0, r->first_dw);
            y1 = fmax(y1, r->first_dw);
        }
        if (!(y1 > y0)) { y0 = 0.0; y1 = 1.0; }
        d.y0 = y0;
        d.y1 = y1;
        snprintf(title, sizeof title, "#gf = %g#uo#d, #gDL = %g: the first instability along #gG", phi_a, dl);
        d.title = title;
        d.x_label = "#gG";
        d.y_label = "#gDW at the first instability";
    } else {
        d.x0 = phi_a;
        d.x1 = phi_b;
        d.y0 = gamma_a;
        d.y1 = gamma_b;
        snprintf(title, sizeof title, "regime of the snap over (#gf, #gG) at #gDL = %g", dl);
        d.title = title;
        d.x_label = "#gf (deg)";
        d.y_label = "#gG";
    }
    size_t np = 0;
    for (size_t k = 0; k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind != 'p' || !inside(r->phi, phi_a, phi_b) || !inside(r->gamma, gamma_a, gamma_b) ||
            !same_dl(r->dl, dl))
            continue;
        plot_regime g = plot_regime_parse(r->regime);
        bool no_state = !strcmp(r->regime, "no-upper");
        /* Only snaps have a Delta W at their first instability. */
        if (line && (no_state || (g != PLOT_REGIME_ASYMMETRIC && g != PLOT_REGIME_SYMMETRIC))) continue;
        /* The bar: to the located fold (two folds: between them), else to where continuation lost it. */
        double bar = NAN, bar_from = 0.0;
        const char *at;
        if (no_state && (!strncmp(r->note, "fold at Gamma ", 14) || !strncmp(r->note, "pitchfork at Gamma ", 19))) {
            at = strstr(r->note, "at Gamma ");
            bar = strtod(at + 9, NULL);
            const char *and = strstr(at, " and ");
            const char *at2 = and ? strstr(and, "at Gamma ") : NULL;
            if (at2 && at2 < strstr(r->note, "(")) {
                bar_from = bar;
                bar = strtod(at2 + 9, NULL);
            }
        } else if (no_state && (at = strstr(r->note, "lost at Gamma "))) {
            bar = strtod(at + 14, NULL);
        }
        pts[np++] = (plot_sweep_point){line ? r->gamma : r->phi, line ? r->first_dw : r->gamma, g, no_state, bar, bar_from};
    }
    d.points = pts;
    d.n_points = np;
    /* Boundaries. */
    size_t nb = 0, nl = 0, used = 0;
    for (size_t k = 0; k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind == 'b' && inside(r->phi, phi_a, phi_b) && inside(r->gamma, gamma_a, gamma_b) && same_dl(r->dl, dl))
            b[nb++] = *r;
    }
    qsort(b, nb, sizeof *b, by_phi);
    if (line) {
        double y0 = d.y0 - 0.08 * (d.y1 - d.y0 > 0 ? d.y1 - d.y0 : 1.0);
        double y1 = d.y1 + 0.08 * (d.y1 - d.y0 > 0 ? d.y1 - d.y0 : 1.0);
        for (size_t k = 0; k < nb; k++) {
            lx[used] = lx[used + 1] = b[k].gamma;
            ly[used] = y0;
            ly[used + 1] = y1;
            /* Named in the legend by where it is and what it separates ("none": no snap). */
            char lo[16], hi[16];
            if (sscanf(b[k].note, "%15s below; %15s above", lo, hi) == 2)
                snprintf(texts[nl], sizeof texts[nl], "#gG = %.4f: %s below, %s above", b[k].gamma,
                         short_regime(lo), short_regime(hi));
            else
                snprintf(texts[nl], sizeof texts[nl], "#gG = %.4f (bisected)", b[k].gamma);
            lines[nl] = (plot_sweep_line){&lx[used], &ly[used], 2, true, false, texts[nl]};
            nl++;
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
            lines[nl++] = (plot_sweep_line){&lx[used], &ly[used], m, dashed, true,
                                            dashed ? "other: no-snap band edges, pitchfork again"
                                                   : "#gG*: asymmetric below, symmetric above"};
            used += m;
        }
    }
    d.lines = lines;
    d.n_lines = nl;
    d.legend = true;
    if (plot_sweep(path, &d, why, why_len) == PLOT_OK)
        rc = 0;
out:
    free(pts);
    free(b);
    free(lines);
    free(lx);
    free(ly);
    free(done);
    free(texts);
    return rc;
}
