/* test_trial_record_principal.c: a rig trial whose camera calibration has no principal point of its
 * own (negative: the image's centre, as `ribbonctl calibrate-camera` from the clamps leaves it) and
 * a saved video cropped off-centre: the trial's record stores the full frame's centre, and the
 * replay's calibration (trial_record_video_calib) puts it at that point in the cropped video's
 * pixels, not at the crop's own centre. Checked through the calibration's camera model
 * (vis_calib_curve_to_plane, the inverse of the tracker's view model, with the same default for a
 * negative point): points seen in the full frame and the same points in the cropped video map to the
 * same place in the rig's plane. A tilted camera, so that the principal point moves the answer.
 * No simulation, no camera: ms. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "trial.h"
#include "trial_camera_setup.h"

enum { W = 640, H = 480 };

static rig_config *rig_cfg(const char *calib_path, trial_roi crop)
{
    static rig_config cfg; /* large: not on the stack */
    cfg_error ce;
    char path[1024], buf[1200];
    snprintf(path, sizeof path, "%s/config/mock.ini", RIBBON_SOURCE_DIR);
    if (rig_config_load(path, NULL, 0, &cfg, &ce) != CFG_OK) fail_msg("%s", cfg_error_format(&ce, buf, sizeof buf));
    cfg.mode = RIG_MODE_RIG; /* the calibration from its file, as on the rig */
    snprintf(cfg.camera.calibration, sizeof cfg.camera.calibration, "%s", calib_path);
    cfg.camera.width_px = W;
    cfg.camera.height_px = H;
    cfg.camera.roi = RIG_ROI_RECT;
    cfg.camera.roi_x = crop.x, cfg.camera.roi_y = crop.y, cfg.camera.roi_w = crop.w, cfg.camera.roi_h = crop.h;
    return &cfg;
}

static void off_centre_crop_keeps_the_principal_point(void **state)
{
    (void)state;
    /* The clamps' calibration: no principal point of its own. */
    vis_calib c;
    memset(&c, 0, sizeof c);
    c.px_per_mm = 2.5;
    c.clamp_left_px[0] = 190.0, c.clamp_left_px[1] = 300.0;
    c.clamp_right_px[0] = 440.0, c.clamp_right_px[1] = 300.0;
    c.principal_px[0] = c.principal_px[1] = -1.0;
    c.camera_distance_mm = 600.0;
    c.camera_tilt_rad = 0.35;
    char dir[] = "/tmp/test_trial_record_principal.XXXXXX", path[256];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/camera.calib", dir);
    vis_error ve = {0};
    assert_int_equal(vis_calib_save(&c, path, &ve), VIS_OK);

    /* A crop well off the frame's centre (its centre 160 px left of and 55 px below the frame's). */
    const trial_roi crop = {40, 170, 400, 280};
    const rig_config *cfg = rig_cfg(path, crop);
    vis_calib cal;
    int w = 0, h = 0;
    trial_roi roi;
    char why[512] = "";
    assert_int_equal(trial_camera_setup(cfg, &cal, &w, &h, &roi, why, sizeof why), 0);
    assert_int_equal(w, W);
    assert_int_equal(h, H);
    assert_int_equal(roi.x, crop.x);
    assert_int_equal(roi.y, crop.y);
    assert_int_equal(roi.w, crop.w);
    assert_int_equal(roi.h, crop.h);
    char *text = trial_record_json(cfg, &cal, roi, why, sizeof why);
    assert_non_null(text);
    trial_record rec;
    assert_int_equal(trial_record_parse(text, &rec, why, sizeof why), 0);
    free(text);
    /* The record: the full frame's centre, in the full frame's pixels. */
    assert_true(fabs(rec.camera.principal_px[0] - 0.5 * (W - 1)) < 1e-12);
    assert_true(fabs(rec.camera.principal_px[1] - 0.5 * (H - 1)) < 1e-12);
    /* The replay's: the same point in the cropped video's pixels. */
    vis_calib vc;
    trial_record_video_calib(&rec, &vc);
    printf("# principal point in the cropped video: (%.1f, %.1f) px (the crop's centre: (%.1f, %.1f))\n",
           vc.principal_px[0], vc.principal_px[1], 0.5 * (crop.w - 1), 0.5 * (crop.h - 1));
    assert_true(fabs(vc.principal_px[0] - (0.5 * (W - 1) - crop.x)) < 1e-12);
    assert_true(fabs(vc.principal_px[1] - (0.5 * (H - 1) - crop.y)) < 1e-12);

    /* Points of an arch seen in the full frame (the live tracker's view, the calibration as loaded)
     * and in the cropped video (the replay's) land at the same place in the rig's plane. */
    enum { N = 5 };
    const double full_uv[2 * N] = {220, 280, 260, 200, 315, 170, 370, 200, 410, 280};
    double crop_uv[2 * N], xz_live[2 * N], xz_replay[2 * N];
    for (int i = 0; i < N; i++) {
        crop_uv[2 * i] = full_uv[2 * i] - crop.x;
        crop_uv[2 * i + 1] = full_uv[2 * i + 1] - crop.y;
    }
    vis_calib_curve_to_plane(&c, W, H, 200.0, full_uv, N, xz_live);
    vis_calib_curve_to_plane(&vc, crop.w, crop.h, 200.0, crop_uv, N, xz_replay);
    double worst = 0.0;
    for (int k = 0; k < 2 * N; k++) worst = fmax(worst, fabs(xz_replay[k] - xz_live[k]));
    printf("# largest difference live - replay in the plane: %.3g (of the length)\n", worst);
    assert_true(worst < 1e-12);

    unlink(path);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(off_centre_crop_keeps_the_principal_point),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
