/* test_trial_replay_times: a replay of an outside rig recording (a Y800 .avi with the
 * VIDEO.frames.csv rig mode's recorder writes beside it) puts each frame at its stored time, not at
 * f / fps: the frames' times here are uneven (a 50 ms period with every other frame 20 ms late and
 * an absolute base on the rails' clock); the rails CSV is a shear ramp, so each sample's time and
 * its shear position both tell which time was used. Also: a frames file with a time going back is
 * a named error. A replay of a trial that has not ended, or of a replay that ended early, is
 * refused with a reason that says so (issue 33, item 4). Both forms of a rig video replay to the
 * same samples: the raw Y800 .avi and its lossless FFV1 transcode (trial_transcode.h), as an
 * outside recording (the .mkv finds the recording's NAME.avi.frames.csv) and as a stored trial. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rig_config.h"
#include "store.h"
#include "trial_replay.h"
#include "trial_transcode.h"
#include "test_dir.h"
#include "vision.h"

#define NF 30
#define W 320
#define H 240
#define FPS 20.0

static char dir[64];

static double frame_t(int k) { return 1000.0 + 0.05 * k + (k % 2 ? 0.02 : 0.0); } /* rails' clock, s */

static void write_files(int bad_times)
{
    char p[160];
    vis_error ve = {0};
    snprintf(p, sizeof p, "%s/rec.avi", dir);
    vis_video_writer *vw = vis_video_writer_open_y800(p, W, H, FPS, &ve);
    if (!vw) fail_msg("video: %s", ve.message);
    vis_frame *f = vis_frame_alloc(W, H, 1, &ve);
    assert_non_null(f);
    for (int k = 0; k < NF; k++) {
        uint8_t *d = vis_frame_data(f);
        for (int y = 0; y < H; y++) memset(d + (size_t)y * vis_frame_stride(f), (k * 7 + y) & 0xff, W);
        assert_int_equal(vis_video_writer_write(vw, f, &ve), VIS_OK);
    }
    vis_video_writer_close(vw);
    vis_frame_free(f);
    snprintf(p, sizeof p, "%s/rec.avi.frames.csv", dir);
    FILE *t = fopen(p, "w");
    assert_non_null(t);
    fprintf(t, "video_frame,capture_index,camera_id,camera_t_s,host_t_s,t_s\n");
    for (int k = 0; k < NF; k++) {
        double tk = bad_times && k == 10 ? frame_t(k - 2) : frame_t(k);
        fprintf(t, "%d,%d,%d,%.9f,%.9f,%.9f\n", k, k, 100 + k, 5e8 + tk, tk + 1e-4, tk);
    }
    fclose(t);
    /* the rails: a shear ramp of 10 mm/s over the recording (on the rails' clock, from frame 0) */
    snprintf(p, sizeof p, "%s/rails.csv", dir);
    t = fopen(p, "w");
    assert_non_null(t);
    fprintf(t, "t_s,compress_mm,shear_mm\n");
    for (int k = -10; k <= 40; k++) fprintf(t, "%.3f,110,%.6f\n", 0.1 * k, 50.0 + 10.0 * (0.1 * k));
    fclose(t);
    vis_calib cal = vis_calib_default();
    const double l[2] = {40, 120}, r[2] = {280, 120};
    assert_int_equal(vis_calib_from_clamps(&cal, l, r, 150.0, &ve), VIS_OK);
    snprintf(p, sizeof p, "%s/camera.calib", dir);
    assert_int_equal(vis_calib_save(&cal, p, &ve), VIS_OK);
    snprintf(p, sizeof p, "%s/replay.ini", dir);
    t = fopen(p, "w");
    assert_non_null(t);
    fprintf(t,
            "[rig]\nmode = replay\nscene = %s/config/scenes/mock-gamma013.ini\n"
            "[calibration]\ncompress_zero_mm = 50\nshear_zero_mm = 50\ncompress_sign = 1\nshear_sign = 1\n"
            "camera_side = front\ncamera_time_offset_s = 0\n"
            "[camera]\ncalibration = %s/camera.calib\n"
            "[replay]\nvideo = %s/rec.avi\nrails = %s/rails.csv\n"
            "[store]\npath = %s/trials.db\n[api]\nport = 0\n",
            RIBBON_SOURCE_DIR, dir, dir, dir, dir);
    fclose(t);
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/test_trial_replay_times.XXXXXX");
    return mkdtemp(dir) ? 0 : -1;
}

