// depth_profile.cpp: the depth of the centreline along the ribbon, which the tracker needs to put
// each pixel's ray on the right plane (tracker.cpp, stage 6).
//
// A single side camera cannot see depth. By default the tracker assumes the shear profile of a
// ribbon clamped flat at both ends, y = shear (3 xi^2 - 2 xi^3) at arc fraction xi. The DER strip
// is not near that under shear: it stays near y = 0 for the first third and takes the shear in the
// middle, and with the camera 1 m away that alone moves Delta Z by 2-2.6 px and A by 0.07-0.27 rad
// (docs/vision-acquisition-and-replay-speed.md, "Depth under shear"). A caller that has a
// prediction of the shape (the trial's own simulation) gives its profile instead: depth over the
// shear against the arc fraction along the ribbon (material arc length, what a simulation has).
//
// The tracker's arc fraction is the one of the x-z projection it measures, which a depth change
// shortens (ds_xz^2 = ds^2 - dy^2 for an inextensible ribbon), so for each frame the profile is
// mapped onto the projected arc fraction with the frame's shear and the ribbon's length.
#include "tracker_impl.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace vis {

bool DepthProfile::set(const double *frac, const double *rel, size_t n, std::string &why)
{
    if (n == 0) {
        frac_.clear();
        rel_.clear();
        proj_.clear();
        return true;
    }
    if (!frac || !rel) {
        why = "depth profile: NULL arrays";
        return false;
    }
    if (n < 2 || n > MAX_POINTS) {
        why = "depth profile: need 2 to " + std::to_string(MAX_POINTS) + " points, got " + std::to_string(n);
        return false;
    }
    for (size_t i = 0; i < n; i++) {
        if (!std::isfinite(frac[i]) || !std::isfinite(rel[i])) {
            why = "depth profile: point " + std::to_string(i) + " is not finite";
            return false;
        }
        if (std::fabs(rel[i]) > MAX_REL) {
            char buf[160];
            snprintf(buf, sizeof buf, "depth profile: depth over shear %g at point %zu is beyond +-%g", rel[i], i,
                     MAX_REL);
            why = buf;
            return false;
        }
        if (i > 0 && !(frac[i] > frac[i - 1])) {
            why = "depth profile: arc fractions must increase (point " + std::to_string(i) + ")";
            return false;
        }
    }
    if (std::fabs(frac[0]) > 1e-9 || std::fabs(frac[n - 1] - 1.0) > 1e-9) {
        why = "depth profile: arc fractions must run from 0 to 1";
        return false;
    }
    std::vector<double> f(frac, frac + n), r(rel, rel + n), q(n);  // a throw leaves the old one
    frac_.swap(f);
    rel_.swap(r);
    proj_.swap(q);
    return true;
}

void DepthProfile::set_checked(const double *frac, const double *rel, size_t n)
{
    frac_.assign(frac, frac + n);
    rel_.assign(rel, rel + n);
    proj_.resize(n);
}

void DepthProfile::prepare(double length_mm, double shear_mm)
{
    if (frac_.empty())
        return;
    const size_t n = frac_.size();
    proj_[0] = 0.0;
    if (!(length_mm > 0)) {
        // Length unknown: the material arc fraction stands in for the projected one.
        std::copy(frac_.begin(), frac_.end(), proj_.begin());
        return;
    }
    for (size_t i = 1; i < n; i++) {
        const double ds = length_mm * (frac_[i] - frac_[i - 1]);
        const double dy = shear_mm * (rel_[i] - rel_[i - 1]);
        proj_[i] = proj_[i - 1] + std::sqrt(std::max(0.0, ds * ds - dy * dy));
    }
    if (!(proj_[n - 1] > 0)) {
        std::copy(frac_.begin(), frac_.end(), proj_.begin());
        return;
    }
    const double total = proj_[n - 1];
    for (size_t i = 1; i < n; i++)
        proj_[i] /= total;
}

double DepthProfile::at(double xi) const
{
    xi = std::min(1.0, std::max(0.0, xi));
    if (frac_.empty())
        return 3 * xi * xi - 2 * xi * xi * xi;
    const auto it = std::upper_bound(proj_.begin(), proj_.end(), xi);
    if (it == proj_.end())
        return rel_.back();
    const size_t j = (size_t)(it - proj_.begin());
    if (j == 0)
        return rel_.front();
    const double span = proj_[j] - proj_[j - 1];
    const double w = span > 0 ? (xi - proj_[j - 1]) / span : 1.0;
    return rel_[j - 1] + w * (rel_[j] - rel_[j - 1]);
}

}  // namespace vis

