/* ctl_calibrate_camera.c: `ribbonctl calibrate-camera`: the rig's camera calibrated the way a lab
 * must (issue 34 C): the clamp points found in the live camera's own stream (vis_find_clamps, the
 * median over several frames) with the specimen mounted at zero shear, the scale from their
 * spacing, written as the rig file's camera.calibration. Owned here, not in the trial: the camera
 * is calibrated once per mounting and the file checked (`ribbonctl check`) before any rail moves;
 * this command never opens a rail.
 *
 *   ribbonctl calibrate-camera --config RIG.ini [--set SECTION.KEY=VALUE ...] --out FILE
 *                              [--dl DL] [--frames N] [--camera-distance-mm D]
 *
 * The spacing: l (1 - DL), l the scene's free length, DL the compression the specimen stands at
 * now (--dl; default the scene's, i.e. the rails at the trial's hold). The tracker wants the clamp
 * points at the hold's compression (the shear starts there), so the right point is moved along the
 * clamp line to the spacing l (1 - scene compression) at the scale found: exact for a level camera
 * (the rails' plane seen face on, a similarity); a tilted camera is not supported (vis_find_clamps
 * finds no jaws there either). Exit status: 0 written, 1 failed (reason printed), 2 usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trial.h"
#include "cfg_number.h"
#include "ctl.h"
#include "rig_config.h"
#include "vision.h"

#define CALCAM_MAX_SET 16
#define CALCAM_MAX_FRAMES 600 /* cap on --frames; reads are capped at 3x the frames asked */

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ribbonctl calibrate-camera --config RIG.ini [--set SECTION.KEY=VALUE ...] --out FILE\n"
            "                                  [--dl DL] [--frames N] [--camera-distance-mm D]\n"
            "  Finds the clamp points in the rig's live camera (specimen mounted, zero shear; the\n"
            "  median over N frames), takes the scale from their spacing l (1 - DL) and writes the\n"
            "  calibration for camera.calibration. Never moves a rail.\n"
            "  --dl DL                  compression the specimen stands at now (default: the scene's)\n"
            "  --frames N               frames to find the clamps in (10; 1 to %d)\n"
            "  --camera-distance-mm D   camera to the rails' plane, measured: enables the depth\n"
            "                           correction (default: none)\n",
            CALCAM_MAX_FRAMES);
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static int num_arg(const char *opt, const char *v, double lo, double hi, double *out)
{
    char *end = NULL;
    const double x = v ? cfg_number_strtod(v, &end) : NAN;
    if (!v || end == v || *end || !isfinite(x) || x < lo || x > hi) {
        fprintf(stderr, "ribbonctl calibrate-camera: %s needs a number in [%g, %g], got '%s'\n", opt, lo, hi,
                v ? v : "");
        return -1;
    }
    *out = x;
    return 0;
}

/* Finds the clamps in up to `want` frames of the live camera: the median points in left/right,
 * the largest distance of a frame's point from its median in *spread. 0, or -1 with why. */
static int find_clamps_live(const rig_config *cfg, int want, double left[2], double right[2], double *spread,
                            int *found, int *width, int *height, char *why, size_t why_len)
{
    const rig_camera *rc = &cfg->camera;
    if (rc->source != RIG_SOURCE_INDEX && rc->source != RIG_SOURCE_DEVICE && rc->source != RIG_SOURCE_ARAVIS) {
        snprintf(why, why_len, "the rig file's camera.source is not a live camera");
        return -1;
    }
    vis_camera_settings cs = trial_camera_settings(rc);
    vis_error ve = {0};
    vis_source *src = vis_source_open_camera(&cs, &ve);
    if (!src) {
        snprintf(why, why_len, "camera: %s", ve.message);
        return -1;
    }
    double *pts = malloc(sizeof *pts * 4 * (size_t)want), *tmp = malloc(sizeof *tmp * (size_t)want);
    vis_frame *fr = vis_frame_alloc(16, 16, 1, &ve);
    int n = 0, rc_out = -1;
    char last[300] = "no frame read";
    if (!pts || !tmp || !fr) {
        snprintf(why, why_len, "out of memory");
        goto done;
    }
    vis_track_params tp = vis_track_params_default();
    for (int reads = 0; n < want && reads < 3 * want; reads++) {
        double t = 0, l[2], r[2], q = 0;
        if (vis_source_read(src, fr, &t, &ve) != VIS_OK) {
            snprintf(why, why_len, "camera: frame %d not read: %s", reads, ve.message);
            goto done;
        }
        if (vis_find_clamps(fr, &tp, l, r, &q, &ve) != VIS_OK) {
            snprintf(last, sizeof last, "%s", ve.message);
            continue;
        }
        double *p = pts + 4 * n++;
        p[0] = l[0], p[1] = l[1], p[2] = r[0], p[3] = r[1];
    }
    *width = vis_frame_width(fr);
    *height = vis_frame_height(fr);
    *found = n;
    if (n < want) {
        snprintf(why, why_len, "the clamps were found in %d of the %d frames read (last: %s): mount the specimen at "
                 "zero shear with both jaws in view", n, 3 * want, last);
        goto done;
    }
    double med[4];
    for (int k = 0; k < 4; k++) {
        for (int i = 0; i < n; i++) tmp[i] = pts[4 * i + k];
        med[k] = median(tmp, n);
    }
    *spread = 0.0;
    for (int i = 0; i < n; i++) {
        const double *p = pts + 4 * i;
        *spread = fmax(*spread, fmax(hypot(p[0] - med[0], p[1] - med[1]), hypot(p[2] - med[2], p[3] - med[3])));
    }
    left[0] = med[0], left[1] = med[1], right[0] = med[2], right[1] = med[3];
    rc_out = 0;
done:
    vis_frame_free(fr);
    free(pts);
    free(tmp);
    vis_source_close(src);
    return rc_out;
}

