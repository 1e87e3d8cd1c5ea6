// video_writer.cpp: lossless video output through OpenCV's ffmpeg backend: FFV1 in Matroska
// (.mkv), or raw Y800 in AVI (.avi) for live trials.
//
// Why two: FFV1 is compact (about a third of the raw size on the ribbon's frames) but costs 16.7 ms
// of one core per 1280x720 grey frame in Debian's OpenCV 4.6, a whole frame period at 60 fps. Raw
// Y800 is a copy (about 0.3 ms per frame, 0.9 MB per frame at 1280x720; bench_video_write measures
// both), so a live trial records every frame on time and a transcode to FFV1 can follow offline.
// OpenCV's HuffYUV, FFVHuff and UT Video writers were not bit-exact on grey frames; Y800 is.
//
// FFV1 is the codec chosen because Debian's OpenCV writes it and reads it back bit-exact (checked by
// test_vision_video); lossy codecs would bias sub-pixel tracking. Grey frames are written as grey;
// OpenCV hands them back as BGR with equal channels, which the sources convert to grey exactly.
#include "vis_internal.hpp"
#include "vis_video.h"

#include <opencv2/videoio.hpp>

#include <cstring>

struct vis_video_writer {
    cv::VideoWriter w;
    int width, height, channels;
    std::string path;
};

extern "C" vis_video_writer *vis_video_writer_open(const char *path, int width_px, int height_px,
                                                   int channels, double fps, vis_error *err)
{
    if (!path || width_px < 8 || height_px < 8 || width_px > 8192 || height_px > 8192 ||
        (channels != 1 && channels != 3) || !vis::finite(fps) || fps <= 0 || fps > 10000) {
        vis::fail(err, VIS_ERR_ARG,
                  "vis_video_writer_open: need a path, 8..8192 px, 1 or 3 channels, 0 < fps <= 10000");
        return nullptr;
    }
    const size_t len = std::strlen(path);
    const bool mkv = len >= 4 && std::strcmp(path + len - 4, ".mkv") == 0;
    const bool avi = len >= 4 && std::strcmp(path + len - 4, ".avi") == 0;
    if (!mkv && !avi) {
        vis::fail(err, VIS_ERR_ARG,
                  "video %s: lossless output needs a .mkv (FFV1 in Matroska) or .avi (raw Y800) name",
                  path);
        return nullptr;
    }
    if (avi && channels != 1) {
        vis::fail(err, VIS_ERR_ARG, "video %s: raw Y800 AVI holds grey frames only", path);
        return nullptr;
    }
    VIS_GUARD(err, nullptr, {
        vis_video_writer *v = new vis_video_writer;
        v->width = width_px;
        v->height = height_px;
        v->channels = channels;
        v->path = path;
        const int fourcc = avi ? cv::VideoWriter::fourcc('Y', '8', '0', '0')
                               : cv::VideoWriter::fourcc('F', 'F', 'V', '1');
        v->w.open(path, cv::CAP_FFMPEG, fourcc, fps, cv::Size(width_px, height_px), channels == 3);
        if (!v->w.isOpened()) {
            delete v;
            vis::fail(err, VIS_ERR_IO, "cannot open video %s for writing (%s)", path,
                      avi ? "raw Y800 AVI" : "FFV1");
            return nullptr;
        }
        vis::ok(err);
        return v;
    })
}

/* The raw writer asked for by name (the vision replays' benchmark and tests): an .avi path, grey. */
extern "C" vis_video_writer *vis_video_writer_open_y800(const char *path, int width_px, int height_px,
                                                        double fps, vis_error *err)
{
    const size_t len = path ? std::strlen(path) : 0;
    if (len < 4 || std::strcmp(path + len - 4, ".avi") != 0) {
        vis::fail(err, VIS_ERR_ARG, "video %s: raw Y800 output needs an .avi name", path ? path : "(null)");
        return nullptr;
    }
    return vis_video_writer_open(path, width_px, height_px, 1, fps, err);
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
