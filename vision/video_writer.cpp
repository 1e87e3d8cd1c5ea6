// video_writer.cpp: lossless video output (FFV1 in Matroska; or, by vis_video_writer_open_y800,
// raw 8-bit grey Y800 in AVI: no compression, so decoding costs next to nothing) through OpenCV's
// ffmpeg backend. vis_video_writer_open keeps refusing other names (an .avi there would be taken
// for a lossy codec); the raw writer is asked for by name.
//
// FFV1 is the codec chosen because Debian's OpenCV writes it and reads it back bit-exact (checked by
// test_vision_video); lossy codecs would bias sub-pixel tracking. Grey frames are written as grey;
// OpenCV hands them back as BGR with equal channels, which the sources convert to grey exactly.
#include "vis_internal.hpp"

#include <opencv2/videoio.hpp>

#include <cstring>

struct vis_video_writer {
    cv::VideoWriter w;
    int width, height, channels;
    std::string path;
};

static vis_video_writer *writer_open(const char *path, int width_px, int height_px, int channels,
                                     double fps, bool y800, vis_error *err);

extern "C" vis_video_writer *vis_video_writer_open(const char *path, int width_px, int height_px,
                                                   int channels, double fps, vis_error *err)
{
    return writer_open(path, width_px, height_px, channels, fps, false, err);
}

extern "C" vis_video_writer *vis_video_writer_open_y800(const char *path, int width_px, int height_px,
                                                        double fps, vis_error *err)
{
    return writer_open(path, width_px, height_px, 1, fps, true, err);
}

static vis_video_writer *writer_open(const char *path, int width_px, int height_px, int channels,
                                     double fps, bool y800, vis_error *err)
{
    if (!path || width_px < 8 || height_px < 8 || width_px > 8192 || height_px > 8192 ||
        (channels != 1 && channels != 3) || !vis::finite(fps) || fps <= 0 || fps > 10000) {
        vis::fail(err, VIS_ERR_ARG,
                  "vis_video_writer_open: need a path, 8..8192 px, 1 or 3 channels, 0 < fps <= 10000");
        return nullptr;
    }
    const size_t len = std::strlen(path);
    if (y800 && (len < 4 || std::strcmp(path + len - 4, ".avi") != 0)) {
        vis::fail(err, VIS_ERR_ARG, "video %s: raw Y800 output needs an .avi name", path);
        return nullptr;
    }
    if (!y800 && (len < 4 || std::strcmp(path + len - 4, ".mkv") != 0)) {
        vis::fail(err, VIS_ERR_ARG, "video %s: lossless output needs a .mkv name (FFV1 in Matroska)",
                  path);
        return nullptr;
    }
    VIS_GUARD(err, nullptr, {
        vis_video_writer *v = new vis_video_writer;
        v->width = width_px;
        v->height = height_px;
        v->channels = channels;
        v->path = path;
        const int fcc = y800 ? cv::VideoWriter::fourcc('Y', '8', '0', '0')
                             : cv::VideoWriter::fourcc('F', 'F', 'V', '1');
        v->w.open(path, cv::CAP_FFMPEG, fcc, fps, cv::Size(width_px, height_px), channels == 3);
        if (!v->w.isOpened()) {
            delete v;
            vis::fail(err, VIS_ERR_IO, "cannot open video %s for writing (%s)", path, y800 ? "Y800" : "FFV1");
            return nullptr;
        }
        vis::ok(err);
        return v;
    })
}

extern "C" vis_status vis_video_writer_write(vis_video_writer *v, const vis_frame *f, vis_error *err)
{
    if (!v || !f)
        return vis::fail(err, VIS_ERR_ARG, "vis_video_writer_write: NULL argument");
    if (f->mat.cols != v->width || f->mat.rows != v->height || f->mat.channels() != v->channels)
        return vis::fail(err, VIS_ERR_ARG, "video %s: frame %dx%dx%d does not match %dx%dx%d",
                         v->path.c_str(), f->mat.cols, f->mat.rows, f->mat.channels(), v->width,
                         v->height, v->channels);
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        v->w.write(f->mat);
        vis::ok(err);
        return VIS_OK;
    })
}

extern "C" void vis_video_writer_close(vis_video_writer *v)
{
    if (!v)
        return;
    try {
        v->w.release();
    } catch (...) {
        // Nothing more can be done with a writer that fails to close; the reader reports damage.
    }
    delete v;
}
