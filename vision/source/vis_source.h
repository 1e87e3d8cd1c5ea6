/* vis_source.h: the face of vision/source/: frame sources behind one handle, vis_source (source.cpp),
 * one implementation per file: V4L2 cameras and video files (source_video.cpp), GenICam cameras
 * through Aravis (source_aravis.cpp, following their block ids with block_ids.cpp), image
 * sequences (source_images.cpp), frames rendered on the fly (source_synth.cpp), and a video decoded
 * ahead on a thread (source_prefetch.cpp); a V4L2 camera's exposure and gain held for a trial
 * (v4l2_exposure.cpp). Its C++ interface for the rooms above is source.hpp. */
#ifndef RIBBON_VIS_SOURCE_H
#define RIBBON_VIS_SOURCE_H

#include "vis_core.h"
#include "vis_render.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- frame sources */

typedef struct vis_camera_settings {
    int index;                /* V4L2 device index (used when path is NULL or empty) */
    const char *path;         /* device path such as /dev/video0, or NULL */
    int width_px;             /* requested width, pixels (0 = driver default) */
    int height_px;            /* requested height, pixels (0 = driver default) */
    double fps;               /* requested frame rate, 1/s (0 = driver default) */
    char fourcc[5];           /* requested pixel format such as "MJPG" ("" = driver default) */
    /* GenICam (Aravis) cameras only: aravis = 1 opens `path` as an Aravis device id ("" or NULL =
     * the first camera found). Mono8 always; 0 / negative = leave the camera's own setting. */
    int aravis;
    int offset_x_px, offset_y_px; /* ROI origin on the sensor, pixels (-1 = leave) */
    double exposure_us;           /* ExposureTime, microseconds (0 = leave) */
    double gain_db;               /* Gain, dB (< 0 = leave); V4L2 cameras refuse it (no dB scale) */
    /* V4L2 cameras only: exposure_us above is held there too (auto exposure switched off); their
     * gain is v4l2_gain, in the gain control's own units (< 0 = leave). vis_v4l2_hold_exposure. */
    double v4l2_gain;
    int n_buffers;                /* stream buffers (0 = 32) */
} vis_camera_settings;
vis_camera_settings vis_camera_settings_default(void);

/* A V4L2 camera's exposure and gain held for a trial (vision/source/v4l2_exposure.cpp). The ioctl is
 * a parameter (NULL = ioctl(2)) so tests can hand a fake control set. */
typedef int (*vis_ioctl_fn)(void *user, int fd, unsigned long request, void *arg);
/* 1 when the camera on fd has control `id` (a V4L2_CID_*) enabled and writable, else 0. */
int vis_v4l2_ctrl_settable(vis_ioctl_fn io, void *user, int fd, unsigned id);
/* exposure_us > 0: auto exposure switched to manual and exposure_time_absolute set (whole 100 us
 * units); gain >= 0 (a whole number): auto gain off and gain (else analogue_gain) set. Each value is
 * checked against the control's range and step, written, and read back. VIS_OK, or VIS_ERR_ARG
 * naming the control and why the camera cannot hold it (no control, out of range, off its step,
 * read back different, auto exposure that cannot be switched off); `name` names the camera. */
vis_status vis_v4l2_hold_exposure(vis_ioctl_fn io, void *user, int fd, const char *name, double exposure_us,
                                  double gain, vis_error *err);

/* Synthetic source: the callback fills `shape` for frame `index` (arrays must stay valid until the
 * next call) and returns 0, or returns 1 at the end of the sequence, or -1 on error. */
typedef int (*vis_shape_fn)(void *user, int index, vis_shape *shape);

typedef struct vis_source vis_source;
vis_source *vis_source_open_camera(const vis_camera_settings *s, vis_error *err);
vis_source *vis_source_open_video(const char *path, vis_error *err);
/* The same video decoded ahead on a thread of its own (up to 16 frames), so decoding runs while the
 * caller tracks: the frames, their order, times and errors are exactly vis_source_open_video's
 * (vision/source/source_prefetch.cpp). For replays and `ribbonctl track`, which use every core this way. */