int ctl_calibrate_camera_main(int argc, char **argv)
{
    const char *config = NULL, *out = NULL, *set[CALCAM_MAX_SET];
    int n_set = 0;
    double dl = NAN, frames = 10, distance = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--config") || !strcmp(a, "--out") || !strcmp(a, "--set")) {
            if (!v) {
                fprintf(stderr, "ribbonctl calibrate-camera: %s needs a value\n", a);
                return 2;
            }
            if (!strcmp(a, "--config")) config = v;
            else if (!strcmp(a, "--out")) out = v;
            else if (n_set >= CALCAM_MAX_SET) {
                fprintf(stderr, "ribbonctl calibrate-camera: at most %d --set\n", CALCAM_MAX_SET);
                return 2;
            } else set[n_set++] = v;
            i++;
        } else if (!strcmp(a, "--dl")) {
            if (num_arg(a, v, 0.0, 0.99, &dl)) return 2;
            i++;
        } else if (!strcmp(a, "--frames")) {
            if (num_arg(a, v, 1, CALCAM_MAX_FRAMES, &frames) || frames != floor(frames)) return 2;
            i++;
        } else if (!strcmp(a, "--camera-distance-mm")) {
            if (num_arg(a, v, 1.0, 1e6, &distance)) return 2;
            i++;
        } else {
            fprintf(stderr, "ribbonctl calibrate-camera: unknown argument '%s'\n", a);
            usage(stderr);
            return 2;
        }
    }
    if (!config || !out) {
        usage(stderr);
        return 2;
    }
    rig_config *cfg = malloc(sizeof *cfg);
    if (!cfg) {
        fprintf(stderr, "ribbonctl calibrate-camera: out of memory\n");
        return 1;
    }
    cfg_error ce;
    if (rig_config_load(config, set, n_set, cfg, &ce) != CFG_OK) {
        char msg[700];
        fprintf(stderr, "ribbonctl calibrate-camera: %s\n", cfg_error_format(&ce, msg, sizeof msg));
        free(cfg);
        return 2;
    }
    const double l_mm = cfg->scene.length * 1000.0, dl_hold = cfg->scene.compression;
    if (!isfinite(dl)) dl = dl_hold;
    double left[2], right[2], spread = 0;
    int found = 0, w = 0, h = 0;
    char why[600] = "";
    int rc = 1;
    if (find_clamps_live(cfg, (int)frames, left, right, &spread, &found, &w, &h, why, sizeof why)) {
        fprintf(stderr, "ribbonctl calibrate-camera: %s\n", why);
        goto done;
    }
    /* Scale from the spacing now; the right point moved to the hold's spacing along the clamp line. */
    const double du = right[0] - left[0], dv = right[1] - left[1], d_px = hypot(du, dv);
    const double spacing_now = l_mm * (1.0 - dl), spacing_hold = l_mm * (1.0 - dl_hold);
    vis_calib cal = vis_calib_default();
    vis_error ve = {0};
    if (vis_calib_from_clamps(&cal, left, right, spacing_now, &ve) != VIS_OK) {
        fprintf(stderr, "ribbonctl calibrate-camera: %s\n", ve.message);
        goto done;
    }
    const double move_px = cal.px_per_mm * (spacing_hold - spacing_now);
    cal.clamp_right_px[0] = right[0] + du / d_px * move_px;
    cal.clamp_right_px[1] = right[1] + dv / d_px * move_px;
    cal.camera_distance_mm = distance;
    if (vis_calib_save(&cal, out, &ve) != VIS_OK) {
        fprintf(stderr, "ribbonctl calibrate-camera: %s: %s\n", out, ve.message);
        goto done;
    }
    printf("clamps found in %d frames (%d x %d), spread %.3f px: left (%.2f, %.2f) px, right (%.2f, %.2f) px at "
           "Delta L %.3f\n",
           found, w, h, spread, left[0], left[1], right[0], right[1], dl);
    printf("scale %.5f px/mm from the spacing %.2f mm; right clamp at the hold (Delta L %.3f): (%.2f, %.2f) px\n",
           cal.px_per_mm, spacing_now, dl_hold, cal.clamp_right_px[0], cal.clamp_right_px[1]);
    printf("calibration: %s\n", out);
    rc = 0;
done:
    free(cfg);
    return rc;
}
