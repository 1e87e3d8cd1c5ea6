// path_walk.cpp: a first path along the ribbon by walking it from one clamp point to the other.
//
// Why a second acquisition beside the geodesic (path_init.cpp): the cheapest path between the
// clamps cuts across wherever the ribbon comes back near itself. A loop that doubles back past a
// clamp, or whose two branches cross in the side view, costs less to skip than to follow, so the
// geodesic takes the shortcut and the fit is a confident wrong curve. A walker follows the ridge
// the way the ribbon goes: it steps `step` px ahead along its current direction (turned by the
// last step's turning, so a tight loop is followed), reads the ridge signal across that direction
// within +-half_band px, and moves to the nearest ridge centre there (never the strongest one: at
// a crossing the other branch is as strong, and the nearest keeps the walk going straight through).
// The direction it leaves a clamp by comes from the arc with the most signal among those leaving
// within 40 deg of the chord (the clamp holds the ribbon along the jaw axis) and turning by up to
// 180 deg but ending within 90 deg of the chord (its first millimetres can turn fast). A short gap (noise, a thin occluder) is bridged along the predicted direction; a gap
// longer than `max_gap` px, a walk longer than `max_len` px, or leaving the image ends the walk
// without a path. The walk succeeds when it comes within reach of the other clamp point.
// Cost: O(length x band), a small fraction of the geodesic search.
#include "tracker_impl.hpp"

#include <algorithm>

