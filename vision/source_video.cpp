// source_video.cpp: frames from a video file or a live camera (OpenCV VideoCapture).
//
// Damage detection: the container announces a frame count; a file that stops delivering frames
// before that count is damaged (truncated or corrupt), and the read says so, naming the last good
// frame, instead of looking like a clean end. Frames already read stay valid: the caller keeps
// everything up to the damage. A file whose container announces no count at all has lost its index
// (Matroska's duration and cues are written last, so a writer killed by a signal or a full disk
// leaves none): its end is damage too, never a clean end. Cameras have no count: a failed grab is
// an I/O error.
#include "source.hpp"
#include "image_header.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cerrno>
#include <cstring>
#include <sys/stat.h>

namespace vis {
namespace {

class VideoSource : public Source {
public:
    cv::VideoCapture cap;
    std::string name;
    bool live = false;
    int count = -1;
    double rate = 0;
    int index = 0;
    cv::Mat raw;

    vis_status read(cv::Mat &grey, double &t_s, vis_error *err) override
    {
        if (!cap.read(raw) || raw.empty()) {
            if (live)
                return fail(err, VIS_ERR_IO, "camera %s: no frame after frame %d", name.c_str(),
                            index - 1);
            if (count > 0 && index < count)
                return fail(err, VIS_ERR_FORMAT,
                            "video %s is damaged: %d of %d announced frames readable (last good "
                            "frame %d)",
                            name.c_str(), index, count, index - 1);
            if (count <= 0)
                return fail(err, VIS_ERR_FORMAT,
                            "video %s is damaged: its container announces no frame count (index "
                            "missing: the writer was killed or its disk filled?); %d frames readable",
                            name.c_str(), index);
            return fail(err, VIS_ERR_END, "end of video %s after %d frames", name.c_str(), index);
        }
        if (raw.depth() != CV_8U)
            raw.convertTo(raw, CV_8U);
        if (raw.channels() == 1)
            raw.copyTo(grey);
        else
            cv::cvtColor(raw, grey, raw.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
        t_s = rate > 0 ? index / rate : cap.get(cv::CAP_PROP_POS_MSEC) * 1e-3;
        index++;
        return VIS_OK;
    }
    // A live V4L2 camera: OpenCV's V4L2 backend answers CAP_PROP_POS_MSEC with the dequeued
    // buffer's timestamp (struct v4l2_buffer.timestamp, in ms), which UVC drivers take from
    // CLOCK_MONOTONIC at the frame's start of capture. OpenCV hides the buffer's sequence number, so
    // ids are counted here and V4L2 drops are not visible as id gaps (said in docs/rig-realtime.md).
    vis_status read_meta(cv::Mat &grey, vis_frame_meta &m, vis_error *err) override
    {
        if (!live)
            return Source::read_meta(grey, m, err);
        double t = 0;
        vis_status s = read(grey, t, err);
        m.host_t_s = monotonic_s();
        const double ms = cap.get(cv::CAP_PROP_POS_MSEC);
        m.camera_t_s = ms > 0 && std::isfinite(ms) ? ms * 1e-3 : NAN;
        m.frame_id = counted++;
        m.lost_before = 0;
        m.incomplete = 0;
        return s;
    }
    int frame_count() const override { return count; }
    double fps() const override { return rate; }
};

}  // namespace

Source *source_video_open(const char *path, vis_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        fail(err, VIS_ERR_IO, "video %s: %s", path, std::strerror(errno));
        return nullptr;
    }
    if (!S_ISREG(st.st_mode)) {
        fail(err, VIS_ERR_IO, "video %s: not a regular file (%s)", path,
             S_ISDIR(st.st_mode)    ? "a directory"
             : S_ISCHR(st.st_mode)  ? "a character device"
             : S_ISBLK(st.st_mode)  ? "a block device"
             : S_ISFIFO(st.st_mode) ? "a FIFO"
                                    : "a socket or other special file");
        return nullptr;
    }
    // A still image opened as a one-frame video: its size from the header, before decoding.
    if (image_size_check(path, err) != VIS_OK)
        return nullptr;
    VideoSource *s = new VideoSource;
    s->name = path;
    if (!s->cap.open(path, cv::CAP_FFMPEG) || !s->cap.isOpened()) {
        delete s;
        fail(err, VIS_ERR_FORMAT, "video %s cannot be decoded (not a video or damaged header)", path);
        return nullptr;
    }
    // The stream's frame size from the container, before any frame is decoded.
    const double fw = s->cap.get(cv::CAP_PROP_FRAME_WIDTH), fh = s->cap.get(cv::CAP_PROP_FRAME_HEIGHT);
    if (fw > VIS_MAX_IMAGE_SIDE || fh > VIS_MAX_IMAGE_SIDE || fw * fh > VIS_MAX_IMAGE_PIXELS) {
        delete s;
        fail(err, VIS_ERR_TOO_LARGE, "image too large: video %s has %.0f x %.0f px frames, above the limit of %d px a side and "
             "%.0f Mpx", path, fw, fh, VIS_MAX_IMAGE_SIDE, VIS_MAX_IMAGE_PIXELS / 1e6);
        return nullptr;
    }
    const double n = s->cap.get(cv::CAP_PROP_FRAME_COUNT);
    s->count = n > 0 && n < 1e9 ? (int)std::lround(n) : -1;
    s->rate = s->cap.get(cv::CAP_PROP_FPS);
    if (!(s->rate > 0 && s->rate < 1e5))
        s->rate = 0;
    return s;
}

Source *source_camera_open(const vis_camera_settings &cs, vis_error *err)
{
    VideoSource *s = new VideoSource;
    s->live = true;
    bool opened;
    if (cs.path && cs.path[0]) {
        s->name = cs.path;
        opened = s->cap.open(cs.path, cv::CAP_V4L2);
    } else {
        s->name = "#" + std::to_string(cs.index);
        opened = s->cap.open(cs.index, cv::CAP_V4L2);
    }
    if (!opened || !s->cap.isOpened()) {
        fail(err, VIS_ERR_IO, "camera %s cannot be opened", s->name.c_str());
        delete s;
        return nullptr;
    }
    if (cs.fourcc[0] && cs.fourcc[1] && cs.fourcc[2] && cs.fourcc[3])
        s->cap.set(cv::CAP_PROP_FOURCC,
                   cv::VideoWriter::fourcc(cs.fourcc[0], cs.fourcc[1], cs.fourcc[2], cs.fourcc[3]));
    if (cs.width_px > 0)
        s->cap.set(cv::CAP_PROP_FRAME_WIDTH, cs.width_px);
    if (cs.height_px > 0)
        s->cap.set(cv::CAP_PROP_FRAME_HEIGHT, cs.height_px);
    if (cs.fps > 0)
        s->cap.set(cv::CAP_PROP_FPS, cs.fps);
    s->rate = s->cap.get(cv::CAP_PROP_FPS);
    if (!(s->rate > 0 && s->rate < 1e5))
        s->rate = 0;
    return s;
}

}  // namespace vis
