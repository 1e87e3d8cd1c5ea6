// source.cpp: vis_source, the one interface every frame source answers to.
//
// The C handle owns a vis::Source (a small C++ vtable: read, frame_count, fps) so the tracker loop is
// the same for a live camera, a recorded video, a folder of images and frames rendered on the fly.
// Every source hands out 8-bit grey frames.
#include "source.hpp"

#include <time.h>

struct vis_source {
    vis::Source *impl;
};

static vis_source *wrap(vis::Source *s)
{
    if (!s)
        return nullptr;
    vis_source *h = new (std::nothrow) vis_source;
    if (!h) {
        delete s;
        return nullptr;
    }
    h->impl = s;
    return h;
}

extern "C" vis_camera_settings vis_camera_settings_default(void)
{
    vis_camera_settings s;
    s.index = 0;
    s.path = nullptr;
    s.width_px = 0;
    s.height_px = 0;
    s.fps = 0;
    s.fourcc[0] = '\0';
    s.aravis = 0;
    s.offset_x_px = -1;
    s.offset_y_px = -1;
    s.exposure_us = 0;
    s.gain_db = -1;
    s.v4l2_gain = -1;
    s.n_buffers = 0;
    return s;
}

extern "C" vis_source *vis_source_open_camera(const vis_camera_settings *s, vis_error *err)
{
    if (!s) {
        vis::fail(err, VIS_ERR_ARG, "vis_source_open_camera: NULL settings");
        return nullptr;
    }
    VIS_GUARD(err, nullptr, {
        return wrap(s->aravis ? vis::source_aravis_open(*s, err) : vis::source_camera_open(*s, err));
    })
}

extern "C" vis_source *vis_source_open_video(const char *path, vis_error *err)
{
    if (!path) {
        vis::fail(err, VIS_ERR_ARG, "vis_source_open_video: NULL path");
        return nullptr;
    }
    VIS_GUARD(err, nullptr, { return wrap(vis::source_video_open(path, err)); })
}

extern "C" vis_source *vis_source_open_video_prefetch(const char *path, vis_error *err)
{
    if (!path) {
        vis::fail(err, VIS_ERR_ARG, "vis_source_open_video_prefetch: NULL path");
        return nullptr;
    }
    VIS_GUARD(err, nullptr, {
        vis::Source *inner = vis::source_video_open(path, err);
        return inner ? wrap(vis::source_prefetch_wrap(inner, 16)) : nullptr;
    })
}

extern "C" vis_source *vis_source_open_images(const char *pattern, int first, vis_error *err)
{
    if (!pattern) {
        vis::fail(err, VIS_ERR_ARG, "vis_source_open_images: NULL pattern");
        return nullptr;
    }
    VIS_GUARD(err, nullptr, { return wrap(vis::source_images_open(pattern, first, err)); })
}

extern "C" vis_source *vis_source_open_synthetic(const vis_render_params *p, double fps,
                                                 vis_shape_fn fn, void *user, vis_error *err)
{
    if (!p || !fn) {
        vis::fail(err, VIS_ERR_ARG, "vis_source_open_synthetic: NULL params or callback");
        return nullptr;
    }
    VIS_GUARD(err, nullptr, { return wrap(vis::source_synth_open(*p, fps, fn, user, err)); })
}

extern "C" vis_status vis_source_read(vis_source *src, vis_frame *out, double *t_s, vis_error *err)
{
    if (!src || !out)
        return vis::fail(err, VIS_ERR_ARG, "vis_source_read: NULL source or frame");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        double t = 0;
        vis_status s = src->impl->read(out->mat, t, err);
        if (t_s)
            *t_s = t;
        if (s == VIS_OK)
            vis::ok(err);
        return s;
    })
}

double vis::Source::monotonic_s()
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

extern "C" vis_status vis_source_read_meta(vis_source *src, vis_frame *out, vis_frame_meta *meta,
                                           vis_error *err)
{
    if (!src || !out || !meta)
        return vis::fail(err, VIS_ERR_ARG, "vis_source_read_meta: NULL source, frame or meta");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        vis_status s = src->impl->read_meta(out->mat, *meta, err);
        if (s == VIS_OK)
            vis::ok(err);
        return s;
    })
}

extern "C" int vis_source_frame_count(const vis_source *src)
{
    return src ? src->impl->frame_count() : -1;
}

extern "C" double vis_source_fps(const vis_source *src) { return src ? src->impl->fps() : 0.0; }

extern "C" void vis_source_close(vis_source *src)
{
    if (!src)
        return;
    delete src->impl;
    delete src;
}
