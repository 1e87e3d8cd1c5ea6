// clamps.cpp: automatic detection of the two clamp points (where the ribbon leaves each jaw).
//
// A clamp point is the ribbon's centre at the inner face of a clamp jaw. In a side view the jaws are
// the two thick blobs that contrast with the backdrop the way the ribbon does, joined by the thin
// ribbon; that is all this file assumes (no grey level of the jaw, no scale). Stages:
//   1. Polarity folded in (objects bright), the backdrop estimated by a grey opening with a square a
//      quarter of the frame wide on a subsampled copy (follows uneven light, removes the ribbon, the
//      jaws and small clutter), the contrast above it lightly smoothed and divided by a reference:
//      the strongest contrast nearby, at least 3/4 of the strongest anywhere (uneven light).
//   2. Jaw candidates: pixels above half the reference, opened with a disc wider than the
//      largest ribbon thickness (`ribbon_max_px`), so the ribbon vanishes and thick blobs remain.
//      Connectivity: pixels above a quarter of the reference; the pair of candidates that
//      lie in one such component (the ribbon joins them) and are farthest apart are the jaws.
//   3. Sub-pixel, in each jaw's frame (axis e toward the other jaw, n across it): the inner face is
//      the median over the jaw's rows (away from the ribbon) of the 50% crossing between the jaw's
//      and the backdrop's grey levels along e (blur is symmetric, so the crossing is the edge, and
//      pixel centres sit at integers as everywhere in the module); the ribbon's centre across e
//      comes from the tracer's own cross-section centroids a few pixels beyond the face, fitted with
//      b0 + b2 a^2 + b3 a^3 (a from the face: the clamp holds the ribbon along the jaw axis, so no
//      linear term; it curves as it leaves) and evaluated at the face, b0. Using the tracer's
//      centroids keeps the clamp points in the same convention as the traced curve.
// Perspective: the jaw is as deep as the ribbon is wide, and its silhouette's inner face is the face
// nearer the optical axis, so the found point sits about |u - u0| w / (2 D) pixels closer to the
// image centre than the point in the plane y = 0 (0.7 px at 290 px off axis for w = 5 mm, D = 1 m).
// Heights are not affected to first order (the face is vertical in the image). Everything lives in
// locals: one call, no state kept.
#include "tracker_impl.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <vector>

namespace {

using vis::Pt;

double median(std::vector<double> &v)
{
    const size_t m = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + (long)m, v.end());
    double x = v[m];
    if (v.size() % 2 == 0) {
        std::nth_element(v.begin(), v.begin() + (long)m - 1, v.end());
        x = 0.5 * (x + v[m - 1]);
    }
    return x;
}

float bilinear(const cv::Mat &m, double x, double y)
{
    x = std::min(std::max(x, 0.0), m.cols - 1.0);
    y = std::min(std::max(y, 0.0), m.rows - 1.0);
    const int x0 = std::min((int)x, m.cols - 2 < 0 ? 0 : m.cols - 2);
    const int y0 = std::min((int)y, m.rows - 2 < 0 ? 0 : m.rows - 2);
    const int x1 = std::min(x0 + 1, m.cols - 1), y1 = std::min(y0 + 1, m.rows - 1);
    const double fx = x - x0, fy = y - y0;
    const float *r0 = m.ptr<float>(y0), *r1 = m.ptr<float>(y1);
    return (float)((1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x1]));
}

struct Blob {
    int label;      // in the thick-blob label image
    int group;      // label of the connectivity component that holds it
    Pt c;           // centroid, pixels
    int area;
};

// One jaw, refined. `pix` are the blob's pixels; `e` points inward (toward the other jaw).
struct JawFit {
    Pt point;       // clamp point, pixels
    double spread;  // median absolute deviation of the per-row face positions, pixels
    double valid;   // share of the ribbon samples beyond the face with a clear ridge
};

