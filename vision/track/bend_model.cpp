// bend_model.cpp: the centreline through a tight bend where the ribbon's face shows, from a model
// of the band's silhouette instead of cross-section centroids.
//
// Why: a twisted ribbon's cross-section projects to a segment that is oblique to the curve. Along a
// straight stretch the band it sweeps is still symmetric about the centreline, so the tracer's
// centroids are right; in a bend whose radius is a few widths, the segments of the neighbouring arc
// reach past the inner edge (by about (h_t)^2 / 2R for a tangential half-extent h_t at radius R),
// the band grows on the inside and every centroid there slides inward. On the simulator family's
// Delta L 0.7 arch (state 531) the traced samples are within 0.1-0.3 px of the truth everywhere but
// at the twisted apex, where they sit 0.96 px inside; the apex is the arc's midpoint, so Delta Z is
// 1 px off and A 0.10 rad.
//
// The model, over a window of arc around the bend (pixels): a centreline c(s) = c0(s) + delta(s)
// n0(s) (c0 the traced samples lightly smoothed, n0 their normal, delta piecewise linear on KNOTS
// knots: about 4 px apart on the usual window, fine enough for a crease's corner and a folded
// apex, which 7 and 13 knots were not), a cross-section segment of half-vector v(s) linear in s
// (its direction and length follow the twist), a half-thickness TAU_PX, a Gaussian blur sigma,
// and the image as a plane of background plus a contrast times the blurred silhouette (those four
// solved in closed form at every step). The silhouette is drawn supersampled (SUPER x SUPER per
// pixel, anti-aliased), the sections joined segment to segment as the renderer joins them.
// Levenberg-Marquardt on the pixels of the window (those nearer to it than to the rest of the
// ribbon), coarse to fine: six starts on COARSE_KNOTS knots (the segment across the curve or tilted
// either way along it; the apex where it was traced or half a band further out), the best one
// fitted on, then all KNOTS knots; a light penalty on delta's second differences. A knot moves only
// the sections between its neighbours, so its Jacobian column is drawn over what they reach (the
// background and contrast held, Kaufman's shortcut for separable least squares); that and the
// coarse starts took a fit from 92 to 33-76 ms on this machine (41-82 ms since the noise is read clear
// of the ribbon, on the same five bends). When that leaves more than the caller's multiple of
// the image's noise on the band, the cross-section's two halves are fitted apart (a crease turns
// it abruptly). The refined centreline replaces the samples of the window's inner part
// (tracker.cpp, refine_bends), and the caller accepts the model only if its residual on the band
// is within that multiple of the noise (measured on the patch's second differences).
#include "tracker_impl.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>

namespace vis {

namespace {

const int KNOTS = 21;
const int COARSE_KNOTS = 7;  // the starts and a first fit: 7 knots, then all KNOTS (coarse to fine)
const int COARSE_ITERS = 10;
// Parameters: delta at the knots; v = (a0 + a1 u, b0 + b1 u) on the first half of the window and
// (c0 + c1 u, d0 + d1 u) on the second (tied to the first half's unless the model is broken at the
// middle, as at a crease); log sigma.
const int IV = KNOTS, IVR = KNOTS + 4, ISIG = KNOTS + 8;
const int NP = KNOTS + 9;
const int SUPER = 4;
const double TAU_PX = 0.3;
const double SMOOTH_W = 0.02;  // penalty on delta's second differences, per knot, in residual units
const int MAX_ITERS = 25;
const int START_ITERS = 4;  // iterations from each start before the best is taken on

struct Patch {
    cv::Rect r;             // the patch, image pixels
    cv::Mat data;           // observed, CV_32F (ribbon bright)
    std::vector<int> idx;   // counted pixels: y * w + x within the patch
};

}  // namespace

struct BendModel::Impl {
    std::vector<Pt> c0, n0;        // base centreline, normals (dense, 1 px)
    std::vector<double> u;         // position in the window, -1..1
    Patch patch;
    cv::Mat fine, coarse, blurred;
    std::vector<cv::Point> poly;
    std::vector<cv::Point> hull;
    bool broken = false;  // the cross-section's two halves fitted apart (IVR..IVR+3 active)
    std::vector<Pt> near_pts;               // traced points of the rest of the ribbon near the patch
    std::vector<unsigned char> clear_px;    // per patch pixel: clear of the ribbon (noise)
    cv::Mat base_model;   // the model at the current params (Jacobian)
    // Levenberg-Marquardt's buffers, kept from fit to fit: residuals at p and at a trial step,
    // the Jacobian (rows: counted pixels, then the smoothness terms), the damped normal equations.
    std::vector<double> r0, r1, Jm;
    cv::Mat M, rhs, dx;
    std::vector<double> cum;
    std::vector<Pt> rs;
    std::vector<double> bg;