static void test_replay_uses_stored_times(void **state)
{
    (void)state;
    write_files(0);
    char p[160], why[512] = "";
    snprintf(p, sizeof p, "%s/replay.ini", dir);
    static rig_config cfg;
    cfg_error ce;
    if (rig_config_load(p, NULL, 0, &cfg, &ce) != CFG_OK) fail_msg("%s", cfg_error_format(&ce, why, sizeof why));
    trial_replay *r = NULL;
    if (trial_replay_from_files(&cfg, &r, why, sizeof why)) fail_msg("replay: %s", why);
    store *st = NULL;
    snprintf(p, sizeof p, "%s/trials.db", dir);
    assert_int_equal(store_open(p, &st, why, sizeof why), STORE_OK);
    int64_t id = 0;
    trial_result res;
    /* The rails CSV holds the compress rail at 110 mm, not the rig file's 150 (Delta L 0.5): the
     * frames are tracked as recorded, with a warning, not refused. */
    const int rc = trial_replay_run(r, st, "uneven times", NULL, NULL, &id, &res, why, sizeof why);
    if (rc) fprintf(stderr, "replay: %s\n", why);
    assert_int_equal(rc, 0);
    trial_replay_free(r);
    assert_true(id > 0);
    store_sample *smp = NULL;
    size_t ns = 0;
    assert_int_equal(store_samples_get(st, id, &smp, &ns, why, sizeof why), STORE_OK);
    int seen = 0;
    double worst_t = 0.0, worst_s = 0.0;
    for (size_t k = 0; k < ns; k++) {
        if (smp[k].kind != STORE_SAMPLE_FRAME) continue;
        const long f = smp[k].frame;
        assert_true(f >= 0 && f < NF);
        const double want = frame_t((int)f) - frame_t(0); /* not f / FPS */
        worst_t = fmax(worst_t, fabs(smp[k].t_s - want));
        worst_s = fmax(worst_s, fabs(smp[k].shear_mm - (50.0 + 10.0 * want)));
        seen++;
    }
    printf("# %d frame samples; |t - stored time| <= %.2g s, |shear - ramp at it| <= %.2g mm (f / fps would put "
           "every odd frame 20 ms early)\n",
           seen, worst_t, worst_s);
    assert_int_equal(seen, NF);
    assert_true(worst_t < 1e-6);
    assert_true(worst_s < 1e-4);
    free(smp);
    store_close(st);
}

static void test_times_going_back_refused(void **state)
{
    (void)state;
    write_files(1);
    char p[160], why[512] = "";
    snprintf(p, sizeof p, "%s/replay.ini", dir);
    static rig_config cfg;
    cfg_error ce;
    assert_int_equal(rig_config_load(p, NULL, 0, &cfg, &ce), CFG_OK);
    trial_replay *r = NULL;
    assert_int_not_equal(trial_replay_from_files(&cfg, &r, why, sizeof why), 0);
    printf("# %s\n", why);
    assert_non_null(strstr(why, "frames.csv line 12"));
}

/* Issue 33, item 4: a replay of a trial that has not ended is refused (it would read a video
 * still being written), and so is a replay of a replay that ended early, in words that say so
 * (it was "has 30 frames; trial N recorded 10 (frames 0..9): not this trial's video"). Uses the
 * store of test_replay_uses_stored_times: trial 1 is a whole replay of the outside recording. */
