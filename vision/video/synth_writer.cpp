// synth_writer.cpp: renders a sequence of simulated shapes into a lossless video plus ground truth.
//
// One object ties a renderer, an FFV1 writer and a CSV file so the two outputs cannot drift apart:
// row k of the CSV describes frame k of the video. The CSV header names every column with its unit;
// numbers are printed with %.17g so the truth round-trips exactly.
#include "vis_internal.hpp"
#include "vis_video.h"

#include <cstdio>

struct vis_synth_writer {
    vis_renderer *r = nullptr;
    vis_video_writer *v = nullptr;
    FILE *csv = nullptr;
    vis_frame frame;
    double fps = 25;
    int index = 0;
    std::string csv_path;
};

static void synth_free(vis_synth_writer *w)
{
    vis_renderer_free(w->r);
    vis_video_writer_close(w->v);
    if (w->csv)
        std::fclose(w->csv);
    delete w;
}

extern "C" vis_synth_writer *vis_synth_writer_open(const char *video_path, const char *truth_csv_path,
                                                   const vis_render_params *p, double fps,
                                                   vis_error *err)
{
    if (!video_path || !truth_csv_path || !p) {
        vis::fail(err, VIS_ERR_ARG, "vis_synth_writer_open: NULL argument");
        return nullptr;
    }
    VIS_GUARD(err, nullptr, {
        vis_synth_writer *w = new vis_synth_writer;
        w->fps = fps;
        w->csv_path = truth_csv_path;
        w->r = vis_renderer_create(p, err);
        if (!w->r) {
            synth_free(w);
            return nullptr;
        }
        w->v = vis_video_writer_open(video_path, p->camera.width_px, p->camera.height_px, 1, fps, err);
        if (!w->v) {
            synth_free(w);
            return nullptr;
        }
        w->csv = std::fopen(truth_csv_path, "w");
        if (!w->csv) {
            synth_free(w);
            vis::fail(err, VIS_ERR_IO, "cannot open ground-truth file %s for writing", truth_csv_path);
            return nullptr;
        }
        std::fprintf(w->csv, "frame,t_s,shear_m,length_m,dz,a,dz_cam,a_cam,clamp_left_u,clamp_left_v,"
                             "clamp_right_u,clamp_right_v,mid_u,mid_v,px_per_m\n");
        vis::ok(err);
        return w;
    })
}

extern "C" vis_status vis_synth_writer_add(vis_synth_writer *w, const vis_shape *shape,
                                           vis_render_truth *truth, vis_error *err)
{
    if (!w)
        return vis::fail(err, VIS_ERR_ARG, "vis_synth_writer_add: NULL writer");
    VIS_GUARD(err, VIS_ERR_INTERNAL, {
        vis_render_truth t;
        vis_status s = vis_renderer_draw(w->r, shape, &w->frame, &t, err);
        if (s != VIS_OK)
            return s;
        s = vis_video_writer_write(w->v, &w->frame, err);
        if (s != VIS_OK)
            return s;
        const vis_truth &g = t.truth;
        if (std::fprintf(w->csv,
                         "%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,"
                         "%.17g,%.17g\n",
                         w->index, w->index / w->fps, g.shear_m, g.length_m, g.dz, g.a, g.dz_cam,
                         g.a_cam, t.clamp_left_px[0], t.clamp_left_px[1], t.clamp_right_px[0],
                         t.clamp_right_px[1], t.mid_px[0], t.mid_px[1], t.px_per_m) < 0)
            return vis::fail(err, VIS_ERR_IO, "cannot write ground truth to %s", w->csv_path.c_str());
        w->index++;
        if (truth)
            *truth = t;
        vis::ok(err);
        return VIS_OK;
    })
}

extern "C" vis_status vis_synth_writer_close(vis_synth_writer *w, vis_error *err)
{
    if (!w)
        return vis::fail(err, VIS_ERR_ARG, "vis_synth_writer_close: NULL writer");
    vis_status s = VIS_OK;
    if (w->csv && std::fclose(w->csv) != 0)
        s = vis::fail(err, VIS_ERR_IO, "cannot close ground-truth file %s", w->csv_path.c_str());
    w->csv = nullptr;
    synth_free(w);
    if (s == VIS_OK)
        vis::ok(err);
    return s;
}
