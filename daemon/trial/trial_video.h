/* trial_video.h: the video every trial keeps for replay: lossless FFV1, cropped to a region of
 * interest (a scene keeps only the pixels it needs).
 *
 * The automatic region is the box the ribbon can ever occupy at the trial's compression (the
 * ellipse bound of twin_camera.h: x within d/2 +- l/2 of the clamp line's middle, z within +-h,
 * h = (l/2) sqrt(1 - (1 - Delta L)^2)), mapped to pixels with the calibration's scale around the
 * clamp points, plus a margin, clipped to the frame. The region's origin is stored with the trial
 * (calibration record) so a replay shifts the clamp points by it. */
#ifndef RIBBON_DAEMON_TRIAL_VIDEO_H
#define RIBBON_DAEMON_TRIAL_VIDEO_H

#include <stddef.h>

#include "vision.h"

typedef struct trial_roi {
    int x, y, w, h; /* pixels, inside the frame */
} trial_roi;

/* The automatic region for a frame of width x height, free length l_mm, compression dl. */
trial_roi trial_roi_auto(const vis_calib *c, int width, int height, double l_mm, double dl, int margin_px);
/* Clips a requested region to the frame (w, h >= 16 after clipping, else the full frame). */
trial_roi trial_roi_clip(trial_roi r, int width, int height);

typedef struct trial_video trial_video;
/* Opens path for frames of the region's size. */
trial_video *trial_video_open(const char *path, trial_roi roi, double fps, char *why, size_t why_len);
/* Bytes that must stay free on the video's file system beyond what the next frame may need (0 by
 * default). The tests' way to make a disk "full" without a small file system (no mount needed). */
void trial_video_set_min_free(trial_video *v, double bytes);
/* Crops f to the region and appends it. Fails (-1, why says "video disk full") before writing when
 * the video's file system has less room than the frame may need plus the reserve: OpenCV's writer
 * reports no write error, so a full disk must be seen before the frame is lost. */
int trial_video_add(trial_video *v, const vis_frame *f, char *why, size_t why_len);
/* Flushes and closes, then reads the container back; returns the frames written, or -1 (why says
 * "video incomplete") when the file holds fewer frames than were written or no count (a write the
 * encoder lost: full disk, file size limit, I/O error). */
long trial_video_close(trial_video *v, char *why, size_t why_len);

#endif