bool fit_jaw(const cv::Mat &F, const cv::Mat &grey, bool dark, const vis_track_params &p,
             const std::vector<cv::Point> &pix, Pt c, Pt e, JawFit &out, char *why, size_t why_len)
{
    const Pt n(-e.y, e.x);
    double amax = -1e9;
    for (const cv::Point &q : pix)
        amax = std::max(amax, (Pt(q) - c).dot(e));
    double bmin = 1e9, bmax = -1e9;
    for (const cv::Point &q : pix) {
        const Pt d = Pt(q) - c;
        if (d.dot(e) >= amax - 8) {
            bmin = std::min(bmin, d.dot(n));
            bmax = std::max(bmax, d.dot(n));
        }
    }
    // Rows within `excl` of the ribbon are not used for the face; a small jaw keeps two rows a side
    // (rows where the ribbon spills over fail the level test below anyway).
    const double excl = std::max(2.5, std::min(0.5 * p.ribbon_max_px + 3.0, 0.5 * (bmax - bmin) - 4.0));
    const double band = p.ribbon_max_px + 2.0;
    double b_rib = 0.5 * (bmin + bmax), a_edge = amax + 0.5;
    std::vector<double> faces, dev;
    std::vector<Pt> guide, rs;
    std::vector<double> cum;
    std::vector<vis::TraceSample> smp;
    std::vector<float> prof, tmp;
    const double a_in0 = 12, a_in1 = 6, step = 0.25;  // level windows, px inside / outside the face
    for (int round = 0; round < 2; round++) {
        // Face: 50% crossings along e on the jaw's rows clear of the ribbon.
        faces.clear();
        for (double b = bmin + 2; b <= bmax - 2; b += 1.0) {
            if (std::fabs(b - b_rib) < excl)
                continue;
            auto at = [&](double a) {
                const Pt q = c + a * e + b * n;
                return (double)bilinear(F, q.x, q.y);
            };
            std::vector<double> in, outl;
            for (double a = a_edge - a_in0; a <= a_edge - a_in1; a += 1.0)
                in.push_back(at(a));
            for (double a = a_edge + a_in1; a <= a_edge + a_in0; a += 1.0)
                outl.push_back(at(a));
            const double J = median(in), G = median(outl);
            if (!(J - G >= p.min_contrast))
                continue;
            const double half = 0.5 * (J + G);
            double prev = at(a_edge - a_in1), cross = NAN;
            for (double a = a_edge - a_in1 + step; a <= a_edge + a_in1; a += step) {
                const double v = at(a);
                if (prev >= half && v < half) {
                    cross = a - step + step * (prev - half) / (prev - v);
                    break;
                }
                prev = v;
            }
            if (std::isfinite(cross))
                faces.push_back(cross);
        }
        if (faces.size() < 2) {
            snprintf(why, why_len, "a clamp-like blob near (%.0f, %.0f) has no clear inner face beside "
                     "the ribbon", c.x, c.y);
            return false;
        }
        a_edge = median(faces);
        dev.clear();
        for (double f : faces)
            dev.push_back(std::fabs(f - a_edge));
        out.spread = median(dev);

        // Ribbon beyond the face: cross-section centroids, then b(a) as above, evaluated at a = 0.
        const double a0 = a_edge + 4.0, a1 = a_edge + 4.0 + std::max(16.0, 3 * p.ribbon_max_px);
        guide = {c + a0 * e + b_rib * n, c + a1 * e + b_rib * n};
        vis::resample(guide, 1.0, nullptr, cum, rs);
        vis::trace_pass(grey, dark, rs, band, 0.0, p.min_contrast, p.ribbon_max_px, smp, prof, tmp);
        cv::Mat A(0, 3, CV_64F), y(0, 1, CV_64F);
        for (const auto &s : smp)
            if (s.valid) {
                const Pt d = s.p - c;
                const double a = d.dot(e) - a_edge;
                const double row[3] = {1.0, a * a, a * a * a};
                A.push_back(cv::Mat(1, 3, CV_64F, (void *)row));
                y.push_back(d.dot(n));
            }
        out.valid = smp.empty() ? 0.0 : (double)A.rows / (double)smp.size();
        if (A.rows < 8 || out.valid < 0.5) {
            snprintf(why, why_len, "no ribbon leaves the clamp-like blob near (%.0f, %.0f)", c.x, c.y);
            return false;
        }
        cv::Mat coef;
        if (!cv::solve(A, y, coef, cv::DECOMP_SVD)) {
            snprintf(why, why_len, "ribbon fit failed beside the blob near (%.0f, %.0f)", c.x, c.y);
            return false;
        }
        b_rib = coef.at<double>(0);
        if (!(b_rib > bmin && b_rib < bmax)) {
            snprintf(why, why_len, "the ribbon does not leave the blob near (%.0f, %.0f) across its face",
                     c.x, c.y);
            return false;
        }
    }
    out.point = c + a_edge * e + b_rib * n;
    return true;
}

}  // namespace

