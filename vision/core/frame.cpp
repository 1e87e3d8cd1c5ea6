// frame.cpp: the vis_frame image handle (8-bit, grey or BGR) and its file input/output.
//
// A frame wraps a cv::Mat so that the C side sees only width, height, channels, stride and a data
// pointer. Frames are reallocated by the calls that fill them, so a caller can allocate one frame
// before a loop and reuse it for every read (no allocation per frame once sizes settle).
#include "vis_internal.hpp"
#include "image_header.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace vis {
cv::Mat grey_of(const cv::Mat &m)
{
    if (m.channels() == 1)
        return m;
    cv::Mat g;
    cv::cvtColor(m, g, m.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
    return g;
}
}  // namespace vis

extern "C" vis_frame *vis_frame_alloc(int w, int h, int channels, vis_error *err)
{
    if (w < 1 || h < 1 || w > 20000 || h > 20000 || (channels != 1 && channels != 3)) {
        vis::fail(err, VIS_ERR_ARG, "frame size %dx%dx%d out of range (1..20000, 1 or 3 channels)",
                  w, h, channels);
        return nullptr;
    }
    VIS_GUARD(err, nullptr, {
        vis_frame *f = new vis_frame;
        f->mat = cv::Mat::zeros(h, w, channels == 1 ? CV_8UC1 : CV_8UC3);
        vis::ok(err);
        return f;
    })
}

extern "C" void vis_frame_free(vis_frame *f) { delete f; }
extern "C" int vis_frame_width(const vis_frame *f) { return f ? f->mat.cols : 0; }
extern "C" int vis_frame_height(const vis_frame *f) { return f ? f->mat.rows : 0; }
extern "C" int vis_frame_channels(const vis_frame *f) { return f ? f->mat.channels() : 0; }
extern "C" size_t vis_frame_stride(const vis_frame *f) { return f ? f->mat.step[0] : 0; }
extern "C" uint8_t *vis_frame_data(vis_frame *f) { return f ? f->mat.data : nullptr; }

extern "C" vis_status vis_frame_copy(const vis_frame *src, vis_frame *dst, vis_error *err)
{
    if (!src || !dst)
        return vis::fail(err, VIS_ERR_ARG, "vis_frame_copy: NULL frame");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        src->mat.copyTo(dst->mat);  // reallocates only when the size or type differs
        vis::ok(err);
        return VIS_OK;
    })
}

extern "C" vis_status vis_frame_save(const vis_frame *f, const char *path, vis_error *err)
{
    if (!f || !path || f->mat.empty())
        return vis::fail(err, VIS_ERR_ARG, "vis_frame_save: no frame or path");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        if (!cv::imwrite(path, f->mat))
            return vis::fail(err, VIS_ERR_IO, "cannot write image %s", path);
        vis::ok(err);
        return VIS_OK;
    })
}

extern "C" vis_status vis_frame_load(vis_frame *f, const char *path, vis_error *err)
{
    if (!f || !path)
        return vis::fail(err, VIS_ERR_ARG, "vis_frame_load: no frame or path");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        if (vis::image_size_check(path, err) != VIS_OK)
            return VIS_ERR_TOO_LARGE;
        cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
        if (m.empty())
            return vis::fail(err, VIS_ERR_FORMAT, "cannot read image %s (missing or damaged)", path);
        if (m.depth() != CV_8U) {
            cv::Mat c;
            m.convertTo(c, CV_8U, m.depth() == CV_16U ? 1.0 / 256.0 : 1.0);
            m = c;
        }
        if (m.channels() == 4)
            cv::cvtColor(m, m, cv::COLOR_BGRA2BGR);
        f->mat = m;
        vis::ok(err);
        return VIS_OK;
    })
}
