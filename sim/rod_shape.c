/* rod_shape.c: the projected centreline resampled by arc length, and its derivative along a
 * direction of the free DOFs (rod_shape.h). */
#include "rod_shape.h"

#include <math.h>
#include <string.h>

int rod_shape_resample(const double *xz, int n, int k, double *out)
{
    if (n < 2 || k < 1 || k > ROD_SHAPE_MAX_POINTS) return -1;
    double total = 0.0;
    for (int i = 0; i < n; i++)
        if (!isfinite(xz[2 * i]) || !isfinite(xz[2 * i + 1])) return -1;
    for (int i = 1; i < n; i++) total += hypot(xz[2 * i] - xz[2 * i - 2], xz[2 * i + 1] - xz[2 * i - 1]);
    if (!(total > 0.0)) return -1;
    /* Walk the segments once: the targets increase. */
    int seg = 1;
    double s0 = 0.0, len = hypot(xz[2] - xz[0], xz[3] - xz[1]);
    for (int p = 0; p < k; p++) {
        double target = total * (p + 0.5) / k;
        while (seg < n - 1 && s0 + len < target) {
            s0 += len;
            seg++;
            len = hypot(xz[2 * seg] - xz[2 * seg - 2], xz[2 * seg + 1] - xz[2 * seg - 1]);
        }
        double t = len > 0.0 ? (target - s0) / len : 0.0;
        t = fmin(1.0, fmax(0.0, t));
        out[2 * p] = xz[2 * seg - 2] + t * (xz[2 * seg] - xz[2 * seg - 2]);
        out[2 * p + 1] = xz[2 * seg - 1] + t * (xz[2 * seg + 1] - xz[2 * seg - 1]);
    }
    return 0;
}

int rod_shape_sample(const rod *r, int k, double *out)
{
    /* Nodes 1 .. N-2 with the left clamp point (node 1) as origin, over l. */
    enum { MAXN = 4096 };
    int n = r->n - 2;
    if (n < 2 || n > MAXN) return -1;
    double xz[2 * MAXN];
    const double *x1 = rod_x(r, 1);
    double l = r->length;
    for (int i = 0; i < n; i++) {
        const double *x = rod_x(r, i + 1);
        xz[2 * i] = (x[0] - x1[0]) / l;
        xz[2 * i + 1] = (x[2] - x1[2]) / l;
    }
    return rod_shape_resample(xz, n, k, out);
}

int rod_shape_directional(rod *r, int k, const double *dir, double *save, double *out)
{
    int nf = rod_nfree(r);
    double big = 0.0;
    for (int i = 0; i < nf; i++) big = fmax(big, fabs(dir[i]));
    if (!isfinite(big)) return -1;
    if (big == 0.0) {
        memset(out, 0, sizeof(double) * 2 * (size_t)k);
        return 0;
    }
    double t = 1e-7 * r->length / big;
    double plus[2 * ROD_SHAPE_MAX_POINTS], minus[2 * ROD_SHAPE_MAX_POINTS];
    double *q = r->q + ROD_FREE_BEGIN;
    memcpy(save, q, sizeof(double) * (size_t)nf);
    for (int i = 0; i < nf; i++) q[i] = save[i] + t * dir[i];
    int rc = rod_shape_sample(r, k, plus);
    for (int i = 0; i < nf; i++) q[i] = save[i] - t * dir[i];
    if (rc == 0) rc = rod_shape_sample(r, k, minus);
    memcpy(q, save, sizeof(double) * (size_t)nf);
    if (rc != 0) return -1;
    for (int i = 0; i < 2 * k; i++) out[i] = (plus[i] - minus[i]) / (2.0 * t);
    return 0;
}