static void test_unfinished_and_cut_replays_refused(void **state)
{
    (void)state;
    char p[160], why[600] = "";
    store *st = NULL;
    snprintf(p, sizeof p, "%s/trials.db", dir);
    assert_int_equal(store_open(p, &st, why, sizeof why), STORE_OK);
    trial_replay *r = NULL;
    if (trial_replay_from_trial(st, 1, NULL, &r, why, sizeof why)) fail_msg("replay of trial 1: %s", why);
    int64_t id = 0;
    assert_int_equal(trial_replay_create(r, st, "running", &id, why, sizeof why), 0); /* status running */
    trial_replay_free(r);
    r = NULL;
    int rc = trial_replay_prepare(st, NULL, id, NULL, &r, why, sizeof why);
    printf("# replay of running trial %lld: %d: %s\n", (long long)id, rc, why);
    assert_int_equal(rc, TRIAL_REPLAY_UNFINISHED);
    assert_null(r);
    assert_non_null(strstr(why, "is not finished (status running"));

    /* It ends aborted after 10 of the video's 30 frames. */
    store_sample *smp = NULL;
    size_t ns = 0;
    assert_int_equal(store_samples_get(st, 1, &smp, &ns, why, sizeof why), STORE_OK);
    store_samples *w = NULL;
    assert_int_equal(store_samples_begin(st, id, NULL, &w, why, sizeof why), STORE_OK);
    for (size_t k = 0; k < ns; k++)
        if (smp[k].kind == STORE_SAMPLE_FRAME && smp[k].frame < 10)
            assert_int_equal(store_samples_add(w, &smp[k], why, sizeof why), STORE_OK);
    assert_int_equal(store_samples_end(w, why, sizeof why), STORE_OK);
    free(smp);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_ABORTED, "abort requested", store_wall_now(), why,
                                            sizeof why),
                     STORE_OK);
    rc = trial_replay_prepare(st, NULL, id, NULL, &r, why, sizeof why);
    printf("# replay of the aborted replay %lld: %s\n", (long long)id, why);
    assert_int_equal(rc, -1);
    char want[160];
    snprintf(want, sizeof want, "trial %lld is a replay of trial 1 that ended aborted after 10 of the video's %d frames",
             (long long)id, NF);
    assert_non_null(strstr(why, want));
    assert_non_null(strstr(why, "replay trial 1 instead"));
    store_close(st);
}

/* Ribbon-like frames: a dark arc between the calibration's clamp points (40, 120) and (280, 120)
 * rising a pixel a frame, on a noisy background no lossy codec keeps bit for bit. */
static void write_ribbon_video(const char *path)
{
    vis_error ve = {0};
    vis_video_writer *vw = vis_video_writer_open_y800(path, W, H, FPS, &ve);
    if (!vw) fail_msg("video: %s", ve.message);
    vis_frame *f = vis_frame_alloc(W, H, 1, &ve);
    assert_non_null(f);
    uint32_t seed = 12345u;
    for (int k = 0; k < NF; k++) {
        uint8_t *d = vis_frame_data(f);
        double hgt = 80.0 + 0.5 * k; /* arc length about the free length, 320 px at 1.6 px/mm */
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) {
                seed = seed * 1103515245u + 12345u;
                double u = (x - 160.0) / 120.0;
                double yc = 120.0 - hgt * (1.0 - u * u);
                int on = fabs(u) <= 1.0 && fabs(y - yc) < 3.0;
                d[(size_t)y * vis_frame_stride(f) + (size_t)x] = (uint8_t)((on ? 30 : 200) + (int)(seed >> 29));
            }
        assert_int_equal(vis_video_writer_write(vw, f, &ve), VIS_OK);
    }
    vis_video_writer_close(vw);
    vis_frame_free(f);
}

static int same_num(double a, double b) { return (isnan(a) && isnan(b)) || a == b; }

static void samples_of(store *st, int64_t id, store_sample **smp, size_t *ns)
{
    char why[256];
    assert_int_equal(store_samples_get(st, id, smp, ns, why, sizeof why), STORE_OK);
}

/* Every sample of trials a and b equal (NaN equals NaN); returns the frames tracked. */
static int same_samples(store *st, int64_t a, int64_t b)
{
    store_sample *x = NULL, *y = NULL;
    size_t nx = 0, ny = 0;
    samples_of(st, a, &x, &nx);
    samples_of(st, b, &y, &ny);
    assert_int_equal(nx, ny);
    int tracked = 0;
    for (size_t k = 0; k < nx; k++) {
        if (x[k].kind != y[k].kind || x[k].frame != y[k].frame || !same_num(x[k].t_s, y[k].t_s) ||
            !same_num(x[k].shear_mm, y[k].shear_mm) || !same_num(x[k].compress_mm, y[k].compress_mm) ||
            !same_num(x[k].dw, y[k].dw) || !same_num(x[k].dz, y[k].dz) || !same_num(x[k].a, y[k].a) ||
            !same_num(x[k].quality, y[k].quality) || strcmp(x[k].reason, y[k].reason) != 0)
            fail_msg("trials %lld and %lld differ at sample %zu (frame %lld): dz %.17g / %.17g, quality %g / %g, "
                     "\"%s\" / \"%s\"",
                     (long long)a, (long long)b, k, (long long)x[k].frame, x[k].dz, y[k].dz, x[k].quality,
                     y[k].quality, x[k].reason, y[k].reason);
        if (x[k].kind == STORE_SAMPLE_FRAME && isfinite(x[k].dz)) tracked++;
    }
    free(x);
    free(y);
    return tracked;
}