    int nk = KNOTS;       // knots in use: p[0 .. nk - 1]

    bool active(int k) const
    {
        if (k < KNOTS)
            return k < nk;
        return broken || k < IVR || k >= IVR + 4;
    }
    // delta at u in [-1, 1] from the nk knots in use.
    double delta_at(const double *p, double uu) const
    {
        const double x = (uu + 1.0) * 0.5 * (nk - 1);
        const int j = std::min(nk - 2, std::max(0, (int)std::floor(x)));
        const double f = x - j;
        return (1 - f) * p[j] + f * p[j + 1];
    }

    std::vector<int> counted_at;  // per patch pixel: its index among the counted ones, or -1
    double lin[4] = {0, 0, 0, 0}; // background plane and contrast of the last full evaluation
    cv::Mat part;                 // a region's blurred model (Jacobian columns)

    // The section corners at dense index k for params p (c - v - th, c - v + th, c + v + th, c + v - th).
    void corners(const double *p, size_t k, Pt out4[4]) const
    {
        const double uk = u[k];
        const Pt c = c0[k] + delta_at(p, uk) * n0[k];
        const int iv = broken && uk >= 0 ? IVR : IV;
        const Pt v(p[iv] + p[iv + 1] * uk, p[iv + 2] + p[iv + 3] * uk);
        const Pt th = TAU_PX * n0[k];
        out4[0] = c - v - th;
        out4[1] = c - v + th;
        out4[2] = c + v + th;
        out4[3] = c + v - th;
    }

    static int blur_radius(double sigma) { return (int)std::ceil(3.0 * sigma); }

    cv::Mat blurred_tmp;  // render_region's scratch

    // The blurred model over `reg` (patch coordinates) into `dst` (reg's size): drawn over `reg`
    // grown by the blur's reach (within the patch), so the values on `reg` are exact; sections
    // whose box misses that are skipped. False on a degenerate sigma.
    bool render_region(const double *p, cv::Rect reg, cv::Mat &dst)
    {
        const double sigma = std::exp(p[ISIG]);
        if (!(sigma > 0.2 && sigma < 5.0))
            return false;
        const int br = blur_radius(sigma);
        const cv::Rect whole(0, 0, patch.r.width, patch.r.height);
        const cv::Rect ext = cv::Rect(reg.x - br, reg.y - br, reg.width + 2 * br, reg.height + 2 * br) & whole;
        fine.create(ext.height * SUPER, ext.width * SUPER, CV_8U);
        fine.setTo(0);
        const int SH = 4;  // fillConvexPoly's fractional bits
        const double ox = patch.r.x + ext.x, oy = patch.r.y + ext.y;
        auto to_fine = [&](Pt q) {
            return cv::Point((int)std::lround(((q.x - ox + 0.5) * SUPER - 0.5) * (1 << SH)),
                             (int)std::lround(((q.y - oy + 0.5) * SUPER - 0.5) * (1 << SH)));
        };
        const double x0 = ox - 1, y0 = oy - 1, x1 = ox + ext.width + 1, y1 = oy + ext.height + 1;
        Pt prev[4], cur[4];
        for (size_t k = 0; k < c0.size(); k++) {
            corners(p, k, cur);
            if (k > 0) {
                double bx0 = 1e18, by0 = 1e18, bx1 = -1e18, by1 = -1e18;
                for (int i = 0; i < 4; i++)
                    for (const Pt &q : {prev[i], cur[i]}) {
                        bx0 = std::min(bx0, q.x);
                        by0 = std::min(by0, q.y);
                        bx1 = std::max(bx1, q.x);
                        by1 = std::max(by1, q.y);
                    }
                if (bx1 >= x0 && bx0 <= x1 && by1 >= y0 && by0 <= y1) {
                    poly.clear();
                    for (int i = 0; i < 4; i++) {
                        poly.push_back(to_fine(prev[i]));
                        poly.push_back(to_fine(cur[i]));
                    }
                    cv::convexHull(poly, hull);
                    cv::fillConvexPoly(fine, hull, cv::Scalar(255), cv::LINE_AA, SH);
                }
            }
            std::copy(cur, cur + 4, prev);
        }
        cv::resize(fine, coarse, ext.size(), 0, 0, cv::INTER_AREA);
        coarse.convertTo(blurred_tmp, CV_32F, 1.0 / 255.0);
        cv::GaussianBlur(blurred_tmp, blurred_tmp, cv::Size(2 * br + 1, 2 * br + 1), sigma, sigma, cv::BORDER_CONSTANT);
        blurred_tmp(cv::Rect(reg.x - ext.x, reg.y - ext.y, reg.width, reg.height)).copyTo(dst);
        return true;
    }

