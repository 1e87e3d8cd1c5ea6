// source_aravis.cpp: frames from a GenICam camera (GigE Vision, USB3 Vision) through Aravis.
//
// The camera is set to Mono8 and to the rig file's region (width, height, offset), frame rate,
// exposure and gain, in that order (the region first: a camera's frame-rate range depends on it).
// Each setting is read back; a feature the camera lacks or refuses is a named error ("camera X:
// Gain refused: ...") and the source is not opened. Aravis's stream thread fills a pool of buffers;
// read() pops the next one with a timeout, so a camera that stops sending is an I/O error within
// ARV_READ_TIMEOUT_US instead of a hang.
//
// Per frame (vision.h vis_frame_meta): the buffer's timestamp (the camera's clock, ns: the GVSP
// leader's timestamp for GigE, the USB3 Vision leader's for U3V), its frame id (block id), and the
// host time the buffer was started (Aravis's system timestamp, real-time clock, converted to
// CLOCK_MONOTONIC at the moment of the pop). Buffers the transport could not complete (missing
// packets, timeouts) are pushed back unread and counted; gaps in the block ids count frames that
// never arrived at all; a buffer delivered after a newer one was counted in that gap already and
// is dropped uncounted (vis_block_ids_next, block_ids.cpp).
#include "source.hpp"

#include <arv.h>

#include <algorithm>
#include <time.h>

namespace vis {
namespace {

constexpr guint64 ARV_READ_TIMEOUT_US = 400000;   // a camera silent this long has stopped
constexpr guint64 ARV_FIRST_TIMEOUT_US = 3000000; // ... and one that sends no first frame

double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

std::string gerr_text(GError *e)
{
    std::string s = e && e->message ? e->message : "unknown error";
    if (e)
        g_error_free(e);
    return s;
}

class AravisSource : public Source {
public:
    ArvCamera *cam = nullptr;
    ArvStream *stream = nullptr;
    std::string name;
    double rate = 0;
    vis_block_ids ids = {0, 0};
    long pending_lost = 0;        // gaps before incomplete buffers, reported with the next frame
    long pending_incomplete = 0;

    ~AravisSource() override
    {
        if (cam)
            arv_camera_stop_acquisition(cam, nullptr);
        if (stream)
            g_object_unref(stream);
        if (cam)
            g_object_unref(cam);
    }

    vis_status read(cv::Mat &grey, double &t_s, vis_error *err) override
    {
        vis_frame_meta m = {NAN, 0.0, 0, 0, 0};
        vis_status s = read_meta(grey, m, err);
        t_s = m.camera_t_s;
        return s;
    }

