/*
 * plot_series.h (private to the plot module): data series with gaps: input checks, axis ranges
 * and drawing on the current PLplot stream. NaN is a gap everywhere here.
 */
#ifndef RIBBON_PLOT_SERIES_H
#define RIBBON_PLOT_SERIES_H

#include "plot.h"

#include <stddef.h>

/* Finite values seen so far. */
typedef struct plot_range {
    double lo, hi;
    size_t n;
} plot_range;

void plot_range_init(plot_range *r);
void plot_range_add(plot_range *r, const double *v, size_t n); /* v may be NULL when n is 0 */
void plot_range_add1(plot_range *r, double v);
/* The axis range to draw: the data span padded by pad_frac of it on both sides; a single value
 * (or equal values) is widened by 5% of its size (at least 0.05); no data gives [def_lo, def_hi]. */
void plot_range_axis(const plot_range *r, double pad_frac, double def_lo, double def_hi, double *lo,
                     double *hi);

/* PLOT_ERR_ARG naming field[i] when v holds +-Inf, or when v is NULL with n > 0. NaN is fine. */
plot_status plot_series_check(const char *field, const double *v, size_t n, char *why, size_t why_len);
/* A single value: finite or NaN. */
plot_status plot_value_check(const char *field, double v, char *why, size_t why_len);

/* Joins consecutive points where both x and y are finite (plline per run); an isolated finite
 * point is drawn as a small dot so that it is not lost. Colour, width and style are the caller's. */
void plot_series_line(const double *x, const double *y, size_t n);
/* glyph (UTF-8) at every stride-th point where x and y are finite. */
void plot_series_points(const double *x, const double *y, size_t n, const char *glyph, size_t stride);
/* Counts the points where x and y are both finite. */
size_t plot_series_finite(const double *x, const double *y, size_t n);

#endif
