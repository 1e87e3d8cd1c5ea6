/* trial_transcode.h: one trial's raw video made small without losing a bit, after the trial.
 *
 * Rig mode records raw Y800 (8-bit grey) in AVI, because that is a copy per frame and never
 * falls behind the camera (docs/rig-realtime.md); at 640 x 480 and 60 fps it is 1.3 GB a trial.
 * Afterwards, off the real-time path, the file is encoded to FFV1 (version 3, Golomb-Rice coder,
 * slice CRCs, slice threads) in Matroska through libavcodec, written as OUT.part, then checked bit for
 * bit: both files are decoded again from disk, frame by frame, and every pixel compared. Only when
 * every frame matches and the counts agree is OUT.part renamed to OUT (and synced) and the raw
 * file removed. Anything else removes OUT.part, keeps the raw file and says why. The frame-time
 * file (RAW.frames.csv) is not touched: replay finds it for either form (trial_replay.c).
 *
 * Why FFV1 through libavcodec and not OpenCV's FFV1 writer: the same bitstream, but OpenCV's
 * writer encodes on one thread with a BGR round trip and a level-1 stream (no slices, no CRCs);
 * `ribbonctl transcode --bench` measures both on the same file. */
#ifndef RIBBON_DAEMON_TRIAL_TRANSCODE_H
#define RIBBON_DAEMON_TRIAL_TRANSCODE_H

#include <stddef.h>
#include <stdint.h>

typedef struct trial_transcode_params {
    int threads;        /* encoder slice threads, [1, 16]; default 2 */
    int slices;         /* FFV1 slices per frame (4, 6, 9, 12, 16, 24 or 30); default 4 */
    int range_coder;    /* 1: FFV1's range coder (0.7% smaller on the twin's frames, twice the
                           time), 0: Golomb-Rice; default 0 */
    int keep_raw;       /* 1: keep the raw file after a good verify (benchmarks); default 0 */
    /* Crop of the kept video inside the raw frame, pixels; w = 0: the whole raw frame. */
    int crop_x, crop_y, crop_w, crop_h;
    const volatile int *cancel; /* may be NULL: when it becomes non-zero the transcode stops (raw kept) */
    /* Fault injection for tests: >= 0 flips the low bit of pixel (0, 0) of that frame before it
     * is encoded (what a lossy codec does), so the verify must refuse the file; default -1. */
    long corrupt_frame;
    /* Tests: called after each frame is encoded (may be NULL), to hold a transcode in progress. */
    void (*on_frame)(void *user, long frame);
    void *on_frame_user;
} trial_transcode_params;

trial_transcode_params trial_transcode_params_default(void);

typedef struct trial_transcode_result {
    long frames;            /* frames in the raw file (and, verified, in the output) */
    int width, height;      /* px of the output */
    int64_t raw_bytes;      /* the raw file's size */
    int64_t out_bytes;      /* the output's size (0 when none was kept) */
    double encode_s;        /* wall s: decode raw + encode + write */
    double verify_s;        /* wall s: decode both again and compare */
    int raw_removed;        /* 1 when the raw file was deleted (only after a good verify) */
} trial_transcode_result;

/* Transcodes raw_path (a raw grey video: Y800 AVI) to out_path (.mkv). Returns 0 with the raw
 * file removed (unless keep_raw), or -1 with why (the raw file always kept, no output left). */
int trial_transcode_run(const char *raw_path, const char *out_path, const trial_transcode_params *p,
                        trial_transcode_result *res, char *why, size_t why_len);

/* Compares two videos frame by frame, decoding both from disk: 0 when they hold the same number
 * of frames of the same size with every pixel equal (frames in *n), or -1 with the first
 * difference in why. crop (may be NULL): x, y, w, h of a's frame that b must equal. */
int trial_transcode_compare(const char *a_path, const char *b_path, const int crop[4], long *n, char *why,
                            size_t why_len);

#endif
