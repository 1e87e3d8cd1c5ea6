// path_init.cpp: a first path along the ribbon when there is no previous curve to follow.
//
// Geodesic (Dijkstra) search over the pixel grid from the left clamp point to the right one, where
// crossing a pixel costs its step length divided by (eps + S / S_ref): a ridge pixel is about 1/eps
// times cheaper than background, so the path follows the ribbon however it winds, including
// overhangs where no column-wise search could (issue 5). S_ref is a high percentile of the signal so
// the cost does not depend on contrast. The path is only a guide at pixel precision: the tracer then
// refines it. Cost is O(P log P) in the image size, paid only when the ribbon is (re)acquired.
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

bool path_init(const cv::Mat &sig, Pt a, Pt b, std::vector<Pt> &path)
{
    const int W = sig.cols, H = sig.rows;
    auto inside = [&](Pt p) { return p.x >= 0 && p.y >= 0 && p.x <= W - 1 && p.y <= H - 1; };
    if (!inside(a) || !inside(b))
        return false;
    const double sref0 = signal_reference(sig);
    if (!(sref0 > 0))
        return false;
    const double sref = std::max(1e-3, sref0);
    const double eps = 0.03;

    const size_t P = (size_t)W * H;
    std::vector<float> cost(P), dist(P, 1e30f);
    std::vector<int> prev(P, -1);
    for (int y = 0; y < H; y++) {
        const float *r = sig.ptr<float>(y);
        for (int x = 0; x < W; x++)
            cost[(size_t)y * W + x] = (float)(1.0 / (eps + std::min(1.0, std::max(0.0, r[x] / sref))));
    }
    const int sx = (int)std::lround(a.x), sy = (int)std::lround(a.y);
    const int tx = (int)std::lround(b.x), ty = (int)std::lround(b.y);
    const int src = sy * W + sx, dst = ty * W + tx;
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
        for (int k = 0; k < 8; k++) {
            const int vx = ux + DX[k], vy = uy + DY[k];
            if (vx < 0 || vy < 0 || vx >= W || vy >= H)
                continue;
            const int v = vy * W + vx;
            const float nd = it.first + DL[k] * 0.5f * (cost[(size_t)u] + cost[(size_t)v]);
            if (nd < dist[(size_t)v]) {
                dist[(size_t)v] = nd;
                prev[(size_t)v] = u;
                pq.push({nd, v});
            }
        }
    }
    if (prev[(size_t)dst] < 0 && dst != src)
        return false;
    path.clear();
    for (int v = dst, guard = 0; v >= 0 && guard < (int)P; v = prev[(size_t)v], guard++)
        path.push_back(Pt(v % W, v / W));
    std::reverse(path.begin(), path.end());
    path.front() = a;
    path.back() = b;
    return path.size() >= 2;
}

}  // namespace vis
