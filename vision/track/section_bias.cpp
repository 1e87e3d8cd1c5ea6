// section_bias.cpp: the tracer's centroids moved back onto the centreline where the ribbon's
// cross-section is oblique to its curve in a bend.
//
// Why: a cross-section projects to a segment, c(s) + u v(s) for u in [-1, 1] (v its half-vector in
// the image, thickness and blur aside). Where v is normal to the curve, the band the segments sweep
// is symmetric about the centreline and its centroid is the centreline. Where v has a component
// h_t along the tangent (the face turned, the width direction sloping in the image), the segments
// of the neighbouring arc cross each profile line too, and in a bend of curvature kappa they reach
// further toward the centre of curvature than away from it: near c(s0), with the curve
// c0 + s t + kappa s^2 / 2 n (n toward the centre) and v = h_t t + h_n n, the segments cross the
// normal line at kappa s^2 / 2 - s h_n / h_t for |s| <= |h_t|, a band from
// kappa h_t^2 / 2 - h_n (or the parabola's vertex, -h_n^2 / (2 kappa h_t^2), when
// h_n <= kappa h_t^2) to h_n + kappa h_t^2 / 2: its centre lies kappa h_t^2 / 4 (h_n = 0) to
// kappa h_t^2 / 2 (h_n large) inside the centreline. On the simulator family's Delta L 0.7 upper
// states (sheared 75-83 mm) the apex's width direction projects along the tangent (4.8 px), the
// apex's radius is 13.7 px, and the rendered band's darkest line lies 0.5 px inside the truth's
// apex (0.43 px by the formula): Delta Z 0.7 px low on every such frame.
//
// v is not seen directly, but the profile's extent is: its half-width above the thinnest (the
// edge-on thickness and blur) is |h_n| = |v x t|. Over a short window of arc v changes little
// while t turns, so the window's half-widths give M = v v^T by linear least squares,
// h_n^2 = n^T M n for the three entries of M; then h_t^2 = t^T M t. Each sample in a bend is moved
// out by the band's centre offset. Nothing is moved where the window's tangent barely turns (M is
// not determined, and there is no bend), where the fit does not explain the widths, or where the
// bend is tighter than the section (a fold: the silhouette model's, bend_model.cpp).
//
// What it does, measured (simulator family, full run, 192 frames with the narrow loop the tracer
// measures since): Delta Z 0.302 -> 0.244 px RMS (48 frames better by more than 0.1 px^2, 9 worse,
// all at Delta L 0.3-0.7), A 0.0137 -> 0.0148 rad RMS; the Delta L 0.7 trial's sheared upper states
// 75-379 0.74 -> 0.51 px RMS. Only part of
// the apex's 0.5 px goes (state 75: 0.72 -> 0.52 px): right at the apex v lies along the tangent,
// which the widths cannot show, so M there comes from the flanks. Where the width stays along the
// depth axis (analytic arches sheared hard, built as test_vision_track_accuracy builds its shapes) the widths show no v and
// nothing moves. Cost: 0.1 ms a frame (1280 x 720, one core).
#include "tracker_impl.hpp"

#include <algorithm>

