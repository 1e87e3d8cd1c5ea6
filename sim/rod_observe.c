/* rod_observe.c: Delta Z, A and their camera (projected) counterparts; see rod_observe.h. */
#include "rod_observe.h"

#include <math.h>

void rod_observe(const rod *r, double *k1, rod_obs *o)
{
    int n = r->n;
    double l = r->length;
    /* Delta Z at the arc-length midpoint. */
    double zm;
    if (r->mid_node >= 0) zm = rod_x(r, r->mid_node)[2];
    else zm = (1.0 - r->mid_w) * rod_x(r, r->mid_edge)[2] + r->mid_w * rod_x(r, r->mid_edge + 1)[2];
    o->dz = zm / l;

    /* Paper's A from the toward-normal curvature. */
    rod_kappa1(r, k1);
    double a = 0.0;
    for (int i = 1; i < n - 1; i++) {
        double psi = 2.0 * atan(0.5 * k1[i]);
        if (i == r->mid_node) continue;
        a += (r->s_node[i] < 0.5) ? psi : -psi;
    }
    o->a = a;

    /* Projected curve: unwrapped tangent angle of each edge in the x-z plane, edge 0 being the
     * left clamp (angle 0); k1 is reused as storage for the angles. theta(1/2) is interpolated
     * linearly between the centres of the two free edges around the projected arc-length
     * midpoint. */
    double *th = k1, total = 0.0;
    th[0] = 0.0;
    for (int j = 1; j < n - 1; j++) {
        const double *xa = rod_x(r, j), *xb = rod_x(r, j + 1);
        double dx = xb[0] - xa[0], dzp = xb[2] - xa[2];
        double t = atan2(dzp, dx);
        th[j] = t + 2.0 * M_PI * round((th[j - 1] - t) / (2.0 * M_PI));
        if (j < n - 2) total += hypot(dx, dzp);
    }
    double half = 0.5 * total, acc = 0.0, prev_c = 0.0, th_mid = th[1], z_mid = 0.0;
    for (int j = 1; j < n - 2; j++) {
        const double *xa = rod_x(r, j), *xb = rod_x(r, j + 1);
        double dx = xb[0] - xa[0], dzp = xb[2] - xa[2], len = hypot(dx, dzp);
        double c = acc + 0.5 * len;
        if (half >= acc && half <= acc + len) z_mid = xa[2] + (len > 0 ? (half - acc) / len : 0.0) * dzp;
        if (j > 1 && prev_c <= half && half <= c)
            th_mid = th[j - 1] + (half - prev_c) / (c - prev_c) * (th[j] - th[j - 1]);
        prev_c = c;
        acc += len;
    }
    o->a_cam = 2.0 * th_mid - th[0] - th[n - 2];
    o->dz_cam = z_mid / l;
}
