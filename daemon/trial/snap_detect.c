/* snap_detect.c: online snap detection on measured frames (see snap_detect.h). */
#include "snap_detect.h"

#include "rod_regime.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The departure's thresholds, measured on the bench's twins (tests/daemon/trial/test_regime_read.c)
 * and on the camera campaigns' trials (docs/trials.md "The measured regime"): symmetric twins read
 * up to 7.6 near the threshold (3D peak |A| 0.35 at phi 90), so asymmetric needs 8. */
#define SNAP_DEPART_ASYM 8.0
#define SNAP_DEPART_SYM 3.5

/* The passage restarts at every slow frame before the snap (the onset moves with it). */
static void passage_reset(snap_detect *d, double dz, double a)
{
    d->pass_n = 0;
    d->pass_dz[d->pass_n] = dz;
    d->pass_a[d->pass_n++] = a;
    d->pass_far = 0.0;
    d->peak_swing = fabs(a);
}

static void passage_add(snap_detect *d, double dz, double a)
{
    d->peak_swing = fmax(d->peak_swing, fabs(a));
    d->pass_far = fmax(d->pass_far, fabs(dz - d->pass_dz[0])); /* every frame's, kept or not */
    if (d->pass_n < SNAP_PASSAGE_MAX) {
        d->pass_dz[d->pass_n] = dz;
        d->pass_a[d->pass_n++] = a;
    }
}

/* The ring of the last measured frames while waiting (snap_detect.h, top). */
static void hist_push(snap_detect *d, long frame, double t, double dw, double dz, double a)
{
    d->hist[d->hist_next] = (snap_frame){frame, t, dw, dz, a};
    d->hist_next = (d->hist_next + 1) % SNAP_HIST;
    if (d->hist_n < SNAP_HIST) d->hist_n++;
}

/* The i-th kept frame, oldest first. */
static const snap_frame *hist_at(const snap_detect *d, int i)
{
    return &d->hist[(d->hist_next - d->hist_n + i + SNAP_HIST) % SNAP_HIST];
}

static double hist_speed(const snap_detect *d, int lo, int hi)
{
    const snap_frame *a = hist_at(d, lo), *b = hist_at(d, hi);
    return fabs(b->dz - a->dz) / (b->t - a->t);
}

/* The onset re-read at the detection (the newest kept frame) with the centred chord: the kept
 * frame's index, or -1 when no chord reads slow (snap_detect.h, top). */
static int chord_onset(const snap_detect *d)
{
    double slow = 0.1 * d->p.snap_speed;
    int n = d->hist_n, last_ok = -1;
    for (int j = n - 2; j >= 1 && last_ok < 0; j--)
        if (hist_speed(d, j - 1, j) <= 2.0 * slow) last_ok = j;
    int on = -1;
    for (int k = 1; k <= last_ok; k++) {
        /* The frame-to-frame interval ending at k widened by h frames on each side (centred where
           the frame-to-frame speed is: no bias on a ramp); near the clip it narrows back to it. */
        int h = SNAP_CHORD_HALF;
        if (h > last_ok - k) h = last_ok - k;
        if (h > k - 1) h = k - 1;
        if (hist_speed(d, k - 1 - h, k + h) < slow) on = k;
    }
    return on;
}

/* The onset moved to kept frame k: the passage (and the peak) restart there. */
static void onset_from_hist(snap_detect *d, int k)
{
    const snap_frame *f = hist_at(d, k);
    d->onset_dw = f->dw;
    d->onset_frame = f->frame;
    d->t_onset = f->t;
    d->peak_abs_a = fabs(f->a);
    passage_reset(d, f->dz, f->a);
    for (int j = k + 1; j < d->hist_n; j++) {
        const snap_frame *g = hist_at(d, j);
        d->peak_abs_a = fmax(d->peak_abs_a, fabs(g->a));
        passage_add(d, g->dz, g->a);
    }
}

