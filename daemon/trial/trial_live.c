/* trial_live.c: a rig-mode trial's camera, capture pipeline and rail poller (see trial_live.h). */
#include "trial_live.h"
#include "trial_camera_settings.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct trial_live {
    vis_source *src;
    trial_capture *cap;
    trial_rail_poller *poller;
};

/* The poller's period: twice each driver's poll rate, so every fresh reading the rate limit allows
 * is taken within half a poll period. */
static double poll_period(rail *a, rail *b)
{
    double hz = fmax(rail_get_params(a)->poll_hz, rail_get_params(b)->poll_hz);
    return hz > 0.0 ? 0.5 / hz : 0.01;
}

int trial_live_open(const rig_config *cfg, rail *compress, rail *shear, const char *video_path, trial_roi roi,
                    int expect_w, int expect_h, const vis_calib *cal, trial_live **out, char *why,
                    size_t why_len)
{
    *out = NULL;
    trial_live *l = calloc(1, sizeof *l);
    if (!l) {
        snprintf(why, why_len, "live pipeline: out of memory");
        return -1;
    }
    const rig_camera *rc = &cfg->camera;
    vis_camera_settings cs = trial_camera_settings(rc);
    vis_error ve = {0};
    l->src = vis_source_open_camera(&cs, &ve);
    if (!l->src) {
        snprintf(why, why_len, "camera: %s", ve.message);
        free(l);
        return -1;
    }
    /* The first frame tells the camera's real size: it must be the calibration's. */
    vis_frame *probe = vis_frame_alloc(16, 16, 1, &ve);
    vis_frame_meta m;
    if (!probe || vis_source_read_meta(l->src, probe, &m, &ve) != VIS_OK) {
        snprintf(why, why_len, "camera: no first frame: %s", ve.message);
        vis_frame_free(probe);
        vis_source_close(l->src);
        free(l);
        return -1;
    }
    int w = vis_frame_width(probe), h = vis_frame_height(probe);
    vis_frame_free(probe);
    if (expect_w > 0 && expect_h > 0 && (w != expect_w || h != expect_h)) {
        snprintf(why, why_len,
                 "camera: its frames are %d x %d but the calibration (camera.calibration) is for %d x %d: "
                 "recalibrate or set camera.width_px/height_px",
                 w, h, expect_w, expect_h);
        vis_source_close(l->src);
        free(l);
        return -1;
    }
    if (cal) {
        const char *bad = NULL;
        double u = 0, v = 0;
        const double pts[4][2] = {{cal->clamp_left_px[0], cal->clamp_left_px[1]},
                                  {cal->clamp_right_px[0], cal->clamp_right_px[1]},
                                  {cal->principal_px[0], cal->principal_px[1]},
                                  {cal->camera_matrix[2], cal->camera_matrix[5]}};
        const char *names[4] = {"left clamp point", "right clamp point", "principal point", "optical centre"};
        for (int k = 0; k < 4 && !bad; k++) {
            if (k == 2 && (pts[k][0] < 0 || pts[k][1] < 0)) continue; /* the image centre */
            if (k == 3 && !cal->has_intrinsics) continue;
            if (!(pts[k][0] >= 0 && pts[k][0] < w && pts[k][1] >= 0 && pts[k][1] < h)) {
                bad = names[k];
                u = pts[k][0];
                v = pts[k][1];
            }
        }
        if (bad) {
            snprintf(why, why_len,
                     "camera: the calibration (camera.calibration) does not match the camera's %d x %d frames: its "
                     "%s (%.1f, %.1f) px is outside them: recalibrate for this size, or set camera.width_px/height_px",
                     w, h, bad, u, v);
            vis_source_close(l->src);
            free(l);
            return -1;
        }
    }
    trial_capture_params cp = trial_capture_params_default();
    cp.slots = rc->ring_frames > 0 ? rc->ring_frames : 64;
    cp.track_max_lag = rc->track_max_lag > 0 ? rc->track_max_lag : 16;
    cp.video_path = video_path;
    cp.roi = roi;
    cp.fps = rc->fps > 0 ? rc->fps : 30.0;
    cp.frame_timeout_s = 0.5;
    cp.loss_window = cp.fps >= 10.0 ? (int)lround(cp.fps) : 10; /* a second of frames */
    const char *delay = getenv("RIBBON_TEST_TRACK_DELAY_S"); /* test hook: a slow tracker */
    if (delay && *delay) cp.track_delay_s = atof(delay);
    l->cap = trial_capture_start(l->src, &cp, why, why_len);
    if (!l->cap) {
        vis_source_close(l->src);
        free(l);
        return -1;
    }
    l->poller = trial_rail_poller_start(compress, shear, poll_period(compress, shear), why, why_len);
    if (!l->poller) {
        char w2[256];
        trial_capture_stop(l->cap, NULL, w2, sizeof w2);
        vis_source_close(l->src);
        free(l);
        return -1;
    }
    *out = l;
    return 0;
}

void trial_live_attach(trial_live *l, trial_runner *tr) { trial_runner_set_live(tr, l->cap, l->poller); }

int trial_live_close(trial_live *l, trial_capture_counts *counts, char *summary, size_t summary_len, char *why,
                     size_t why_len)
{
    if (!l) return 0;
    trial_capture_counts k;
    memset(&k, 0, sizeof k);
    double max_poll = 0.0, max_gap = 0.0;
    long polls = 0;
    trial_rail_poller_stats(l->poller, &max_poll, &max_gap, &polls);
    trial_rail_poller_stop(l->poller);
    int rc = trial_capture_stop(l->cap, &k, why, why_len);
    vis_source_close(l->src);
    free(l);
    if (counts) *counts = k;
    snprintf(summary, summary_len,
             "pipeline: %ld frames captured, %ld lost by the camera or link (id gaps), %ld incomplete buffers, "
             "%ld dropped by the pipeline, %ld recorded, %ld not tracked (loop behind); camera clock %s "
             "(offset %.6f s, drift %.2g, after %ld warm-up frames); slowest write %.1f ms after arrival; %ld rail "
             "polls, slowest %.1f ms, longest gap %.1f ms",
             k.captured, k.lost, k.incomplete, k.dropped, k.recorded, k.skipped,
             k.identity_clock ? "is the host's monotonic clock" : "mapped by its arrivals' lower envelope",
             k.offset_s, k.drift, k.warmup, 1e3 * k.max_capture_to_record_s, polls, 1e3 * max_poll, 1e3 * max_gap);
    return rc;
}