    // The whole patch's model into `blurred`.
    bool render(const double *p)
    {
        return render_region(p, cv::Rect(0, 0, patch.r.width, patch.r.height), blurred);
    }

    // The patch pixels the sections of dense indices [k0, k1] (and their joins) cover, for params p
    // and q, grown by the blur's reach: what moving those sections can change.
    cv::Rect reach_of(const double *p, const double *q, size_t k0, size_t k1) const
    {
        double bx0 = 1e18, by0 = 1e18, bx1 = -1e18, by1 = -1e18;
        Pt c4[4];
        for (const double *pp : {p, q})
            for (size_t k = k0 > 0 ? k0 - 1 : 0; k <= std::min(k1 + 1, c0.size() - 1); k++) {
                corners(pp, k, c4);
                for (const Pt &c : c4) {
                    bx0 = std::min(bx0, c.x);
                    by0 = std::min(by0, c.y);
                    bx1 = std::max(bx1, c.x);
                    by1 = std::max(by1, c.y);
                }
            }
        const int br = blur_radius(std::exp(std::max(p[ISIG], q[ISIG]))) + 2;
        const cv::Rect r((int)std::floor(bx0 - patch.r.x) - br, (int)std::floor(by0 - patch.r.y) - br,
                         (int)std::ceil(bx1 - bx0) + 2 * br + 2, (int)std::ceil(by1 - by0) + 2 * br + 2);
        return r & cv::Rect(0, 0, patch.r.width, patch.r.height);
    }

    // Residuals for params p (counted pixels, then the smoothness terms), with the background plane
    // and contrast solved in closed form. Returns false on a degenerate model.
    bool residuals(const double *p, std::vector<double> &r, double *contrast)
    {
        if (!render(p))
            return false;
        const int w = patch.r.width;
        // Least squares for data ~ b0 + bx x + by y + k m.
        double A[4][4] = {{0}}, b[4] = {0};
        for (int id : patch.idx) {
            const int y = id / w, x = id % w;
            const double m = blurred.at<float>(y, x), d = patch.data.at<float>(y, x);
            const double q[4] = {1.0, (double)x, (double)y, m};
            for (int i = 0; i < 4; i++) {
                for (int k = 0; k < 4; k++)
                    A[i][k] += q[i] * q[k];
                b[i] += q[i] * d;
            }
        }
        double c[4];
        if (!solve4(A, b, c))
            return false;
        if (contrast)
            *contrast = c[3];
        std::copy(c, c + 4, lin);
        r.resize(patch.idx.size() + KNOTS - 2);
        size_t n = 0;
        for (int id : patch.idx) {
            const int y = id / w, x = id % w;
            r[n++] = c[0] + c[1] * x + c[2] * y + c[3] * blurred.at<float>(y, x) - patch.data.at<float>(y, x);
        }
        const double sw = SMOOTH_W * std::fabs(c[3]);
        for (int j = 1; j + 1 < KNOTS; j++)
            r[n++] = j + 1 < nk ? sw * (p[j - 1] - 2 * p[j] + p[j + 1]) : 0.0;
        return true;
    }

    static bool solve4(double A[4][4], double b[4], double x[4])
    {
        double M[4][5];
        for (int i = 0; i < 4; i++) {
            for (int k = 0; k < 4; k++)
                M[i][k] = A[i][k];
            M[i][4] = b[i];
        }
        for (int col = 0; col < 4; col++) {
            int piv = col;
            for (int i = col + 1; i < 4; i++)
                if (std::fabs(M[i][col]) > std::fabs(M[piv][col]))
                    piv = i;
            if (!(std::fabs(M[piv][col]) > 1e-12))
                return false;
            for (int k = 0; k < 5; k++)
                std::swap(M[col][k], M[piv][k]);
            for (int i = 0; i < 4; i++)
                if (i != col) {
                    const double f = M[i][col] / M[col][col];
                    for (int k = col; k < 5; k++)
                        M[i][k] -= f * M[col][k];
                }
        }
        for (int i = 0; i < 4; i++)
            x[i] = M[i][4] / M[i][i];
        return true;
    }

