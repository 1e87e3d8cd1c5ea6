/* trial_transcoder.h: the daemon's background worker that transcodes each finished rig trial's raw
 * video (trial_transcode.h), one at a time, off the real-time path.
 *
 * A session hands its raw video over when its trial has ended (trial_transcoder_submit only queues
 * and returns), so the next trial starts and captures while the previous video is encoded. The
 * worker is one thread in SCHED_IDLE (thread_class.h; the encoder's slice threads inherit it: the
 * next trial's loop, capture and poller always win the cores), with its own store connection: on success the trial's video becomes the .mkv
 * with its size (store_trial_set_video_file) and an event gives sizes and times; on failure the
 * raw file stays the trial's video and an event says why. Stopping (daemon shutdown) stops the
 * running transcode at its next frame and leaves every raw file not yet transcoded in place, each
 * with an event. */
#ifndef RIBBON_DAEMON_TRIAL_TRANSCODER_H
#define RIBBON_DAEMON_TRIAL_TRANSCODER_H

#include <stddef.h>
#include <stdint.h>

#include "store.h"
#include "trial_transcode.h"

#define TRIAL_TRANSCODER_QUEUE 64 /* videos waiting at most; a submit beyond is refused */

typedef struct trial_transcoder_params {
    const char *store_path;        /* the store the trials are in (the worker's own connection) */
    trial_transcode_params codec;  /* threads, slices (crop is per job) */
    int idle;                      /* 1 (default): the worker runs in SCHED_IDLE; 0: in the caller's class */
    void (*log)(const char *line); /* may be NULL: one line per video */
} trial_transcoder_params;

trial_transcoder_params trial_transcoder_params_default(void);

typedef struct trial_transcoder trial_transcoder;

trial_transcoder *trial_transcoder_start(const trial_transcoder_params *p, char *why, size_t why_len);
/* The worker's Linux thread id once it runs (0 before), for thread_class_is_idle. */
long trial_transcoder_worker_tid(trial_transcoder *t);
/* Queues trial_id's raw video raw_path (...avi; the output is the same name with .mkv). crop (may
 * be NULL): x, y, w, h of the raw frame to keep, and rec_roi the kept region inside the full
 * frame, stored into the trial's calibration record with the new file (so a replay places the
 * clamps). Never waits for a transcode. -1 (why) when the queue is full or the worker has
 * stopped: the raw file stays the trial's video. */
int trial_transcoder_submit(trial_transcoder *t, int64_t trial_id, const char *raw_path, const int crop[4],
                            const int rec_roi[4], char *why, size_t why_len);
/* Start-up: queues (whole, uncropped) the raw .avi videos of ended rig trials in st that an earlier
 * run left (it stopped before their transcode), except those the trial's events keep raw on
 * purpose (a video not closed complete, a transcode that failed: by hand only, ribbonctl
 * transcode) and interrupted trials' (their recording may be cut: evidence). Returns how many were
 * queued, or -1 (why). */
int trial_transcoder_queue_left(trial_transcoder *t, store *st, char *why, size_t why_len);
/* Videos queued or in progress. */
int trial_transcoder_pending(trial_transcoder *t);
/* Waits until nothing is queued or in progress: 0, or -1 after timeout_s. */
int trial_transcoder_wait_idle(trial_transcoder *t, double timeout_s);
/* Stops the worker (the running transcode at its next frame, raw kept), drops the queue (raw files
 * kept, an event each), joins and frees. NULL is fine. */
void trial_transcoder_stop(trial_transcoder *t);

#endif
