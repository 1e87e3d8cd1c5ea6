/* trial_cam_watch.c: the runner's side of the camera's time offset (see trial_cam_watch.h). */
#include "trial_cam_watch.h"

#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define CAM_WATCH_MAX_READINGS 4096
#define CAM_WATCH_WINDOW_REL 0.15 /* a jaw's window half size, of the clamp points' spacing */
#define CAM_WATCH_MARGIN_PX 3.0   /* the window starts this far beyond the clamp point, px */
#define CAM_WATCH_MAX_MOVE_REL 0.25 /* a jaw's motion, of the window's half size, still used */

struct trial_cam_watch {
    trial_cam_offset *o;
    double win[2][2];     /* each jaw's window centre (u, v), px */
    double half_px;       /* the windows' half size, px */
    double window_s, fps, configured_s, t_cmd, t_left;
    int measure;
    int phase;            /* 0 idle, 1 standing, 2 shearing, 3 said */
    double stand[2][2];   /* the jaws' first standing centroids, px */
    int have_stand, left_window; /* the jaw moved out of the part of its window that holds it whole */
    long clamp_misses;
};

/* A jaw's centroid in the window of half size h around (cu, cv): the pixels' contrast against the
 * window's border (its median), less a noise floor (4 x the border's median absolute deviation,
 * at least 6 grey levels), as weights. A jaw is hundreds of pixels, so the centroid moves with it
 * to about 0.01 px (measured on ribbon-rigsim's images: residual 0.011 px). Without the floor
 * (every pixel's signed contrast, a linear centroid) the window's other structure and noise moved
 * it by 0.13 px. The floor locks the centroid a little to the pixel grid (0.02-0.06 px in the
 * first pixel of motion, seen on a sharp synthetic image). 0 with the centroid, -1 when the window
 * holds no contrast. */
static int jaw_centroid(const vis_frame *f, double cu, double cv, double h, double out[2])
{
    const int W = vis_frame_width(f), H = vis_frame_height(f), ch = vis_frame_channels(f);
    const size_t stride = vis_frame_stride(f);
    const uint8_t *d = vis_frame_data((vis_frame *)f);
    const int u0 = (int)fmax(0.0, floor(cu - h)), u1 = (int)fmin(W - 1.0, ceil(cu + h));
    const int v0 = (int)fmax(0.0, floor(cv - h)), v1 = (int)fmin(H - 1.0, ceil(cv + h));
    if (u1 - u0 < 4 || v1 - v0 < 4 || ch < 1) return -1;
    long hist[256] = {0}, n = 0;
    for (int v = v0; v <= v1; v++)
        for (int u = u0; u <= u1; u++)
            if (v == v0 || v == v1 || u == u0 || u == u1) {
                hist[d[(size_t)v * stride + (size_t)u * ch]]++;
                n++;
            }
    int med = 0;
    for (long acc = 0; med < 255 && (acc += hist[med]) < (n + 1) / 2; med++) continue;
    long dev[256] = {0};
    for (int g = 0; g < 256; g++) dev[abs(g - med)] += hist[g];
    int mad = 0;
    for (long acc = 0; mad < 255 && (acc += dev[mad]) < (n + 1) / 2; mad++) continue;
    const double floor_g = fmax(6.0, 4.0 * mad);
    double sw = 0.0, su = 0.0, sv = 0.0;
    for (int v = v0; v <= v1; v++) {
        const uint8_t *row = d + (size_t)v * stride;
        for (int u = u0; u <= u1; u++) {
            const double wgt = fabs((double)row[(size_t)u * ch] - med) - floor_g;
            if (wgt <= 0.0) continue;
            sw += wgt;
            su += wgt * u;
            sv += wgt * v;
        }
    }
    if (!(sw > 0.0)) return -1;
    out[0] = su / sw;
    out[1] = sv / sw;
    return 0;
}

trial_cam_watch *trial_cam_watch_alloc(double window_s, double fps, int measure, double configured_s,
                                       const double left_px[2], const double right_px[2])
{
    if (!(window_s > 0.0) || !(fps > 0.0) || !isfinite(configured_s)) return NULL;
    const double du = right_px[0] - left_px[0], dv = right_px[1] - left_px[1], spacing = hypot(du, dv);
    if (!(spacing >= 20.0) || !isfinite(spacing)) return NULL;
    trial_cam_watch *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    /* Frames of the standing span and the window, with room for a late frame rate. */
    size_t frames = (size_t)ceil((TRIAL_CAM_WATCH_STAND_S + 10.0 + window_s) * fps * 1.5) + 64;
    w->o = trial_cam_offset_alloc(frames, CAM_WATCH_MAX_READINGS);
    if (!w->o) {
        free(w);
        return NULL;
    }
    /* Each jaw lies outside the free length, beyond its clamp point: its window starts
     * CAM_WATCH_MARGIN_PX beyond it, so the strip (whose shape lags the clamp by its own dynamics)
     * stays out of it. The window never moves: what it holds is a smooth function of the jaw's
     * position (a window that followed the jaw jumped by 1.5 px when it moved). */
    w->half_px = CAM_WATCH_WINDOW_REL * spacing;
    const double e[2] = {du / spacing, dv / spacing};
    for (int k = 0; k < 2; k++) {
        const double *c = k ? right_px : left_px, sgn = k ? 1.0 : -1.0;
        w->win[k][0] = c[0] + sgn * (CAM_WATCH_MARGIN_PX + w->half_px) * e[0];
        w->win[k][1] = c[1] + sgn * (CAM_WATCH_MARGIN_PX + w->half_px) * e[1];
    }
    w->window_s = window_s;
    w->fps = fps;
    w->measure = measure;
    w->configured_s = configured_s;
    w->t_cmd = NAN;
    return w;
}

