/* snap_detect.h: finds the snap in a stream of measured frames as they arrive, with the same
 * definition the simulator uses (sim/rod_protocol.h, README "Snap"), so measured and predicted
 * snaps are the same quantity:
 *   - the ribbon is snapping at the first frame where |d(Delta Z)/dt| between consecutive measured
 *     frames exceeds snap_speed (1/s) and the jump exceeds dz_jump (a floor above the tracker's
 *     noise);
 *   - the snap Delta W is the Delta W of the last frame before that where |d(Delta Z)/dt| was
 *     still below a tenth of snap_speed (the onset);
 *   - the pathway is asymmetric when the peak |A| from the onset until the ribbon settles (speed
 *     below a tenth of snap_speed for settle_frames frames) or post_snap_s after detection exceeds
 *     asym_threshold (the simulator's own rule, sim/rod_regime.h: 0.5 rad by default, derived
 *     from creases up to 5% apart with the tracker's noise; the camera must resolve the snap's
 *     passage, docs/trials.md "Snap detection").
 * Frames the tracker could not measure are skipped (they neither start nor end anything).
 * Across a gap (unmeasured frames between two measured ones, e.g. frames stored untracked while the
 * trial loop was behind) the snap's own fast frames may be unseen and the speed over the gap
 * diluted below snap_speed: the first measured frame after the gap is then also a snap when its
 * jump from the last measured frame exceeds dz_jump, what snap_speed gives in ONE frame period
 * (the gap's time over its frame count), and its mean speed over the gap exceeds both a tenth of
 * snap_speed (the slow bound) and twice the speed measured before the gap (so a ribbon that was
 * already moving steadily, below snap_speed, is not called snapping by a gap). Its onset is bounded by the gap: the last slow frame (at or before the gap's
 * start) up to the detection frame; gap_frames and onset_dw_hi say so (issue 34 F). */
#ifndef RIBBON_DAEMON_SNAP_DETECT_H
#define RIBBON_DAEMON_SNAP_DETECT_H

typedef struct snap_params {
    double snap_speed;     /* 1/s, normalised Delta Z speed that means snapping (scene snap.speed) */
    double dz_jump;        /* normalised jump between consecutive measured frames also required */
    double asym_threshold; /* rad, peak |A| above which the snap is asymmetric */
    double post_snap_s;    /* s after detection at most spent on the pathway */
    int settle_frames;     /* consecutive slow frames that end the snap */
} snap_params;

typedef enum snap_phase {
    SNAP_WAITING = 0, /* no snap yet */
    SNAP_SNAPPING,    /* detected; following the pathway */
    SNAP_DONE         /* detected and settled (or post_snap_s passed): result final */
} snap_phase;

typedef struct snap_detect {
    snap_params p;
    snap_phase phase;
    int have_prev;
    double t_prev, dz_prev;
    double onset_dw;       /* Delta W of the last slow frame */
    long onset_frame;
    double t_onset;        /* its time */
    double peak_abs_a;
    double t_detect;
    long detect_frame;     /* first frame seen snapping */
    int slow_run;
    long frame_prev;       /* the last measured frame's index */
    double v_prev;         /* the last measured |d(Delta Z)/dt| (0 before the second frame) */
    double dw_prev;        /* ... and its Delta W */
    long gap_frames;       /* unmeasured frames just before the detection frame (0: seen directly) */
    double onset_dw_hi;    /* the onset's upper bound: the detection frame's Delta W when it was
                              caught across a gap (the onset lies in [onset_dw, onset_dw_hi]);
                              equal to onset_dw otherwise */
} snap_detect;

snap_params snap_params_default(void);
void snap_detect_init(snap_detect *d, const snap_params *p);
/* One frame. valid = 0 for a frame without a measurement. Returns the phase after the frame. */
snap_phase snap_detect_add(snap_detect *d, long frame, double t_s, double dw, double dz, double a, int valid);
/* Result (meaningful once phase >= SNAP_SNAPPING; the regime is final at SNAP_DONE). */
int snap_detect_snapped(const snap_detect *d);
double snap_detect_dw(const snap_detect *d);
int snap_detect_asymmetric(const snap_detect *d);
/* Unmeasured frames the detection spanned (0: the snap's fast frames were seen). */
long snap_detect_gap_frames(const snap_detect *d);
/* Upper bound of the onset's Delta W (= snap_detect_dw when no gap). */
double snap_detect_dw_hi(const snap_detect *d);
/* "asymmetric", "symmetric" or "no snap". */
const char *snap_detect_regime(const snap_detect *d);

#endif
