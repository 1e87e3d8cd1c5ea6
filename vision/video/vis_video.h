/* vis_video.h: the face of vision/video/: lossless video writers (video_writer.cpp), and a rendered
 * sequence written as a video with its ground truth beside it (synth_writer.cpp). Reading a video
 * back is a frame source (vis_source.h). */
#ifndef RIBBON_VIS_VIDEO_H
#define RIBBON_VIS_VIDEO_H

#include "vis_core.h"
#include "vis_render.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- video writing */

/* Lossless video. By the name's ending: .mkv = FFV1 in Matroska (compressed, 16.7 ms per 1280x720
 * grey frame on one core); .avi = raw Y800 (uncompressed 8-bit grey, 1 byte per pixel) in AVI, about
 * 0.3 ms per frame, what live trials record. Both read back bit-exact. */
typedef struct vis_video_writer vis_video_writer;
vis_video_writer *vis_video_writer_open(const char *path, int width_px, int height_px, int channels,
                                        double fps, vis_error *err);
/* Raw 8-bit grey Y800 in AVI (.avi): bit-exact too, and no CPU to encode or decode (what a rig
 * recording in real time would write). Same write and close calls. */
vis_video_writer *vis_video_writer_open_y800(const char *path, int width_px, int height_px, double fps,
                                             vis_error *err);
vis_status vis_video_writer_write(vis_video_writer *w, const vis_frame *f, vis_error *err);
void vis_video_writer_close(vis_video_writer *w);

/* Render a sequence of shapes into OUT.mkv plus a ground-truth CSV beside it, one row per frame:
 * frame,t_s,shear_m,length_m,dz,a,dz_cam,a_cam,clamp_left_u,clamp_left_v,clamp_right_u,
 * clamp_right_v,mid_u,mid_v,px_per_m */
typedef struct vis_synth_writer vis_synth_writer;
vis_synth_writer *vis_synth_writer_open(const char *video_path, const char *truth_csv_path,
                                        const vis_render_params *p, double fps, vis_error *err);
vis_status vis_synth_writer_add(vis_synth_writer *w, const vis_shape *shape, vis_render_truth *truth,
                                vis_error *err);
/* Flushes and closes; returns the first error met while closing. */
vis_status vis_synth_writer_close(vis_synth_writer *w, vis_error *err);

#ifdef __cplusplus
}
#endif

#endif
