/* rod_symmetry.c: parity of modes and asymmetry of states under the clamp-swapping C2 rotation
 * (see rod_symmetry.h). */
#include "rod_symmetry.h"

#include <math.h>

double rod_mode_parity(const rod *r, const double *v)
{
    static const double sign[3] = {-1.0, -1.0, 1.0};
    int n = r->n;
    double vv = 0.0, vsv = 0.0;
    for (int i = 2; i <= n - 3; i++) {
        int m = n - 1 - i;
        for (int c = 0; c < 3; c++) {
            double a = v[4 * i + c - ROD_FREE_BEGIN], b = v[4 * m + c - ROD_FREE_BEGIN];
            vv += a * a;
            vsv += a * sign[c] * b;
        }
    }
    return vv > 0.0 ? vsv / vv : 0.0;
}

double rod_state_asymmetry(const rod *r)
{
    int n = r->n;
    /* Centre of the rotation: middle of the clamp points (nodes 1 and N-2), in x and y. */
    const double *a = rod_x(r, 1), *b = rod_x(r, n - 2);
    double cx = 0.5 * (a[0] + b[0]), cy = 0.5 * (a[1] + b[1]), worst = 0.0;
    for (int i = 0; i < n; i++) {
        const double *p = rod_x(r, i), *q = rod_x(r, n - 1 - i);
        double d0 = p[0] - (2.0 * cx - q[0]), d1 = p[1] - (2.0 * cy - q[1]), d2 = p[2] - q[2];
        worst = fmax(worst, sqrt(d0 * d0 + d1 * d1 + d2 * d2));
    }
    return worst / r->length;
}
