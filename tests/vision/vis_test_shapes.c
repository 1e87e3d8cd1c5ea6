/* vis_test_shapes.c: analytic ribbon shapes for the vision tests (see the header). */
#include "vis_test_shapes.h"

#include <math.h>
#include <string.h>

#define DENSE 8192

double vt_depth_cubic(double xi) { return 3 * xi * xi - 2 * xi * xi * xi; }

void vt_from_dense(vt_shape *s, size_t n, const double *xd, const double *zd, size_t m, double dw)
{
    vt_from_dense_depth(s, n, xd, zd, m, dw, vt_depth_cubic);
}

/* The unit tangent at point i of s (central difference, one-sided at the ends). */
static void unit_tangent(const vt_shape *s, size_t i, double t[3])
{
    const size_t n = s->n, a = i ? i - 1 : 0, b = i + 1 < n ? i + 1 : n - 1;
    double tl = 0;
    for (int k = 0; k < 3; k++) {
        t[k] = s->pos[3 * b + k] - s->pos[3 * a + k];
        tl += t[k] * t[k];
    }
    tl = sqrt(tl);
    for (int k = 0; k < 3; k++)
        t[k] /= tl;
}

void vt_from_dense_depth(vt_shape *s, size_t n, const double *xd, const double *zd, size_t m, double dw,
                         double (*depth)(double xi))
{
    /* Resample the dense planar curve (xd, zd) at n points equally spaced in arc length. */
    double cum[DENSE];
    cum[0] = 0;
    for (size_t i = 1; i < m; i++)
        cum[i] = cum[i - 1] + hypot(xd[i] - xd[i - 1], zd[i] - zd[i - 1]);
    const double L = cum[m - 1];
    size_t j = 0;
    for (size_t i = 0; i < n; i++) {
        const double sv = L * (double)i / (double)(n - 1);
        while (j + 2 < m && cum[j + 1] < sv)
            j++;
        const double w = (sv - cum[j]) / (cum[j + 1] - cum[j]);
        const double xi = (double)i / (double)(n - 1);
        s->pos[3 * i] = xd[j] + w * (xd[j + 1] - xd[j]);
        s->pos[3 * i + 1] = dw * depth(xi);
        s->pos[3 * i + 2] = zd[j] + w * (zd[j + 1] - zd[j]);
    }
    s->n = n;
    for (size_t i = 0; i < n; i++) {
        double t[3], d[3] = {0, 1, 0}, nn[3];
        unit_tangent(s, i, t);
        const double dt = d[1] * t[1];
        double dl = 0;
        for (int k = 0; k < 3; k++) {
            d[k] -= dt * t[k];
            dl += d[k] * d[k];
        }
        dl = sqrt(dl);
        for (int k = 0; k < 3; k++)
            d[k] /= dl;
        nn[0] = t[1] * d[2] - t[2] * d[1];
        nn[1] = t[2] * d[0] - t[0] * d[2];
        nn[2] = t[0] * d[1] - t[1] * d[0];
        memcpy(s->normal + 3 * i, nn, sizeof nn);
    }
    s->view.n = n;
    s->view.pos = s->pos;
    s->view.normal = s->normal;
    s->view.width_m = 0.005;
    s->view.thickness_m = 0.002;
}

static double arch_fill(double *xd, double *zd, double X, double R, double phi)
{
    double L = 0;
    for (size_t i = 0; i < DENSE; i++) {
        const double xi = (double)i / (DENSE - 1), c = cos(2 * M_PI * xi);
        xd[i] = X * xi;
        zd[i] = R * (cos(phi) * (1 - c) / 2 + sin(phi) * sin(2 * M_PI * xi) * (1 - c) / 2);
        if (i)
            L += hypot(xd[i] - xd[i - 1], zd[i] - zd[i - 1]);
    }
    return L;
}

void vt_arch(vt_shape *s, size_t n, double l, double X, double phi, double dw)
{
    vt_arch_depth(s, n, l, X, phi, dw, vt_depth_cubic);
}

void vt_arch_depth(vt_shape *s, size_t n, double l, double X, double phi, double dw, double (*depth)(double xi))
{
    static double xd[DENSE], zd[DENSE];
    /* Inextensible ribbon between fixed clamps: find the amplitude R that gives arc length l
     * (bisection, capped; the length grows with R). */
    double lo = 0, hi = 2 * l;
    for (int it = 0; it < 60; it++) {
        const double R = 0.5 * (lo + hi);
        if (arch_fill(xd, zd, X, R, phi) > l)
            hi = R;
        else
            lo = R;
    }
    arch_fill(xd, zd, X, 0.5 * (lo + hi), phi);
    vt_from_dense_depth(s, n, xd, zd, DENSE, dw, depth);
}

void vt_overhang(vt_shape *s, size_t n, double l, double T, double dw)
{
    static double xd[DENSE], zd[DENSE];
    xd[0] = zd[0] = 0;
    const double ds = l / (DENSE - 1);
    for (size_t i = 1; i < DENSE; i++) {
        const double sm = (i - 0.5) * ds; /* midpoint rule for the integral of the tangent */
        const double th = T * sin(2 * M_PI * sm / l);
        xd[i] = xd[i - 1] + ds * cos(th);
        zd[i] = zd[i - 1] + ds * sin(th);
    }
    vt_from_dense(s, n, xd, zd, DENSE, dw);
}

void vt_twist(vt_shape *s, double (*psi)(double xi, void *ctx), void *ctx)
{
    const size_t n = s->n;
    for (size_t k = 0; k < n; k++) {
        double t[3];
        unit_tangent(s, k, t);
        double *nn = s->normal + 3 * k;
        const double tn[3] = {t[1] * nn[2] - t[2] * nn[1], t[2] * nn[0] - t[0] * nn[2], t[0] * nn[1] - t[1] * nn[0]};
        const double ps = psi((double)k / (double)(n - 1), ctx), cp = cos(ps), sp = sin(ps);
        for (int c = 0; c < 3; c++)
            nn[c] = cp * nn[c] + sp * tn[c];
    }
}

vis_render_params vt_render_params(const vt_shape *s, int w, int h)
{
    vis_render_params p = vis_render_params_default();
    p.camera.width_px = w;
    p.camera.height_px = h;
    double x0 = 1e9, x1 = -1e9, z0 = 1e9, z1 = -1e9;
    for (size_t i = 0; i < s->n; i++) {
        x0 = fmin(x0, s->pos[3 * i]);
        x1 = fmax(x1, s->pos[3 * i]);
        z0 = fmin(z0, s->pos[3 * i + 2]);
        z1 = fmax(z1, s->pos[3 * i + 2]);
    }
    vis_camera_fit(&p.camera, x0 - 0.02, x1 + 0.02, z0 - 0.01, z1 + 0.01, 0.9, NULL);
    return p;
}

vis_calib vt_calib(const vis_render_params *p, const vt_shape *s)
{
    vis_calib c = vis_calib_default();
    vis_calib_from_camera(&c, &p->camera, s->pos, s->pos + 3 * (s->n - 1), NULL);
    return c;
}
