// overlay.cpp: draws the tracker's result over a frame, for the overlay video and for eyes.
//
// Green centreline, red midpoint, and a text line (frame, Delta Z, A, quality, or the reason). The
// input may be grey or BGR; the output is always BGR.
#include "vis_internal.hpp"
#include "vis_track.h"

#include <opencv2/imgproc.hpp>

#include <cstdio>
#include <vector>

extern "C" vis_status vis_overlay_draw_curve(const vis_frame *in, const double *uv, size_t n, const vis_measure *m,
                                             int frame, vis_frame *out, vis_error *err)
{
    if (!in || !out || !m || in->mat.empty() || (n > 0 && !uv))
        return vis::fail(err, VIS_ERR_ARG, "vis_overlay_draw: NULL or empty argument");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        cv::Mat bgr;
        if (in->mat.channels() == 1)
            cv::cvtColor(in->mat, bgr, cv::COLOR_GRAY2BGR);
        else
            bgr = in->mat.clone();
        const int shift = 4;  // sub-pixel drawing
        const double sc = 1 << shift;
        // Pixel -> fixed point, clamped so that no coordinate can overflow an int.
        auto fx = [&](double v) { return (int)std::lround(std::isfinite(v) ? std::min(1e5, std::max(-1e5, v)) * sc : 0.0); };
        if (m->reason == VIS_REASON_NONE) {
            std::vector<cv::Point> pts(n);
            for (size_t i = 0; i < n; i++)
                pts[i] = cv::Point(fx(uv[2 * i]), fx(uv[2 * i + 1]));
            if (n >= 2)
                cv::polylines(bgr, pts, false, cv::Scalar(0, 200, 0), 1, cv::LINE_AA, shift);
            cv::circle(bgr, cv::Point(fx(m->mid_px[0]), fx(m->mid_px[1])),
                       3 << shift, cv::Scalar(0, 0, 255), 1, cv::LINE_AA, shift);
        }
        char text[160];
        if (m->reason == VIS_REASON_NONE)
            std::snprintf(text, sizeof text, "frame %d dZ=%+.4f A=%+.4f q=%.2f", frame, m->dz, m->a, m->quality);
        else
            std::snprintf(text, sizeof text, "frame %d %s", frame, vis_reason_str(m->reason));
        const double fs = std::max(0.35, bgr.cols / 900.0);
        cv::putText(bgr, text, cv::Point(4, (int)(14 * fs / 0.35 * 0.9)), cv::FONT_HERSHEY_SIMPLEX, fs,
                    cv::Scalar(0, 0, 255), 1, cv::LINE_AA);
        out->mat = bgr;
        vis::ok(err);
        return VIS_OK;
    })
}

extern "C" vis_status vis_overlay_draw(const vis_frame *in, const vis_tracker *t, const vis_measure *m,
                                       int frame, vis_frame *out, vis_error *err)
{
    if (!in || !out || !m || in->mat.empty())
        return vis::fail(err, VIS_ERR_ARG, "vis_overlay_draw: NULL or empty argument");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        const size_t n = t && m->reason == VIS_REASON_NONE ? vis_tracker_curve(t, nullptr, 0) : 0;
        std::vector<double> uv(2 * n);
        vis_tracker_curve(t, uv.data(), n);
        return vis_overlay_draw_curve(in, uv.data(), n, m, frame, out, err);
    })
}