    vis_status read_meta(cv::Mat &grey, vis_frame_meta &m, vis_error *err) override
    {
        for (int tries = 0; tries < 1000; tries++) {
            // The first frame may take the stream's set-up (packet size, the camera's own start).
            const guint64 wait = ids.have ? ARV_READ_TIMEOUT_US : ARV_FIRST_TIMEOUT_US;
            ArvBuffer *b = arv_stream_timeout_pop_buffer(stream, wait);
            if (!b)
                return fail(err, VIS_ERR_IO, "camera %s %s: no frame for %.1f s", name.c_str(),
                            ids.have ? "stopped sending" : "sends nothing", wait * 1e-6);
            const double mono = clock_s(CLOCK_MONOTONIC), real = clock_s(CLOCK_REALTIME);
            const guint64 id = arv_buffer_get_frame_id(b);
            const long gap = vis_block_ids_next(&ids, id);
            if (gap == VIS_BLOCK_LATE) {
                // Delivered after a newer frame: already counted lost in that frame's gap, and a
                // frame older than one published is not published (stamps stay in order).
                arv_stream_push_buffer(stream, b);
                continue;
            }
            if (arv_buffer_get_status(b) != ARV_BUFFER_STATUS_SUCCESS) {
                pending_lost += gap;
                pending_incomplete++;
                arv_stream_push_buffer(stream, b);
                continue;
            }
            const int w = arv_buffer_get_image_width(b), h = arv_buffer_get_image_height(b);
            size_t size = 0;
            const void *data = arv_buffer_get_image_data(b, &size);
            if (arv_buffer_get_image_pixel_format(b) != ARV_PIXEL_FORMAT_MONO_8 || !data ||
                size < (size_t)w * (size_t)h || w <= 0 || h <= 0) {
                arv_stream_push_buffer(stream, b);
                return fail(err, VIS_ERR_FORMAT,
                            "camera %s: frame %llu is not a %dx%d Mono8 image (pixel format 0x%08x, %zu bytes)",
                            name.c_str(), (unsigned long long)id, w, h,
                            (unsigned)arv_buffer_get_image_pixel_format(b), size);
            }
            grey.create(h, w, CV_8UC1);
            cv::Mat(h, w, CV_8UC1, const_cast<void *>(data)).copyTo(grey);
            const guint64 cam_ns = arv_buffer_get_timestamp(b);
            const guint64 sys_ns = arv_buffer_get_system_timestamp(b);
            m.camera_t_s = cam_ns ? (double)cam_ns * 1e-9 : NAN;
            m.host_t_s = sys_ns ? (double)sys_ns * 1e-9 - (real - mono) : mono;
            m.frame_id = id;
            m.lost_before = pending_lost + gap;
            m.incomplete = (int)pending_incomplete;
            pending_lost = 0;
            pending_incomplete = 0;
            arv_stream_push_buffer(stream, b);
            return VIS_OK;
        }
        return fail(err, VIS_ERR_IO, "camera %s: 1000 incomplete buffers in a row", name.c_str());
    }
    double fps() const override { return rate; }
};

// One setting, read back: returns false with a named error when the camera refuses it.
bool refused(GError *e, const std::string &cam, const char *feature, vis_error *err)
{
    if (!e)
        return false;
    fail(err, VIS_ERR_ARG, "camera %s: %s refused: %s", cam.c_str(), feature, gerr_text(e).c_str());
    return true;
}

}  // namespace

Source *source_aravis_open(const vis_camera_settings &cs, vis_error *err)
{
    GError *e = nullptr;
    const char *id = cs.path && cs.path[0] ? cs.path : nullptr;
    AravisSource *s = new AravisSource;
    s->name = id ? id : "(first Aravis camera)";
    s->cam = arv_camera_new(id, &e);
    if (!s->cam) {
        fail(err, VIS_ERR_IO, "camera aravis:%s not found: %s", id ? id : "", gerr_text(e).c_str());
        delete s;
        return nullptr;
    }
    bool bad = false;
    arv_camera_set_pixel_format(s->cam, ARV_PIXEL_FORMAT_MONO_8, &e);
    bad = refused(e, s->name, "PixelFormat Mono8", err);
    e = nullptr;
    if (!bad && arv_camera_get_pixel_format(s->cam, nullptr) != ARV_PIXEL_FORMAT_MONO_8) {
        fail(err, VIS_ERR_ARG, "camera %s: PixelFormat Mono8 refused (it stays %s)", s->name.c_str(),
             arv_camera_get_pixel_format_as_string(s->cam, nullptr));
        bad = true;
    }
    if (!bad && (cs.width_px > 0 || cs.height_px > 0 || cs.offset_x_px >= 0 || cs.offset_y_px >= 0)) {
        gint x, y, w, h;
        arv_camera_get_region(s->cam, &x, &y, &w, &h, &e);
        bad = refused(e, s->name, "region", err);
        e = nullptr;
        if (!bad) {
            const gint wx = cs.offset_x_px >= 0 ? cs.offset_x_px : x;
            const gint wy = cs.offset_y_px >= 0 ? cs.offset_y_px : y;
            const gint ww = cs.width_px > 0 ? cs.width_px : w;
            const gint wh = cs.height_px > 0 ? cs.height_px : h;
            // Aravis clamps a region to the sensor silently: a request outside the bounds is refused
            // here, by name, before anything is written.
            gint wmin = 0, wmax = 0, hmin = 0, hmax = 0;
            arv_camera_get_width_bounds(s->cam, &wmin, &wmax, nullptr);
            arv_camera_get_height_bounds(s->cam, &hmin, &hmax, nullptr);
            if (wmax > 0 && (ww < wmin || ww > wmax || wx + ww > wmax)) {
                fail(err, VIS_ERR_ARG, "camera %s: Width %d at OffsetX %d refused: the sensor allows %d..%d px",
                     s->name.c_str(), ww, wx, wmin, wmax);
                delete s;
                return nullptr;
            }
            if (hmax > 0 && (wh < hmin || wh > hmax || wy + wh > hmax)) {
                fail(err, VIS_ERR_ARG, "camera %s: Height %d at OffsetY %d refused: the sensor allows %d..%d px",
                     s->name.c_str(), wh, wy, hmin, hmax);
                delete s;
                return nullptr;
            }
            arv_camera_set_region(s->cam, wx, wy, ww, wh, &e);
            bad = refused(e, s->name, "region (Width, Height, OffsetX, OffsetY)", err);
            e = nullptr;
            if (!bad) {
                arv_camera_get_region(s->cam, &x, &y, &w, &h, nullptr);
                if (x != wx || y != wy || w != ww || h != wh) {
                    fail(err, VIS_ERR_ARG,
                         "camera %s: region %dx%d+%d+%d refused (the camera set %dx%d+%d+%d)",
                         s->name.c_str(), ww, wh, wx, wy, w, h, x, y);
                    bad = true;
                }
            }
        }
    }
    if (!bad && cs.fps > 0) {
        arv_camera_set_frame_rate(s->cam, cs.fps, &e);
        bad = refused(e, s->name, "AcquisitionFrameRate", err);
        e = nullptr;
        if (!bad) {
            const double got = arv_camera_get_frame_rate(s->cam, nullptr);
            if (!(std::fabs(got - cs.fps) <= 1e-3 * cs.fps)) {
                fail(err, VIS_ERR_ARG, "camera %s: AcquisitionFrameRate %g refused (it runs at %g)",
                     s->name.c_str(), cs.fps, got);
                bad = true;
            }
        }
    }
    // Aravis writes an exposure or gain outside the feature's GenICam bounds without a word (its
    // fake camera then reads it back unchanged; a real one clamps or ignores it): refused here by
    // name with the bounds, before it is written.
    if (!bad && cs.exposure_us > 0) {
        double lo = 0.0, hi = 0.0;
        arv_camera_get_exposure_time_bounds(s->cam, &lo, &hi, nullptr);
        if (hi > lo && (cs.exposure_us < lo || cs.exposure_us > hi)) {
            fail(err, VIS_ERR_ARG, "camera %s: ExposureTime %g us refused: the camera allows %g..%g us",
                 s->name.c_str(), cs.exposure_us, lo, hi);
            bad = true;
        }
    }
    if (!bad && cs.gain_db >= 0) {
        double lo = 0.0, hi = 0.0;
        arv_camera_get_gain_bounds(s->cam, &lo, &hi, nullptr);
        if (hi > lo && (cs.gain_db < lo || cs.gain_db > hi)) {
            fail(err, VIS_ERR_ARG, "camera %s: Gain %g dB refused: the camera allows %g..%g dB", s->name.c_str(),
                 cs.gain_db, lo, hi);
            bad = true;
        }
    }
    if (!bad && cs.exposure_us > 0) {
        arv_camera_set_exposure_time(s->cam, cs.exposure_us, &e);
        bad = refused(e, s->name, "ExposureTime", err);
        e = nullptr;
        const double got = bad ? cs.exposure_us : arv_camera_get_exposure_time(s->cam, nullptr);
        if (!bad && !(std::fabs(got - cs.exposure_us) <= 1e-3 * cs.exposure_us + 1.0)) {
            fail(err, VIS_ERR_ARG, "camera %s: ExposureTime %g us refused (it is %g us)", s->name.c_str(),
                 cs.exposure_us, got);
            bad = true;
        }
    }
    if (!bad && cs.gain_db >= 0) {
        arv_camera_set_gain(s->cam, cs.gain_db, &e);
        bad = refused(e, s->name, "Gain", err);
        e = nullptr;
        const double got = bad ? cs.gain_db : arv_camera_get_gain(s->cam, nullptr);
        if (!bad && !(std::fabs(got - cs.gain_db) <= 0.01 + 1e-3 * cs.gain_db)) {
            fail(err, VIS_ERR_ARG, "camera %s: Gain %g dB refused (it is %g dB)", s->name.c_str(), cs.gain_db, got);
            bad = true;
        }
    }
    guint payload = 0;
    if (!bad) {
        payload = arv_camera_get_payload(s->cam, &e);
        bad = refused(e, s->name, "PayloadSize", err);
        e = nullptr;
    }
    if (!bad) {
        // GigE Vision: Aravis's packet socket (a memory-mapped ring, used when the process may open
        // one, e.g. as root) hands packets over by ring block, retired when full or on a timeout,
        // so the host times the clock map learns from arrive late and unevenly (0.9 ms floor, 3 ms
        // median on loopback); the ordinary UDP socket hands each packet over as it comes.
        if (arv_camera_is_gv_device(s->cam))
            arv_camera_gv_set_stream_options(s->cam, ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED);
        s->stream = arv_camera_create_stream(s->cam, nullptr, nullptr, &e);
        if (!s->stream) {
            fail(err, VIS_ERR_IO, "camera %s: no stream: %s", s->name.c_str(), gerr_text(e).c_str());
            bad = true;
        }
        e = nullptr;
    }
    if (!bad && ARV_IS_GV_STREAM(s->stream)) {
        // Room in the socket for 8 frames (the kernel caps it at net.core.rmem_max): Aravis's
        // automatic size is one frame, and a receiver descheduled for a frame period overflows it.
        g_object_set(s->stream, "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED, "socket-buffer-size",
                     (gint)std::min<guint64>((guint64)payload * 8u, 1u << 30), nullptr);
    }
    if (!bad) {
        const int n = cs.n_buffers > 0 ? cs.n_buffers : 32;
        for (int k = 0; k < n; k++)
            arv_stream_push_buffer(s->stream, arv_buffer_new(payload, nullptr));
        arv_camera_set_acquisition_mode(s->cam, ARV_ACQUISITION_MODE_CONTINUOUS, nullptr);
        arv_camera_start_acquisition(s->cam, &e);
        bad = refused(e, s->name, "AcquisitionStart", err);
        e = nullptr;
    }
    if (bad) {
        delete s;
        return nullptr;
    }
    s->rate = arv_camera_get_frame_rate(s->cam, nullptr);
    return s;
}

}  // namespace vis

extern "C" int vis_aravis_list(void (*fn)(void *user, const char *id, const char *vendor,
                                          const char *model, const char *protocol),
                               void *user, vis_error *err)
{
    VIS_GUARD(err, -1, {
        arv_update_device_list();
        const unsigned n = arv_get_n_devices();
        for (unsigned k = 0; k < n && fn; k++) {
            const char *id = arv_get_device_id(k), *vendor = arv_get_device_vendor(k);
            const char *model = arv_get_device_model(k), *proto = arv_get_device_protocol(k);
            fn(user, id ? id : "", vendor ? vendor : "", model ? model : "", proto ? proto : "");
        }
        vis::ok(err);
        return (int)n;
    })
}
