/*
 * plot_series.c: gap-aware data series for the plot module (see plot_series.h).
 *
 * A measured curve has holes (frames where the tracker lost the ribbon are NaN); a line must
 * break there, not bridge the hole, and a NaN must never reach PLplot (it would draw to a
 * garbage coordinate). So every series is cut into runs of finite points before plline.
 * PLplot takes PLINT (int) counts: runs are at most INT_MAX long, far beyond any real series.
 */
#include "plot_series.h"

#include "plot_session.h"

#include <limits.h>
#include <math.h>
#include <plplot.h>

_Static_assert(sizeof(PLFLT) == sizeof(double), "PLplot is built with double PLFLT (Debian: PL_DOUBLE)");

void plot_range_init(plot_range *r)
{
    r->lo = INFINITY;
    r->hi = -INFINITY;
    r->n = 0;
}

void plot_range_add1(plot_range *r, double v)
{
    if (!isfinite(v))
        return;
    if (v < r->lo)
        r->lo = v;
    if (v > r->hi)
        r->hi = v;
    r->n++;
}

void plot_range_add(plot_range *r, const double *v, size_t n)
{
    if (!v)
        return;
    for (size_t i = 0; i < n; i++)
        plot_range_add1(r, v[i]);
}

void plot_range_axis(const plot_range *r, double pad_frac, double def_lo, double def_hi, double *lo,
                     double *hi)
{
    if (r->n == 0) {
        *lo = def_lo;
        *hi = def_hi;
        return;
    }
    double span = r->hi - r->lo;
    if (!(span > 0.0)) {
        double w = fmax(0.05 * fabs(r->lo), 0.05);
        *lo = r->lo - w;
        *hi = r->hi + w;
        return;
    }
    *lo = r->lo - pad_frac * span;
    *hi = r->hi + pad_frac * span;
}

plot_status plot_series_check(const char *field, const double *v, size_t n, char *why, size_t why_len)
{
    if (n == 0)
        return PLOT_OK;
    if (!v)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "%s is NULL but has %zu points", field, n);
    if (n > (size_t)INT_MAX)
        return plot_fail(PLOT_ERR_ARG, why, why_len, "%s has %zu points, more than PLplot can take", field, n);
    for (size_t i = 0; i < n; i++)
        if (isinf(v[i]))
            return plot_fail(PLOT_ERR_ARG, why, why_len, "%s[%zu] is infinite (use NaN for a gap)", field, i);
    return PLOT_OK;
}

plot_status plot_value_check(const char *field, double v, char *why, size_t why_len)
{
    if (isinf(v))
        return plot_fail(PLOT_ERR_ARG, why, why_len, "%s is infinite (use NaN for none)", field);
    return PLOT_OK;
}

static int finite_pair(const double *x, const double *y, size_t i)
{
    return isfinite(x[i]) && isfinite(y[i]);
}

void plot_series_line(const double *x, const double *y, size_t n)
{
    if (!x || !y)
        return;
    size_t i = 0;
    while (i < n) {
        while (i < n && !finite_pair(x, y, i))
            i++;
        size_t start = i;
        while (i < n && finite_pair(x, y, i))
            i++;
        size_t len = i - start;
        if (len >= 2)
            plline((PLINT)len, &x[start], &y[start]);
        else if (len == 1)
            plstring(1, &x[start], &y[start], "·");
    }
}

void plot_series_points(const double *x, const double *y, size_t n, const char *glyph, size_t stride)
{
    if (!x || !y)
        return;
    if (stride == 0)
        stride = 1;
    for (size_t i = 0; i < n; i += stride)
        if (finite_pair(x, y, i))
            plstring(1, &x[i], &y[i], glyph);
}

size_t plot_series_finite(const double *x, const double *y, size_t n)
{
    size_t k = 0;
    if (x && y)
        for (size_t i = 0; i < n; i++)
            k += (size_t)finite_pair(x, y, i);
    return k;
}
