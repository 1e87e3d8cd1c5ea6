/* rod_snap_watch.c: a simulated ribbon's own snap, found step by step (see rod_snap_watch.h). */
#include "rod_snap_watch.h"

#include <math.h>
#include <string.h>

void rod_snap_watch_init(rod_snap_watch *w, double snap_speed, double asym_threshold, double post_snap_time)
{
    memset(w, 0, sizeof *w);
    w->snap_speed = snap_speed;
    w->slow = 0.1 * snap_speed;
    w->asym_threshold = asym_threshold;
    w->post_snap_time = post_snap_time;
    w->r.snap_dw = NAN;
    w->r.t_onset = NAN;
    w->r.t_detect = NAN;
    w->r.dz_onset = NAN;
}

void rod_snap_watch_add(rod_snap_watch *w, double t, double dw, const rod_obs *o)
{
    if (!o || !isfinite(t) || !isfinite(dw) || !isfinite(o->dz) || !isfinite(o->a) || !isfinite(o->a_cam)) return;
    rod_snap_report *r = &w->r;
    if (!w->have_prev || !(t > w->t_prev)) {
        if (!w->have_prev) {
            /* The first state is the onset until a step says otherwise. */
            r->snap_dw = dw;
            r->t_onset = t;
            r->dz_onset = o->dz;
        }
        w->have_prev = 1;
        w->t_prev = t;
        w->dz_prev = o->dz;
        return;
    }
    double h = t - w->t_prev, step = o->dz - w->dz_prev;
    double speed = fabs(step) / h;
    if (h > r->dt_max) r->dt_max = h;
    double aa = fabs(o->a), ac = fabs(o->a_cam);
    if (!r->snapped) {
        if (speed < w->slow) {
            r->snap_dw = dw;
            r->t_onset = t;
            r->dz_onset = o->dz;
            r->peak_abs_a = r->peak_abs_a_post = aa;
            r->peak_abs_a_cam = ac;
        } else {
            r->peak_abs_a = fmax(r->peak_abs_a, aa);
            r->peak_abs_a_post = fmax(r->peak_abs_a_post, aa);
            r->peak_abs_a_cam = fmax(r->peak_abs_a_cam, ac);
        }
        if (speed > w->snap_speed) {
            r->snapped = 1;
            r->t_detect = t;
            w->dir = step > 0.0 ? 1.0 : -1.0;
        }
    } else if (!r->final) {
        /* The first swing ends where Delta Z turns round. */
        if (!r->swing_over && step * w->dir < 0.0) r->swing_over = 1;
        if (!r->swing_over) r->peak_abs_a = fmax(r->peak_abs_a, aa);
        r->peak_abs_a_post = fmax(r->peak_abs_a_post, aa);
        r->peak_abs_a_cam = fmax(r->peak_abs_a_cam, ac);
        if (t - r->t_detect >= w->post_snap_time) r->final = 1;
    }
    r->asymmetric = r->snapped && r->peak_abs_a > w->asym_threshold;
    w->t_prev = t;
    w->dz_prev = o->dz;
}

const char *rod_snap_report_regime(const rod_snap_report *r)
{
    if (!r || !r->snapped) return "no snap";
    return r->asymmetric ? "asymmetric" : "symmetric";
}