namespace vis {

namespace {

// Half-window of arc for the fit of M, px: short enough for v to be nearly constant, long enough
// for the tangent to turn in a bend of a few widths.
const double WINDOW_PX = 12.0;
// The tangent and curvature from samples this far apart along the arc, px.
const double TANGENT_PX = 3.0;
// Least turning of the tangent over the window (radians) for M to be determined.
const double MIN_TURN = 0.35;
// The fit must explain the half-widths within this RMS, px.
const double MAX_FIT_RMS = 0.6;
// The bend must be gentler than the section: kappa |v| at most this (beyond, a fold).
const double MAX_KAPPA_V = 0.6;
// Moves larger than this are not made, px.
const double MAX_MOVE_PX = 1.5;
// The moves are averaged over this half-window of arc, px.
const double SMOOTH_PX = 4.0;
// Nothing is moved within this fraction of the traced arc (its first and last valid samples) from
// either end. There the section turns from
// edge-on at the jaw to the face within a few widths (v's length changes threefold over a window:
// the constant-v model does not hold), and the end tangents, which carry A, come from there. On the
// simulator family, moving them too took A from 0.0138 to 0.0152 rad RMS and made the symmetric
// snap's worst frame at 120 fps 0.004 rad worse, over the regime threshold.
const double END_FRACTION = 0.2;

}  // namespace

void correct_section_bias(std::vector<TraceSample> &smp, SectionScratch &ws)
{
    std::vector<size_t> &idx = ws.idx;
    idx.clear();
    for (size_t i = 0; i < smp.size(); i++)
        if (smp[i].valid)
            idx.push_back(i);
    const size_t n = idx.size();
    if (n < 16)
        return;
    // The edge-on extent (thickness and blur): the thinnest tenth of the half-widths.
    std::vector<double> &hw = ws.hw;
    hw.resize(n);
    for (size_t k = 0; k < n; k++)
        hw[k] = 0.5 * smp[idx[k]].width;
    std::vector<double> &tmp = ws.tmp;
    tmp.assign(hw.begin(), hw.end());
    std::nth_element(tmp.begin(), tmp.begin() + (long)(n / 10), tmp.end());
    const double tau = tmp[n / 10];
    // Tangent angle (unwrapped) and position along the arc of every valid sample.
    std::vector<double> &th = ws.th, &s = ws.s;
    th.resize(n);
    s.resize(n);
    for (size_t k = 0; k < n; k++)
        s[k] = smp[idx[k]].s;
    size_t a = 0, b = 0;
    for (size_t k = 0; k < n; k++) {
        while (a + 1 < k && s[k] - s[a + 1] >= TANGENT_PX)
            a++;
        while (b + 1 < n && s[b] - s[k] < TANGENT_PX)
            b++;
        const Pt d = smp[idx[b]].p - smp[idx[a]].p;
        double t = std::atan2(d.y, d.x);
        if (k > 0) {
            while (t - th[k - 1] > M_PI)
                t -= 2 * M_PI;
            while (t - th[k - 1] < -M_PI)
                t += 2 * M_PI;
        }
        th[k] = t;
    }
    // Each sample's unit normal n = (-t_y, t_x), and its half-width above tau (|v . n| to be).
    std::vector<Pt> &nrm = ws.nrm;
    nrm.resize(n);
    for (size_t k = 0; k < n; k++) {
        nrm[k] = Pt(-std::sin(th[k]), std::cos(th[k]));
        hw[k] = std::max(0.0, hw[k] - tau);
    }
    std::vector<double> &shift = ws.shift;  // the move toward +n, px
    shift.assign(n, 0.0);
    auto in_end_zone = [&](size_t k) {
        const double span = s[n - 1] - s[0];
        return s[k] - s[0] < END_FRACTION * span || s[n - 1] - s[k] < END_FRACTION * span;
    };
    size_t lo = 0, hi = 0, ca = 0, cb = 0;
    for (size_t k = 0; k < n; k++) {
        while (lo < k && s[k] - s[lo] > WINDOW_PX)
            lo++;
        while (hi + 1 < n && s[hi + 1] - s[k] <= WINDOW_PX)
            hi++;
        if (hi - lo < 8 || std::fabs(th[hi] - th[lo]) < MIN_TURN)
            continue;
        if (in_end_zone(k))
            continue;
        // Curvature from the tangent's turning over +-TANGENT_PX.
        while (ca < k && s[k] - s[ca] > TANGENT_PX)
            ca++;
        while (cb + 1 < n && s[cb + 1] - s[k] <= TANGENT_PX)
            cb++;
        if (!(s[cb] > s[ca]))
            continue;
        const double kappa = (th[cb] - th[ca]) / (s[cb] - s[ca]);  // signed, per px
        // M = [[A, B], [B, C]] from the normal n = (-t_y, t_x) and the half-widths above tau:
        // h_n^2 = (v . n)^2 = A n_x^2 + 2 B n_x n_y + C n_y^2.
        double S[3][3] = {{0}}, r[3] = {0};
        for (size_t j = lo; j <= hi; j++) {
            const double nx = nrm[j].x, ny = nrm[j].y;
            const double f[3] = {nx * nx, 2 * nx * ny, ny * ny};
            const double hn = hw[j];
            for (int p = 0; p < 3; p++) {
                for (int q = 0; q < 3; q++)
                    S[p][q] += f[p] * f[q];
                r[p] += f[p] * hn * hn;
            }
        }
        // Solve by Cramer's rule (3 x 3); a determinant near 0 leaves the sample where it is.
        auto det3 = [](const double m[3][3]) {
            return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                   m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        };
        const double D = det3(S);
        const double scale = S[0][0] * S[1][1] * S[2][2];
        if (!(std::fabs(D) > 1e-6 * scale) || !(scale > 0))
            continue;
        double x[3];
        for (int c = 0; c < 3; c++) {
            double m[3][3];
            for (int p = 0; p < 3; p++)
                for (int q = 0; q < 3; q++)
                    m[p][q] = q == c ? r[p] : S[p][q];
            x[c] = det3(m) / D;
        }
        // The nearest rank-one M = v v^T: the larger eigenvector of [[A, B], [B, C]].
        const double A = x[0], B = x[1], C = x[2];
        const double tr = 0.5 * (A + C), df = std::sqrt(0.25 * (A - C) * (A - C) + B * B);
        const double lam = tr + df;
        if (!(lam > 0))
            continue;
        const double phi = 0.5 * std::atan2(2 * B, A - C);
        const Pt v = std::sqrt(lam) * Pt(std::cos(phi), std::sin(phi));
        // How well |v . n| explains the half-widths over the window.
        double ss = 0;
        for (size_t j = lo; j <= hi; j++) {
            const double e = std::fabs(v.dot(nrm[j])) - hw[j];
            ss += e * e;
        }
        if (!(std::sqrt(ss / (double)(hi - lo + 1)) <= MAX_FIT_RMS))
            continue;
        const double vl = cv::norm(v);
        const double ak = std::fabs(kappa);
        if (!(ak * vl <= MAX_KAPPA_V) || !(ak > 0))
            continue;
        const Pt t(nrm[k].y, -nrm[k].x);
        const double ht = std::fabs(v.dot(t)), hn = std::fabs(v.dot(nrm[k]));
        const double q = ak * ht * ht;
        const double top = hn + 0.5 * q;
        const double bottom = q > 0 && hn <= q ? -hn * hn / (2 * q) : 0.5 * q - hn;
        const double inward = 0.5 * (top + bottom);
        if (!(inward > 0) || !std::isfinite(inward))
            continue;
        const double move = std::min(MAX_MOVE_PX, inward);
        shift[k] = kappa > 0 ? move : -move;  // signed: toward +n = (-t_y, t_x) when positive
    }
    // The moves smoothed along the arc (the widths are read to a quarter pixel each: unsmoothed,
    // the moves would roughen the curve and its tangents), then made along the normal.
    size_t ma = 0, mb = 0;
    for (size_t k = 0; k < n; k++) {
        while (ma < k && s[k] - s[ma] > SMOOTH_PX)
            ma++;
        while (mb + 1 < n && s[mb + 1] - s[k] <= SMOOTH_PX)
            mb++;
        if (in_end_zone(k))
            continue;  // not even by the smoothing
        double sum = 0;
        for (size_t j = ma; j <= mb; j++)
            sum += shift[j];
        smp[idx[k]].p -= (sum / (double)(mb - ma + 1)) * nrm[k];  // shift[] holds no position
    }
}

}  // namespace vis
