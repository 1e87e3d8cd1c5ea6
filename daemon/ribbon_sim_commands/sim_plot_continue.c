/* sim_plot_continue.c: the continuation diagram with PLplot (see sim_plot_continue.h).
 *
 * Two panels side by side: Delta Z against Delta W, and A against Delta W. Each branch is drawn
 * as runs of consecutive points of equal stability (a segment is stable when both its ends are),
 * stable in black, unstable in grey, switched branches dashed. Events are outlined circles
 * (pitchfork) and squares (saddle-node), other events diamonds, sized in page units so they stay
 * round whatever the axis ranges. PLplot keeps its state in a stream: the page (sim_plot_page.h)
 * is one stream of this call's own, ended before it returns, so nothing outlives the call. */
#include "sim_plot_continue.h"
#include "sim_plot_page.h"

#include <math.h>
#include <plplot.h>
#include <stdio.h>
#include <string.h>

#define PAGE_W 1400
#define PAGE_H 600

enum { COL_BG = 0, COL_FG = 1, COL_STABLE = 2, COL_UNSTABLE = 3, COL_EVENT = 4 };

typedef struct range {
    double x0, x1, y0, y1;
} range;

static double value(const rod_cont_point *p, int panel) { return panel == 0 ? p->dz : p->a; }

static range data_range(const rod_analysis *a, int panel)
{
    range r = {INFINITY, -INFINITY, INFINITY, -INFINITY};
    for (int b = 0; b < a->nbranches; b++)
        for (size_t i = 0; i < a->branches[b].n; i++) {
            const rod_cont_point *p = &a->branches[b].points[i];
            r.x0 = fmin(r.x0, p->dw);
            r.x1 = fmax(r.x1, p->dw);
            r.y0 = fmin(r.y0, value(p, panel));
            r.y1 = fmax(r.y1, value(p, panel));
        }
    if (!(r.x1 > r.x0)) { r.x0 -= 0.5; r.x1 += 0.5; }
    if (!(r.y1 > r.y0)) { r.y0 -= 0.5; r.y1 += 0.5; }
    double mx = 0.05 * (r.x1 - r.x0), my = 0.08 * (r.y1 - r.y0);
    r.x0 -= mx; r.x1 += mx; r.y0 -= my; r.y1 += my;
    return r;
}

static void draw_panel(const rod_analysis *a, int panel, const char *title)
{
    range r = data_range(a, panel);
    plcol0(COL_FG);
    plwidth(1.0);
    plenv(r.x0, r.x1, r.y0, r.y1, 0, 0);
    pllab("#gDW", panel == 0 ? "#gDZ" : "A (rad)", panel == 0 ? (title ? title : "midpoint height") : "asymmetry A");
    plwidth(2.0);
    for (int b = 0; b < a->nbranches; b++) {
        const rod_branch *br = &a->branches[b];
        pllsty(br->parent_event >= 0 ? 2 : 1);
        for (size_t i = 0; i + 1 < br->n; i++) {
            const rod_cont_point *p = &br->points[i], *q = &br->points[i + 1];
            plcol0(p->stable && q->stable ? COL_STABLE : COL_UNSTABLE);
            PLFLT x[2] = {p->dw, q->dw}, y[2] = {value(p, panel), value(q, panel)};
            plline(2, x, y);
        }
    }
    pllsty(1);
    /* Marker size: 1.1% of the x range; y radius scaled by the panel's aspect (each panel is
     * PAGE_W / 2 wide, PAGE_H high, the box taking similar fractions of both). */
    double rx = 0.011 * (r.x1 - r.x0), ry = rx / (r.x1 - r.x0) * (r.y1 - r.y0) * (PAGE_W / 2.0) / PAGE_H;
    plcol0(COL_EVENT);
    for (int e = 0; e < a->nevents; e++) {
        const rod_event *ev = &a->events[e];
        double x = ev->at.dw, y = value(&ev->at, panel);
        if (ev->kind == ROD_EVENT_PITCHFORK)
            sim_plot_polygon(x, y, rx, ry, 48, 0.0);
        else if (ev->kind == ROD_EVENT_SADDLE_NODE)
            sim_plot_polygon(x, y, rx * M_SQRT2, ry * M_SQRT2, 4, M_PI / 4);
        else
            sim_plot_polygon(x, y, rx, ry, 4, 0.0);
    }
    plwidth(1.0);
}

int sim_plot_continue(const char *path, const rod_analysis *a, const char *title, char *err, size_t errlen)
{
    if (sim_plot_page_open(path, PAGE_W, PAGE_H, err, errlen) != 0)
        return -1;
    plscol0(COL_BG, 255, 255, 255);
    plscol0(COL_FG, 0, 0, 0);
    plscol0(COL_STABLE, 0, 0, 0);
    plscol0(COL_UNSTABLE, 160, 160, 160);
    plscol0(COL_EVENT, 0, 0, 0);
    plssub(2, 1);
    plinit();
    for (int panel = 0; panel < 2; panel++) draw_panel(a, panel, title);
    if (!sim_plot_page_close(path)) {
        snprintf(err, errlen, "PLplot wrote nothing to %s (is the pngcairo driver, plplot-driver-cairo, installed?)",
                 path);
        return -1;
    }
    return 0;
}
