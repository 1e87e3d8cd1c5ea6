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
 * The onset at a slow passage (a saddle-node's departure: the speed rises through a tenth of
 * snap_speed over several frames, e.g. 0.09 to 0.12 /s over 6 frames at the rehearsal's Gamma
 * 0.21): a single frame-to-frame speed there is noisy (the frames' stamps against the instant
 * they show, the tracker: 0.007-0.010 /s measured in the rehearsal), and "the last slow frame"
 * takes the LAST of the frames that happened to read slow, late by up to the whole dwell near the
 * threshold (+0.0021 of Delta W, 2.5 frames, measured). So once the snap is seen the onset is
 * re-read back from the detection over the kept frames (SNAP_HIST) with a centred chord: the
 * speed at a frame is read over its frame-to-frame interval widened by SNAP_CHORD_HALF measured
 * frames on each side (centred where the frame-to-frame speed is, so no bias on a ramp), narrowed
 * back symmetrically so that it never reaches past the last frame before the detection whose
 * frame-to-frame speed was at most twice the slow bound (a fast passage's own frames never enter
 * it and its onset stays the last slow frame), and the onset is the last frame whose chord speed
 * is below the slow bound (the frame-to-frame rule when no chord is; always across a gap); the
 * passage and the peak |A| restart there. And a frame that
 * repeats the one before (Delta Z moved less than SNAP_REPEAT_FRAC of what the slow bound gives
 * in the interval, right after a frame at or above it: a rig simulator's twin one step behind real
 * time sends the same state twice; a strip approaching its snap does not stop within a frame) is
 * skipped like an unmeasured one, at most SNAP_REPEAT_MAX in a row: before, it read a speed of 0
 * and restarted the onset (+0.0037, 4 frames late, measured in the rehearsal).
 * Across a gap (unmeasured frames between two measured ones, e.g. frames stored untracked while the
 * trial loop was behind) the snap's own fast frames may be unseen and the speed over the gap
 * diluted below snap_speed: the first measured frame after the gap is then also a snap when its
 * jump from the last measured frame exceeds dz_jump, what snap_speed gives in ONE frame period
 * (the gap's time over its frame count), and its mean speed over the gap exceeds both a tenth of
 * snap_speed (the slow bound) and twice the speed measured before the gap (so a ribbon that was
 * already moving steadily, below snap_speed, is not called snapping by a gap). Its onset is bounded by the gap: the last slow frame (at or before the gap's
 * start) up to the detection frame; gap_frames and onset_dw_hi say so (issue 34 F).
 *
 * The regime (issue 35 D, docs/trials.md "The measured regime"). The rule is the simulator's: peak
 * |A| (the paper's 3D A) over the first swing above asym_threshold. A side camera cannot apply it
 * as such: the swing's fast part lasts about 25 ms (one frame at 30-60 fps, and the tracker loses
 * the strip in its sharpest frames), and the projected A it measures is 0.3 to 3 times the 3D A
 * there. What it does see in many frames is how the snap departs: a pitchfork's critical mode is
 * odd (A grows while Delta Z hardly moves), a saddle-node's even (Delta Z falls, A follows only as
 * the imperfection's response). So the regime is read from the departure: |A - A_onset| /
 * |Delta Z - Delta Z_onset| at depart_at (0.06) of Delta Z travel from the onset, interpolated
 * between the two measured frames around it (when no frame reaches it, at the frame that went
 * furthest), reading only frames within the first depart_frac of the first swing's Delta Z travel
 * and at least depart_min_dz from the onset: asymmetric at or above depart_asym, symmetric at or
 * below depart_sym, undecided between. A fixed travel, not the furthest frame: at 60 fps the
 * furthest frame within 30% of the swing is often already in the passage, where the side view's A
 * is several times the 3D A (5 times at phi 60), and symmetric twins read asymmetric there.
 * Without such a frame, the peak |A| over the first swing decides only outside a factor
 * peak_margin of asym_threshold; else undecided. The first swing ends at the first measured frame
 * whose Delta Z turns back against the snap's direction (as rod_snap_watch.h ends it). */
#ifndef RIBBON_DAEMON_SNAP_DETECT_H
#define RIBBON_DAEMON_SNAP_DETECT_H

#include <stddef.h>

typedef struct snap_params {
    double snap_speed;     /* 1/s, normalised Delta Z speed that means snapping (scene snap.speed) */
    double dz_jump;        /* normalised jump between consecutive measured frames also required */
    double asym_threshold; /* rad, peak |A| above which the snap is asymmetric */
    double post_snap_s;    /* s after detection at most spent on the pathway */
    int settle_frames;     /* consecutive slow frames that end the snap */
    double depart_frac;    /* the departure's frames lie within this share of the first swing's
                              Delta Z travel (0.3) */
    double depart_min_dz;  /* ... and at least this far from the onset's Delta Z (normalised, 0.01:
                              the tracker's 0.015 rad on A then moves the ratio by about 2) */
    double depart_at;      /* the departure is read at this Delta Z travel from the onset (0.06),
                              interpolated between the kept frames around it; when none reaches
                              it, at the furthest kept frame */
    double depart_asym;    /* |dA / dDelta Z| of the departure at or above which it is asymmetric */
    double depart_sym;     /* ... at or below which it is symmetric (between: undecided) */
    double peak_margin;    /* without a departure: asymmetric above asym_threshold times this,
                              symmetric below it divided by this, undecided between (2) */
} snap_params;

/* The regime a snap's frames read. */
typedef enum snap_regime {
    SNAP_REGIME_NONE = 0,    /* no snap */
    SNAP_REGIME_SYMMETRIC,
    SNAP_REGIME_ASYMMETRIC,
    SNAP_REGIME_UNDECIDED    /* the frames cannot tell (stored as unknown) */
} snap_regime;

/* The passage's frames kept for the departure: from the onset frame to the first swing's end. */
#define SNAP_PASSAGE_MAX 256

typedef struct snap_reading {
    snap_regime regime;
    int by_departure;      /* 1: decided (or left undecided) by the departure; 0: by the peak */
    double departure;      /* |dA / dDelta Z| at the departure frame; NaN without one */
    double departure_dz;   /* that frame's Delta Z travel from the onset; NaN without one */
    double swing_dz;       /* the first swing's Delta Z travel seen by the frames */
    double peak_swing;     /* rad, peak |A| from the onset to the first swing's end */
    int passage_frames;    /* measured frames from the onset to the swing's end */
    int inside;            /* a measured frame lies inside the passage (less than
                              SNAP_INSIDE_FRAC of the swing's travel from the onset): without
                              one the peak cannot read "symmetric", only a high |A| counts */
} snap_reading;
#define SNAP_INSIDE_FRAC 0.8

/* The frames kept for re-reading the onset (snap_detect.h, top): the last SNAP_HIST measured ones
 * while waiting for the snap. */
#define SNAP_HIST 64
#define SNAP_CHORD_HALF 2
#define SNAP_REPEAT_FRAC 0.25
#define SNAP_REPEAT_MAX 2

typedef struct snap_frame {
    long frame;
    double t, dw, dz, a;
} snap_frame;

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
    double dir;            /* +1 / -1: Delta Z's direction at the detection */
    int swing_over;        /* 1 once Delta Z turned back (the first swing ended) */
    double peak_swing;     /* peak |A| from the onset to the first swing's end */
    int pass_n;            /* the passage's frames kept (from the onset; at most SNAP_PASSAGE_MAX) */
    double pass_far;       /* the largest |Delta Z - Delta Z_onset| of the passage's frames, kept or not */
    double pass_dz[SNAP_PASSAGE_MAX], pass_a[SNAP_PASSAGE_MAX];
    snap_frame hist[SNAP_HIST]; /* the last measured frames while waiting (a ring) */
    int hist_n, hist_next;      /* frames in the ring; the slot the next one goes to */
    int repeats;                /* repeated frames skipped in a row just now */
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
/* 1 when the reading is asymmetric (snap_detect_read). */
int snap_detect_asymmetric(const snap_detect *d);
/* The regime the frames read, with its numbers (meaningful once snapped; final at SNAP_DONE). */
void snap_detect_read(const snap_detect *d, snap_reading *out);
/* The reading in words for the trial's events, e.g. "asymmetric by the departure: |dA/dDelta Z| =
 * 14.3 over the first 0.018 of Delta Z (asymmetric at or above 8, symmetric at or below 3.5); peak
 * |A| over the first swing 0.407 rad in 4 frames". */
void snap_reading_format(const snap_reading *r, const snap_params *p, char *buf, size_t len);
/* Unmeasured frames the detection spanned (0: the snap's fast frames were seen). */
long snap_detect_gap_frames(const snap_detect *d);
/* Upper bound of the onset's Delta W (= snap_detect_dw when no gap). */
double snap_detect_dw_hi(const snap_detect *d);
/* "asymmetric", "symmetric", "unknown" (undecided) or "no snap". */
const char *snap_detect_regime(const snap_detect *d);

#endif