void trial_cam_watch_free(trial_cam_watch *w)
{
    if (!w) return;
    trial_cam_offset_free(w->o);
    free(w);
}

void trial_cam_watch_standing(trial_cam_watch *w)
{
    if (w->phase != 0) return;
    trial_cam_offset_clear(w->o);
    w->phase = 1;
}

void trial_cam_watch_shear(trial_cam_watch *w, double t_cmd)
{
    if (w->phase != 1) return;
    w->t_cmd = t_cmd;
    w->phase = 2;
}

void trial_cam_watch_frame(trial_cam_watch *w, double t_frame, const vis_frame *f)
{
    if (w->phase != 1 && w->phase != 2) return;
    if (w->phase == 2 && t_frame > w->t_cmd + w->window_s) return;
    double c[2][2];
    if (w->left_window) return;
    for (int k = 0; k < 2; k++) {
        if (jaw_centroid(f, w->win[k][0], w->win[k][1], w->half_px, c[k])) {
            w->clamp_misses++;
            return;
        }
    }
    /* A jaw that moved a quarter of its window from where it stood begins to leave it (its
     * centroid then no longer follows it smoothly): the frames from there on are not used. */
    if (!w->have_stand) {
        memcpy(w->stand, c, sizeof c);
        w->have_stand = 1;
    }
    for (int k = 0; k < 2; k++)
        if (hypot(c[k][0] - w->stand[k][0], c[k][1] - w->stand[k][1]) > CAM_WATCH_MAX_MOVE_REL * w->half_px) {
            w->left_window = 1;
            w->t_left = t_frame;
            return;
        }
    trial_cam_offset_add_frame(w->o, t_frame, c[0], c[1]);
}

void trial_cam_watch_reading(trial_cam_watch *w, double t_s, double shear_mm)
{
    if (w->phase != 1 && w->phase != 2) return;
    if (w->phase == 2 && t_s > w->t_cmd + w->window_s) return;
    trial_cam_offset_add_reading(w->o, t_s, shear_mm);
}

trial_cam_watch_verdict trial_cam_watch_poll(trial_cam_watch *w, double t, int force, trial_cam_offset_fit *fit,
                                             char *msg, size_t msg_len)
{
    if (w->phase != 2 || (!force && !(t > w->t_cmd + w->window_s))) return TRIAL_CAM_WATCH_PENDING;
    w->phase = 3;
    char why[256];
    trial_cam_offset_params p = trial_cam_offset_params_default();
    if (trial_cam_offset_estimate(w->o, w->t_cmd, &p, fit, why, sizeof why)) {
        snprintf(msg, msg_len, "%s (%ld frames without a clamp pair); the configured offset %.1f ms stays", why,
                 w->clamp_misses, 1e3 * w->configured_s);
        return TRIAL_CAM_WATCH_FAILED;
    }
    const double frame = 1.0 / w->fps, diff = fit->offset_s - w->configured_s;
    int n = snprintf(msg, msg_len,
                     "camera time offset measured at the shear's start: %+.1f ms +- %.1f ms (the images show the "
                     "rails %.1f ms %s their stamps; shear clamp moved %.1f px at %.2f mm/s, %d frames over %.1f s "
                     "of shear, residual %.3f px); configured %+.1f ms",
                     1e3 * fit->offset_s, 1e3 * fit->sd_s, 1e3 * fabs(fit->offset_s),
                     fit->offset_s <= 0.0 ? "before" : "after", fit->motion_px, fit->speed_mm_s, fit->frames_used,
                     (w->left_window ? w->t_left : w->t_cmd + w->window_s) - w->t_cmd, fit->rms_px,
                     1e3 * w->configured_s);
    if (n < 0 || (size_t)n >= msg_len) n = (int)msg_len - 1;
    if (w->measure && fit->sd_s > 0.5 * frame) {
        snprintf(msg + n, msg_len - (size_t)n,
                 "; not used: its standard deviation is above half a frame period (%.1f ms), the configured offset "
                 "stays",
                 0.5e3 * frame);
        return TRIAL_CAM_WATCH_UNCERTAIN;
    }
    if (w->measure) {
        snprintf(msg + n, msg_len - (size_t)n, "; used for this trial's Delta W from here on (camera.time_offset = measure)");
        return TRIAL_CAM_WATCH_USED;
    }
    if (fabs(diff) > frame + 2.0 * fit->sd_s) {
        snprintf(msg + n, msg_len - (size_t)n,
                 ": they differ by %.1f ms, more than a frame period (%.1f ms) and two standard deviations: check "
                 "calibration.camera_time_offset_s, or set camera.time_offset = measure",
                 1e3 * fabs(diff), 1e3 * frame);
        return TRIAL_CAM_WATCH_DISAGREES;
    }
    snprintf(msg + n, msg_len - (size_t)n, ": they agree within a frame period");
    return TRIAL_CAM_WATCH_AGREES;
}
