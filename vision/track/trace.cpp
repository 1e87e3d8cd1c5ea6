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
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace vis {

namespace {
// The nearest ridge is followed if it stands at least this share of the strongest in the band. An
// edge-on stretch beside a face-on one reads about half as high: at the narrow loop of the
// simulator family's Delta L 0.7 trial (state 614) the edge-on leg's dip is 77 grey levels and the
// face-on leg's beside it 156 (0.49), and with 0.6 the tracer jumped to the face-on leg there.
const double NEAR_SHARE = 0.4;
}  // namespace

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

// The lower quartile of every second value of the profile p[0..n) (the (nt / 4)-th smallest of
// the nt values at even k): the q + 1 smallest kept sorted in `b` by insertion, one pass. The
// same value as std::nth_element on a copy (a selection, nothing summed).
static float lower_quartile(const float *p, size_t n, float *b)
{
    const size_t nt = (n + 1) / 2, q = nt / 4;
    size_t m = 0;  // values kept, sorted increasing: b[0..m)
    for (size_t k = 0; k < n; k += 2) {
        const float v = p[k];
        if (m == q + 1) {
            if (!(v < b[q]))
                continue;
            m--;  // b[q] drops out
        }
        size_t j = m++;
        for (; j > 0 && b[j - 1] > v; j--)
            b[j] = b[j - 1];
        b[j] = v;
    }
    return b[q];
}

#if defined(__SSE2__)
// The same for four profiles of n values at p, p + n, p + 2 n, p + 3 n at once, one per lane, for
// q = nt / 4 == Q: the Q + 1 smallest kept sorted in registers, each value inserted without a
// branch (b[j] = min(b[j], max(b[j - 1], v)) keeps a sorted list sorted, v in its place and the
// largest out).
template <int Q>
static void lower_quartiles4(const float *p, size_t n, float *base)
{
    __m128 b[Q + 1];
    for (int j = 0; j <= Q; j++)
        b[j] = _mm_set1_ps(INFINITY);
    for (size_t k = 0; k < n; k += 2) {
        const __m128 v = _mm_setr_ps(p[k], p[n + k], p[2 * n + k], p[3 * n + k]);
        for (int j = Q; j > 0; j--)
            b[j] = _mm_min_ps(b[j], _mm_max_ps(b[j - 1], v));
        b[0] = _mm_min_ps(b[0], v);
    }
    _mm_storeu_ps(base, b[Q]);
}
#endif

// The lower quartiles of nb profiles of n values each, one after the other at p, into base;
// `b` is scratch of n values.
static void lower_quartiles(const float *p, size_t n, int nb, float *base, float *b)
{
#if defined(__SSE2__)
    if (nb == 4)
        switch ((n + 1) / 2 / 4) {
        case 4: lower_quartiles4<4>(p, n, base); return;
        case 5: lower_quartiles4<5>(p, n, base); return;
        case 6: lower_quartiles4<6>(p, n, base); return;
        case 7: lower_quartiles4<7>(p, n, base); return;
        default: break;
        }
#endif
    for (int j = 0; j < nb; j++)
        base[j] = lower_quartile(p + (size_t)j * n, n, b);
}

// Index of the first largest value of p[0..n) (what a scan keeping strict improvements finds):
// the largest value four lanes at a time, then its first position.
static int first_max(const float *p, size_t n)
{
    float vmax = p[0];
    size_t k = 0;
#if defined(__SSE2__)
    if (n >= 4) {
        __m128 m = _mm_loadu_ps(p);
        for (k = 4; k + 4 <= n; k += 4)
            m = _mm_max_ps(m, _mm_loadu_ps(p + k));
        m = _mm_max_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(2, 3, 0, 1)));
        m = _mm_max_ps(m, _mm_shuffle_ps(m, m, _MM_SHUFFLE(1, 0, 3, 2)));
        vmax = _mm_cvtss_f32(m);
    }
#endif
    for (; k < n; k++)
        vmax = p[k] > vmax ? p[k] : vmax;
    k = 0;
#if defined(__SSE2__)
    const __m128 vm = _mm_set1_ps(vmax);
    for (; k + 4 <= n; k += 4) {
        const int hit = _mm_movemask_ps(_mm_cmpeq_ps(_mm_loadu_ps(p + k), vm));
        if (hit)
            return (int)k + __builtin_ctz((unsigned)hit);
    }
