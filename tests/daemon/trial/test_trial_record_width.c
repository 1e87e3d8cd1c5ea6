/* test_trial_record_width.c: a trial's record keeps the ribbon's width, and a replay's tracker is
 * sized from it as the trial's was (vis_track_params_for_ribbon): the mock strip (5 mm at the twin
 * camera's 2.49 px/mm) gets ribbon_max_px 15 and band_px 22.5, so a replay measures the frames of a
 * twisted strip its trial measured (the phi 60 loss, test_vision_sheared_fold). A record from before
 * the width was kept parses and replays with the defaults. No simulation: ms. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trial.h"

static rig_config *mock_cfg(void)
{
    static rig_config cfg; /* large: not on the stack */
    cfg_error ce;
    char path[1024], buf[1200];
    snprintf(path, sizeof path, "%s/config/mock.ini", RIBBON_SOURCE_DIR);
    if (rig_config_load(path, NULL, 0, &cfg, &ce) != CFG_OK) fail_msg("%s", cfg_error_format(&ce, buf, sizeof buf));
    return &cfg;
}

static vis_calib twin_like_calib(void)
{
    vis_calib c;
    memset(&c, 0, sizeof c);
    c.px_per_mm = 2.4941531628991833; /* the twin camera's, 640 x 480, for the 200 mm strip */
    c.clamp_left_px[0] = 194.8, c.clamp_left_px[1] = 239.5;
    c.clamp_right_px[0] = 444.2, c.clamp_right_px[1] = 239.5;
    c.principal_px[0] = 319.5, c.principal_px[1] = 239.5;
    c.camera_distance_mm = 1000.0;
    return c;
}

static void record_keeps_width(void **state)
{
    (void)state;
    const rig_config *cfg = mock_cfg();
    vis_calib cal = twin_like_calib();
    trial_roi roi = {100, 20, 440, 440};
    char why[512] = "";
    char *text = trial_record_json(cfg, &cal, roi, why, sizeof why);
    assert_non_null(text);
    trial_record rec;
    assert_int_equal(trial_record_parse(text, &rec, why, sizeof why), 0);
    assert_true(rec.width_m == cfg->scene.width);
    assert_true(fabs(rec.width_m - 0.005) < 1e-15);
    vis_calib vc;
    trial_record_video_calib(&rec, &vc);
    const vis_track_params tp = trial_record_track_params(&rec, &vc);
    assert_true(tp.ribbon_max_px == 15.0); /* ceil(5 x 2.494 + 2) */
    assert_true(fabs(tp.band_px - 22.5) < 1e-12);
    assert_true(fabs(tp.length_mm - 200.0) < 1e-9);
    free(text);
}

static void older_record_keeps_defaults(void **state)
{
    (void)state;
    const rig_config *cfg = mock_cfg();
    vis_calib cal = twin_like_calib();
    trial_roi roi = {0, 0, 640, 480};
    char why[512] = "";
    char *text = trial_record_json(cfg, &cal, roi, why, sizeof why);
    assert_non_null(text);
    json_error_t je;
    json_t *root = json_loads(text, 0, &je);
    free(text);
    assert_non_null(root);
    assert_int_equal(json_object_del(root, "width_m"), 0); /* as recorded before */
    char *old = json_dumps(root, JSON_COMPACT);
    json_decref(root);
    assert_non_null(old);
    trial_record rec;
    assert_int_equal(trial_record_parse(old, &rec, why, sizeof why), 0);
    free(old);
    assert_true(rec.width_m == 0.0);
    vis_calib vc;
    trial_record_video_calib(&rec, &vc);
    const vis_track_params tp = trial_record_track_params(&rec, &vc), d = vis_track_params_default();
    assert_true(tp.ribbon_max_px == d.ribbon_max_px && tp.band_px == d.band_px);
    assert_true(fabs(tp.length_mm - 200.0) < 1e-9);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(record_keeps_width),
        cmocka_unit_test(older_record_keeps_defaults),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
