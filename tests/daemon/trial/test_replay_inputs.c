/* test_replay_inputs: an outside replay's files refused with a reason that says what is wrong
 * (issue 33). A rails CSV with a position beyond any rail (1e300 mm once became a "done" trial
 * with Delta L = 5e297) is refused naming its line, by the parser and by the replay; a "video"
 * that is text, empty, /dev/zero, a FIFO or a directory gives its reason (it was "video PATH: "
 * with nothing after: the frame allocated after the failed open cleared the reason). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "replay_rails_csv.h"
#include "rig_config.h"
#include "test_dir.h"
#include "trial_replay.h"
#include "vision.h"

static char dir[64];

static int parse(const char *text, char *why, size_t why_len)
{
    FILE *f = fmemopen((void *)text, strlen(text), "r");
    assert_non_null(f);
    rail_reading *r = NULL;
    size_t n = 0;
    int rc = replay_rails_csv_read(f, "rails.csv", &r, &n, why, why_len);
    fclose(f);
    free(r);
    return rc;
}

static void test_positions_beyond_any_rail_refused(void **state)
{
    (void)state;
    char why[512];
    assert_int_equal(parse("t_s,compress_mm,shear_mm\n0,110,50\n0.1,1e300,50\n", why, sizeof why), -1);
    printf("# %s\n", why);
    assert_non_null(strstr(why, "line 3"));
    assert_non_null(strstr(why, "compress_mm"));
    assert_int_equal(parse("0,110,50\n0.1,110,50\n0.2,110,-2e6\n", why, sizeof why), -1);
    assert_non_null(strstr(why, "line 3"));
    assert_non_null(strstr(why, "shear_mm"));
    /* The bound itself is a position a rig file's soft limits may name. */
    assert_int_equal(parse("0,-1e6,0\n0.1,1e6,1e6\n", why, sizeof why), 0);
}

/* A rig file in replay mode with a 4-frame video, a calibration and rails (rails_text). */
static void write_files(const char *rails_text, rig_config *cfg)
{
    char p[160], why[512];
    vis_error ve = {0};
    snprintf(p, sizeof p, "%s/rec.avi", dir);
    vis_video_writer *vw = vis_video_writer_open_y800(p, 64, 48, 20.0, &ve);
    if (!vw) fail_msg("video: %s", ve.message);
    vis_frame *f = vis_frame_alloc(64, 48, 1, &ve);
    assert_non_null(f);
    for (int k = 0; k < 4; k++) {
        memset(vis_frame_data(f), 40 * k, (size_t)vis_frame_stride(f) * 48);
        assert_int_equal(vis_video_writer_write(vw, f, &ve), VIS_OK);
    }
    vis_video_writer_close(vw);
    vis_frame_free(f);
    snprintf(p, sizeof p, "%s/rails.csv", dir);
    FILE *t = fopen(p, "w");
    assert_non_null(t);
    fputs(rails_text, t);
    fclose(t);
    vis_calib cal = vis_calib_default();
    const double l[2] = {8, 24}, r[2] = {56, 24};
    assert_int_equal(vis_calib_from_clamps(&cal, l, r, 150.0, &ve), VIS_OK);
    snprintf(p, sizeof p, "%s/camera.calib", dir);
    assert_int_equal(vis_calib_save(&cal, p, &ve), VIS_OK);
    snprintf(p, sizeof p, "%s/replay.ini", dir);
    t = fopen(p, "w");
    assert_non_null(t);
    fprintf(t,
            "[rig]\nmode = replay\nscene = %s/config/scenes/mock-gamma013.ini\n"
            "[calibration]\ncompress_zero_mm = 50\nshear_zero_mm = 50\ncompress_sign = 1\nshear_sign = 1\n"
            "camera_side = front\n"
            "[camera]\ncalibration = %s/camera.calib\n"
            "[replay]\nvideo = %s/rec.avi\nrails = %s/rails.csv\n"
            "[store]\npath = %s/trials.db\n[api]\nport = 0\n",
            RIBBON_SOURCE_DIR, dir, dir, dir, dir);
    fclose(t);
    cfg_error ce;
    if (rig_config_load(p, NULL, 0, cfg, &ce) != CFG_OK) fail_msg("%s", cfg_error_format(&ce, why, sizeof why));
}

static void test_replay_refuses_rails_beyond_any_rail(void **state)
{
    (void)state;
    static rig_config cfg;
    write_files("t_s,compress_mm,shear_mm\n0,110,50\n0.1,110,50\n# a glitch\n0.2,1e300,1e300\n0.3,110,50\n", &cfg);
    trial_replay *r = NULL;
    char why[512] = "";
    assert_int_not_equal(trial_replay_from_files(&cfg, &r, why, sizeof why), 0);
    printf("# %s\n", why);
    assert_null(r);
    assert_non_null(strstr(why, "rails.csv line 5"));
}

/* Each not-a-video gives a reason after "video PATH: ", naming what it is. */
static void test_video_reasons_are_not_empty(void **state)
{
    (void)state;
    static rig_config cfg;
    write_files("0,110,50\n0.1,110,50\n", &cfg);
    char text[160], empty[160], fifo[160], sub[160];
    snprintf(text, sizeof text, "%s/text.avi", dir);
    snprintf(empty, sizeof empty, "%s/empty.avi", dir);
    snprintf(fifo, sizeof fifo, "%s/fifo.avi", dir);
    snprintf(sub, sizeof sub, "%s/dir.avi", dir);
    FILE *f = fopen(text, "w");
    assert_non_null(f);
    fputs("this is not a video\n", f);
    fclose(f);
    f = fopen(empty, "w");
    assert_non_null(f);
    fclose(f);
    assert_int_equal(mkfifo(fifo, 0600), 0);
    assert_int_equal(mkdir(sub, 0700), 0);
    const char *paths[] = {text, empty, "/dev/zero", fifo, sub};
    const char *says[] = {"cannot be decoded", "empty file", "character device", "FIFO", "directory"};
    for (size_t k = 0; k < sizeof paths / sizeof paths[0]; k++) {
        snprintf(cfg.replay.video, sizeof cfg.replay.video, "%s", paths[k]);
        trial_replay *r = NULL;
        char why[512] = "";
        assert_int_not_equal(trial_replay_from_files(&cfg, &r, why, sizeof why), 0);
        assert_null(r);
        printf("# %s\n", why);
        char head[256];
        snprintf(head, sizeof head, "video %s", paths[k]);
        assert_true(strncmp(why, head, strlen(head)) == 0);
        const char *rest = why + strlen(head);
        assert_true(strlen(rest) >= 10); /* a reason, not ": " and nothing */
        assert_non_null(strstr(rest, says[k]));
    }
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/test_replay_inputs.XXXXXX");
    return mkdtemp(dir) ? 0 : -1;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_positions_beyond_any_rail_refused),
        cmocka_unit_test(test_replay_refuses_rails_beyond_any_rail),
        cmocka_unit_test(test_video_reasons_are_not_empty),
    };
    int failed = cmocka_run_group_tests(tests, setup, NULL);
    test_dir_done(dir, !failed, "the recording, calibration and files that are not videos");
    return failed;
}
