/*
 * plot_marker.c: outlined polygon and cross markers on the current PLplot stream (see
 * plot_marker.h). Moved here from ribbon-sim's own page helpers, so its figures draw with the
 * plot module's stack.
 */
#include "plot_marker.h"

#include <math.h>
#include <plplot.h>

void plot_marker_polygon(double x, double y, double rx, double ry, int n_sides, double rot)
{
    PLFLT px[65], py[65];
    if (n_sides < 3 || n_sides > 64)
        return;
    for (int k = 0; k <= n_sides; k++) {
        double t = rot + 2.0 * M_PI * k / n_sides;
        px[k] = x + rx * cos(t);
        py[k] = y + ry * sin(t);
    }
    plline(n_sides + 1, px, py);
}

void plot_marker_cross(double x, double y, double rx, double ry)
{
    PLFLT a[2] = {x - rx, x + rx}, b[2] = {y - ry, y + ry}, c[2] = {y + ry, y - ry};
    plline(2, a, b);
    plline(2, a, c);
}
