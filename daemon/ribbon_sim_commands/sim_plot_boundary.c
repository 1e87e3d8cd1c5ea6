/* sim_plot_boundary.c: the boundary figures with PLplot (see sim_plot_boundary.h). One stream per
 * call (sim_plot_page.h). The legend is drawn as text lines in the top-left corner, each with a
 * sample of its marker or line, so every mark on the page is explained on the page. */
#include "sim_plot_boundary.h"
#include "sim_plot_page.h"

#include <math.h>
#include <plplot.h>
#include <stdio.h>
#include <string.h>

#define PAGE_W 1000
#define PAGE_H 700

/* Colours: 0 background, 1 ink, 2 grey, then one per Delta L line. */
static const int line_rgb[6][3] = {{31, 119, 180}, {214, 39, 40}, {44, 160, 44}, {148, 103, 189}, {255, 127, 14},
                                   {23, 190, 207}};

static void palette(void)
{
    plscol0(0, 255, 255, 255);
    plscol0(1, 0, 0, 0);
    plscol0(2, 150, 150, 150);
    for (int k = 0; k < 6; k++) plscol0(3 + k, line_rgb[k][0], line_rgb[k][1], line_rgb[k][2]);
}

static void cross(double x, double y, double rx, double ry)
{
    PLFLT a[2] = {x - rx, x + rx}, b[2] = {y - ry, y + ry}, c[2] = {y + ry, y - ry};
    plline(2, a, b);
    plline(2, a, c);
}

/* Marker kind: 0 circle, 1 square, 2 cross. */
static void marker(int kind, double x, double y, double rx, double ry)
{
    if (kind == 0) sim_plot_polygon(x, y, rx, ry, 36, 0.0);
    else if (kind == 1) sim_plot_polygon(x, y, rx * M_SQRT2, ry * M_SQRT2, 4, M_PI / 4);
    else cross(x, y, rx, ry);
}

/* Legend line k (from the top) at the upper left of the window (x0..x1, y0..y1): a sample (marker
 * kind >= 0, or a line of style lsty when kind < 0) and the text. */
static void legend_line(int k, double x0, double x1, double y0, double y1, int col, int kind, int lsty,
                        const char *text)
{
    double dx = x1 - x0, dy = y1 - y0, x = x0 + 0.03 * dx, y = y1 - (0.05 + 0.045 * k) * dy;
    double rx = 0.008 * dx, ry = rx / dx * dy * PAGE_W / PAGE_H;
    plcol0(col);
    if (kind >= 0) {
        marker(kind, x + 0.02 * dx, y, rx, ry);
    } else {
        pllsty(lsty);
        PLFLT a[2] = {x, x + 0.04 * dx}, b[2] = {y, y};
        plline(2, a, b);
        pllsty(1);
    }
    plcol0(1);
    plptex(x + 0.055 * dx, y, 1.0, 0.0, 0.0, text);
}

int sim_plot_boundary(const char *path, const rod_boundary_curve *curves, const double *dl, int ncurves,
                      const sweep_table *sweep, char *err, size_t errlen)
{
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (int c = 0; c < ncurves; c++)
        for (size_t k = 0; k < curves[c].n; k++) {
            x0 = fmin(x0, curves[c].pts[k].phi_deg);
            x1 = fmax(x1, curves[c].pts[k].phi_deg);
            y0 = fmin(y0, curves[c].pts[k].gamma);
            y1 = fmax(y1, curves[c].pts[k].gamma);
        }
    for (size_t k = 0; sweep && k < sweep->n; k++) {
        const sweep_row *r = &sweep->rows[k];
        if (r->kind != 'p') continue;
        x0 = fmin(x0, r->phi);
        x1 = fmax(x1, r->phi);
        y0 = fmin(y0, r->gamma);
        y1 = fmax(y1, r->gamma);
    }
    if (!(x1 > x0)) { x0 -= 1.0; x1 += 1.0; }
    if (!(y1 > y0)) { y0 -= 0.01; y1 += 0.01; }
    double mx = 0.06 * (x1 - x0), my = 0.08 * (y1 - y0);
    x0 -= mx; x1 += mx; y0 -= my; y1 += 0.35 * (y1 - y0) + my; /* room for the legend */
    if (sim_plot_page_open(path, PAGE_W, PAGE_H, err, errlen) != 0) return -1;
    palette();
    plinit();
    plcol0(1);
    plenv(x0, x1, y0, y1, 0, 0);
    pllab("#gf (deg)", "#gG", "regime boundary #gG*(#gf): pitchfork and saddle-node coincide");
    double rx = 0.008 * (x1 - x0), ry = rx / (x1 - x0) * (y1 - y0) * PAGE_W / PAGE_H;
    int have_sweep = 0, have_fail = 0;
    plwidth(1.2);
    for (size_t k = 0; sweep && k < sweep->n; k++) {
        const sweep_row *r = &sweep->rows[k];
        if (r->kind != 'p') continue;
        int kind = !strcmp(r->regime, "asymmetric") ? 0 : !strcmp(r->regime, "symmetric") ? 1 : 2;
        have_sweep = 1;
        have_fail |= kind == 2;
        plcol0(2);
        marker(kind, r->phi, r->gamma, rx, ry);
    }
    plwidth(2.5);
    for (int c = 0; c < ncurves; c++) {
        PLFLT x[4096], y[4096];
        int m = 0;
        for (size_t k = 0; k < curves[c].n && m < 4096; k++, m++) {
            x[m] = curves[c].pts[k].phi_deg;
            y[m] = curves[c].pts[k].gamma;
        }
        plcol0(3 + c % 6);
        if (m > 1) plline(m, x, y);
        else if (m == 1) sim_plot_polygon(x[0], y[0], 0.5 * rx, 0.5 * ry, 4, 0.0);
    }
    plwidth(1.2);
    int line = 0;
    for (int c = 0; c < ncurves; c++) {
        char t[96];
        snprintf(t, sizeof t, "#gG*(#gf) traced at #gDL = %g", dl[c]);
        legend_line(line++, x0, x1, y0, y1, 3 + c % 6, -1, 1, t);
    }
    if (have_sweep) {
        legend_line(line++, x0, x1, y0, y1, 2, 0, 1, "sweep point: pitchfork first (asymmetric snap)");
        legend_line(line++, x0, x1, y0, y1, 2, 1, 1, "sweep point: saddle-node first (symmetric snap)");
        if (have_fail) legend_line(line++, x0, x1, y0, y1, 2, 2, 1, "sweep point: failed or no instability");
    }
    if (!sim_plot_page_close(path)) {
        snprintf(err, errlen, "PLplot wrote nothing to %s (is plplot-driver-cairo installed?)", path);
        return -1;
    }
    return 0;
}

