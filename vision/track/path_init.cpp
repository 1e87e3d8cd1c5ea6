// path_init.cpp: a first path along the ribbon when there is no previous curve to follow.
//
// Geodesic (Dijkstra) search over the pixel grid from the left clamp point to the right one, where
// crossing a pixel costs its step length divided by (eps + S / S_ref): a ridge pixel is about 1/eps
// times cheaper than background, so the path follows the ribbon however it winds, including
// overhangs where no column-wise search could (issue 5). S_ref is a high percentile of the signal so
// the cost does not depend on contrast. The path is only a guide at pixel precision: the tracer then
// refines it. Cost is O(P log P) in the image size, paid only when the ribbon is (re)acquired; on
// large frames the search runs coarse to fine (a max-pooled grid first, then a corridor around its
// path), which takes the rehearsal scene's 1280 x 720 fresh search from 0.13-0.3 s to about 25 ms.
#include "tracker_impl.hpp"

#include <algorithm>
#include <queue>

namespace vis {

double signal_reference(const cv::Mat &sig)
{
    // Ridge pixels are a small share of the frame: a high percentile is the ridge's level.
    std::vector<float> vals;
    vals.reserve((size_t)sig.cols * sig.rows / 4 + 1);
    for (int y = 0; y < sig.rows; y += 2) {
        const float *r = sig.ptr<float>(y);
        for (int x = 0; x < sig.cols; x += 2)
            if (r[x] > 0)
                vals.push_back(r[x]);
    }
    if (vals.empty())
        return 0.0;
    const size_t q = std::min(vals.size() - 1, (size_t)(0.995 * vals.size()));
    std::nth_element(vals.begin(), vals.begin() + (long)q, vals.end());
    return vals[q];
}

namespace {

// Pixel cost of the geodesic: step length / (eps + S / sref), S clamped to [0, sref].
inline float pixel_cost(float v, double sref, double eps)
{
    return (float)(1.0 / (eps + std::min(1.0, std::max(0.0, v / sref))));
}

// Dijkstra over the 8-connected grid of `sig` from pixel src to pixel dst, through pixels whose
// `allow` entry is non-zero (all when `allow` is empty). The path (pixel indices, src first) into
// `out`; false when dst is not reached.
bool grid_geodesic(const cv::Mat &sig, double sref, double eps, const std::vector<uint8_t> &allow, int src,
                   int dst, std::vector<int> &out)
{
    const int W = sig.cols, H = sig.rows;
    const size_t P = (size_t)W * H;
    std::vector<float> dist(P, 1e30f);
    std::vector<int> prev(P, -1);
    const bool all = allow.empty();
    auto cost = [&](int u) { return pixel_cost(sig.ptr<float>(u / W)[u % W], sref, eps); };
    using Item = std::pair<float, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> pq;
    dist[(size_t)src] = 0;
    pq.push({0.f, src});
    static const int DX[8] = {1, -1, 0, 0, 1, 1, -1, -1}, DY[8] = {0, 0, 1, -1, 1, -1, 1, -1};
    static const float DL[8] = {1, 1, 1, 1, 1.41421356f, 1.41421356f, 1.41421356f, 1.41421356f};
    size_t pops = 0;
    const size_t cap = 8 * P + 16;  // every node is settled once; stale entries bounded by pushes
    while (!pq.empty() && pops++ < cap) {
        const Item it = pq.top();
        pq.pop();
        const int u = it.second;
        if (it.first > dist[(size_t)u])
            continue;
        if (u == dst)
            break;
        const int ux = u % W, uy = u / W;
        const float cu = cost(u);
        for (int k = 0; k < 8; k++) {
            const int vx = ux + DX[k], vy = uy + DY[k];
            if (vx < 0 || vy < 0 || vx >= W || vy >= H)
                continue;
            const int v = vy * W + vx;
            if (!all && !allow[(size_t)v])
                continue;
            const float nd = it.first + DL[k] * 0.5f * (cu + cost(v));
            if (nd < dist[(size_t)v]) {
                dist[(size_t)v] = nd;
                prev[(size_t)v] = u;
                pq.push({nd, v});
            }
        }
    }
    if (prev[(size_t)dst] < 0 && dst != src)
        return false;
    out.clear();
    for (int v = dst, guard = 0; v >= 0 && guard < (int)P; v = prev[(size_t)v], guard++)
        out.push_back(v);
    std::reverse(out.begin(), out.end());
    return true;
}

}  // namespace

bool path_init(const cv::Mat &sig, double sref0, Pt a, Pt b, std::vector<Pt> &path)
{
    const int W = sig.cols, H = sig.rows;
    auto inside = [&](Pt p) { return p.x >= 0 && p.y >= 0 && p.x <= W - 1 && p.y <= H - 1; };
    if (!inside(a) || !inside(b))
        return false;
    if (!(sref0 > 0))
        return false;
    const double sref = std::max(1e-3, sref0);
    const double eps = 0.03;
    const int sx = (int)std::lround(a.x), sy = (int)std::lround(a.y);
    const int tx = (int)std::lround(b.x), ty = (int)std::lround(b.y);
    std::vector<int> idx;
    std::vector<uint8_t> allow;
    // Coarse to fine: on large frames the search over every pixel is most of a fresh acquisition
    // (0.13-0.3 s at 1280 x 720). First the geodesic on the signal max-pooled over f x f blocks
    // (a thin ridge survives the max), then the full-resolution one inside a corridor of +-f coarse
    // pixels around it (f to 2 f px), which holds the full search's path wherever the coarse one
    // follows the same ridge.
    const int f = (double)W * H >= 6e5 ? 4 : (double)W * H >= 2e5 ? 2 : 1;
    if (f > 1) {
        const int Wc = (W + f - 1) / f, Hc = (H + f - 1) / f;
        cv::Mat coarse(Hc, Wc, CV_32F);
        for (int yc = 0; yc < Hc; yc++) {
            float *r = coarse.ptr<float>(yc);
            for (int xc = 0; xc < Wc; xc++) {
                float m = 0.f;
                for (int y = yc * f; y < std::min(H, yc * f + f); y++) {
                    const float *q = sig.ptr<float>(y);
                    for (int x = xc * f; x < std::min(W, xc * f + f); x++)
                        m = std::max(m, q[x]);
                }
                r[xc] = m;
            }
        }
        if (!grid_geodesic(coarse, sref, eps, allow, (sy / f) * Wc + sx / f, (ty / f) * Wc + tx / f, idx))
            return false;
        allow.assign((size_t)W * H, 0);
        for (const int c : idx) {
            const int xc = c % Wc, yc = c / Wc;
            for (int y = std::max(0, (yc - 1) * f); y < std::min(H, (yc + 2) * f); y++)
                std::fill(allow.begin() + (long)y * W + std::max(0, (xc - 1) * f),
                          allow.begin() + (long)y * W + std::min(W, (xc + 2) * f), (uint8_t)1);
        }
    }
    if (!grid_geodesic(sig, sref, eps, allow, sy * W + sx, ty * W + tx, idx))
        return false;
    path.clear();
    for (const int v : idx)
        path.push_back(Pt(v % W, v / W));
    path.front() = a;
    path.back() = b;
    return path.size() >= 2;
}

}  // namespace vis
