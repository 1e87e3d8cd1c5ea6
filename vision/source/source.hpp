// source.hpp: the private frame-source interface behind vis_source (one implementation per file).
#ifndef RIBBON_VIS_SOURCE_HPP
#define RIBBON_VIS_SOURCE_HPP

#include "vis_internal.hpp"
#include "vis_source.h"

namespace vis {
// A source of grey frames. read() returns VIS_OK, VIS_ERR_END at a clean end, or an error.
class Source {
public:
    virtual ~Source() = default;
    virtual vis_status read(cv::Mat &grey, double &t_s, vis_error *err) = 0;
    // With the frame's metadata (vision.h). The default: the source's own time, counted ids.
    virtual vis_status read_meta(cv::Mat &grey, vis_frame_meta &m, vis_error *err)
    {
        double t = 0;
        vis_status s = read(grey, t, err);
        m.camera_t_s = t;
        m.host_t_s = monotonic_s();
        m.frame_id = counted++;
        m.lost_before = 0;
        m.incomplete = 0;
        return s;
    }
    static double monotonic_s();
    uint64_t counted = 0;
    // Pass over the next frame: VIS_OK, VIS_ERR_END or an error, as read() would say. Cheap only
    // where cheap_skip() (raw grey packets: demuxed, not copied); otherwise it is a read.
    virtual vis_status skip(vis_error *err)
    {
        cv::Mat m;
        double t = 0;
        return read(m, t, err);
    }
    virtual bool cheap_skip() const { return false; }
    virtual int frame_count() const { return -1; }
    virtual double fps() const { return 0.0; }
};
Source *source_video_open(const char *path, vis_error *err);
Source *source_camera_open(const vis_camera_settings &s, vis_error *err);
Source *source_aravis_open(const vis_camera_settings &s, vis_error *err);
Source *source_images_open(const char *pattern, int first, vis_error *err);
// Takes `inner` over and decodes it ahead on a thread into `depth` frames (source_prefetch.cpp).
Source *source_prefetch_wrap(Source *inner, size_t depth);
Source *source_synth_open(const vis_render_params &p, double fps, vis_shape_fn fn, void *user,
                          vis_error *err);
}  // namespace vis

#endif