    static double sumsq(const std::vector<double> &r)
    {
        double s = 0;
        for (double v : r)
            s += v * v;
        return s;
    }

    // The image's noise, from the patch itself: the absolute second differences along rows and
    // columns at the pixels clear of the ribbon (`clear`: farther than its half-width and 4 px
    // from every traced point; the whole patch when fewer than 100 are), over sqrt(6) for
    // independent pixels. Read over the whole patch it came out 20-30% high (the band's edges),
    // 2.9-3.25 clear of it where the renderer's noise was 3.
    double data_noise = 0;
    void measure_noise(const std::vector<unsigned char> &clear)
    {
        bg.clear();
        const cv::Mat &d = patch.data;
        for (int pass = 0; pass < 2 && (pass == 0 || bg.size() < 200); pass++) {
            bg.clear();
            for (int y = 1; y + 1 < d.rows; y++)
                for (int x = 1; x + 1 < d.cols; x++) {
                    if (pass == 0 && !clear[(size_t)(y * d.cols + x)])
                        continue;
                    const float c = d.at<float>(y, x);
                    bg.push_back(std::fabs(d.at<float>(y, x - 1) - 2 * c + d.at<float>(y, x + 1)));
                    bg.push_back(std::fabs(d.at<float>(y - 1, x) - 2 * c + d.at<float>(y + 1, x)));
                }
        }
        data_noise = 0;
        if (bg.size() < 40)
            return;
        // The mean of the lowest three quarters (the median of 8-bit data is an integer, too
        // coarse): 0.5148 s for |N(0, s^2)|.
        const size_t q = bg.size() * 3 / 4;
        std::nth_element(bg.begin(), bg.begin() + (long)q, bg.end());
        double sum = 0;
        for (size_t i = 0; i < q; i++)
            sum += bg[i];
        data_noise = sum / (double)q / 0.5148 / std::sqrt(6.0);
    }

    // The residual over the band (model above 5% of the contrast) against the image's noise: a
    // model that explains the pixels leaves only the noise.
    bool quality(const double *p, double *rms, double *noise, double *contrast)
    {
        std::vector<double> &r = r1;
        if (!residuals(p, r, contrast))
            return false;
        double ss = 0;
        int nb = 0;
        bg.clear();
        for (size_t i = 0; i < patch.idx.size(); i++) {
            const int id = patch.idx[i];
            const float mv = blurred.at<float>(id / patch.r.width, id % patch.r.width);
            if (mv >= 0.05f) {
                ss += r[i] * r[i];
                nb++;
            }
        }
        if (nb < 20)
            return false;
        *noise = data_noise;
        *rms = std::sqrt(ss / (double)nb);
        return data_noise > 0;
    }

