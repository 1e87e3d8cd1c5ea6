/* trial_capture.h: the live camera pipeline of a rig trial: capture, ring, recorder, tracker feed.
 *
 *   camera --capture thread--> ring of `slots` frames --recorder thread--> video (every frame)
 *                                  `--> trial_capture_next (the runner: tracking, storage, snap)
 *
 * Capture thread: reads the source (vis_source_read_meta: camera timestamp, frame id, ids lost,
 * buffers incomplete), maps the camera time onto the rails' monotonic clock (trial_clock_map.h)
 * and publishes the frame. The first `warmup_s` of frames only teach the map (a frame's time is
 * mapped when it arrives, so the first frames would otherwise be mapped from a handful of
 * arrivals: 10 ms off seen under load); trial_capture_start returns once it is over. It never waits for a consumer: when the ring is full (the recorder is
 * `slots` frames behind) the frame is read into a scratch frame and counted as dropped.
 * Recorder thread: writes every published frame, cropped, to the video, and one line per frame to
 * the frame-times file beside it (video index, capture index, camera id, camera time, host time,
 * mapped time), so a replay has each frame's true time.
 * Quality: each frame's pixels are hashed (64 bits, 0.05 ms at 640 x 480) so a frozen image (the
 * same pixels, or the same camera id, frame after frame) shows as a growing `same_run`: a real
 * sensor's noise never repeats a frame bit for bit, and the runner decides (trial_runner.c: while
 * the rails move). Lost and incomplete frames are counted per frame and over a sliding window.
 * Runner (trial_capture_next): gets every frame's record in order (dropped ones too, flagged). When
 * it is more than `track_max_lag` frames behind the camera, or the frame arrived more than
 * `track_max_age_s` ago, frames come flagged `skip`: the runner
 * stores their sample (time, rail positions) without tracking them, and the count says how many.
 * So under overload what gives way is tracking, then (only if the recorder itself falls `slots`
 * frames behind) the video; capture never does.
 * Locks: one mutex guards the ring's counters; a tracked frame's pixels are copied out under it
 * (0.1-0.3 ms at 1280x720), the only time capture can wait on a consumer. */
#ifndef RIBBON_DAEMON_TRIAL_CAPTURE_H
#define RIBBON_DAEMON_TRIAL_CAPTURE_H

#include <stddef.h>
#include <stdint.h>

#include "trial_video.h"
#include "vision.h"

/* A frozen image (trial_runner.c): this many identical frames in a row while a rail moved at least
 * TRIAL_FROZEN_MOVE_MM since the first of them (0.2 s at 60 fps; 0.05 mm is 2.5 ms at 20 mm/s,
 * 50 ms at 1 mm/s, and about a third of a pixel of the rehearsal's camera). The defaults of the rig
 * file's camera.frozen_frames and camera.frozen_move_mm (trial_plan). */
#define TRIAL_FROZEN_FRAMES 12
#define TRIAL_FROZEN_MOVE_MM 0.05

typedef struct trial_capture_params {
    int slots;               /* ring size, frames (>= 4) */
    int track_max_lag;       /* frames behind the camera after which tracking skips (1..slots-1) */
    double track_max_age_s;  /* ... or a frame older than this when its turn comes (s, 0 = no limit):
                                bounds the delay from exposure to the snap detector (and so to the
                                stop) when the loop falls behind */
    double frame_timeout_s;  /* trial_capture_next waits this long for a frame before an error */
    const char *video_path;  /* .avi (raw Y800) or .mkv (FFV1); NULL = no video */
    trial_roi roi;           /* the video's region */
    double fps;              /* for the video header */
    double track_delay_s;    /* test hook: trial_capture_next sleeps this long per tracked frame */
    double max_loss_fraction; /* frames lost or incomplete over the last loss_window frames (default
                                0.25) above which capture ends: "camera ...: N of the last M frames
                                lost or incomplete" (0 = no limit) */
    int loss_window;         /* frames (default 60: a second at 60 fps) */
    double warmup_s;         /* the clock map's warm-up (s of camera time, default 1): frames before it
                                only teach the map and are not published; trial_capture_start
                                returns after it */
} trial_capture_params;
trial_capture_params trial_capture_params_default(void);

/* One frame as the runner sees it. */
typedef struct trial_frame_info {
    long index;              /* capture index, 0.. */
    long video_index;        /* index in the video, -1 for a dropped frame */
    uint64_t camera_id;      /* the camera's frame id */
    double camera_t_s;       /* camera clock, s (NaN: none) */
    double host_t_s;         /* host monotonic arrival, s */
    double t_s;              /* mapped onto the host monotonic clock, s */
    int dropped;             /* the ring was full: no pixels, not in the video */
    int skip;                /* the runner is behind: store without tracking */
    long lost_before;        /* frames the camera's ids say never arrived, just before this one */
    int incomplete;          /* damaged buffers discarded just before this one */
    long same_run;           /* 1 + how many frames in a row before this one had the same pixels (or
                                the same camera id): a camera resending one image (frozen) */
} trial_frame_info;

typedef struct trial_capture_counts {
    long warmup;             /* frames read for the clock map's warm-up (not published, not recorded) */
    long captured;           /* frames read from the camera after the warm-up */
    long lost;               /* frames the camera's ids say never arrived */
    long incomplete;         /* buffers the transport delivered damaged */
    long dropped;            /* frames the pipeline dropped (ring full): not in the video */
    long recorded;           /* frames in the video */
    long skipped;            /* frames not tracked (runner behind) */
    double offset_s, drift;  /* camera -> host clock: offset at the last frame (s), drift (s/s) */
    int identity_clock;      /* the camera stamps on the host's monotonic clock */
    double max_capture_to_record_s; /* largest delay from arrival to written in the video */
} trial_capture_counts;

typedef struct trial_capture trial_capture;

/* Starts the threads on an open source (borrowed until trial_capture_stop). */
trial_capture *trial_capture_start(vis_source *src, const trial_capture_params *p, char *why, size_t why_len);
/* The next frame in order. Copies its pixels into `out` unless it is dropped or skipped.
 * Returns 0, or -1 (why says: the camera failed or stopped sending, a timeout). */
int trial_capture_next(trial_capture *c, vis_frame *out, trial_frame_info *info, char *why, size_t why_len);
void trial_capture_get_counts(trial_capture *c, trial_capture_counts *out);
/* Stops the capture, lets the recorder finish the frames it has, closes the video. Returns 0, or -1
 * with why when the video or the frame-times file could not be completed. NULL is a no-op. */
int trial_capture_stop(trial_capture *c, trial_capture_counts *out, char *why, size_t why_len);

#endif
