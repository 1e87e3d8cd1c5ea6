/* snap_detect.c: online snap detection on measured frames (see snap_detect.h). */
#include "snap_detect.h"

#include "rod_regime.h"

#include <math.h>
#include <string.h>

snap_params snap_params_default(void)
{
    snap_params p;
    p.snap_speed = 1.0;
    p.dz_jump = 0.005;
    p.asym_threshold = ROD_REGIME_ASYM_THRESHOLD;
    p.post_snap_s = 2.0;
    p.settle_frames = 5;
    return p;
}

void snap_detect_init(snap_detect *d, const snap_params *p)
{
    memset(d, 0, sizeof *d);
    d->p = *p;
    d->onset_frame = -1;
    d->detect_frame = -1;
    d->frame_prev = -1;
}

snap_phase snap_detect_add(snap_detect *d, long frame, double t_s, double dw, double dz, double a, int valid)
{
    if (!valid || !isfinite(t_s) || !isfinite(dw) || !isfinite(dz) || !isfinite(a)) return d->phase;
    if (d->phase == SNAP_DONE) return d->phase;
    if (!d->have_prev || !(t_s > d->t_prev)) {
        /* First measured frame (or a repeated time stamp): a reference, not a speed. */
        if (!d->have_prev) {
            d->onset_dw = dw;
            d->onset_frame = frame;
            d->t_onset = t_s;
            d->peak_abs_a = fabs(a);
        }
        d->have_prev = 1;
        d->t_prev = t_s;
        d->dz_prev = dz;
        d->frame_prev = frame;
        d->dw_prev = dw;
        return d->phase;
    }
    double dt = t_s - d->t_prev, jump = fabs(dz - d->dz_prev), speed = jump / dt;
    double slow = 0.1 * d->p.snap_speed;
    long gap = frame - d->frame_prev - 1;
    double v_before = d->v_prev;
    d->v_prev = speed;
    d->t_prev = t_s;
    d->dz_prev = dz;
    d->frame_prev = frame;
    d->dw_prev = dw;
    if (d->phase == SNAP_WAITING) {
        if (speed < slow) {
            d->onset_dw = dw;
            d->onset_frame = frame;
            d->t_onset = t_s;
            d->peak_abs_a = fabs(a);
        } else {
            d->peak_abs_a = fmax(d->peak_abs_a, fabs(a));
        }
        int seen = speed > d->p.snap_speed && jump > d->p.dz_jump;
        /* Across a gap: the post-snap state without the snap's frames (snap_detect.h). */
        int across = !seen && gap > 0 && jump > d->p.dz_jump && jump > d->p.snap_speed * dt / (double)(gap + 1) &&
                     speed > slow && speed > 2.0 * v_before;
        if (seen || across) {
            d->phase = SNAP_SNAPPING;
            d->t_detect = t_s;
            d->detect_frame = frame;
            d->slow_run = 0;
            d->gap_frames = across ? gap : 0;
            d->onset_dw_hi = across ? dw : d->onset_dw;
        }
        return d->phase;
    }
    /* Snapping: follow the pathway until it settles. */
    d->peak_abs_a = fmax(d->peak_abs_a, fabs(a));
    d->slow_run = speed < slow ? d->slow_run + 1 : 0;
    if (d->slow_run >= d->p.settle_frames || t_s - d->t_detect >= d->p.post_snap_s) d->phase = SNAP_DONE;
    return d->phase;
}

int snap_detect_snapped(const snap_detect *d) { return d->phase != SNAP_WAITING; }
double snap_detect_dw(const snap_detect *d) { return d->onset_dw; }
int snap_detect_asymmetric(const snap_detect *d)
{
    return snap_detect_snapped(d) && rod_regime_asymmetric(d->peak_abs_a, d->p.asym_threshold);
}

long snap_detect_gap_frames(const snap_detect *d) { return d->gap_frames; }
double snap_detect_dw_hi(const snap_detect *d) { return d->gap_frames > 0 ? d->onset_dw_hi : d->onset_dw; }

const char *snap_detect_regime(const snap_detect *d)
{
    if (!snap_detect_snapped(d)) return "no snap";
    return snap_detect_asymmetric(d) ? "asymmetric" : "symmetric";
}