#endif
    while (p[k] != vmax)
        k++;
    return (int)k;
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
    const size_t P = (size_t)(2 * K + 1);  // values in a profile
    prof.resize(4 * P);                    // four profiles
    tmp.resize(P + 4);                     // selection scratch, then their four background levels
    double s = 0;
    for (size_t i = 1; i < n; i++)
        s += cv::norm(guide[i] - guide[i - 1]);
    const double L = s;
    s = 0;
    // Four normals at a time: their profiles, then their four background levels together, then
    // each profile's ridge, in the guide's order.
    size_t i = 0;
    for (;;) {
        size_t idx[4];
        double sv[4];
        Pt nv[4];
        int nb = 0;
        for (; i < n && nb < 4; i++) {
            if (i > 0)
                s += cv::norm(guide[i] - guide[i - 1]);
            if (s < margin || s > L - margin)
                continue;
            const Pt t = guide[std::min(i + 1, n - 1)] - guide[i > 0 ? i - 1 : 0];
            const double tl = cv::norm(t);
            if (!(tl > 0))
                continue;
            const Pt nrm(-t.y / tl, t.x / tl);
            float *const pr = prof.data() + (size_t)nb * P;
            idx[nb] = i;
            sv[nb] = s;
            nv[nb] = nrm;
            nb++;
            const Pt c = guide[i];
            const Pt e0 = c - (K * d) * nrm, e1 = c + (K * d) * nrm;
            const bool inside = std::min(e0.x, e1.x) >= 0 && std::min(e0.y, e1.y) >= 0 &&
                                std::max(e0.x, e1.x) < img.cols - 1 && std::max(e0.y, e1.y) < img.rows - 1;
            if (inside && u8) {
                // The whole profile is inside the image: unchecked bilinear on the 8-bit frame.
                const float sx = (float)(d * nrm.x), sy = (float)(d * nrm.y);
                float x = (float)e0.x, y = (float)e0.y;
                const size_t step = img.step[0];
                const uint8_t *const data = img.data;
                int k0 = 0;
#if defined(__SSE2__) && defined(__x86_64__)
                // Four points at a time: the same positions (a running sum, lane by lane: x and y side
                // by side in one register), the same single-precision operations in the same order on
                // each lane, so bit for bit the scalar loop's values. The row offsets y0 * step come
                // from 16-bit multiplies (exact: both below 2^15, which the frame's size is checked for)
                // and each point's four neighbours are inserted as two 16-bit words into one lane
                // (top pair low, bottom pair high).
                if (step < 32768 && img.rows < 32768) {
                    const __m128 one = _mm_set1_ps(1.f), c255 = _mm_set1_ps(255.f);
                    const __m128i lo8 = _mm_set1_epi32(0xff), step16 = _mm_set1_epi32((int)step);
                    const __m128 sxy = _mm_setr_ps(sx, sy, 0.f, 0.f);
                    __m128 xy = _mm_setr_ps(x, y, 0.f, 0.f);
                    auto word = [](const uint8_t *q) {
                        uint16_t w;
                        memcpy(&w, q, 2);
                        return (int)w;
                    };
                    for (; k0 + 4 <= 2 * K + 1; k0 += 4) {
                        const __m128 p0 = xy, p1 = _mm_add_ps(p0, sxy), p2 = _mm_add_ps(p1, sxy),
                                     p3 = _mm_add_ps(p2, sxy);
                        xy = _mm_add_ps(p3, sxy);
                        const __m128 q01 = _mm_movelh_ps(p0, p1), q23 = _mm_movelh_ps(p2, p3);  // x y x y
                        const __m128 X = _mm_shuffle_ps(q01, q23, _MM_SHUFFLE(2, 0, 2, 0));
                        const __m128 Y = _mm_shuffle_ps(q01, q23, _MM_SHUFFLE(3, 1, 3, 1));
                        const __m128i IX = _mm_cvttps_epi32(X), IY = _mm_cvttps_epi32(Y);
                        const __m128 FX = _mm_sub_ps(X, _mm_cvtepi32_ps(IX)), FY = _mm_sub_ps(Y, _mm_cvtepi32_ps(IY));
                        const __m128i OFF = _mm_add_epi32(_mm_madd_epi16(IY, step16), IX);
                        const uint64_t o01 = (uint64_t)_mm_cvtsi128_si64(OFF),
                                       o23 = (uint64_t)_mm_cvtsi128_si64(_mm_unpackhi_epi64(OFF, OFF));
                        const uint8_t *r0 = data + (uint32_t)o01, *r1 = data + (o01 >> 32),
                                      *r2 = data + (uint32_t)o23, *r3 = data + (o23 >> 32);
                        __m128i T = _mm_cvtsi32_si128(word(r0));
                        T = _mm_insert_epi16(T, word(r1), 2);
                        T = _mm_insert_epi16(T, word(r2), 4);
                        T = _mm_insert_epi16(T, word(r3), 6);
                        __m128i B = _mm_cvtsi32_si128(word(r0 + step) << 16);
                        B = _mm_insert_epi16(B, word(r1 + step), 3);
                        B = _mm_insert_epi16(B, word(r2 + step), 5);
                        B = _mm_insert_epi16(B, word(r3 + step), 7);
                        const __m128i TB = _mm_or_si128(T, B);  // per lane: r0[0], r0[1], r1[0], r1[1]
                        const __m128 P00 = _mm_cvtepi32_ps(_mm_and_si128(TB, lo8));
                        const __m128 P01 = _mm_cvtepi32_ps(_mm_and_si128(_mm_srli_epi32(TB, 8), lo8));
                        const __m128 P10 = _mm_cvtepi32_ps(_mm_and_si128(_mm_srli_epi32(TB, 16), lo8));
                        const __m128 P11 = _mm_cvtepi32_ps(_mm_srli_epi32(TB, 24));
                        const __m128 GX = _mm_sub_ps(one, FX), GY = _mm_sub_ps(one, FY);
                        const __m128 top_v = _mm_add_ps(_mm_mul_ps(GX, P00), _mm_mul_ps(FX, P01));
                        const __m128 bot_v = _mm_add_ps(_mm_mul_ps(GX, P10), _mm_mul_ps(FX, P11));
                        __m128 V = _mm_add_ps(_mm_mul_ps(GY, top_v), _mm_mul_ps(FY, bot_v));
                        if (invert)
                            V = _mm_sub_ps(c255, V);
                        _mm_storeu_ps(pr + k0, V);
                    }
                    x = _mm_cvtss_f32(xy);
                    y = _mm_cvtss_f32(_mm_shuffle_ps(xy, xy, _MM_SHUFFLE(1, 1, 1, 1)));
                }
#endif
                for (int k = k0; k <= 2 * K; k++, x += sx, y += sy) {
                    const int x0 = (int)x, y0 = (int)y;
                    const float fx = x - (float)x0, fy = y - (float)y0;
                    const uint8_t *r0 = data + (size_t)y0 * step + x0, *r1 = r0 + step;
                    const float v = (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
                    pr[k] = invert ? 255.f - v : v;
                }
            } else {
                for (int k = -K; k <= K; k++) {
                    const Pt q = c + (k * d) * nrm;
                    const float v = u8 ? bilinear<uint8_t>(img, q.x, q.y) : bilinear<float>(img, q.x, q.y);
                    pr[k + K] = invert ? 255.f - v : v;
                }
            }
        }
        if (nb == 0)
            break;
        // Background level: the lower quartile (the band is at least twice the ribbon, so at least
        // half of the profile is background).
        // Every second sample (1 px apart) is plenty for a quartile and halves the selection.
        float *const bases = tmp.data() + P;
        lower_quartiles(prof.data(), P, nb, bases, tmp.data());
        for (int jb = 0; jb < nb; jb++) {
            const float *const pf = prof.data() + (size_t)jb * P;
            const size_t ii = idx[jb];
            const Pt nrm = nv[jb];
            const double base = bases[jb];
            const int kmax = first_max(pf, P);
            // The ridge followed is the local maximum nearest the guide among those at least
            // NEAR_SHARE as high as the strongest: where another branch of the ribbon (a loop, a
            // crossing) enters the band, the strongest peak may be the other branch. (Searched outward from the guide, lower
            // side first: the first one found is the one a scan in increasing k keeps, the nearest and,
            // of two as near, the lower; none nearer than the strongest leaves the strongest.)
            const double hmax = pf[(size_t)kmax] - base;
            int kp = kmax;
            const int dmax = std::abs(kmax - K);
            for (int dk = 0; dk < dmax && kp == kmax; dk++)
                for (int k = K - dk; k <= K + dk; k += dk > 0 ? 2 * dk : 1) {
                    const float v = pf[(size_t)k];
                    if (k >= 1 && k < 2 * K && v - base >= std::max(NEAR_SHARE * hmax, min_contrast) &&
                        v >= pf[(size_t)k - 1] && v > pf[(size_t)k + 1]) {
                        kp = k;
                        break;
                    }
                }
            // The stretch around k above t (stopping at the band's ends).
            auto extent = [&](int k, double t, int &a, int &b) {
                a = b = k;
                while (a > 0 && pf[(size_t)(a - 1)] > t)
                    a--;
                while (b < 2 * K && pf[(size_t)(b + 1)] > t)
                    b++;
            };
            const double peak = pf[(size_t)kp] - base;
            TraceSample ts{guide[ii], sv[jb], peak, false, 0.0, base};
            const double thr = base + 0.3 * peak;
            int lo, hi;
            extent(kp, thr, lo, hi);
            // The other branch's extent, left out of the noise estimate below.
            int lo2 = -100, hi2 = -100;
            if (kmax != kp) {
                extent(kmax, base + 0.3 * hmax, lo2, hi2);
                if (lo2 <= hi && hi2 >= lo) {
                    // The two peaks are one blob (a shoulder of one ridge): keep the one peak.
                    lo2 = hi2 = -100;
                }
            } else {
                // The strongest is the one followed: another branch in the band (the other leg of a
                // narrow loop, which may run on past the band's end) is the highest point outside the
                // ridge's extent, if it stands out as a ribbon would (at least min_contrast).
                int k2 = -1;
                for (int k = 0; k < 2 * K + 1; k++)
                    if ((k < lo - 1 || k > hi + 1) && (k2 < 0 || pf[(size_t)k] > pf[(size_t)k2]))
                        k2 = k;
                if (k2 >= 0 && pf[(size_t)k2] - base >= std::max(0.3 * peak, min_contrast))
                    extent(k2, thr, lo2, hi2);
            }
            // Noise: spread of the profile outside the peak (1 px clear of it on each side) and
            // outside the other branch's (counted as noise, a narrow loop's second leg made every
            // sample beside it invalid: a third of the arc at the simulator family's state 614).
            // (In increasing k, as one loop with the test would, skipping the excluded stretches.)
            const int a1 = lo - 4, b1 = hi + 4;
            auto spread = [&](int a2, int b2, int &cnt) {
                double ss = 0;
                cnt = 0;
                for (int k = 0; k < 2 * K + 1;) {
                    if (k >= a1 && k <= b1) {
                        k = b1 + 1;
                        continue;
                    }
                    if (k >= a2 && k <= b2) {
                        k = b2 + 1;
                        continue;
                    }
                    int end = 2 * K + 1;  // up to the next excluded stretch
                    if (a1 > k)
                        end = std::min(end, a1);
                    if (a2 > k)
                        end = std::min(end, a2);
                    cnt += end - k;
                    for (; k < end; k++) {
                        const double dv = pf[(size_t)k] - base;
                        ss += dv * dv;
                    }
                }
                return ss;
            };
            int cnt;
            double ss = spread(lo2 - 4, hi2 + 4, cnt);
            // Left out, the other branch may leave too little of the profile to read the noise on
            // (8 values): then it stays in.
            if (cnt < 8 && lo2 >= 0)
                ss = spread(-100, -100, cnt);
            const double noise = cnt >= 8 ? std::sqrt(ss / cnt) : 0.0;
            const double width = (hi - lo) * d;
            if (peak >= min_contrast && peak >= 5.0 * noise && width <= max_width + 2.0 && lo > 0 &&
                hi < 2 * K) {
                double sw = 0, so = 0, kk = lo - K;  // kk = k - K, exact
                for (int k = lo; k <= hi; k++, kk += 1.0) {
                    const double w = pf[(size_t)k] - thr;
                    sw += w;
                    so += w * kk * d;
                }
                if (sw > 0) {
                    ts.p = guide[ii] + (so / sw) * nrm;
                    ts.valid = true;
                    ts.width = width;
                }
            }
            out.push_back(ts);
        }
    }
}

}  // namespace vis
