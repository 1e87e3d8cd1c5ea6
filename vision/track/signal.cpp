// signal.cpp: from a grey frame to a ridge signal the tracer can follow.
//
// Uneven lighting and either polarity are handled in one step: the ribbon is thinner than
// `ribbon_max_px`, so a morphological closing (dark ribbon) or opening (light ribbon) with a larger
// square removes it and leaves the local background; the difference (black-hat / top-hat) is the
// ribbon's contrast above its own surroundings, zero on flat background however bright. Clamp jaws
// and clutter larger than the square vanish as well. Only the region of interest around the expected
// curve is filtered, which keeps the per-frame cost proportional to the ribbon, not the image.
// Exposure and polarity come from the 256-bin histogram (no sort, no allocation per frame).
#include "tracker_impl.hpp"

#include <opencv2/imgproc.hpp>

namespace vis {

namespace {
// Histogram of every second pixel of every second row (a quarter of the cost; a ribbon a few
// pixels thick still contributes its share); every fourth of every fourth on large frames.
void histogram(const cv::Mat &g, double h[256], double &total)
{
    // Integer counts (two tables, so consecutive pixels of one grey level do not wait on each
    // other), exact, then the same doubles as counting in doubles directly.
    uint32_t c[2][256] = {{0}};
    total = 0;
    const int st = (double)g.rows * g.cols > 5e5 ? 4 : 2;
    for (int y = 0; y < g.rows; y += st) {
        const uint8_t *r = g.ptr<uint8_t>(y);
        int x = 0;
        for (; x + st < g.cols; x += 2 * st) {
            c[0][r[x]]++;
            c[1][r[x + st]]++;
        }
        for (; x < g.cols; x += st)
            c[0][r[x]]++;
    }
    for (int i = 0; i < 256; i++) {
        h[i] = (double)(c[0][i] + c[1][i]);
        total += h[i];
    }
}
int percentile(const double h[256], double total, double q)
{
    double acc = 0;
    for (int i = 0; i < 256; i++) {
        acc += h[i];
        if (acc >= q * total)
            return i;
    }
    return 255;
}
}  // namespace

Exposure exposure_check(const cv::Mat &grey, double min_contrast)
{
    double h[256], total;
    histogram(grey, h, total);
    const int lo = percentile(h, total, 0.001), hi = percentile(h, total, 0.999);
    const int med = percentile(h, total, 0.5);
    if (hi - lo < min_contrast || (h[0] + h[1] + h[2]) > 0.95 * total ||
        (h[255] + h[254] + h[253]) > 0.95 * total)
        return med < 128 ? Exposure::dark : Exposure::saturated;
    return Exposure::ok;
}

bool noise_check(const cv::Mat &grey, double min_contrast)
{
    // For independent pixels E|I(x+1) - I(x)| = 2 sigma / sqrt(pi) (Gaussian) or sqrt(2/3) sigma
    // (uniform): about 0.8 sqrt(2) sigma. A frame with structure (backdrop, ribbon, jaws, blur)
    // has neighbours far more alike than that. Every eighth row, every second pair.
    // Integer sums: exact, so the same values as summing in doubles, and they vectorise.
    int64_t isd = 0, is1 = 0, is2 = 0, in = 0;
    for (int y = 0; y < grey.rows; y += 8) {
        const uint8_t *r = grey.ptr<uint8_t>(y);
        uint32_t rsd = 0, rs1 = 0, rs2 = 0;  // one row: at most 10000 pairs * 65025 < 2^32
        int x = 0;
        for (; x + 1 < grey.cols; x += 2) {
            const uint32_t a = r[x], b = r[x + 1];
            rsd += a > b ? a - b : b - a;
            rs1 += a;
            rs2 += a * a;
        }
        isd += rsd;
        is1 += rs1;
        is2 += rs2;
        in += x / 2;
    }
    const double sd = (double)isd, s1 = (double)is1, s2 = (double)is2, n = (double)in;
    if (n < 16)
        return false;
    const double var = s2 / n - (s1 / n) * (s1 / n);
    const double sigma = var > 0 ? std::sqrt(var) : 0.0;
    return sigma > 2.0 * std::max(min_contrast, 1.0) && sd / n > 0.6 * std::sqrt(2.0) * sigma;
}

bool polarity_is_dark(const cv::Mat &grey)
{
    double h[256], total;
    histogram(grey, h, total);
    const int lo = percentile(h, total, 0.002), hi = percentile(h, total, 0.998);
    const int med = percentile(h, total, 0.5);
    return med - lo >= hi - med;
}

void ridge_signal(const cv::Mat &grey, bool dark, int r, cv::Rect roi, cv::Mat &work, cv::Mat &sig)
{
    // Pad the ROI by the kernel radius so the filter sees the background around the ribbon.
    const cv::Rect img(0, 0, grey.cols, grey.rows);
    const cv::Rect big = cv::Rect(roi.x - r, roi.y - r, roi.width + 2 * r, roi.height + 2 * r) & img;
    const cv::Mat k = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1));
    cv::morphologyEx(grey(big), work, dark ? cv::MORPH_BLACKHAT : cv::MORPH_TOPHAT, k,
                     cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
    sig.create(grey.rows, grey.cols, CV_32F);
    sig.setTo(0);
    work.convertTo(sig(big), CV_32F);
}

}  // namespace vis