snap_params snap_params_default(void)
{
    snap_params p;
    p.snap_speed = 1.0;
    p.dz_jump = 0.005;
    p.asym_threshold = ROD_REGIME_ASYM_THRESHOLD;
    p.post_snap_s = 2.0;
    p.settle_frames = 5;
    p.depart_frac = 0.3;
    p.depart_min_dz = 0.01;
    p.depart_at = 0.06;
    p.depart_asym = SNAP_DEPART_ASYM;
    p.depart_sym = SNAP_DEPART_SYM;
    p.peak_margin = 2.0;
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
            passage_reset(d, dz, a);
            hist_push(d, frame, t_s, dw, dz, a);
        }
        d->have_prev = 1;
        d->t_prev = t_s;
        d->dz_prev = dz;
        d->frame_prev = frame;
        d->dw_prev = dw;
        return d->phase;
    }
    double dt = t_s - d->t_prev, step = dz - d->dz_prev, jump = fabs(step), speed = jump / dt;
    double slow = 0.1 * d->p.snap_speed;
    /* A repeated frame is skipped, not read as a standstill (snap_detect.h, top). */
    if (d->phase == SNAP_WAITING && d->v_prev >= slow && jump < SNAP_REPEAT_FRAC * slow * dt &&
        d->repeats < SNAP_REPEAT_MAX) {
        d->repeats++;
        d->frame_prev = frame;
        return d->phase;
    }
    d->repeats = 0;
    long gap = frame - d->frame_prev - 1;
    double v_before = d->v_prev;
    d->v_prev = speed;
    d->t_prev = t_s;
    d->dz_prev = dz;
    d->frame_prev = frame;
    d->dw_prev = dw;
    if (d->phase == SNAP_WAITING) {
        hist_push(d, frame, t_s, dw, dz, a);
        if (speed < slow) {
            d->onset_dw = dw;
            d->onset_frame = frame;
            d->t_onset = t_s;
            d->peak_abs_a = fabs(a);
            passage_reset(d, dz, a);
        } else {
            d->peak_abs_a = fmax(d->peak_abs_a, fabs(a));
            passage_add(d, dz, a);
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
            d->dir = step > 0.0 ? 1.0 : -1.0;
            d->swing_over = 0;
            if (seen) {
                int k = chord_onset(d);
                if (k >= 0) {
                    onset_from_hist(d, k);
                    d->onset_dw_hi = d->onset_dw;
                }
            }
        }
        return d->phase;
    }
    /* Snapping: follow the pathway until it settles. */
    d->peak_abs_a = fmax(d->peak_abs_a, fabs(a));
    if (!d->swing_over && step * d->dir < 0.0) d->swing_over = 1;
    if (!d->swing_over) passage_add(d, dz, a);
    d->slow_run = speed < slow ? d->slow_run + 1 : 0;
    if (d->slow_run >= d->p.settle_frames || t_s - d->t_detect >= d->p.post_snap_s) d->phase = SNAP_DONE;
    return d->phase;
}

int snap_detect_snapped(const snap_detect *d) { return d->phase != SNAP_WAITING; }
double snap_detect_dw(const snap_detect *d) { return d->onset_dw; }
/* The departure (snap_detect.h): |A - A_onset| / travel at depart_at of Delta Z travel from the
 * onset, interpolated between the two kept frames around it; when no frame reaches it, at the
 * furthest frame. Only frames within depart_frac of the swing's travel and at least depart_min_dz
 * from the onset are read (so a 30 fps camera whose next frame is already far down reads its last
 * frame before the passage). 0 without one. */
static int departure(const snap_detect *d, double *ratio, double *travel, double *swing)
{
    double dz0 = d->pass_dz[0], a0 = d->pass_a[0], s = d->pass_far;
    *swing = s;
    int best = -1;
    double far = 0.0, prev_tr = 0.0, prev_da = 0.0;
    for (int k = 1; k < d->pass_n; k++) {
        double tr = fabs(d->pass_dz[k] - dz0), da = fabs(d->pass_a[k] - a0);
        if (tr > d->p.depart_frac * s) continue;
        if (tr >= d->p.depart_at && d->p.depart_at >= d->p.depart_min_dz && tr > prev_tr) {
            /* the travel crossed depart_at between the last frame below it and this one */
            double w = (d->p.depart_at - prev_tr) / (tr - prev_tr);
            *travel = d->p.depart_at;
            *ratio = (prev_da + w * (da - prev_da)) / d->p.depart_at;
            return 1;
        }
        if (tr > prev_tr) {
            prev_tr = tr;
            prev_da = da;
        }
        if (tr >= d->p.depart_min_dz && tr > far) {
            far = tr;
            best = k;
        }
    }
    if (best < 0) return 0;
    *travel = far;
    *ratio = fabs(d->pass_a[best] - a0) / far;
    return 1;
}

