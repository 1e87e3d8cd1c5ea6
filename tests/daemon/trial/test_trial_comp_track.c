/* test_trial_comp_track: the compression frames' calibration (issue 32 B,
 * daemon/trial/trial_comp_track.h) against an independent construction: the synthetic camera's
 * calibration made for the strip at that Delta L (twin_calib_for_scene projects the clamp points
 * at their world positions, 0 and l (1 - Delta L)); a front camera moves the right point, a back
 * camera (mirrored) the left one; points that cannot be placed are refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <time.h>

#include "scene.h"
#include "trial_comp_track.h"
#include "twin_camera.h"
#include "vis_test_shapes.h"

static void moved_points_match_the_camera(void **state)
{
    (void)state;
    rod_scene sc = rod_scene_default();
    sc.length = 0.2;
    sc.compression = 0.5;
    twin_camera_params cp = twin_camera_params_default();
    vis_render_params rp;
    char why[256];
    assert_int_equal(twin_render_params_for_scene(&sc, &cp, &rp, why, sizeof why), TWIN_OK);
    vis_calib base;
    assert_int_equal(twin_calib_for_scene(&sc, &rp.camera, &base, why, sizeof why), TWIN_OK);
    double worst = 0.0;
    const double dls[] = {0.5, 0.48, 0.45, 0.3};
    for (size_t k = 0; k < sizeof dls / sizeof *dls; k++) {
        rod_scene at = sc;
        at.compression = dls[k];
        vis_calib ref, got;
        assert_int_equal(twin_calib_for_scene(&at, &rp.camera, &ref, why, sizeof why), TWIN_OK);
        assert_int_equal(trial_comp_track_calib(&base, RIG_CAMERA_FRONT, sc.length, sc.compression, dls[k], &got), 0);
        double e = hypot(got.clamp_right_px[0] - ref.clamp_right_px[0], got.clamp_right_px[1] - ref.clamp_right_px[1]);
        printf("Delta L %.2f: right clamp point (%.3f, %.3f) px, the camera's (%.3f, %.3f): %.2g px apart\n", dls[k],
               got.clamp_right_px[0], got.clamp_right_px[1], ref.clamp_right_px[0], ref.clamp_right_px[1], e);
        worst = fmax(worst, e);
        assert_true(got.clamp_left_px[0] == base.clamp_left_px[0] && got.clamp_left_px[1] == base.clamp_left_px[1]);
        assert_true(got.px_per_mm == base.px_per_mm);
    }
    assert_true(worst < 0.01); /* a fiftieth of the tracker's half-pixel rule */
    /* A back camera: the image's left point is the compression clamp. */
    vis_calib back;
    assert_int_equal(trial_comp_track_calib(&base, RIG_CAMERA_BACK, sc.length, 0.5, 0.45, &back), 0);
    double shift = 1000.0 * sc.length * 0.05 * base.px_per_mm;
    double d = hypot(back.clamp_left_px[0] - back.clamp_right_px[0], back.clamp_left_px[1] - back.clamp_right_px[1]);
    double d0 = hypot(base.clamp_left_px[0] - base.clamp_right_px[0], base.clamp_left_px[1] - base.clamp_right_px[1]);
    assert_true(back.clamp_right_px[0] == base.clamp_right_px[0]);
    assert_true(fabs(d - d0 - shift) < 1e-9);
}

static void unplaceable_refused(void **state)
{
    (void)state;
    vis_calib c = vis_calib_default(), out;
    c.px_per_mm = 2.0;
    c.clamp_left_px[0] = 10;
    c.clamp_left_px[1] = 50;
    c.clamp_right_px[0] = 210;
    c.clamp_right_px[1] = 50;
    assert_int_equal(trial_comp_track_calib(&c, RIG_CAMERA_FRONT, 0.2, 0.5, 0.45, &out), 0);
    assert_int_equal(trial_comp_track_calib(&c, RIG_CAMERA_FRONT, 0.2, 0.5, 0.55, &out), -1); /* beyond */
    assert_int_equal(trial_comp_track_calib(&c, RIG_CAMERA_FRONT, 0.2, 0.5, NAN, &out), -1);
    vis_calib z = c;
    z.px_per_mm = 0.0;
    assert_int_equal(trial_comp_track_calib(&z, RIG_CAMERA_FRONT, 0.2, 0.5, 0.45, &out), -1);
    z = c;
    z.clamp_right_px[0] = z.clamp_left_px[0];
    assert_int_equal(trial_comp_track_calib(&z, RIG_CAMERA_FRONT, 0.2, 0.5, 0.45, &out), -1);
    vis_measure m;
    vis_error ve = {0};
    vis_track_params tp = vis_track_params_default();
    assert_int_equal(trial_comp_track_measure(&tp, &z, RIG_CAMERA_FRONT, 0.2, 0.5, 0.45, NULL, &m, &ve), VIS_OK);
    assert_int_equal(m.reason, VIS_REASON_CLAMP_NOT_FOUND);
    assert_true(fabs(trial_comp_track_from_dl(0.5) - 0.45) < 1e-12);
    assert_true(fabs(trial_comp_track_from_dl(0.08) - 0.04) < 1e-12);
}

