// trace.cpp: the sub-pixel centreline tracer (cross-section centroids along the arc).
//
// The guide curve (the previous frame's centreline, or a fresh geodesic path) is resampled every
// `step` px along its arc length; at each sample the image (the grey frame with the polarity folded
// in, or the ridge signal) is read along the normal, +-band px, every 0.5 px by bilinear
// interpolation (OpenCV's convention: pixel centres at integers, so no half-pixel shift). The
// ribbon's cross-section is the peak of that profile: its centre is the centroid of the part above
// the lower quartile (the local background) + 30% of the peak height, which is unbiased for the
// symmetric blurred profile of a ribbon. Working along normals (not image columns) is what lets the
// tracer follow overhangs and tangents beyond vertical. A sample is valid only when the peak stands
// out from the profile's own noise (peak - lower quartile >= min_contrast and >= 5 times the RMS of
// the profile away from the peak), is narrower than the largest expected thickness and lies inside
// the band: on a corrupted or noise-only frame the profiles fail that test and the frame is reported
// instead of measured.
#include "tracker_impl.hpp"

#include <algorithm>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace vis {

void resample(const std::vector<Pt> &g, double step, double *len, std::vector<double> &cum,
              std::vector<Pt> &out)
{
    cum.assign(g.size(), 0.0);
    for (size_t i = 1; i < g.size(); i++)
        cum[i] = cum[i - 1] + cv::norm(g[i] - g[i - 1]);
    const double L = cum.back();
    if (len)
        *len = L;
    const size_t m = std::max<size_t>(2, (size_t)std::ceil(L / step) + 1);
    out.resize(m);
    size_t j = 0;
    for (size_t i = 0; i < m; i++) {
        const double s = L * (double)i / (double)(m - 1);
        while (j + 2 < g.size() && cum[j + 1] < s)
            j++;
        const double d = cum[j + 1] - cum[j];
        const double w = d > 0 ? std::min(1.0, std::max(0.0, (s - cum[j]) / d)) : 0.0;
        out[i] = g[j] + w * (g[j + 1] - g[j]);
    }
}

void smooth(const std::vector<Pt> &c, int h, std::vector<Pt> &out)
{
    const int n = (int)c.size();
    out.assign(c.begin(), c.end());
    for (int i = 1; i + 1 < n; i++) {
        const int k = std::min(h, std::min(i, n - 1 - i));  // shrink the window near the ends
        Pt acc(0, 0);
        for (int j = i - k; j <= i + k; j++)
            acc += c[(size_t)j];
        out[(size_t)i] = acc * (1.0 / (2 * k + 1));
    }
}

// Bilinear sample of a CV_8U or CV_32F image at (x, y), 0 outside.
template <typename T>
static inline float bilinear(const cv::Mat &m, double x, double y)
{
    if (!(x >= 0 && y >= 0 && x <= m.cols - 1 && y <= m.rows - 1))
        return 0.f;
    const int x0 = std::min((int)x, m.cols - 2 < 0 ? 0 : m.cols - 2);
    const int y0 = std::min((int)y, m.rows - 2 < 0 ? 0 : m.rows - 2);
    const float fx = (float)(x - x0), fy = (float)(y - y0);
    const T *r0 = m.ptr<T>(y0), *r1 = m.ptr<T>(std::min(y0 + 1, m.rows - 1));
    const int x1 = std::min(x0 + 1, m.cols - 1);
    return (1 - fy) * ((1 - fx) * (float)r0[x0] + fx * (float)r0[x1]) +
           fy * ((1 - fx) * (float)r1[x0] + fx * (float)r1[x1]);
}

float sample_at(const cv::Mat &img, bool invert, Pt q)
{
    const float v = img.depth() == CV_8U ? bilinear<uint8_t>(img, q.x, q.y) : bilinear<float>(img, q.x, q.y);
    return invert ? 255.f - v : v;
}