void snap_detect_read(const snap_detect *d, snap_reading *out)
{
    memset(out, 0, sizeof *out);
    out->departure = out->departure_dz = NAN;
    out->regime = SNAP_REGIME_NONE;
    if (!snap_detect_snapped(d) || d->pass_n < 1) return;
    out->peak_swing = d->peak_swing;
    out->passage_frames = d->pass_n;
    double ratio, travel, swing = 0.0;
    int seen = departure(d, &ratio, &travel, &swing);
    out->swing_dz = swing;
    if (seen) {
        out->by_departure = 1;
        out->departure = ratio;
        out->departure_dz = travel;
        out->regime = ratio >= d->p.depart_asym   ? SNAP_REGIME_ASYMMETRIC
                      : ratio <= d->p.depart_sym ? SNAP_REGIME_SYMMETRIC
                                                 : SNAP_REGIME_UNDECIDED;
        return;
    }
    /* A low peak says "symmetric" only when some frame saw the passage itself: frames that show
       only the state before and the state after (lost or untracked ones between: the clean
       .ci/run's test_modbus_trial, 3 frames all at the lower state, 0.201 rad, an asymmetric twin)
       say nothing of it. */
    for (int k = 1; k < d->pass_n; k++)
        if (fabs(d->pass_dz[k] - d->pass_dz[0]) < SNAP_INSIDE_FRAC * swing) out->inside = 1;
    double thr = d->p.asym_threshold, m = d->p.peak_margin > 1.0 ? d->p.peak_margin : 1.0;
    out->regime = rod_regime_asymmetric(d->peak_swing, m * thr)                  ? SNAP_REGIME_ASYMMETRIC
                  : out->inside && !rod_regime_asymmetric(d->peak_swing, thr / m) ? SNAP_REGIME_SYMMETRIC
                                                                                  : SNAP_REGIME_UNDECIDED;
}

static const char *regime_word(snap_regime r)
{
    return r == SNAP_REGIME_ASYMMETRIC ? "asymmetric"
           : r == SNAP_REGIME_SYMMETRIC ? "symmetric"
           : r == SNAP_REGIME_UNDECIDED ? "unknown"
                                        : "no snap";
}

void snap_reading_format(const snap_reading *r, const snap_params *p, char *buf, size_t len)
{
    if (!buf || !len) return;
    if (r->regime == SNAP_REGIME_NONE) {
        snprintf(buf, len, "no snap");
        return;
    }
    if (r->by_departure)
        snprintf(buf, len,
                 "regime %s by the departure: |dA/dDelta Z| = %.2f over the first %.4f of Delta Z (swing %.4f; "
                 "asymmetric at or above %g, symmetric at or below %g); peak |A| over the first swing %.3f rad in %d "
                 "frames",
                 regime_word(r->regime), r->departure, r->departure_dz, r->swing_dz, p->depart_asym, p->depart_sym,
                 r->peak_swing, r->passage_frames);
    else
        snprintf(buf, len,
                 "regime %s by the peak: no frame within the first %g of the swing's Delta Z travel (%.4f) and %g "
                 "from the onset; peak |A| over the first swing %.3f rad in %d frames (asymmetric above %g, "
                 "symmetric at or below %g%s)",
                 regime_word(r->regime), p->depart_frac, r->swing_dz, p->depart_min_dz, r->peak_swing,
                 r->passage_frames, p->asym_threshold * p->peak_margin, p->asym_threshold / p->peak_margin,
                 r->inside ? "" : ", and only with a frame inside the passage: none");
}

int snap_detect_asymmetric(const snap_detect *d)
{
    snap_reading r;
    snap_detect_read(d, &r);
    return r.regime == SNAP_REGIME_ASYMMETRIC;
}

long snap_detect_gap_frames(const snap_detect *d) { return d->gap_frames; }
double snap_detect_dw_hi(const snap_detect *d) { return d->gap_frames > 0 ? d->onset_dw_hi : d->onset_dw; }

const char *snap_detect_regime(const snap_detect *d)
{
    snap_reading r;
    snap_detect_read(d, &r);
    return regime_word(r.regime);
}
