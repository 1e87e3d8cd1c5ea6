// source_video.cpp: frames from a video file or a live camera (OpenCV VideoCapture).
//
// Damage detection: the container announces a frame count; a file that stops delivering frames
// before that count is damaged (truncated or corrupt), and the read says so, naming the last good
// frame, instead of looking like a clean end. Frames already read stay valid: the caller keeps
// everything up to the damage. A file whose container announces no count at all has lost its index
// (Matroska's duration and cues are written last, so a writer killed by a signal or a full disk
// leaves none): its end is damage too, never a clean end. Cameras have no count: a failed grab is
// an I/O error.
//
// Raw grey video (Y800, the trials' own recordings) is read without decoding: OpenCV's reader
// hands out each stored packet as it is (CAP_PROP_FORMAT -1) and, for raw grey, the packet is the
// frame's pixels, row after row. Decoding it instead costs a grey -> BGR conversion in the reader
// and BGR -> grey here (2.2 ms per 1280 x 720 frame against 0.12 ms). Whether a file is raw grey
// is not guessed from its tags: at open the first frame is read both ways, and the packets are
// used only when the packet is exactly width x height bytes and those bytes are the decoded
// frame's (every other format, FFV1 included, is decoded as before). A later packet of another
// size is damage, said as such.
#include "source.hpp"
#include "image_header.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace vis {
namespace {

// A decoded frame (any depth, 1, 3 or 4 channels) as 8-bit grey; m may be converted in place.
void to_grey(cv::Mat &m, cv::Mat &grey)
{
    if (m.depth() != CV_8U)
        m.convertTo(m, CV_8U);
    if (m.channels() == 1)
        m.copyTo(grey);
    else
        cv::cvtColor(m, grey, m.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
}

class VideoSource : public Source {
public:
    cv::VideoCapture cap;
    std::string name;
    bool live = false;
    int count = -1;
    double rate = 0;
    int index = 0;
    cv::Mat raw;
    bool packets = false;  // cap hands out raw grey packets (see the top of the file)
    int width = 0, height = 0;
    cv::Mat first;  // frame 0, read at open, handed out by the first read
    bool have_first = false;

    vis_status read(cv::Mat &grey, double &t_s, vis_error *err) override
    {
        if (have_first) {
            have_first = false;
            first.copyTo(grey);
            first.release();
            t_s = rate > 0 ? 0.0 : cap.get(cv::CAP_PROP_POS_MSEC) * 1e-3;
            index++;
            return VIS_OK;
        }
        if (!cap.read(raw) || raw.empty())
            return failed_read(err);
        if (packets) {
            if (raw.total() * raw.elemSize() != (size_t)width * (size_t)height)
                return short_packet(err);
            raw.reshape(1, height).copyTo(grey);
        } else {
            to_grey(raw, grey);
        }
        t_s = rate > 0 ? index / rate : cap.get(cv::CAP_PROP_POS_MSEC) * 1e-3;
        index++;
        return VIS_OK;
    }
    // Raw packets: the next one demuxed, its bytes not copied out (nor its size checked: whoever
    // reads that frame does).
    vis_status skip(vis_error *err) override
    {
        if (!packets || have_first)
            return Source::skip(err);
        if (!cap.grab())
            return failed_read(err);
        index++;
        return VIS_OK;
    }
    bool cheap_skip() const override { return packets; }
    // No frame where one was expected: the end, damage, or a camera's failure.
    vis_status failed_read(vis_error *err)
    {
        if (live)
            return fail(err, VIS_ERR_IO, "camera %s: no frame after frame %d", name.c_str(), index - 1);
        if (count > 0 && index < count)
            return fail(err, VIS_ERR_FORMAT,
                        "video %s is damaged: %d of %d announced frames readable (last good frame %d)",
                        name.c_str(), index, count, index - 1);
        if (count <= 0)
            return fail(err, VIS_ERR_FORMAT,
                        "video %s is damaged: its container announces no frame count (index missing: the "
                        "writer was killed or its disk filled?); %d frames readable",
                        name.c_str(), index);
        return fail(err, VIS_ERR_END, "end of video %s after %d frames", name.c_str(), index);
    }
    vis_status short_packet(vis_error *err)
    {
        return fail(err, VIS_ERR_FORMAT,
                    "video %s is damaged: frame %d holds %zu bytes, not %d x %d (last good frame %d)",
                    name.c_str(), index, raw.total() * raw.elemSize(), width, height, index - 1);
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

// The rig file's exposure and gain held on the camera (v4l2_exposure.cpp), through a descriptor of
// its own: V4L2 controls belong to the device, not to the descriptor OpenCV streams from.
vis_status hold_exposure(const vis_camera_settings &cs, const std::string &name, vis_error *err)
{
    if (!(cs.exposure_us > 0) && !(cs.v4l2_gain >= 0))
        return VIS_OK;
    const std::string dev = cs.path && cs.path[0] ? std::string(cs.path) : "/dev/video" + std::to_string(cs.index);
    const int fd = ::open(dev.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0)
        return fail(err, VIS_ERR_IO, "camera %s: %s cannot be opened to set its exposure: %s", name.c_str(),
                    dev.c_str(), std::strerror(errno));
    const vis_status st = vis_v4l2_hold_exposure(nullptr, nullptr, fd, name.c_str(), cs.exposure_us, cs.v4l2_gain, err);
    ::close(fd);
    return st;
}

// The next decoded frame as grey, as read() makes it.
bool decoded_grey(cv::VideoCapture &cap, cv::Mat &grey)
{
    cv::Mat m;
    if (!cap.read(m) || m.empty())
        return false;
    to_grey(m, grey);
    return true;
}

// Switch s to raw packets when frame 0's packet is exactly its decoded pixels; either way frame
// 0 is read here and kept for the first read. A file whose frame 0 does not decode is left to
// read() to report.
void choose_reader(VideoSource *s, const char *path, int w, int h)
{
    cv::Mat dec;
    if (!decoded_grey(s->cap, dec))
        return;  // read() tries again and reports the failure
    s->first = dec;
    s->have_first = true;
    if (w <= 0 || h <= 0 || dec.cols != w || dec.rows != h)
        return;
    cv::VideoCapture rc;
    if (!rc.open(path, cv::CAP_FFMPEG) || !rc.isOpened() || !rc.set(cv::CAP_PROP_FORMAT, -1))
        return;
    cv::Mat pk;
    if (!rc.read(pk) || pk.empty() || pk.depth() != CV_8U || !pk.isContinuous() ||
        pk.total() * pk.elemSize() != (size_t)w * (size_t)h)
        return;
    const cv::Mat as_frame = pk.reshape(1, h);
    if (cv::norm(as_frame, dec, cv::NORM_INF) != 0)
        return;
    s->cap.release();
    s->cap = rc;
    s->packets = true;
    s->width = w;
    s->height = h;
}

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
    if (st.st_size == 0) {
        fail(err, VIS_ERR_FORMAT, "video %s: an empty file (0 bytes)", path);
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
    choose_reader(s, path, (int)fw, (int)fh);
    return s;
}

Source *source_camera_open(const vis_camera_settings &cs, vis_error *err)
{
    VideoSource *s = new VideoSource;
    s->live = true;
    s->name = cs.path && cs.path[0] ? std::string(cs.path) : "#" + std::to_string(cs.index);
    if (cs.gain_db >= 0) {  // refused before the device is touched
        fail(err, VIS_ERR_ARG, "camera %s: gain %g dB refused: a V4L2 camera's gain has no dB scale (gain in dB is "
             "for GenICam cameras; a V4L2 gain is set in its control's own units, v4l2_gain)", s->name.c_str(),
             cs.gain_db);
        delete s;
        return nullptr;
    }
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
    if (hold_exposure(cs, s->name, err) != VIS_OK) {
        delete s;
        return nullptr;
    }
    s->rate = s->cap.get(cv::CAP_PROP_FPS);
    if (!(s->rate > 0 && s->rate < 1e5))
        s->rate = 0;
    return s;
}

}  // namespace vis