extern "C" vis_status vis_find_clamps(const vis_frame *f, const vis_track_params *tp, double left_px[2],
                                      double right_px[2], double *quality, vis_error *err)
{
    if (!f || !left_px || !right_px)
        return vis::fail(err, VIS_ERR_ARG, "vis_find_clamps: NULL frame or output");
    const vis_track_params p = tp ? *tp : vis_track_params_default();
    if (!vis::finite(p.ribbon_max_px) || p.ribbon_max_px < 1 || p.ribbon_max_px > 100 ||
        !vis::finite(p.min_contrast) || p.min_contrast < 0 || p.min_contrast > 255 ||
        (p.polarity != VIS_POLARITY_AUTO && p.polarity != VIS_POLARITY_DARK &&
         p.polarity != VIS_POLARITY_LIGHT))
        return vis::fail(err, VIS_ERR_ARG,
                         "vis_find_clamps: need 1 <= ribbon_max_px <= 100, 0 <= min_contrast <= 255 "
                         "and a valid polarity");
    if (f->mat.empty() || f->mat.depth() != CV_8U)
        return vis::fail(err, VIS_ERR_ARG, "vis_find_clamps: empty or not 8-bit frame");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        const cv::Mat grey = vis::grey_of(f->mat);
        const int W = grey.cols, H = grey.rows;
        if (W < 32 || H < 32)
            return vis::fail(err, VIS_ERR_NOT_FOUND, "clamps: frame %dx%d too small", W, H);
        const vis::Exposure ex = vis::exposure_check(grey, p.min_contrast);
        if (ex != vis::Exposure::ok)
            return vis::fail(err, VIS_ERR_NOT_FOUND, "clamps: no contrast in the frame (%s)",
                             ex == vis::Exposure::dark ? "dark" : "bright or saturated");
        const bool dark = p.polarity == VIS_POLARITY_AUTO ? vis::polarity_is_dark(grey)
                                                          : p.polarity == VIS_POLARITY_DARK;
        // 1. Objects bright; backdrop by an opening on a subsampled copy; contrast above it.
        cv::Mat F;
        grey.convertTo(F, CV_32F, dark ? -1.0 : 1.0, dark ? 255.0 : 0.0);
        const int sub = std::max(1, std::min(W, H) / 120);
        cv::Mat small, bg_small, bg;
        cv::resize(F, small, cv::Size((W + sub - 1) / sub, (H + sub - 1) / sub), 0, 0, cv::INTER_AREA);
        const int ks = std::max(3, (std::max(W, H) / 4 / sub) | 1);
        cv::morphologyEx(small, bg_small, cv::MORPH_OPEN,
                         cv::getStructuringElement(cv::MORPH_RECT, cv::Size(ks, ks)), cv::Point(-1, -1),
                         1, cv::BORDER_REPLICATE);
        cv::resize(bg_small, bg, grey.size(), 0, 0, cv::INTER_LINEAR);
        cv::Mat C = F - bg;
        cv::GaussianBlur(C, C, cv::Size(5, 5), 0, 0, cv::BORDER_REPLICATE);
        double peak = 0;
        cv::minMaxLoc(C, nullptr, &peak);
        if (!(peak >= 2 * p.min_contrast))
            return vis::fail(err, VIS_ERR_NOT_FOUND,
                             "clamps: nothing stands out from the backdrop (strongest contrast %.0f)", peak);
        // Reference contrast: the strongest within a fifth of the frame, but at least 3/4 of the
        // strongest anywhere. A jaw with 2/3 of the ribbon's contrast passes half of it even where
        // the light falls by a third; clutter far from the ribbon is judged against the ribbon's
        // contrast, not its own. Thresholds are fractions of it.
        cv::Mat ref;
        const int kr = std::max(3, (std::max(W, H) / 5) | 1);
        cv::dilate(C, ref, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(kr, kr)), cv::Point(-1, -1),
                   1, cv::BORDER_REPLICATE);
        cv::max(ref, 0.75 * peak, ref);
        cv::divide(C, ref, C);

        // 2. Thick blobs, and which of them the ribbon joins.
        cv::Mat hi = C >= 0.5, lo = C >= 0.25, thick;
        const int kt = (int)std::ceil(p.ribbon_max_px) + 2;
        cv::morphologyEx(hi, thick, cv::MORPH_OPEN,
                         cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(kt, kt)));
        cv::Mat lab, stats, cents, glab;
        const int nl = cv::connectedComponentsWithStats(thick, lab, stats, cents, 8, CV_32S);
        cv::connectedComponents(lo | thick, glab, 8, CV_32S);
        std::vector<Blob> blobs;
        for (int l = 1; l < nl; l++)
            if (stats.at<int>(l, cv::CC_STAT_AREA) >= kt * kt)
                blobs.push_back({l, 0, Pt(cents.at<double>(l, 0), cents.at<double>(l, 1)),
                                 stats.at<int>(l, cv::CC_STAT_AREA)});
        if (blobs.size() < 2)
            return vis::fail(err, VIS_ERR_NOT_FOUND,
                             "clamps: %s clamp-like blob (thicker than %d px, contrast above half "
                             "the ribbon's)", blobs.empty() ? "no" : "only one", kt);
        std::sort(blobs.begin(), blobs.end(), [](const Blob &a, const Blob &b) { return a.area > b.area; });
        if (blobs.size() > 64)
            blobs.resize(64);
        std::vector<int> group_of(nl, 0);
        std::vector<std::vector<cv::Point>> pix(nl);
        for (int y = 0; y < H; y++) {
            const int *lr = lab.ptr<int>(y), *gr = glab.ptr<int>(y);
            for (int x = 0; x < W; x++)
                if (lr[x]) {
                    group_of[lr[x]] = gr[x];
                    pix[lr[x]].emplace_back(x, y);
                }
        }
        for (Blob &b : blobs)
            b.group = group_of[b.label];
        const double min_gap = std::max(8.0 * kt, 0.15 * W);
        int bi = -1, bj = -1;
        double best = 0;
        for (size_t i = 0; i < blobs.size(); i++)
            for (size_t j = i + 1; j < blobs.size(); j++) {
                const double d = cv::norm(blobs[i].c - blobs[j].c);
                if (blobs[i].group == blobs[j].group && d >= min_gap && d > best) {
                    best = d;
                    bi = (int)i;
                    bj = (int)j;
                }
            }
        if (bi < 0)
            return vis::fail(err, VIS_ERR_NOT_FOUND,
                             "clamps: %zu clamp-like blobs but no ribbon joins two of them at least "
                             "%.0f px apart", blobs.size(), min_gap);
        const Blob *L = &blobs[(size_t)bi], *R = &blobs[(size_t)bj];
        if (L->c.x > R->c.x)
            std::swap(L, R);

        // 3. Sub-pixel faces and the ribbon's centre at each.
        const Pt e = (R->c - L->c) * (1.0 / cv::norm(R->c - L->c));
        JawFit jl, jr;
        char why[200];
        if (!fit_jaw(F, grey, dark, p, pix[L->label], L->c, e, jl, why, sizeof why) ||
            !fit_jaw(F, grey, dark, p, pix[R->label], R->c, -1.0 * e, jr, why, sizeof why))
            return vis::fail(err, VIS_ERR_NOT_FOUND, "clamps: %s", why);
        left_px[0] = jl.point.x;
        left_px[1] = jl.point.y;
        right_px[0] = jr.point.x;
        right_px[1] = jr.point.y;
        if (quality) {
            auto q = [](const JawFit &j) { return j.valid / (1.0 + (j.spread / 0.5) * (j.spread / 0.5)); };
            *quality = std::min(q(jl), q(jr));
        }
        vis::ok(err);
        return VIS_OK;
    })
}
