/* rod_richardson.c: observed orders and Richardson extrapolation (see rod_richardson.h). */
#include "rod_richardson.h"

#include <math.h>
#include <stdio.h>

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

/* (r0^p - 1) / (1 - r1^-p): the ratio of successive differences that order p gives. */
static double diff_ratio(double p, double r0, double r1)
{
    return (pow(r0, p) - 1.0) / (1.0 - pow(r1, -p));
}

double rod_observed_order_ratios(double s0, double s1, double s2, double r0, double r1)
{
    double d1 = s1 - s0, d2 = s2 - s1;
    if (!(r0 > 1.0) || !(r1 > 1.0) || !isfinite(r0) || !isfinite(r1) || !isfinite(d1) || !isfinite(d2)) return NAN;
    if (!(d1 * d2 > 0.0) || !(fabs(d2) < fabs(d1))) return NAN;
    if (fabs(r0 - r1) <= 1e-12 * r0) return log(d1 / d2) / log(r0);
    double want = d1 / d2, lo = 1e-3, hi = 30.0;
    if (!(want >= diff_ratio(lo, r0, r1)) || !(want <= diff_ratio(hi, r0, r1))) return NAN;
    for (int it = 0; it < 60; it++) {
        double mid = 0.5 * (lo + hi);
        if (diff_ratio(mid, r0, r1) < want) lo = mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

void rod_ladder_estimate(const double *h, const double *s, int n, double *err, rod_ladder_verdict *v)
{
    rod_ladder_verdict tmp;
    if (!v) v = &tmp;
    v->order = NAN;
    v->asymptotic = 0;
    v->extrapolated = NAN;
    v->safety = ROD_LADDER_SAFETY;
    v->note[0] = '\0';
    for (int k = 0; k < n; k++) err[k] = -1.0;
    if (n < 2) {
        snprintf(v->note, sizeof v->note, "one rung: no error to estimate");
        return;
    }
    for (int k = 0; k < n; k++)
        if (!isfinite(s[k]) || !isfinite(h[k]) || !(h[k] > 0.0) || (k > 0 && !(h[k] < h[k - 1]))) {
            snprintf(v->note, sizeof v->note, "rung %d: no finite value or resolution not refined", k + 1);
            return;
        }
    double s_fin = s[n - 1], d = s_fin - s[n - 2], r = h[n - 2] / h[n - 1];
    if (d == 0.0) {
        snprintf(v->note, sizeof v->note, "the two finest rungs agree exactly: no error to estimate");
        return;
    }
    if (n >= 3) v->order = rod_observed_order_ratios(s[n - 3], s[n - 2], s_fin, h[n - 3] / h[n - 2], r);
    v->asymptotic = isfinite(v->order) && v->order >= ROD_LADDER_ORDER_LO && v->order <= ROD_LADDER_ORDER_HI;
    if (v->asymptotic) {
        v->safety = 1.0;
    } else if (n < 3) {
        snprintf(v->note, sizeof v->note, "not in the asymptotic range: two rungs observe no order (safety factor %g)",
                 ROD_LADDER_SAFETY);
    } else if (!isfinite(v->order)) {
        snprintf(v->note, sizeof v->note,
                 "not in the asymptotic range: the differences %+.3g then %+.3g do not shrink with one sign "
                 "(safety factor %g)",
                 s[n - 2] - s[n - 3], d, ROD_LADDER_SAFETY);
    } else {
        snprintf(v->note, sizeof v->note,
                 "not in the asymptotic range: observed order %.2f outside [%.1f, %.1f] (safety factor %g)", v->order,
                 ROD_LADDER_ORDER_LO, ROD_LADDER_ORDER_HI, ROD_LADDER_SAFETY);
    }
    double tail = fabs(d) / (pow(r, ROD_LADDER_ORDER_FORMAL) - 1.0); /* |s* - s_fin| at the formal order */
    v->extrapolated = s_fin + copysign(tail, d);
    double scale = fabs(v->extrapolated);
    if (!(scale > 0.0) || !isfinite(scale)) return;
    for (int k = 0; k < n; k++) err[k] = (fabs(s[k] - s_fin) + v->safety * tail) / scale;
}
