/*
 * plot_marker.h (private to the plot module): markers drawn as outlined polygons in data units,
 * scaled by the caller so they stay round on the page whatever the axis ranges (the sweep's
 * regime map; glyph markers are plot_series_points').
 */
#ifndef RIBBON_PLOT_MARKER_H
#define RIBBON_PLOT_MARKER_H

/* An outlined regular polygon of n_sides (3..64) around (x, y), rotated by rot (radians), with
 * radius rx in x units and ry in y units (a circle for many sides). Colour and width are the
 * caller's. */
void plot_marker_polygon(double x, double y, double rx, double ry, int n_sides, double rot);

/* A diagonal cross of half-widths rx, ry around (x, y). */
void plot_marker_cross(double x, double y, double rx, double ry);

#endif