static double mono_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* What one compression frame costs at the rig's resolutions (the rehearsal's 640 x 480, the lab
 * rig files' 1280 x 720), on the rig's camera (twin_render_params_for_scene): an analytic arch of
 * free length l at Delta L 0.47 (the strip's upper state late in the compression of a 0.5 trial)
 * rendered, then measured by trial_comp_track_measure (a fresh tracker: acquisition from scratch)
 * against a tracker that already holds the strip (the hold's and shear's frames). The measured
 * Delta Z against the arch's own (the renderer's ground truth), within the runner test's 0.005;
 * the times are printed (docs/trials.md quotes them), not asserted. */
static void cost_at_rig_resolution(void **state)
{
    (void)state;
    static const int size[2][2] = {{640, 480}, {1280, 720}};
    rod_scene sc = rod_scene_default();
    sc.length = 0.2;
    sc.compression = 0.5;
    const double dl = 0.47;
    static vt_shape arch;
    vt_arch(&arch, 401, sc.length, sc.length * (1.0 - dl), 0.0, 0.0);
    for (int k = 0; k < 2; k++) {
        twin_camera_params cp = twin_camera_params_default();
        cp.width_px = size[k][0];
        cp.height_px = size[k][1];
        vis_render_params rp;
        char why[256];
        assert_int_equal(twin_render_params_for_scene(&sc, &cp, &rp, why, sizeof why), TWIN_OK);
        vis_calib base;
        assert_int_equal(twin_calib_for_scene(&sc, &rp.camera, &base, why, sizeof why), TWIN_OK);
        vis_error ve = {0};
        vis_renderer *ren = vis_renderer_create(&rp, &ve);
        vis_frame *f = vis_frame_alloc(16, 16, 1, &ve);
        assert_non_null(ren);
        assert_non_null(f);
        vis_render_truth rt;
        assert_int_equal(vis_renderer_draw(ren, &arch.view, f, &rt, &ve), VIS_OK);
        vis_track_params tp = vis_track_params_default();
        tp.length_mm = 1000.0 * sc.length;
        enum { REPS = 5 };
        vis_measure m;
        double t0 = mono_s();
        for (int r = 0; r < REPS; r++)
            assert_int_equal(trial_comp_track_measure(&tp, &base, RIG_CAMERA_FRONT, sc.length, sc.compression, dl, f,
                                                      &m, &ve),
                             VIS_OK);
        const double fresh_ms = 1e3 * (mono_s() - t0) / REPS;
        assert_int_equal(m.reason, VIS_REASON_NONE);
        const double err = fabs(m.dz - rt.truth.dz);
        vis_calib moved;
        assert_int_equal(trial_comp_track_calib(&base, RIG_CAMERA_FRONT, sc.length, sc.compression, dl, &moved), 0);
        vis_tracker *warm = vis_tracker_create(&tp, &moved, &ve);
        assert_non_null(warm);
        vis_measure mw;
        assert_int_equal(vis_tracker_process(warm, f, 0.0, &mw, &ve), VIS_OK); /* acquires */
        t0 = mono_s();
        for (int r = 0; r < REPS; r++) assert_int_equal(vis_tracker_process(warm, f, 0.0, &mw, &ve), VIS_OK);
        const double warm_ms = 1e3 * (mono_s() - t0) / REPS;
        printf("%d x %d (%.2f px/mm): a compression frame (fresh tracker) %.2f ms, a tracked frame (warm) %.2f ms; "
               "frame period at 60 fps 16.7 ms; Delta Z %.5f, the arch's %.5f (error %.2g)\n",
               size[k][0], size[k][1], base.px_per_mm, fresh_ms, warm_ms, m.dz, rt.truth.dz, err);
        assert_true(err < 0.005);
        vis_tracker_free(warm);
        vis_frame_free(f);
        vis_renderer_free(ren);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(moved_points_match_the_camera),
        cmocka_unit_test(unplaceable_refused),
        cmocka_unit_test(cost_at_rig_resolution),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
