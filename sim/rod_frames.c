/* rod_frames.c: reference frames by parallel transport in time, the reference twist, and the
 * material frame.
 *
 * Each edge's reference frame is carried from the tangent it was last updated at to the current
 * tangent by the minimal rotation (parallel transport in time, Bergou 2010), so it never twists
 * about the tangent by itself. The reference twist m_ref at interior node i is the signed angle,
 * about t_i, from the space-parallel transport of d1_{i-1} onto edge i to d1_i; it is tracked
 * continuously (the 2 pi branch closest to the previous value), so a ribbon may twist by more
 * than pi between two clamps. */
#include "rod.h"
#include "vec3.h"

#include <math.h>

/* Rotates v by the minimal rotation taking unit a onto unit b:
 * R = I + [k]x + [k]x^2 / (1 + c), k = a x b, c = a . b. For c -> -1 (a reversal within one
 * update) the transport is undefined; such a jump never happens in a converged step, and we
 * leave v unchanged rather than divide by zero. */
static void transport(const double a[3], const double b[3], const double v[3], double out[3])
{
    double k[3], kv[3], kkv[3];
    double c = v3_dot(a, b);
    v3_cross(a, b, k);
    if (1.0 + c < 1e-12) {
        v3_copy(v, out);
        return;
    }
    v3_cross(k, v, kv);
    v3_cross(k, kv, kkv);
    for (int j = 0; j < 3; j++) out[j] = v[j] + kv[j] + kkv[j] / (1.0 + c);
}

static void edge_tangent(const rod *r, int i, double t[3])
{
    double e[3];
    v3_sub(rod_x(r, i + 1), rod_x(r, i), e);
    v3_scale(e, 1.0 / v3_norm(e), t);
}

void rod_frames_update(rod *r)
{
    int n = r->n;
    for (int i = 0; i < n - 1; i++) {
        double t[3], d1[3];
        edge_tangent(r, i, t);
        transport(r->tref[i], t, r->d1[i], d1);
        /* Re-orthonormalise against round-off drift. */
        v3_axpy(d1, -v3_dot(d1, t), t, d1);
        v3_scale(d1, 1.0 / v3_norm(d1), r->d1[i]);
        v3_cross(t, r->d1[i], r->d2[i]);
        v3_copy(t, r->tref[i]);
    }
    for (int i = 1; i < n - 1; i++) {
        double p[3], c[3];
        transport(r->tref[i - 1], r->tref[i], r->d1[i - 1], p);
        v3_cross(p, r->d1[i], c);
        double ang = atan2(v3_dot(c, r->tref[i]), v3_dot(p, r->d1[i]));
        double prev = r->mref[i];
        double k = round((prev - ang) / (2.0 * M_PI));
        r->mref[i] = ang + 2.0 * M_PI * k;
    }
}

void rod_material_frame(const rod *r, int i, double m1[3], double m2[3])
{
    double th = rod_theta(r, i), c = cos(th), s = sin(th);
    for (int j = 0; j < 3; j++) {
        m1[j] = c * r->d1[i][j] + s * r->d2[i][j];
        m2[j] = -s * r->d1[i][j] + c * r->d2[i][j];
    }
}
