// shape.cpp: validation of a vis_shape and its ground truth (Delta Z, A, projected counterparts).
//
// The simulator hands over a dense polyline, so the truth is computed on it directly: arc length by
// chords, the arc-length midpoint by linear interpolation, tangents by second-order differences
// (central inside, one-sided three-point at the ends, non-uniform spacing allowed). The tangent
// angle is measured in the vertical plane that contains the clamp chord's horizontal direction:
// theta = atan2(t . z, t . e) with e the unit horizontal chord, so an overhanging arch (tangent beyond
// vertical) keeps a continuous angle. The *_cam values repeat the computation on the curve projected
// orthographically onto the x-z plane (y dropped), which is what a distant side camera sees.
#include "vis_internal.hpp"

#include "shape_truth.hpp"

#include <vector>

namespace vis {

bool shape_valid(const vis_shape *s, vis_error *err)
{
    if (!s || !s->pos || !s->normal) {
        fail(err, VIS_ERR_ARG, "shape: NULL shape or arrays");
        return false;
    }
    if (s->n < 3 || s->n > 1000000) {
        fail(err, VIS_ERR_ARG, "shape: n = %zu points, need 3..1000000", s->n);
        return false;
    }
    if (!finite(s->width_m) || s->width_m < 0 || !finite(s->thickness_m) || s->thickness_m <= 0) {
        fail(err, VIS_ERR_ARG, "shape: width_m must be >= 0 and thickness_m > 0");
        return false;
    }
    for (size_t i = 0; i < 3 * s->n; i++) {
        if (!finite(s->pos[i]) || !finite(s->normal[i])) {
            fail(err, VIS_ERR_ARG, "shape: point %zu has a non-finite coordinate or normal", i / 3);
            return false;
        }
    }
    for (size_t i = 0; i + 1 < s->n; i++) {
        const double *a = s->pos + 3 * i, *b = a + 3;
        double d = std::hypot(std::hypot(b[0] - a[0], b[1] - a[1]), b[2] - a[2]);
        if (!(d > 0)) {
            fail(err, VIS_ERR_ARG, "shape: points %zu and %zu coincide", i, i + 1);
            return false;
        }
    }
    return true;
}

// Measures of a polyline given as (h, z) pairs with h the coordinate along the clamp chord's
// horizontal direction. pts: n points, dims = 2 (h, z).
CurveTruth curve_truth(const std::vector<double> &h, const std::vector<double> &z,
                       const std::vector<double> &seg)
{
    const size_t n = h.size();
    std::vector<double> s(n, 0.0);
    for (size_t i = 1; i < n; i++)
        s[i] = s[i - 1] + seg[i - 1];
    CurveTruth r{};
    r.length = s[n - 1];
    // Tangent angle at node i from a quadratic through three neighbours (non-uniform spacing).
    auto deriv = [&](const std::vector<double> &f, size_t i) {
        size_t a, b, c;
        if (i == 0) {
            a = 0; b = 1; c = 2;
        } else if (i == n - 1) {
            a = n - 3; b = n - 2; c = n - 1;
        } else {
            a = i - 1; b = i; c = i + 1;
        }
        const double x = s[i], xa = s[a], xb = s[b], xc = s[c];
        // Derivative of the Lagrange interpolant at x.
        return f[a] * ((x - xb) + (x - xc)) / ((xa - xb) * (xa - xc)) +
               f[b] * ((x - xa) + (x - xc)) / ((xb - xa) * (xb - xc)) +
               f[c] * ((x - xa) + (x - xb)) / ((xc - xa) * (xc - xb));
    };
    auto theta = [&](size_t i) { return std::atan2(deriv(z, i), deriv(h, i)); };
    const double half = 0.5 * r.length;
    size_t k = 0;
    while (k + 2 < n && s[k + 1] < half)
        k++;
    const double w = (half - s[k]) / (s[k + 1] - s[k]);
    const double hm = h[k] + w * (h[k + 1] - h[k]);
    const double zm = z[k] + w * (z[k + 1] - z[k]);
    double t0 = theta(k), t1 = theta(k + 1);
    if (t1 - t0 > M_PI) t1 -= 2 * M_PI;
    if (t0 - t1 > M_PI) t1 += 2 * M_PI;
    const double tm = t0 + w * (t1 - t0);
    // Height above the clamp line (perpendicular, sign of +z).
    const double dh = h[n - 1] - h[0], dzc = z[n - 1] - z[0];
    const double cl = std::hypot(dh, dzc);
    r.height = ((hm - h[0]) * (-dzc) + (zm - z[0]) * dh) / cl;
    r.a = 2.0 * tm - theta(0) - theta(n - 1);
    r.mid_index = k;
    r.mid_weight = w;
    return r;
}

}  // namespace vis

extern "C" vis_status vis_shape_truth(const vis_shape *shape, vis_truth *out, vis_error *err)
{
    if (!out)
        return vis::fail(err, VIS_ERR_ARG, "vis_shape_truth: NULL output");
    if (!vis::shape_valid(shape, err))
        return VIS_ERR_ARG;
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        vis::ShapeTruth t = vis::shape_truth(*shape);
        *out = t.truth;
        vis::ok(err);
        return VIS_OK;
    })
}

namespace vis {
ShapeTruth shape_truth(const vis_shape &sh)
{
    const size_t n = sh.n;
    const double *p = sh.pos;
    // Horizontal chord direction e (3D) for the paper's A; x for the projection.
    double ex = p[3 * (n - 1)] - p[0], ey = p[3 * (n - 1) + 1] - p[1];
    double el = std::hypot(ex, ey);
    if (!(el > 0)) {
        ex = 1;
        ey = 0;
        el = 1;
    }
    ex /= el;
    ey /= el;
    std::vector<double> h3(n), h2(n), z(n), seg3(n - 1), seg2(n - 1);
    for (size_t i = 0; i < n; i++) {
        h3[i] = p[3 * i] * ex + p[3 * i + 1] * ey;
        h2[i] = p[3 * i];
        z[i] = p[3 * i + 2];
    }
    for (size_t i = 0; i + 1 < n; i++) {
        const double dx = p[3 * i + 3] - p[3 * i], dy = p[3 * i + 4] - p[3 * i + 1],
                     dz = p[3 * i + 5] - p[3 * i + 2];
        seg3[i] = std::sqrt(dx * dx + dy * dy + dz * dz);
        seg2[i] = std::hypot(dx, dz);
    }
    CurveTruth c3 = curve_truth(h3, z, seg3);
    CurveTruth c2 = curve_truth(h2, z, seg2);
    ShapeTruth r{};
    r.truth.length_m = c3.length;
    r.truth.dz = c3.height / c3.length;
    r.truth.a = c3.a;
    r.truth.dz_cam = c2.height / c3.length;
    r.truth.a_cam = c2.a;
    r.truth.shear_m = p[3 * (n - 1) + 1] - p[1];
    const size_t k = c3.mid_index;
    const double w = c3.mid_weight;
    for (int j = 0; j < 3; j++)
        r.mid3[j] = p[3 * k + j] + w * (p[3 * k + 3 + j] - p[3 * k + j]);
    return r;
}
}  // namespace vis