vis_source *vis_source_open_video_prefetch(const char *path, vis_error *err);
/* printf-style pattern with one integer conversion, e.g. "dir/frame_%04d.png", starting at `first`. */
vis_source *vis_source_open_images(const char *pattern, int first, vis_error *err);
vis_source *vis_source_open_synthetic(const vis_render_params *p, double fps, vis_shape_fn fn,
                                      void *user, vis_error *err);
/* Next frame as grey into `out` (reallocated as needed); `t_s` (may be NULL) gets its time in seconds.
 * Returns VIS_ERR_END at a clean end; VIS_ERR_FORMAT when the stream is damaged (a video that stops
 * before its announced length, an unreadable image): the message says after which frame. */
vis_status vis_source_read(vis_source *src, vis_frame *out, double *t_s, vis_error *err);
/* What a live camera says about one frame (vis_source_read_meta).
 * camera_t_s: the camera's own timestamp of the frame, seconds on the camera's clock (GenICam buffer
 *   timestamp; V4L2 buffer timestamp, CLOCK_MONOTONIC for UVC); NaN when the source has none.
 * host_t_s: CLOCK_MONOTONIC when the frame was handed to the program (seconds).
 * frame_id: the camera's frame counter (GenICam block id); sources without one count frames.
 * lost_before: frames that never arrived just before this one (a gap in the camera's ids).
 * incomplete: buffers the transport delivered damaged (missing packets, timeout) just before this
 *   one; they are dropped unread (their pixels are not an image). */
typedef struct vis_frame_meta {
    double camera_t_s;
    double host_t_s;
    uint64_t frame_id;
    long lost_before;
    int incomplete;
} vis_frame_meta;
/* A camera's block ids, followed to count the frames that never arrived. GigE Vision 1.x ids are
 * 16 bits and wrap 65535 -> 1 (0 is never used); GigE Vision 2 and USB3 Vision ids are 64 bits.
 * A transport may deliver a frame late, after a newer one (a buffer with missing packets is closed
 * when its timeout runs out, after the frames behind it completed): its id was already counted in
 * the gap before the newer frame, so it is late, counted nowhere again, and the ids' position stays
 * at the newest frame. */
typedef struct vis_block_ids {
    int have;      /* an id was seen */
    uint64_t last; /* the newest id seen */
} vis_block_ids;
#define VIS_BLOCK_LATE (-1L)
/* The frames lost just before `id` (0 or more), or VIS_BLOCK_LATE for an id at most 1,024 behind
 * the newest one seen (a late or repeated buffer; in the 16-bit range also just across a wrap).
 * Further back is a 16-bit wrap (the ids' last value at most 65535) or, for 64-bit ids, the camera
 * starting its ids again (0 lost). */
long vis_block_ids_next(vis_block_ids *ids, uint64_t id);

/* Like vis_source_read, with the frame's metadata. A source that is not a live camera gives
 * camera_t_s = its own time (t_s) and counts frames. */
vis_status vis_source_read_meta(vis_source *src, vis_frame *out, vis_frame_meta *meta, vis_error *err);
/* Lists the GenICam cameras Aravis sees: calls fn once per camera with its device id, vendor, model,
 * and transport ("GigEVision", "USB3Vision"); returns how many, or -1 with err when Aravis cannot
 * enumerate. */
int vis_aravis_list(void (*fn)(void *user, const char *id, const char *vendor, const char *model,
                               const char *protocol),
                    void *user, vis_error *err);
int vis_source_frame_count(const vis_source *src);  /* announced count, or -1 if unknown */
double vis_source_fps(const vis_source *src);       /* frames per second, or 0 if unknown */
void vis_source_close(vis_source *src);

#ifdef __cplusplus
}
#endif

#endif