void trace_pass(const cv::Mat &img, bool invert, const std::vector<Pt> &guide, double band,
                double margin, double min_contrast, double max_width, std::vector<TraceSample> &out,
                std::vector<float> &prof, std::vector<float> &tmp)
{
    out.clear();
    const size_t n = guide.size();
    if (n < 3)
        return;
    const bool u8 = img.depth() == CV_8U;
    const double d = 0.5;  // profile step, px: finer steps measured no more accurate
    const int K = (int)std::floor(band / d);
    prof.resize((size_t)(2 * K + 1));
    tmp.resize(prof.size());
    double s = 0;
    for (size_t i = 1; i < n; i++)
        s += cv::norm(guide[i] - guide[i - 1]);
    const double L = s;
    s = 0;
    for (size_t i = 0; i < n; i++) {
        if (i > 0)
            s += cv::norm(guide[i] - guide[i - 1]);
        if (s < margin || s > L - margin)
            continue;
        const Pt t = guide[std::min(i + 1, n - 1)] - guide[i > 0 ? i - 1 : 0];
        const double tl = cv::norm(t);
        if (!(tl > 0))
            continue;
        const Pt nrm(-t.y / tl, t.x / tl);
        const Pt c = guide[i];
        const Pt e0 = c - (K * d) * nrm, e1 = c + (K * d) * nrm;
        const bool inside = std::min(e0.x, e1.x) >= 0 && std::min(e0.y, e1.y) >= 0 &&
                            std::max(e0.x, e1.x) < img.cols - 1 && std::max(e0.y, e1.y) < img.rows - 1;
        if (inside && u8) {
            // The whole profile is inside the image: unchecked bilinear on the 8-bit frame.
            const float sx = (float)(d * nrm.x), sy = (float)(d * nrm.y);
            float x = (float)e0.x, y = (float)e0.y;
            const size_t step = img.step[0];
            int k0 = 0;
#if defined(__SSE2__)
            // Four points at a time: the same positions (a running sum, lane by lane), the same
            // single-precision operations in the same order on each lane, so bit for bit the
            // scalar loop's values; only the neighbours are loaded one point at a time.
            {
                const __m128 one = _mm_set1_ps(1.f), c255 = _mm_set1_ps(255.f);
                const __m128i lo8 = _mm_set1_epi32(0xff);
                alignas(16) float xs[4], ys[4];
                alignas(16) int ix[4], iy[4];
                for (; k0 + 4 <= 2 * K + 1; k0 += 4) {
                    for (int l = 0; l < 4; l++, x += sx, y += sy) {
                        xs[l] = x;
                        ys[l] = y;
                    }
                    const __m128 X = _mm_load_ps(xs), Y = _mm_load_ps(ys);
                    const __m128i IX = _mm_cvttps_epi32(X), IY = _mm_cvttps_epi32(Y);
                    const __m128 FX = _mm_sub_ps(X, _mm_cvtepi32_ps(IX)), FY = _mm_sub_ps(Y, _mm_cvtepi32_ps(IY));
                    _mm_store_si128((__m128i *)ix, IX);
                    _mm_store_si128((__m128i *)iy, IY);
                    int top[4], bot[4];
                    for (int l = 0; l < 4; l++) {
                        const uint8_t *r0 = img.data + (size_t)iy[l] * step + ix[l], *r1 = r0 + step;
                        top[l] = r0[0] | (r0[1] << 8);
                        bot[l] = r1[0] | (r1[1] << 8);
                    }
                    const __m128i T = _mm_setr_epi32(top[0], top[1], top[2], top[3]);
                    const __m128i B = _mm_setr_epi32(bot[0], bot[1], bot[2], bot[3]);
                    const __m128 P00 = _mm_cvtepi32_ps(_mm_and_si128(T, lo8));
                    const __m128 P01 = _mm_cvtepi32_ps(_mm_srli_epi32(T, 8));
                    const __m128 P10 = _mm_cvtepi32_ps(_mm_and_si128(B, lo8));
                    const __m128 P11 = _mm_cvtepi32_ps(_mm_srli_epi32(B, 8));
                    const __m128 GX = _mm_sub_ps(one, FX), GY = _mm_sub_ps(one, FY);
                    const __m128 top_v = _mm_add_ps(_mm_mul_ps(GX, P00), _mm_mul_ps(FX, P01));
                    const __m128 bot_v = _mm_add_ps(_mm_mul_ps(GX, P10), _mm_mul_ps(FX, P11));
                    __m128 V = _mm_add_ps(_mm_mul_ps(GY, top_v), _mm_mul_ps(FY, bot_v));
                    if (invert)
                        V = _mm_sub_ps(c255, V);
                    _mm_storeu_ps(prof.data() + k0, V);
                }
            }
#endif
            for (int k = k0; k <= 2 * K; k++, x += sx, y += sy) {
                const int x0 = (int)x, y0 = (int)y;
                const float fx = x - (float)x0, fy = y - (float)y0;
                const uint8_t *r0 = img.data + (size_t)y0 * step + x0, *r1 = r0 + step;
                const float v = (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
                prof[(size_t)k] = invert ? 255.f - v : v;
            }
        } else {
            for (int k = -K; k <= K; k++) {
                const Pt q = c + (k * d) * nrm;
                const float v = u8 ? bilinear<uint8_t>(img, q.x, q.y) : bilinear<float>(img, q.x, q.y);
                prof[(size_t)(k + K)] = invert ? 255.f - v : v;
            }
        }
        // Background level: the lower quartile (the band is at least twice the ribbon, so at least
        // half of the profile is background).
        // Every second sample (1 px apart) is plenty for a quartile and halves the selection.
        size_t nt = 0;
        for (size_t k = 0; k < prof.size(); k += 2)
            tmp[nt++] = prof[k];
        const size_t q = nt / 4;
        std::nth_element(tmp.begin(), tmp.begin() + (long)q, tmp.begin() + (long)nt);
        const double base = tmp[q];
        int kmax = 0;
        float vmax = prof[0];
        for (int k = 1; k < 2 * K + 1; k++)
            if (prof[(size_t)k] > vmax) {
                vmax = prof[(size_t)k];
                kmax = k;
            }
        // The ridge followed is the local maximum nearest the guide among those at least 60% as
        // high as the strongest: where another branch of the ribbon (a loop, a crossing) enters the
        // band, the strongest peak may be the other branch.
        const double hmax = prof[(size_t)kmax] - base;
        int kp = kmax;
        for (int k = 1; k < 2 * K; k++) {
            const float v = prof[(size_t)k];
            if (v - base >= 0.6 * hmax && v >= prof[(size_t)k - 1] && v > prof[(size_t)k + 1] &&
                std::abs(k - K) < std::abs(kp - K))
                kp = k;
        }
        const double peak = prof[(size_t)kp] - base;
        TraceSample ts{guide[i], s, peak, false, 0.0, base};
        const double thr = base + 0.3 * peak;
        int lo = kp, hi = kp;
        while (lo > 0 && prof[(size_t)(lo - 1)] > thr)
            lo--;
        while (hi < 2 * K && prof[(size_t)(hi + 1)] > thr)
            hi++;
        // The other branch's extent, left out of the noise estimate below.
        int lo2 = kmax, hi2 = kmax;
        if (kmax != kp) {
            const double thr2 = base + 0.3 * hmax;
            while (lo2 > 0 && prof[(size_t)(lo2 - 1)] > thr2)
                lo2--;
            while (hi2 < 2 * K && prof[(size_t)(hi2 + 1)] > thr2)
                hi2++;
            if (lo2 <= hi && hi2 >= lo) {
                // The two peaks are one blob (a shoulder of one ridge): keep the one peak.
                lo2 = hi2 = -100;
            }
        } else {
            lo2 = hi2 = -100;
        }
        // Noise: spread of the profile outside the peak (1 px clear of it on each side).
        // (In increasing k, as one loop with the test would, skipping the excluded stretches.)
        double ss = 0;
        int cnt = 0;
        for (int k = 0; k < 2 * K + 1; k++) {
            if (k >= lo - 4 && k <= hi + 4) {
                k = hi + 4;
                continue;
            }
            if (k >= lo2 - 4 && k <= hi2 + 4) {
                k = hi2 + 4;
                continue;
            }
            const double dv = prof[(size_t)k] - base;
            ss += dv * dv;
            cnt++;
        }
        const double noise = cnt >= 8 ? std::sqrt(ss / cnt) : 0.0;
        const double width = (hi - lo) * d;
        if (peak >= min_contrast && peak >= 5.0 * noise && width <= max_width + 2.0 && lo > 0 &&
            hi < 2 * K) {
            double sw = 0, so = 0;
            for (int k = lo; k <= hi; k++) {
                const double w = prof[(size_t)k] - thr;
                sw += w;
                so += w * (k - K) * d;
            }
            if (sw > 0) {
                ts.p = guide[i] + (so / sw) * nrm;
                ts.valid = true;
                ts.width = width;
            }
        }
        out.push_back(ts);
    }
}

}  // namespace vis
