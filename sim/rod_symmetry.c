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

void rod_mode_mirror(const rod *r, const double *v, double *out)
{
    static const double sign[3] = {-1.0, -1.0, 1.0};
    int n = r->n, nf = rod_nfree(r);
    for (int k = 0; k < nf; k++) {
        int gk = k + ROD_FREE_BEGIN, i = gk / 4, c = gk % 4;
        if (c == 3) out[k] = -v[4 * (n - 2 - i) + 3 - ROD_FREE_BEGIN];
        else out[k] = sign[c] * v[4 * (n - 1 - i) + c - ROD_FREE_BEGIN];
    }
}

void rod_mode_project(const rod *r, int sign, double *v, double *scratch)
{
    int nf = rod_nfree(r);
    rod_mode_mirror(r, v, scratch);
    double s = sign > 0 ? 1.0 : -1.0;
    for (int k = 0; k < nf; k++) v[k] = 0.5 * (v[k] + s * scratch[k]);
}

void rod_state_symmetrize(rod *r)
{
    int n = r->n;
    const double *a = rod_x(r, 1), *b = rod_x(r, n - 2);
    double cx = 0.5 * (a[0] + b[0]), cy = 0.5 * (a[1] + b[1]);
    for (int i = 2; i <= (n - 1) / 2; i++) {
        double *p = rod_x(r, i), *q = rod_x(r, n - 1 - i);
        if (p == q) {
            p[0] = cx;
            p[1] = cy;
            continue;
        }
        double m0 = 0.5 * (p[0] + 2.0 * cx - q[0]), m1 = 0.5 * (p[1] + 2.0 * cy - q[1]), m2 = 0.5 * (p[2] + q[2]);
        p[0] = m0; p[1] = m1; p[2] = m2;
        q[0] = 2.0 * cx - m0; q[1] = 2.0 * cy - m1; q[2] = m2;
    }
    /* Twist: symmetrise the material normals themselves (frames may differ from mirror images
     * by a rotation about the tangent), then read each angle back against its own frame, on the
     * 2 pi sheet nearest the old angle. */
    rod_frames_update(r);
    for (int e = 1; e <= n - 3; e++) {
        int m = n - 2 - e;
        if (m < e) break;
        double m1e[3], m2e[3], m1m[3], m2m[3];
        rod_material_frame(r, e, m1e, m2e);
        rod_material_frame(r, m, m1m, m2m);
        double u[3] = {0.5 * (m1e[0] - m1m[0]), 0.5 * (m1e[1] - m1m[1]), 0.5 * (m1e[2] + m1m[2])};
        for (int pass = 0; pass < 2; pass++) {
            int k = pass == 0 ? e : m;
            double w[3] = {u[0], u[1], u[2]};
            if (pass == 1) { w[0] = -u[0]; w[1] = -u[1]; }
            double c1 = w[0] * r->d1[k][0] + w[1] * r->d1[k][1] + w[2] * r->d1[k][2];
            double c2 = w[0] * r->d2[k][0] + w[1] * r->d2[k][1] + w[2] * r->d2[k][2];
            double th = atan2(c2, c1), old = r->q[4 * k + 3];
            th += 2.0 * M_PI * round((old - th) / (2.0 * M_PI));
            r->q[4 * k + 3] = th;
        }
    }
}