    // Levenberg-Marquardt from p; returns the final sum of squares (inf when it failed).
    double fit(double *p, int iters)
    {
        if (!residuals(p, r0, nullptr))
            return INFINITY;
        double f0 = sumsq(r0), lambda = 1e-2;
        const size_t m = r0.size();
        Jm.resize(m * NP);
        for (int it = 0; it < iters; it++) {
            // Forward differences at the background and contrast of p (the step itself solves
            // them again). A knot moves only the sections between its neighbours: its column is
            // drawn over what they reach, not the whole patch. `blurred`, `lin` and r0 are p's
            // here: from the call above, or from the step just taken.
            blurred.copyTo(base_model);
            const double cst = lin[3];
            std::fill(Jm.begin(), Jm.end(), 0.0);
            const int w = patch.r.width;
            for (int k = 0; k < NP; k++) {
                if (!active(k))
                    continue;
                double q[NP];
                std::copy(p, p + NP, q);
                // sigma's probe goes down near its upper bound (render refuses sigma >= 5).
                const double h = k == ISIG ? (p[ISIG] > std::log(4.5) ? -0.02 : 0.02) : 0.1;
                q[k] += h;
                if (k < KNOTS) {
                    const double ua = -1.0 + 2.0 * (k - 1) / (nk - 1), ub = -1.0 + 2.0 * (k + 1) / (nk - 1);
                    const size_t n = c0.size();
                    const size_t ka = (size_t)std::max(0.0, std::floor((ua + 1.0) * 0.5 * (double)(n - 1)));
                    const size_t kb = std::min(n - 1, (size_t)std::ceil((ub + 1.0) * 0.5 * (double)(n - 1)));
                    const cv::Rect reg = reach_of(p, q, ka, kb);
                    if (reg.width <= 0 || reg.height <= 0)
                        continue;
                    if (!render_region(q, reg, part))
                        return INFINITY;
                    for (int y = 0; y < reg.height; y++)
                        for (int x = 0; x < reg.width; x++) {
                            const int id = (y + reg.y) * w + (x + reg.x);
                            const int i = counted_at[(size_t)id];
                            if (i >= 0)
                                Jm[(size_t)i * NP + k] = cst * (part.at<float>(y, x) - base_model.at<float>(y + reg.y, x + reg.x)) / h;
                        }
                } else {
                    if (!render(q))
                        return INFINITY;
                    for (size_t i = 0; i < patch.idx.size(); i++) {
                        const int id = patch.idx[i];
                        Jm[i * NP + k] = cst * (blurred.at<float>(id / w, id % w) - base_model.at<float>(id / w, id % w)) / h;
                    }
                }
                // The smoothness rows: exact (linear in the knots).
                if (k < KNOTS) {
                    const double sw = SMOOTH_W * std::fabs(cst);
                    for (int j = 1; j + 1 < nk; j++) {
                        const double d = (k == j - 1 || k == j + 1) ? 1.0 : k == j ? -2.0 : 0.0;
                        Jm[(patch.idx.size() + (size_t)(j - 1)) * NP + k] = sw * d;
                    }
                }
            }
            double JtJ[NP][NP] = {{0}}, g[NP] = {0};
            for (size_t i = 0; i < m; i++) {
                const double *ji = &Jm[i * NP];
                for (int a = 0; a < NP; a++) {
                    g[a] += ji[a] * r0[i];
                    for (int b2 = a; b2 < NP; b2++)
                        JtJ[a][b2] += ji[a] * ji[b2];
                }
            }
            for (int a = 0; a < NP; a++)
                for (int b2 = 0; b2 < a; b2++)
                    JtJ[a][b2] = JtJ[b2][a];
            bool improved = false;
            for (int tries = 0; tries < 6 && !improved; tries++) {
                M.create(NP, NP, CV_64F);
                rhs.create(NP, 1, CV_64F);
                for (int a = 0; a < NP; a++) {
                    for (int b2 = 0; b2 < NP; b2++)
                        M.at<double>(a, b2) = JtJ[a][b2] + (a == b2 ? lambda * (JtJ[a][a] + 1e-9) + (active(a) ? 0.0 : 1.0) : 0.0);
                    rhs.at<double>(a) = -g[a];
                }
                if (!cv::solve(M, rhs, dx, cv::DECOMP_CHOLESKY)) {
                    lambda *= 10;
                    continue;
                }
                double q[NP];
                for (int a = 0; a < NP; a++)
                    q[a] = p[a] + dx.at<double>(a);
                if (residuals(q, r1, nullptr) && r1.size() == m) {
                    const double f1 = sumsq(r1);
                    if (f1 < f0) {
                        std::copy(q, q + NP, p);
                        r0.swap(r1);
                        const double gain = (f0 - f1) / f0;
                        f0 = f1;
                        lambda = std::max(1e-6, lambda * 0.3);
                        improved = true;
                        if (gain < 1e-5)
                            return f0;
                        break;
                    }
                }
                lambda *= 10;
            }
            if (!improved)
                break;
        }
        return f0;
    }
};

namespace {
// Of several starts, the fit with the smaller sum of squares.
void keep_better(double f, const double *p, double &best_f, double *best_p)
{
    if (f < best_f) {
        best_f = f;
        std::copy(p, p + NP, best_p);
    }
}
}  // namespace

BendModel::BendModel() : impl_(new Impl) {}
BendModel::~BendModel() = default;
BendModel::BendModel(const BendModel &) : impl_(new Impl) {}
BendModel &BendModel::operator=(const BendModel &)
{
    impl_.reset(new Impl);
    return *this;
}

bool BendModel::refine(const cv::Mat &img, bool invert, const std::vector<Pt> &window,
                       const std::vector<Pt> &others, double half_width_px, double max_rms_over_noise,
                       std::vector<Pt> &out, BendFitInfo *info)
{
    Impl &m = *impl_;
    out.clear();
    if (info)
        *info = BendFitInfo{};
    if (window.size() < 8 || img.empty())
        return false;
    // Base: the window resampled every 1 px and lightly smoothed, with normals.
    double len = 0;
    resample(window, 1.0, &len, m.cum, m.rs);
    if (m.rs.size() < 8)
        return false;
    smooth(m.rs, 2, m.c0);
    const size_t n = m.c0.size();
    m.n0.resize(n);
    m.u.resize(n);
    for (size_t k = 0; k < n; k++) {
        const Pt t = m.c0[std::min(k + 2, n - 1)] - m.c0[k >= 2 ? k - 2 : 0];
        const double tl = cv::norm(t);
        m.n0[k] = tl > 0 ? Pt(-t.y / tl, t.x / tl) : Pt(0, 0);
        m.u[k] = -1.0 + 2.0 * (double)k / (double)(n - 1);
    }
    // The patch: the window's box, grown by the band's half-width, the blur and a margin.
    const double grow = half_width_px + 5.0;
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (const Pt &q : m.c0) {
        x0 = std::min(x0, q.x);
        y0 = std::min(y0, q.y);
        x1 = std::max(x1, q.x);
        y1 = std::max(y1, q.y);
    }
    const cv::Rect box((int)std::floor(x0 - grow), (int)std::floor(y0 - grow),
                       (int)std::ceil(x1 - x0 + 2 * grow) + 1, (int)std::ceil(y1 - y0 + 2 * grow) + 1);
    m.patch.r = box & cv::Rect(0, 0, img.cols, img.rows);
    if (m.patch.r.width < 8 || m.patch.r.height < 8)
        return false;
    img(m.patch.r).convertTo(m.patch.data, CV_32F);
    if (invert)
        m.patch.data = 255.0f - m.patch.data;
    // Counted pixels: within reach of the window's inner part (|u| <= 0.8), nearer to it than to
    // the rest of the ribbon.
    m.patch.idx.clear();
    const double reach = half_width_px + 3.5, clear_r = half_width_px + 4.0;
    // The traced points near the patch (the noise is read clear of all of them).
    m.near_pts.clear();
    const cv::Rect grown(m.patch.r.x - (int)clear_r - 1, m.patch.r.y - (int)clear_r - 1,
                         m.patch.r.width + 2 * (int)clear_r + 2, m.patch.r.height + 2 * (int)clear_r + 2);
    for (const Pt &o : others)
        if (grown.contains(cv::Point((int)o.x, (int)o.y)))
            m.near_pts.push_back(o);
    m.clear_px.assign((size_t)m.patch.r.width * (size_t)m.patch.r.height, 0);
    for (int y = 0; y < m.patch.r.height; y++)
        for (int x = 0; x < m.patch.r.width; x++) {
            const Pt q(x + m.patch.r.x, y + m.patch.r.y);
            double dw = 1e18, du = 0;
            for (size_t k = 0; k < n; k++) {
                const double d = (q - m.c0[k]).dot(q - m.c0[k]);
                if (d < dw) {
                    dw = d;
                    du = m.u[k];
                }
            }
            if (dw > clear_r * clear_r) {
                bool clear = true;
                for (const Pt &o : m.near_pts)
                    if ((q - o).dot(q - o) <= clear_r * clear_r) {
                        clear = false;
                        break;
                    }
                m.clear_px[(size_t)(y * m.patch.r.width + x)] = clear;
            }
            if (std::fabs(du) > 0.8 || dw > reach * reach)
                continue;
            bool nearer_other = false;
            for (const Pt &o : others)
                if ((q - o).dot(q - o) < dw) {
                    nearer_other = true;
                    break;
                }
            if (!nearer_other)
                m.patch.idx.push_back(y * m.patch.r.width + x);
        }
    if (m.patch.idx.size() < 40)
        return false;
    m.measure_noise(m.clear_px);
    m.counted_at.assign((size_t)m.patch.r.width * (size_t)m.patch.r.height, -1);
    for (size_t i = 0; i < m.patch.idx.size(); i++)
        m.counted_at[(size_t)m.patch.idx[i]] = (int)i;
    // Starts: the segment across the curve (the half-width), then tilted either way along it.
    const Pt nm = m.n0[n / 2], tm(nm.y, -nm.x);
    const double hw0 = std::max(0.5, half_width_px - 1.0);
    const Pt v_start[3] = {hw0 * nm, hw0 * (0.6 * nm + 0.8 * tm), hw0 * (0.6 * nm - 0.8 * tm)};
    // The bend's outside: away from the middle of the window's chord. The traced apex lies inside
    // the true one (the centroids slide inward), so half the starts put it half a band outward.
    const Pt chord_mid = 0.5 * (m.c0.front() + m.c0.back());
    const double out_sign = (m.c0[n / 2] - chord_mid).dot(nm) >= 0 ? 1.0 : -1.0;
    double best_p[NP] = {0}, best_f = INFINITY;
    m.broken = false;
    m.nk = COARSE_KNOTS;
    for (int start = 0; start < 6; start++) {
        double p[NP] = {0};
        p[IV] = p[IVR] = v_start[start % 3].x;
        p[IV + 2] = p[IVR + 2] = v_start[start % 3].y;
        p[ISIG] = std::log(1.0);
        if (start >= 3)
            for (int j = 0; j < m.nk; j++) {
                const double uj = -1.0 + 2.0 * j / (m.nk - 1);
                p[j] = out_sign * 0.5 * hw0 * std::max(0.0, 1.0 - 2.0 * std::fabs(uj));
            }
        keep_better(m.fit(p, START_ITERS), p, best_f, best_p);
    }
    if (!std::isfinite(best_f))
        return false;
    best_f = m.fit(best_p, COARSE_ITERS);
    if (!std::isfinite(best_f))
        return false;
    {
        double fine_delta[KNOTS];
        for (int j = 0; j < KNOTS; j++)
            fine_delta[j] = m.delta_at(best_p, -1.0 + 2.0 * j / (KNOTS - 1));
        std::copy(fine_delta, fine_delta + KNOTS, best_p);
        m.nk = KNOTS;
    }
    best_f = m.fit(best_p, MAX_ITERS);
    double rms = 0, noise = 0, contrast = 0;
    if (!std::isfinite(best_f) || !m.quality(best_p, &rms, &noise, &contrast))
        return false;
    if (rms > max_rms_over_noise * noise) {
        // A crease: the cross-section turns abruptly where the ribbon is folded, so its two
        // halves get a segment each (from the smooth fit's, and from the three starts on either side).
        m.broken = true;
        double bp[NP], bf = INFINITY;
        for (int start = 0; start < 7; start++) {
            double p[NP];
            std::copy(best_p, best_p + NP, p);
            for (int k = 0; k < 4; k++)
                p[IVR + k] = p[IV + k];
            if (start > 0) {
                const int half = start <= 3 ? IV : IVR;
                const Pt v0 = v_start[(start - 1) % 3];
                p[half] = v0.x;
                p[half + 1] = 0;
                p[half + 2] = v0.y;
                p[half + 3] = 0;
            }
            keep_better(m.fit(p, START_ITERS), p, bf, bp);
        }
        if (!std::isfinite(bf))
            return false;
        bf = m.fit(bp, MAX_ITERS);
        double rms2 = 0, noise2 = 0, contrast2 = 0;
        if (std::isfinite(bf) && m.quality(bp, &rms2, &noise2, &contrast2) && rms2 < rms) {
            std::copy(bp, bp + NP, best_p);
            rms = rms2;
            noise = noise2;
            contrast = contrast2;
        } else {
            m.broken = false;  // the smooth section explains the pixels better
            if (!m.quality(best_p, &rms, &noise, &contrast))
                return false;
        }
    }
    out.resize(n);
    for (size_t k = 0; k < n; k++) {
        out[k] = m.c0[k] + m.delta_at(best_p, m.u[k]) * m.n0[k];
    }
    if (info) {
        info->rms = rms;
        info->noise = noise;
        info->contrast = contrast;
        info->sigma = std::exp(best_p[ISIG]);
        double dmax = 0;
        for (size_t k = 0; k < n; k++)
            if (std::fabs(m.u[k]) <= BEND_INNER)
                dmax = std::max(dmax, std::fabs(m.delta_at(best_p, m.u[k])));
        info->delta_max = std::isfinite(dmax) ? dmax : INFINITY;
    }
    return true;
}

}  // namespace vis
