/* rod_richardson.c: observed orders and Richardson extrapolation (see rod_richardson.h). */
#include "rod_richardson.h"

#include <math.h>

double rod_observed_order(double s0, double s1, double s2, double ratio)
{
    double d1 = s1 - s0, d2 = s2 - s1;
    if (!(ratio > 1.0) || !isfinite(d1) || !isfinite(d2)) return NAN;
    if (!(d1 * d2 > 0.0) || !(fabs(d2) < fabs(d1))) return NAN;
    return log(d1 / d2) / log(ratio);
}

double rod_richardson(double s1, double s2, double ratio, double p)
{
    double den = pow(ratio, p) - 1.0;
    if (!(den > 0.0) || !isfinite(den) || !isfinite(s1) || !isfinite(s2)) return NAN;
    return s2 + (s2 - s1) / den;
}
