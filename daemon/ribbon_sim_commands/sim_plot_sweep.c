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

#define PAGE_W 1250
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

static int same_dl(double a, double b) { return fabs(a - b) <= 1e-9 * fmax(1.0, fabs(a)); }

static void diamond_filled(double x, double y, double rx, double ry)
{
    PLFLT px[4] = {x - rx, x, x + rx, x}, py[4] = {y, y + ry, y, y - ry};
    plcol0(3);
    plfill(4, px, py);
    plcol0(1);
    plline(4, px, py);
    PLFLT cx[2] = {x, x - rx}, cy[2] = {y - ry, y};
    plline(2, cx, cy);
}

static void marker(const char *regime, double x, double y, double rx, double ry)
{
    plcol0(1);
    if (!strcmp(regime, "asymmetric")) sim_plot_polygon(x, y, rx, ry, 36, 0.0);
    else if (!strcmp(regime, "symmetric")) sim_plot_polygon(x, y, rx * M_SQRT2, ry * M_SQRT2, 4, M_PI / 4);
    else if (!strcmp(regime, "none")) sim_plot_polygon(x, y, rx * 1.2, ry * 1.2, 3, M_PI / 2);
    else if (!strcmp(regime, "no-upper")) diamond_filled(x, y, rx, ry);
    else cross(x, y, rx, ry);
}

/* The legend, in its own viewport on the right of the page. */
static void legend(int line)
{
    plvpor(0.70, 0.995, 0.12, 0.90);
    plwind(0.0, 1.0, 0.0, 1.0);
    plschr(0.0, 0.62);
    double rx = 0.03, ry = rx * (0.295 * PAGE_W) / (0.78 * PAGE_H), y = 0.97, dy = 0.085;
    static const char *const regimes[] = {"asymmetric", "symmetric", "none", "no-upper", "failed"};
    static const char *const text[] = {"pitchfork first: asymmetric snap", "saddle-node first: symmetric snap",
                                       "no instability up to #gDW = 1: no snap",
                                       "no stable upper state found", "analysis failed (reason in the CSV note)"};
    for (int k = 0; k < (line ? 2 : 5); k++, y -= dy) {
        marker(regimes[k], 0.06, y, rx, ry);
        plcol0(1);
        plptex(0.14, y - 0.012, 1.0, 0.0, 0.0, text[k]);
    }
    plcol0(2);
    plwidth(2.0);
    PLFLT lx[2] = {0.0, 0.11}, ly[2];
    if (!line) {
        ly[0] = ly[1] = y;
        plline(2, lx, ly);
        plcol0(1);
        plptex(0.14, y - 0.012, 1.0, 0.0, 0.0, "#gG*: asymmetric below, symmetric above");
        y -= dy;
        plcol0(2);
        pllsty(2);
        ly[0] = ly[1] = y;
        plline(2, lx, ly);
        pllsty(1);
        plcol0(1);
        plptex(0.14, y - 0.012, 1.0, 0.0, 0.0, "other boundary: edges of the no-snap");
        plptex(0.14, y - 0.012 - 0.045, 1.0, 0.0, 0.0, "band, or back to pitchfork first above");
        y -= dy + 0.045;
        plcol0(2);
        sim_plot_polygon(0.055, y, 0.4 * rx, 0.4 * ry, 4, 0.0);
        plcol0(1);
        plptex(0.14, y - 0.012, 1.0, 0.0, 0.0, "boundary located by bisection");
        y -= dy;
        plcol0(3);
        PLFLT bx[4] = {0.03, 0.09, 0.09, 0.03}, by[4] = {y - 0.03, y - 0.03, y + 0.03, y + 0.03};
        plfill(4, bx, by);
        plcol0(1);
        plptex(0.14, y - 0.012, 1.0, 0.0, 0.0, "grey bar: up to the #gG where");
        plptex(0.14, y - 0.012 - 0.045, 1.0, 0.0, 0.0, "continuation in #gG lost the upper");
        plptex(0.14, y - 0.012 - 0.090, 1.0, 0.0, 0.0, "state (the route fails there too)");
    } else {
        pllsty(2);
        ly[0] = ly[1] = y;
        plline(2, lx, ly);
        pllsty(1);
        plcol0(1);
        plptex(0.14, y - 0.012, 1.0, 0.0, 0.0, "boundary located by bisection");
        plptex(0.14, y - 0.012 - dy, 1.0, 0.0, 0.0, "(no snap, no upper state and failed");
        plptex(0.14, y - 0.012 - dy - 0.045, 1.0, 0.0, 0.0, "points have no #gDW: not drawn)");
    }
    plschr(0.0, 1.0);
}

int sim_plot_sweep(const char *path, const sweep_table *t, double phi_a, double phi_b, double gamma_a,
                   double gamma_b, double dl, char *err, size_t errlen)
{
    int line = phi_a == phi_b;
    double x0 = fmin(gamma_a, gamma_b), x1 = fmax(gamma_a, gamma_b), y0 = INFINITY, y1 = -INFINITY;
    if (line) {
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
    plscol0(3, 200, 200, 200);
    plinit();
    pladv(0);
    legend(line);
    plcol0(1);
    plvpor(0.09, 0.66, 0.12, 0.90);
    plwind(x0, x1, y0, y1);
    plbox("bcnst", 0.0, 0, "bcnstv", 0.0, 0);
    char title[128];
    if (line) {
        snprintf(title, sizeof title, "#gf = %g#uo#d, #gDL = %g: the first instability along #gG", phi_a, dl);
        pllab("#gG", "#gDW at the first instability", title);
    } else {
        snprintf(title, sizeof title, "regime of the snap over (#gf, #gG) at #gDL = %g", dl);
        pllab("#gf (deg)", "#gG", title);
    }
    double rx = 0.012 * (x1 - x0), ry = rx / (x1 - x0) * (y1 - y0) * (0.57 * PAGE_W) / (0.78 * PAGE_H);
    if (!line) {
        /* Grey bars: each no-upper point up to the Gamma where continuation lost the state. */
        for (size_t k = 0; k < t->n; k++) {
            const sweep_row *r = &t->rows[k];
            if (r->kind != 'p' || strcmp(r->regime, "no-upper") || !same_dl(r->dl, dl) ||
                !inside(r->phi, phi_a, phi_b))
                continue;
            const char *at = strstr(r->note, "lost at Gamma ");
            double g = at ? strtod(at + 14, NULL) : r->gamma;
            PLFLT bx[4] = {r->phi - 0.6 * rx, r->phi + 0.6 * rx, r->phi + 0.6 * rx, r->phi - 0.6 * rx};
            PLFLT by[4] = {r->gamma, r->gamma, g, g};
            plcol0(3);
            plfill(4, bx, by);
        }
    }
    plwidth(1.5);
    for (size_t k = 0; k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind != 'p' || !inside(r->phi, phi_a, phi_b) || !inside(r->gamma, gamma_a, gamma_b) ||
            !same_dl(r->dl, dl))
            continue;
        double x = line ? r->gamma : r->phi, y = line ? r->first_dw : r->gamma;
        int fail = strcmp(r->regime, "asymmetric") && strcmp(r->regime, "symmetric");
        if (line && fail) continue;
        marker(r->regime, x, y, rx, ry);
    }
    /* Boundaries. */
    sweep_row *b = malloc(sizeof(sweep_row) * (t->n ? t->n : 1));
    int nb = 0;
    for (size_t k = 0; b && k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind == 'b' && inside(r->phi, phi_a, phi_b) && inside(r->gamma, gamma_a, gamma_b) && same_dl(r->dl, dl))
            b[nb++] = *r;
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
