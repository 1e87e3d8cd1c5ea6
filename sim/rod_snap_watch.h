/* rod_snap_watch.h: the snap of a simulated ribbon found from its own states, step by step, with
 * the definition the prediction (rod_protocol.h) and the camera's detector (snap_detect.h) use, so
 * a twin's own snap is the same quantity as the measured and the predicted one:
 *   - the ribbon is snapping at the first step where |d(Delta Z)/dt| exceeds snap_speed (1/s);
 *   - the snap Delta W is the Delta W of the last step before that where |d(Delta Z)/dt| was still
 *     below a tenth of snap_speed (the onset);
 *   - the pathway is asymmetric when the peak |A| (the paper's A, rod_observe.h) from the onset to
 *     the end of the snap's first swing (Delta Z turning round, as the fast prediction does)
 *     exceeds asym_threshold; the peak over post_snap_time after the detection is kept as well.
 * Only the first snap counts: a snap back on the way home is not the trial's. Owned apart from
 * rod_twin.c so the rule can be tested on closed-form input (tests/sim/test_rod_snap_watch.c). */
#ifndef RIBBON_SIM_ROD_SNAP_WATCH_H
#define RIBBON_SIM_ROD_SNAP_WATCH_H

#include "rod_observe.h"

typedef struct rod_snap_report {
    int snapped;          /* 1 once a snap was detected */
    int final;            /* 1 once post_snap_time passed after the detection */
    int swing_over;       /* 1 once the first swing ended (the regime is decided) */
    double snap_dw;       /* Delta W at the onset (snapped only) */
    double t_onset;       /* s, time of the onset step */
    double t_detect;      /* s, time of the first step faster than snap_speed */
    double dz_onset;      /* Delta Z at the onset */
    double peak_abs_a;    /* rad, peak |A| from the onset to the end of the first swing */
    double peak_abs_a_post; /* rad, peak |A| from the onset to post_snap_time after detection */
    double peak_abs_a_cam;  /* rad, the same as peak_abs_a_post for the camera's A (a_cam) */
    int asymmetric;       /* peak_abs_a > asym_threshold (snapped only) */
    double dt_max;        /* s, the longest step seen (the onset is known to within it) */
} rod_snap_report;

typedef struct rod_snap_watch {
    double snap_speed, slow, asym_threshold, post_snap_time;
    int have_prev;
    double t_prev, dz_prev, dir;
    rod_snap_report r;
} rod_snap_watch;

/* snap_speed (1/s, > 0), asym_threshold (rad), post_snap_time (s, >= 0): the scene's snap.speed
 * and snap.asym_threshold, and how long to follow the pathway (the prediction's 2 s). */
void rod_snap_watch_init(rod_snap_watch *w, double snap_speed, double asym_threshold, double post_snap_time);
/* One accepted state at time t (s, increasing) and shear dw; o: its observation. Non-finite input
 * is ignored (it neither starts nor ends anything). */
void rod_snap_watch_add(rod_snap_watch *w, double t, double dw, const rod_obs *o);
/* "asymmetric", "symmetric" or "no snap". */
const char *rod_snap_report_regime(const rod_snap_report *r);

#endif