namespace vis {

bool DepthLibrary::set(const vis_depth_library *lib, std::string &why)
{
    if (!lib || lib->n_shapes == 0) {
        shear_.clear();
        key_xz_.clear();
        dz_.clear();
        a_.clear();
        frac_.clear();
        rel_.clear();
        n_points_ = 0;
        return true;
    }
    const size_t ns = lib->n_shapes, np = lib->n_points;
    if (!lib->shear_mm || !lib->dz || !lib->a || !lib->frac || !lib->depth_rel) {
        why = "depth library: NULL arrays";
        return false;
    }
    if (ns > MAX_SHAPES || np < 2 || np > MAX_POINTS || ns * np > MAX_VALUES) {
        char buf[200];
        snprintf(buf, sizeof buf,
                 "depth library: %zu shapes of %zu points; need up to %zu shapes of 2 to %zu points, %zu values in all",
                 ns, np, MAX_SHAPES, MAX_POINTS, MAX_VALUES);
        why = buf;
        return false;
    }
    DepthProfile check;
    for (size_t i = 0; i < ns; i++) {
        if (!std::isfinite(lib->shear_mm[i]) || !std::isfinite(lib->dz[i]) || !std::isfinite(lib->a[i])) {
            why = "depth library: shape " + std::to_string(i) + " has a non-finite shear, Delta Z or A";
            return false;
        }
        std::string w;
        if (!check.set(lib->frac + i * np, lib->depth_rel + i * np, np, w)) {
            why = "depth library: shape " + std::to_string(i) + ": " + w;
            return false;
        }
    }
    std::vector<Pt> kx;
    if (lib->xz_mm) {
        kx.resize(ns * KEY_POINTS);
        std::vector<Pt> c(np);
        for (size_t i = 0; i < ns; i++) {
            for (size_t j = 0; j < np; j++) {
                c[j] = Pt(lib->xz_mm[2 * (i * np + j)], lib->xz_mm[2 * (i * np + j) + 1]);
                if (!std::isfinite(c[j].x) || !std::isfinite(c[j].y)) {
                    why = "depth library: shape " + std::to_string(i) + " has a non-finite projection point";
                    return false;
                }
            }
            resample_even(c, kx.data() + i * KEY_POINTS);
        }
    }
    std::vector<double> s(lib->shear_mm, lib->shear_mm + ns), z(lib->dz, lib->dz + ns), a(lib->a, lib->a + ns),
        f(lib->frac, lib->frac + ns * np), r(lib->depth_rel, lib->depth_rel + ns * np);
    key_xz_.swap(kx);
    shear_.swap(s);
    dz_.swap(z);
    a_.swap(a);
    frac_.swap(f);
    rel_.swap(r);
    n_points_ = np;
    return true;
}

// Index of the smallest cost(i) over i < n (the first of equal ones), -1 when n is 0.
template <class Cost> static long argmin(size_t n, Cost cost)
{
    long best = -1;
    double dbest = 0;
    for (size_t i = 0; i < n; i++) {
        const double d = cost(i);
        if (best < 0 || d < dbest) {
            best = (long)i;
            dbest = d;
        }
    }
    return best;
}

long DepthLibrary::nearest(double shear_mm, double dz, double a) const
{
    return argmin(shear_.size(), [&](size_t i) {
        const double ds = (shear_[i] - shear_mm) / KEY_SHEAR_MM, dd = (dz_[i] - dz) / KEY_DZ,
                     da = (a_[i] - a) / KEY_A_RAD;
        return ds * ds + dd * dd + da * da;
    });
}

void DepthLibrary::resample_even(const std::vector<Pt> &c, Pt *out)
{
    double len = 0;
    for (size_t j = 1; j < c.size(); j++)
        len += cv::norm(c[j] - c[j - 1]);
    size_t j = 0;
    double at = 0;  // arc length at c[j]
    for (int k = 0; k < KEY_POINTS; k++) {
        const double target = len * k / (KEY_POINTS - 1);
        while (j + 2 < c.size() && at + cv::norm(c[j + 1] - c[j]) < target) {
            at += cv::norm(c[j + 1] - c[j]);
            j++;
        }
        const double seg = cv::norm(c[j + 1] - c[j]);
        const double w = seg > 0 ? std::min(1.0, std::max(0.0, (target - at) / seg)) : 0.0;
        out[k] = c[j] + w * (c[j + 1] - c[j]);
    }
}

long DepthLibrary::nearest_curve(double shear_mm, const std::vector<Pt> &curve) const
{
    if (key_xz_.empty() || curve.size() < 2)
        return -1;
    probe_.resize(KEY_POINTS);
    resample_even(curve, probe_.data());
    return argmin(shear_.size(), [&](size_t i) {
        const Pt *q = key_xz_.data() + i * KEY_POINTS;
        double ss = 0;
        for (int k = 0; k < KEY_POINTS; k++) {
            const Pt e = q[k] - probe_[k];
            ss += e.dot(e);
        }
        const double ds = (shear_[i] - shear_mm) / KEY_SHEAR_MM;
        return ds * ds + ss / KEY_POINTS / (KEY_XZ_MM * KEY_XZ_MM);
    });
}

bool DepthLibrary::use(long i, DepthProfile &into) const
{
    if (i < 0 || (size_t)i >= shear_.size())
        return false;
    into.set_checked(frac_.data() + (size_t)i * n_points_, rel_.data() + (size_t)i * n_points_, n_points_);
    return true;
}

}  // namespace vis