namespace vis {

namespace {

inline float sample(const cv::Mat &sig, double x, double y)
{
    if (!(x >= 0 && y >= 0 && x < sig.cols - 1 && y < sig.rows - 1))
        return 0.f;
    const int x0 = (int)x, y0 = (int)y;
    const float fx = (float)(x - x0), fy = (float)(y - y0);
    const float *r0 = sig.ptr<float>(y0), *r1 = sig.ptr<float>(y0 + 1);
    return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

Pt rot(Pt v, double a)
{
    const double c = std::cos(a), s = std::sin(a);
    return Pt(c * v.x - s * v.y, s * v.x + c * v.y);
}

}  // namespace

bool path_walk(const cv::Mat &sig, Pt a, Pt b, const WalkParams &wp, std::vector<Pt> &path)
{
    path.clear();
    const Pt chord = b - a;
    const double cl = cv::norm(chord);
    if (!(cl > 2 * wp.step) || !(wp.threshold > 0))
        return false;
    const Pt e = chord * (1.0 / cl);
    // Leaving direction. The clamp holds the ribbon's end tangent along the jaw axis, which the
    // image shows along the clamp chord (within the camera's tilt and perspective: LEAVE_DEV), but
    // the ribbon may curve away from it within a few pixels. So the candidates are arcs that leave
    // within LEAVE_DEV of the chord and turn by up to LEAVE_TURN over their length (3 .. 3 + reach
    // px); the one with the largest mean signal gives the first direction and turning rate. Straight
    // rays over a wider fan were tried first: at zero shear (the ribbon edge-on and faint) they left
    // along the bright sliver the ridge filter leaves on the jaw's face, at 84 deg from the chord,
    // and the walk came back along it or wandered off (the simulator family's folded ribbons at
    // Delta L 0.6-0.7 and zero shear). An arc may not end heading more than LEAVE_END from the
    // chord: one that turns back toward the jaw follows clutter or a jaw edge (with clutter and a
    // 40% light gradient, an arc that ended at 220 deg made a confident wrong answer, A off 0.5).
    const double reach = std::max(6.0, 3.0 * wp.half_band);
    const double LEAVE_DEV = 40.0 * M_PI / 180.0, LEAVE_TURN = M_PI, LEAVE_END = 0.5 * M_PI;
    double best = -1, best_ang = 0, best_rate = 0;
    for (int k = -20; k <= 20; k++) {
        const double ang = LEAVE_DEV * k / 20.0;
        for (int j = -18; j <= 18; j++) {
            const double rate = LEAVE_TURN * j / 18.0 / (3.0 + reach);  // radians per px
            if (std::fabs(ang + rate * (3.0 + reach)) > LEAVE_END + 1e-9)
                continue;
            double acc = 0, x = a.x, y = a.y, h = ang;
            int cnt = 0;
            for (double r = 0.0; r < 3.0 + reach; r += 1.0) {
                const Pt d = rot(e, h + 0.5 * rate);
                x += d.x;
                y += d.y;
                h += rate;
                if (r + 1.0 >= 3.0) {
                    acc += sample(sig, x, y);
                    cnt++;
                }
            }
            acc /= cnt;
            if (acc > best) {
                best = acc;
                best_ang = ang;
                best_rate = rate;
            }
        }
    }
    if (best < wp.threshold)
        return false;
    Pt t = rot(e, best_ang);
    double turn = best_rate * wp.step;  // radians per step
    Pt p = a;
    path.push_back(a);
    const int K = (int)std::ceil(wp.half_band / 0.5);
    std::vector<float> prof((size_t)(2 * K + 1));
    double len = 0, gap = 0;
    const size_t max_steps = (size_t)(wp.max_len / wp.step) + 2;
    for (size_t it = 0; it < max_steps; it++) {
        const Pt tp = rot(t, turn);
        const Pt q0 = p + wp.step * tp;
        if (!(q0.x >= 1 && q0.y >= 1 && q0.x < sig.cols - 2 && q0.y < sig.rows - 2))
            return false;  // walked out of the image
        const Pt nrm(-tp.y, tp.x);
        for (int k = -K; k <= K; k++)
            prof[(size_t)(k + K)] = sample(sig, q0.x + 0.5 * k * nrm.x, q0.y + 0.5 * k * nrm.y);
        // Nearest local maximum above the threshold.
        int kp = -1;
        for (int k = 1; k < 2 * K; k++) {
            const float v = prof[(size_t)k];
            if (v >= wp.threshold && v >= prof[(size_t)k - 1] && v >= prof[(size_t)k + 1] &&
                (kp < 0 || std::abs(k - K) < std::abs(kp - K)))
                kp = k;
        }
        Pt q = q0;
        if (kp >= 0) {
            // Centroid of the part of that peak above half its height.
            const float thr = 0.5f * prof[(size_t)kp];
            int lo = kp, hi = kp;
            while (lo > 0 && prof[(size_t)lo - 1] > thr && prof[(size_t)lo - 1] <= prof[(size_t)lo] + thr)
                lo--;
            while (hi < 2 * K && prof[(size_t)hi + 1] > thr && prof[(size_t)hi + 1] <= prof[(size_t)hi] + thr)
                hi++;
            double sw = 0, so = 0;
            for (int k = lo; k <= hi; k++) {
                const double w = prof[(size_t)k] - thr;
                sw += w;
                so += w * 0.5 * (k - K);
            }
            if (sw > 0)
                q = q0 + (so / sw) * nrm;
            gap = 0;
        } else {
            gap += wp.step;
            turn *= 0.5;
            if (gap > wp.max_gap)
                return false;
        }
        const Pt d = q - p;
        const double dl = cv::norm(d);
        if (!(dl > 0.2 * wp.step))
            return false;
        const Pt tn = d * (1.0 / dl);
        // Direction and turning, smoothed over a few steps (the centroids carry sub-pixel noise).
        const double dturn = std::atan2(t.x * tn.y - t.y * tn.x, t.x * tn.x + t.y * tn.y);
        if (kp >= 0)
            turn = 0.6 * turn + 0.4 * dturn;
        t = rot(t, 0.5 * dturn + 0.5 * turn);
        p = q;
        len += dl;
        path.push_back(p);
        if (cv::norm(b - p) <= wp.arrive && len > 0.5 * cl) {
            path.push_back(b);
            return true;
        }
    }
    return false;
}

}  // namespace vis
