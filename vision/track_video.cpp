// track_video.cpp: a whole video decoded and tracked on every core, results identical to the serial
// loop (vis_track_video).
//
// The tracker is sequential by nature: frame k is followed from frame k-1's curve, so two frames
// cannot be tracked at once without changing the results. What runs in parallel is everything
// else: decoding runs on its own thread (plus libavcodec's own threads) through the prefetching
// source (source_prefetch.cpp) while the calling thread tracks, so the wall time is about
// max(decode, track) per frame instead of their sum. The tracker sees exactly the frames, in
// exactly the order, of the serial loop, so each frame's vis_measure is bit for bit the serial one
// (test_vision_track_video checks it). threads = 1 is the plain serial loop (the reference and
// the one-core figure); any other count decodes ahead on one extra thread (there is no more
// parallelism in a sequential tracker to hand out).
#include "vis_internal.hpp"

extern "C" vis_status vis_track_video(const char *path, vis_tracker *t, const double *shear_mm,
                                      size_t n_shear, int threads, vis_measure *out, size_t max_frames,
                                      size_t *n_frames, vis_error *err)
{
    if (!path || !t || !out || !n_frames || threads < 0 || threads > 64)
        return vis::fail(err, VIS_ERR_ARG, "vis_track_video: NULL argument or threads outside 0..64");
    *n_frames = 0;
    vis_source *src = threads == 1 ? vis_source_open_video(path, err) : vis_source_open_video_prefetch(path, err);
    if (!src)
        return err ? err->code : VIS_ERR_IO;
    vis_frame *f = vis_frame_alloc(8, 8, 1, err);
    vis_status rc = f ? VIS_OK : VIS_ERR_NOMEM;
    for (size_t i = 0; rc == VIS_OK && i < max_frames; i++) {
        const vis_status s = vis_source_read(src, f, nullptr, err);
        if (s == VIS_ERR_END)
            break;
        if (s != VIS_OK) {
            rc = s;
            break;
        }
        rc = vis_tracker_process(t, f, shear_mm && i < n_shear ? shear_mm[i] : 0.0, &out[i], err);
        if (rc == VIS_OK)
            *n_frames = i + 1;
    }
    vis_frame_free(f);
    vis_source_close(src);
    if (rc == VIS_OK)
        vis::ok(err);
    return rc;
}