int sim_plot_boundary_curves(const char *path, const rod_crit_curve *fold, const rod_crit_curve *pitchfork,
                             const rod_codim2_point *star, char *err, size_t errlen)
{
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    const rod_crit_curve *cs[2] = {fold, pitchfork};
    for (int c = 0; c < 2; c++)
        for (size_t k = 0; k < cs[c]->n; k++) {
            x0 = fmin(x0, cs[c]->pts[k].gamma);
            x1 = fmax(x1, cs[c]->pts[k].gamma);
            y0 = fmin(y0, cs[c]->pts[k].dw);
            y1 = fmax(y1, cs[c]->pts[k].dw);
        }
    if (!(x1 > x0)) { x0 = star->gamma - 0.01; x1 = star->gamma + 0.01; }
    if (!(y1 > y0)) { y0 = star->dw - 0.01; y1 = star->dw + 0.01; }
    double mx = 0.06 * (x1 - x0), my = 0.08 * (y1 - y0);
    x0 -= mx; x1 += mx; y0 -= my; y1 += 0.25 * (y1 - y0) + my;
    if (sim_plot_page_open(path, PAGE_W, PAGE_H, err, errlen) != 0) return -1;
    palette();
    plinit();
    plcol0(1);
    plenv(x0, x1, y0, y1, 0, 0);
    char title[128];
    snprintf(title, sizeof title, "#gf = %g#uo#d, #gDL = %g: bifurcations of the upper symmetric branch", star->phi_deg,
             star->dl);
    pllab("#gG", "#gDW", title);
    double rx = 0.007 * (x1 - x0), ry = rx / (x1 - x0) * (y1 - y0) * PAGE_W / PAGE_H;
    plwidth(2.0);
    for (int c = 0; c < 2; c++) {
        PLFLT x[4096], y[4096];
        int m = 0;
        for (size_t k = 0; k < cs[c]->n && m < 4096; k++, m++) {
            x[m] = cs[c]->pts[k].gamma;
            y[m] = cs[c]->pts[k].dw;
        }
        plcol0(3 + c);
        if (m > 1) plline(m, x, y);
        for (int k = 0; k < m; k++) marker(c == 0 ? 1 : 0, x[k], y[k], rx, ry);
    }
    plcol0(1);
    PLFLT vx[2] = {star->gamma, star->gamma}, vy[2] = {y0, y1};
    pllsty(2);
    plline(2, vx, vy);
    pllsty(1);
    sim_plot_polygon(star->gamma, star->dw, 1.8 * rx, 1.8 * ry, 5, M_PI / 2);
    char t[128];
    legend_line(0, x0, x1, y0, y1, 3, 1, 1, "saddle-node (fold in #gDW, even mode)");
    legend_line(1, x0, x1, y0, y1, 4, 0, 1, "pitchfork (odd mode)");
    snprintf(t, sizeof t, "dashed: #gG* = %.4f, both critical (#gDW = %.4f)", star->gamma, star->dw);
    legend_line(2, x0, x1, y0, y1, 1, -1, 2, t);
    legend_line(3, x0, x1, y0, y1, 1, -1, 1, "left of #gG*: pitchfork first (asymmetric); right: saddle-node first");
    if (!sim_plot_page_close(path)) {
        snprintf(err, errlen, "PLplot wrote nothing to %s (is plplot-driver-cairo installed?)", path);
        return -1;
    }
    return 0;
}
