/* sim_plot_sweep.c: the sweep figure with PLplot (see sim_plot_sweep.h). One PLplot stream is
 * created and ended per call (sim_plot_page.h); markers are drawn as outlined polygons in data
 * units scaled to stay round on the page. */
#include "sim_plot_page.h"
#include "sim_plot_sweep.h"

#include <math.h>
#include <plplot.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PAGE_W 900
#define PAGE_H 650

static void cross(double x, double y, double rx, double ry)
{
    PLFLT a[2] = {x - rx, x + rx}, b[2] = {y - ry, y + ry}, c[2] = {y + ry, y - ry};
    plline(2, a, b);
    plline(2, a, c);
}

static int inside(double v, double a, double b) { return v >= fmin(a, b) - 1e-9 && v <= fmax(a, b) + 1e-9; }

static int by_phi(const void *a, const void *b)
{
    const sweep_row *x = a, *y = b;
    return x->phi < y->phi ? -1 : x->phi > y->phi;
}

int sim_plot_sweep(const char *path, const sweep_table *t, double phi_a, double phi_b, double gamma_a,
                   double gamma_b, char *err, size_t errlen)
{
    int line = phi_a == phi_b;
    double x0 = fmin(gamma_a, gamma_b), x1 = fmax(gamma_a, gamma_b), y0 = INFINITY, y1 = -INFINITY;
    if (line) {
        for (size_t k = 0; k < t->n; k++) {
            const sweep_row *r = &t->rows[k];
            if (r->kind == 'b' || !inside(r->phi, phi_a, phi_b) || !inside(r->gamma, gamma_a, gamma_b)) continue;
            if (strcmp(r->first_type, "none") == 0) continue;
            y0 = fmin(y0, r->first_dw);
            y1 = fmax(y1, r->first_dw);
        }
        if (!(y1 > y0)) { y0 = 0.0; y1 = 1.0; }
    } else {
        x0 = fmin(phi_a, phi_b);
        x1 = fmax(phi_a, phi_b);
        y0 = fmin(gamma_a, gamma_b);
        y1 = fmax(gamma_a, gamma_b);
    }
    double mx = 0.06 * (x1 - x0 > 0 ? x1 - x0 : 1.0), my = 0.08 * (y1 - y0 > 0 ? y1 - y0 : 1.0);
    x0 -= mx; x1 += mx; y0 -= my; y1 += my;
    if (sim_plot_page_open(path, PAGE_W, PAGE_H, err, errlen) != 0)
        return -1;
    plscol0(0, 255, 255, 255);
    plscol0(1, 0, 0, 0);
    plscol0(2, 120, 120, 120);
    plinit();
    plcol0(1);
    plenv(x0, x1, y0, y1, 0, 0);
    char title[128];
    if (line) {
        snprintf(title, sizeof title, "#gf = %g#uo#d: circle pitchfork first, square saddle-node first", phi_a);
        pllab("#gG", "#gDW at the first instability", title);
    } else {
        pllab("#gf (deg)", "#gG", "circle: pitchfork first (asymmetric), square: saddle-node first");
    }
    double rx = 0.012 * (x1 - x0), ry = rx / (x1 - x0) * (y1 - y0) * PAGE_W / PAGE_H;
    plwidth(1.5);
    for (size_t k = 0; k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind != 'p' || !inside(r->phi, phi_a, phi_b) || !inside(r->gamma, gamma_a, gamma_b)) continue;
        double x = line ? r->gamma : r->phi, y = line ? r->first_dw : r->gamma;
        int fail = strcmp(r->regime, "asymmetric") && strcmp(r->regime, "symmetric");
        if (line && fail) continue;
        plcol0(1);
        if (fail) cross(x, y, rx, ry);
        else if (!strcmp(r->regime, "asymmetric")) sim_plot_polygon(x, y, rx, ry, 36, 0.0);
        else sim_plot_polygon(x, y, rx * M_SQRT2, ry * M_SQRT2, 4, M_PI / 4);
    }
    /* Boundaries. */
    sweep_row *b = malloc(sizeof(sweep_row) * (t->n ? t->n : 1));
    int nb = 0;
    for (size_t k = 0; b && k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind == 'b' && inside(r->phi, phi_a, phi_b) && inside(r->gamma, gamma_a, gamma_b)) b[nb++] = *r;
    }
    if (b) qsort(b, (size_t)nb, sizeof *b, by_phi);
    plcol0(2);
    plwidth(2.0);
    if (line) {
        pllsty(2);
        for (int k = 0; k < nb; k++) {
            PLFLT x[2] = {b[k].gamma, b[k].gamma}, y[2] = {y0, y1};
            plline(2, x, y);
        }
        pllsty(1);
    } else if (nb > 0) {
        /* One line per kind of boundary (the regimes either side, in the note), through its
         * points in order of phi: asymmetric/symmetric solid, the others dashed. */
        PLFLT *x = malloc(sizeof(PLFLT) * (size_t)nb), *y = malloc(sizeof(PLFLT) * (size_t)nb);
        char *done = calloc((size_t)nb, 1);
        for (int k = 0; x && y && done && k < nb; k++) {
            if (done[k]) continue;
            int m = 0;
            for (int q = k; q < nb; q++)
                if (!done[q] && !strcmp(b[q].note, b[k].note)) {
                    done[q] = 1;
                    x[m] = b[q].phi;
                    y[m] = b[q].gamma;
                    m++;
                }
            pllsty(strstr(b[k].note, "asymmetric below; symmetric above") ? 1 : 2);
            if (m > 1) plline(m, x, y);
            for (int q = 0; q < m; q++) sim_plot_polygon(x[q], y[q], 0.4 * rx, 0.4 * ry, 4, 0.0);
        }
        pllsty(1);
        free(done);
        free(x);
        free(y);
    }
    free(b);
    if (!sim_plot_page_close(path)) {
        snprintf(err, errlen, "PLplot wrote nothing to %s (is plplot-driver-cairo installed?)", path);
        return -1;
    }
    return 0;
}