static int64_t replay_files(const char *video_override)
{
    char p[160], ov[200], why[512] = "";
    snprintf(p, sizeof p, "%s/replay.ini", dir);
    static rig_config cfg;
    cfg_error ce;
    const char *ovs[1] = {ov};
    if (video_override) snprintf(ov, sizeof ov, "replay.video=%s", video_override);
    if (rig_config_load(p, video_override ? ovs : NULL, video_override ? 1 : 0, &cfg, &ce) != CFG_OK)
        fail_msg("%s", cfg_error_format(&ce, why, sizeof why));
    trial_replay *r = NULL;
    if (trial_replay_from_files(&cfg, &r, why, sizeof why)) fail_msg("replay: %s", why);
    store *st = NULL;
    snprintf(p, sizeof p, "%s/trials.db", dir);
    assert_int_equal(store_open(p, &st, why, sizeof why), STORE_OK);
    int64_t id = 0;
    trial_result res;
    if (trial_replay_run(r, st, "form", NULL, NULL, &id, &res, why, sizeof why)) fail_msg("replay: %s", why);
    trial_replay_free(r);
    store_close(st);
    return id;
}

static int64_t replay_stored(store *st, int64_t src)
{
    char why[512] = "";
    trial_replay *r = NULL;
    if (trial_replay_from_trial(st, src, NULL, &r, why, sizeof why)) fail_msg("replay of %lld: %s", (long long)src, why);
    int64_t id = 0;
    trial_result res;
    if (trial_replay_run(r, st, "form", NULL, NULL, &id, &res, why, sizeof why)) fail_msg("replay: %s", why);
    trial_replay_free(r);
    return id;
}

static void test_both_video_forms_replay_the_same(void **state)
{
    (void)state;
    write_files(0);
    char avi[160], mkv[160], why[512] = "";
    snprintf(avi, sizeof avi, "%s/rec.avi", dir);
    snprintf(mkv, sizeof mkv, "%s/rec.mkv", dir);
    write_ribbon_video(avi);
    int64_t a = replay_files(NULL); /* the raw form, as an outside recording */
    store *st = NULL;
    char p[160];
    snprintf(p, sizeof p, "%s/trials.db", dir);
    assert_int_equal(store_open(p, &st, why, sizeof why), STORE_OK);
    int64_t b = replay_stored(st, a); /* the raw form, as a stored trial's video */
    trial_transcode_result tr;
    if (trial_transcode_run(avi, mkv, NULL, &tr, why, sizeof why)) fail_msg("transcode: %s", why);
    assert_true(tr.raw_removed);
    assert_int_equal(access(avi, F_OK), -1);
    int64_t d0 = replay_stored(st, a); /* the store still names the .avi (a transcode by hand) */
    assert_int_equal(store_trial_set_video_file(st, a, mkv, tr.out_bytes, NULL, why, sizeof why), STORE_OK);
    store_close(st);
    int64_t c = replay_files(mkv); /* the FFV1 form, with the recording's frame times */
    assert_int_equal(store_open(p, &st, why, sizeof why), STORE_OK);
    int64_t d = replay_stored(st, a); /* the FFV1 form, as the stored trial's video */
    int tracked = same_samples(st, a, c);
    assert_int_equal(same_samples(st, b, d), tracked);
    assert_int_equal(same_samples(st, b, d0), tracked);
    printf("# raw %lld bytes, FFV1 %lld; replays %lld = %lld (outside recording) and %lld = %lld (stored trial): "
           "every sample equal, %d frames tracked\n",
           (long long)tr.raw_bytes, (long long)tr.out_bytes, (long long)a, (long long)c, (long long)b, (long long)d,
           tracked);
    assert_true(tracked > NF / 2);
    store_close(st);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_replay_uses_stored_times),
        cmocka_unit_test(test_times_going_back_refused),
        cmocka_unit_test(test_unfinished_and_cut_replays_refused),
        cmocka_unit_test(test_both_video_forms_replay_the_same),
    };
    int failed = cmocka_run_group_tests(tests, setup, NULL);
    test_dir_done(dir, !failed, "the recording, calibration and store");
    return failed;
}
