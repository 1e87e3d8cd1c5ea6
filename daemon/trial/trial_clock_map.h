/* trial_clock_map.h: a camera's clock mapped onto the rails' monotonic clock, frame by frame.
 *
 * A camera stamps each frame on its own clock (a GenICam device's tick counter, ns); the program
 * sees the frame arrive on the host's CLOCK_MONOTONIC, which is the rails' clock (rail_clock_real).
 * Model: host_i = camera_i + offset(t) + delay_i, with delay_i >= d0 >= 0 (readout, transport,
 * scheduling) and offset(t) drifting slowly (two crystals: up to about 1e-4, 6 ms per minute).
 * The lower envelope of host_i - camera_i is offset + d0, so:
 *   - frames are grouped in blocks of TRIAL_CLOCK_BLOCK; each block keeps its smallest
 *     host - camera (the frame that arrived fastest) and that frame's camera time;
 *   - the mapping is a line under the last TRIAL_CLOCK_BLOCKS block minima: once they span
 *     TRIAL_CLOCK_MIN_DRIFT_SPAN_S of camera time its slope (the drift) joins the lowest minimum of
 *     the window's first third to the lowest of its last third (at most TRIAL_CLOCK_MAX_DRIFT), and
 *     it passes through the lowest point of the last third; before that it is flat at the lowest
 *     block minimum, and before three blocks the smallest difference seen. Not a least-squares
 *     line: under load few frames arrive at the floor (1 in 150 on a loaded 2-core machine), and a
 *     fit through the minima sits at their mean, 0.7 ms above it;
 *   - mapped time = camera time + the line at that camera time.
 * A late frame (scheduling, a burst) never moves the estimate: only the fastest arrival of a block
 * counts. The constant d0 (a camera that stamps at exposure start delivers a readout later) stays
 * in the mapping; it is the rig's calibrated camera.time_offset_s, added by the runner.
 * A camera whose clock already is the host's monotonic clock (UVC cameras through V4L2 stamp
 * buffers with CLOCK_MONOTONIC) is recognised by its first difference lying in [0, 1) s and
 * mapped unchanged: the identity, no estimate.
 * A frame without a camera time (NaN) is mapped to its host time. */
#ifndef RIBBON_DAEMON_TRIAL_CLOCK_MAP_H
#define RIBBON_DAEMON_TRIAL_CLOCK_MAP_H

#define TRIAL_CLOCK_BLOCK 16  /* frames per block minimum */
#define TRIAL_CLOCK_BLOCKS 64 /* block minima in the fit (about 17 s at 60 fps) */
#define TRIAL_CLOCK_MIN_DRIFT_SPAN_S 8.0 /* a drift is fitted only over at least this much camera time */
#define TRIAL_CLOCK_MAX_DRIFT 1e-3       /* two crystals differ by 1e-4 at most: a larger slope is noise */

typedef struct trial_clock_map {
    int identity;           /* 1: the camera's clock is the host's monotonic clock */
    int started;
    long n;                 /* frames added */
    double cur_min, cur_cam; /* the current block's smallest host - camera, and its camera time */
    int cur_n;
    double blk_min[TRIAL_CLOCK_BLOCKS], blk_cam[TRIAL_CLOCK_BLOCKS];
    int n_blk, next_blk;
    double all_min;         /* smallest host - camera so far */
    double a, b;            /* offset(cam) = a + b (cam - cam_ref) once fitted */
    double cam_ref;
    int fitted;
} trial_clock_map;

void trial_clock_map_init(trial_clock_map *m);
/* Adds one frame (camera time, host arrival time; s) and returns its time on the host clock. */
double trial_clock_map_add(trial_clock_map *m, double camera_t_s, double host_t_s);
/* The current offset (host - camera, s) at camera time camera_t_s; 0 for the identity. */
double trial_clock_map_offset(const trial_clock_map *m, double camera_t_s);
/* The drift (s per s) of the current fit, 0 before it. */
double trial_clock_map_drift(const trial_clock_map *m);

#endif
