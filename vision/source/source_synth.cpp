// source_synth.cpp: frames rendered on the fly from shapes supplied by a callback (mock mode).
//
// The callback owns the shapes (it typically steps the simulator); the source owns a renderer and
// turns each shape into a grey frame. The sequence ends when the callback says so.
#include "source.hpp"

namespace vis {
namespace {

class SynthSource : public Source {
public:
    vis_renderer *r = nullptr;
    vis_shape_fn fn = nullptr;
    void *user = nullptr;
    double rate = 25;
    int index = 0;
    vis_frame frame;

    ~SynthSource() override { vis_renderer_free(r); }
    vis_status read(cv::Mat &grey, double &t_s, vis_error *err) override
    {
        vis_shape sh{};
        const int rc = fn(user, index, &sh);
        if (rc == 1)
            return fail(err, VIS_ERR_END, "synthetic sequence ends after %d frames", index);
        if (rc != 0)
            return fail(err, VIS_ERR_FORMAT, "shape callback failed at frame %d", index);
        vis_status s = vis_renderer_draw(r, &sh, &frame, nullptr, err);
        if (s != VIS_OK)
            return s;
        frame.mat.copyTo(grey);
        t_s = index / rate;
        index++;
        return VIS_OK;
    }
    double fps() const override { return rate; }
};

}  // namespace

Source *source_synth_open(const vis_render_params &p, double fps, vis_shape_fn fn, void *user,
                          vis_error *err)
{
    if (!finite(fps) || fps <= 0) {
        fail(err, VIS_ERR_ARG, "synthetic source: fps must be > 0");
        return nullptr;
    }
    vis_renderer *r = vis_renderer_create(&p, err);
    if (!r)
        return nullptr;
    SynthSource *s = new SynthSource;
    s->r = r;
    s->fn = fn;
    s->user = user;
    s->rate = fps;
    return s;
}

}  // namespace vis
