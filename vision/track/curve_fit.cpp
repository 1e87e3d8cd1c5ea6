// curve_fit.cpp: from traced centreline samples to a smooth curve and the two numbers.
//
// The smooth fit is local: a cubic in the arc parameter, fitted by weighted least squares (tricube
// weights) to the samples within +-hw of each evaluation point, with the window shifted inward at
// the ends so that the end tangents come from a one-sided cubic (a Savitzky-Golay-like edge rule).
// A global polynomial or spline would smear the sharp creases of a folded ribbon into the tangent at
// the midpoint and ends; a local fit only sees the arc near where it is evaluated. The clamp points
// themselves are the first and last samples.
// Measures: the smooth curve and its speed are evaluated at n_out points; the arc length is the
// integral of the speed; the
// arc-length midpoint is found on it and re-evaluated by the local fit for position and tangent.
// Tangent angles are taken relative to the clamp chord (A is invariant under rotation, and this keeps
// angles away from the +-pi cut even for overhangs or a rolled camera).
#include "tracker_impl.hpp"

#include <algorithm>

namespace vis {

namespace {

// Degrees of the local fits. Fifth degree around interior points: with a symmetric window the
// derivative's bias then starts at the 6th Taylor term, which matters for the fast-turning
// asymmetric mode at the midpoint. Fourth degree at the ends, on a one-sided window of 11% of the
// length (end_window): the end tangents carry most of A's noise, and a longer window brings it down
// (the spread of A over 40 renderings of one state, 640 x 480: 0.0119 rad with the cubic on 6%,
// 0.0082 now); the fourth degree keeps the bias of the longer window off the strongly asymmetric
// shapes (a cubic on 9%: 0.015 rad RMS on test_vision_track_accuracy's asymmetric arch, 0.0058
// now). Creases at Gamma >= 0.13 stay outside the window.
const int DEG_MID = 5;
// Third degree for the curve samples (display, arc length) and the residual: the speed integral and
// a median residual do not need the 5th degree, and they are most of the evaluations.
const int DEG_CURVE = 3;
const int DEG_END = 4;

// The weighted normal equations of a degree M - 1 fit over samples [lo, hi) around s0 (tricube
// weights out to `far`), added into A, bx, bz. A template so that the loops over j and k unroll.
template <int M>
inline void accumulate(const FitInput &in, size_t lo, size_t hi, double s0, double hw, double far,
                       double (&A)[6][6], double (&bx)[6], double (&bz)[6])
{
    for (size_t i = lo; i < hi; i++) {
        const double u = (in.s[i] - s0) / hw;
        const double r = std::fabs(in.s[i] - s0) / far;
        const double w3 = 1 - r * r * r;
        const double w = w3 * w3 * w3;
        const double pw[6] = {1, u, u * u, u * u * u, u * u * u * u, u * u * u * u * u};
        const double px = in.xz[i].x, pz = in.xz[i].y;
        for (int j = 0; j < M; j++) {
            const double wj = w * pw[j];
            for (int k = 0; k < M; k++)
                A[j][k] += wj * pw[k];
            bx[j] += wj * px;
            bz[j] += wj * pz;
        }
    }
}

// Value and first derivative of x(s), z(s) at s0 from a local weighted cubic.
bool local_eval(const FitInput &in, double s0, double hw, int max_deg, Pt &pos, Pt &der)
{
    const double L = in.s.back();
    double a = s0 - hw, b = s0 + hw;
    if (a < 0) {
        b = std::min(L, b - a);
        a = 0;
    }
    if (b > L) {
        a = std::max(0.0, a - (b - L));
        b = L;
    }
    const size_t lo = (size_t)(std::lower_bound(in.s.begin(), in.s.end(), a) - in.s.begin());
    const size_t hi = (size_t)(std::upper_bound(in.s.begin(), in.s.end(), b) - in.s.begin());
    if (hi <= lo + 1)
        return false;
    // The farthest sample from s0: s is increasing, so one of the two ends of the window.
    double far = std::max(std::fabs(in.s[lo] - s0), std::fabs(in.s[hi - 1] - s0));
    far = far * 1.1 + 1e-12;
    const size_t cnt = hi - lo;
    int deg = std::min(max_deg, (int)cnt / 3);
    deg = std::max(1, std::min(deg, 5));
    const int m = deg + 1;
    double A[6][6] = {{0}}, bx[6] = {0}, bz[6] = {0};
    switch (m) {  // the sums unrolled for the size at hand (same operations, same order)
    case 2: accumulate<2>(in, lo, hi, s0, hw, far, A, bx, bz); break;
    case 3: accumulate<3>(in, lo, hi, s0, hw, far, A, bx, bz); break;
    case 4: accumulate<4>(in, lo, hi, s0, hw, far, A, bx, bz); break;
    case 5: accumulate<5>(in, lo, hi, s0, hw, far, A, bx, bz); break;
    default: accumulate<6>(in, lo, hi, s0, hw, far, A, bx, bz); break;
    }
    // Solve the small normal equations by Gaussian elimination with partial pivoting.
    for (int c = 0; c < m; c++) {
        int piv = c;
        for (int r = c + 1; r < m; r++)
            if (std::fabs(A[r][c]) > std::fabs(A[piv][c]))
                piv = r;
        if (!(std::fabs(A[piv][c]) > 1e-14))
            return false;
        if (piv != c) {
            for (int k = 0; k < m; k++)
                std::swap(A[c][k], A[piv][k]);
            std::swap(bx[c], bx[piv]);
            std::swap(bz[c], bz[piv]);
        }
        for (int r = c + 1; r < m; r++) {
            const double f = A[r][c] / A[c][c];
            for (int k = c; k < m; k++)
                A[r][k] -= f * A[c][k];
            bx[r] -= f * bx[c];
            bz[r] -= f * bz[c];
        }
    }
    double cx[6] = {0}, cz[6] = {0};
    for (int r = m - 1; r >= 0; r--) {
        double sx = bx[r], sz = bz[r];
        for (int k = r + 1; k < m; k++) {
            sx -= A[r][k] * cx[k];
            sz -= A[r][k] * cz[k];
        }
        cx[r] = sx / A[r][r];
        cz[r] = sz / A[r][r];
    }
    pos = Pt(cx[0], cz[0]);
    der = Pt(cx[1] / hw, cz[1] / hw);
    return std::isfinite(pos.x) && std::isfinite(pos.y) && std::isfinite(der.x) &&
           std::isfinite(der.y);
}

}  // namespace

bool curve_fit(const FitInput &in, double hw, double he, int n_out, FitResult &out, FitScratch &ws)
{
    const size_t n = in.xz.size();
    if (n < 4 || in.s.size() != n || n_out < 8 || !(hw > 0))
        return false;
    const double L = in.s.back();
    out.curve.resize((size_t)n_out);
    std::vector<double> &cum = ws.cum, &speed = ws.speed;
    cum.assign((size_t)n_out, 0.0);
    speed.resize((size_t)n_out);
    const double h = L / (n_out - 1);
    Pt der;
    for (int j = 0; j < n_out; j++) {
        if (!local_eval(in, h * j, hw, DEG_CURVE, out.curve[(size_t)j], der))
            return false;
        speed[(size_t)j] = cv::norm(der);
        // Arc length by the trapezoid rule on the fitted speed |r'(s)|: the parameter is nearly arc
        // length, so the speed is nearly constant and the rule nearly exact, unlike chords, which
        // cut every bend short by (kappa h)^2 / 24.
        if (j > 0)
            cum[(size_t)j] = cum[(size_t)j - 1] + 0.5 * h * (speed[(size_t)j - 1] + speed[(size_t)j]);
    }
    out.length = cum.back();
    const double half = 0.5 * out.length;
    size_t k = 0;
    while (k + 2 < (size_t)n_out && cum[k + 1] < half)
        k++;
    const double w = (half - cum[k]) / std::max(1e-300, cum[k + 1] - cum[k]);
    const double s_mid = h * (k + w);
    Pt pm, dm, p0, d0, p1, d1;
    if (!local_eval(in, s_mid, hw, DEG_MID, pm, dm) || !local_eval(in, 0.0, 0.5 * he, DEG_END, p0, d0) ||
        !local_eval(in, L, 0.5 * he, DEG_END, p1, d1))
        return false;
    const Pt c = in.xz.back() - in.xz.front();
    const double cl = cv::norm(c);
    if (!(cl > 0))
        return false;
    auto ang = [&](Pt d) { return std::atan2(c.x * d.y - c.y * d.x, c.x * d.x + c.y * d.y); };
    out.a = 2 * ang(dm) - ang(d0) - ang(d1);
    out.mid = pm;
    const Pt r = pm - in.xz.front();
    out.height = (c.x * r.y - c.y * r.x) / cl;
    // Residual: the median distance of the samples from the fit (robust: a sharp crease, which the
    // smooth fit rounds off, touches only a few samples and must not lower the quality).
    std::vector<double> &res = ws.res;
    res.clear();
    const size_t stride = std::max<size_t>(1, n / 64);  // 64 samples are plenty for a median
    res.reserve(n / stride + 1);
    for (size_t i = 0; i < n; i += stride) {
        Pt p, d;
        if (local_eval(in, in.s[i], hw, DEG_CURVE, p, d))
            res.push_back(cv::norm(p - in.xz[i]));
    }
    if (!res.empty()) {
        std::nth_element(res.begin(), res.begin() + (long)(res.size() / 2), res.end());
        out.residual = res[res.size() / 2];
    } else {
        out.residual = 0.0;
    }
    return true;
}

}  // namespace vis
