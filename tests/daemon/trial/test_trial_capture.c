/* test_trial_capture: the live pipeline (capture thread, ring, recorder, clock mapping) against
 * Aravis's fake GigE Vision camera served on 127.0.0.1 in this process, so the path is the real
 * one: GVCP control, GVSP stream, camera timestamps, block ids.
 * The camera's fill callback writes a frame counter into the first 8 pixels and a pattern derived
 * from it into the rest, and records the host's monotonic time at which it made that frame (the
 * truth). Checked: every frame captured and recorded, the video reads back bit-exact, each recorded
 * frame's mapped time against the truth, the counts under a slowed tracker (skipped, video still
 * complete), a camera that stops (an error within 0.5 s + the stream timeout), and the named errors
 * of a missing camera and a refused region.
 * Full rate (60 fps, 640 x 480) in the normal build; 20 fps under the sanitizers (same paths). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <arv.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "trial_capture.h"
#include "test_dir.h"
#include "vision.h"

#if defined(__SANITIZE_ADDRESS__)
#define FPS 20.0
/* Under the sanitizers on a loaded machine the transport floor itself wanders (2-13 ms seen at
 * load 18): the bounds are half a frame period (median), a frame period (every frame) and 1 s for
 * the stop; the normal build checks the tight ones. */
#define MEDIAN_BOUND_S (0.5 / FPS)
#define WORST_BOUND_S (1.0 / FPS)
#define STOP_BOUND_S 1.0
#else
#define FPS 60.0
#define MEDIAN_BOUND_S 0.5e-3
#define WORST_BOUND_S 1e-3 /* issue 13: every frame's stored time within 1 ms of its true send time */
#define STOP_BOUND_S 0.5
#endif
#define W 640
#define H 480
#define MAX_TRUTH 100000

static double mono(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct fake {
    ArvGvFakeCamera *gv;
    uint64_t counter;
    int frozen;              /* 1: every frame is the last one's image again */
    uint64_t frozen_k;
    double truth[MAX_TRUTH]; /* host monotonic time each frame was made */
} fake;

static uint8_t pattern(uint64_t k, size_t i) { return (uint8_t)((i * 7u + k * 13u + (i / W) * 3u) & 0xffu); }

static void fill(ArvBuffer *b, void *user, guint32 exposure_us, guint32 gain, ArvPixelFormat pf)
{
    (void)exposure_us;
    (void)gain;
    (void)pf;
    fake *f = user;
    size_t n = 0;
    uint8_t *p = (uint8_t *)arv_buffer_get_data(b, &n);
    /* The buffer's received size is set after this callback: the image is width x height. */
    n = (size_t)arv_buffer_get_image_width(b) * (size_t)arv_buffer_get_image_height(b);
    if (n < 8) return;
    uint64_t k = f->counter++;
    if (__atomic_load_n(&f->frozen, __ATOMIC_ACQUIRE)) {
        if (!f->frozen_k) f->frozen_k = k;
        k = f->frozen_k;
    }
    for (size_t i = 8; i < n; i++) p[i] = pattern(k, i);
    memcpy(p, &k, 8);
    /* Stamped as it leaves (the leader goes out right after this callback), like ribbon-rigsim's
     * camera: the real-time clock is the camera's, the monotonic time the truth.
     * Both clocks as one instant: the real-time read between two monotonic reads, again if a
     * preemption split them (the truth is the midpoint). */
    struct timespec r;
    double m1, m2;
    int tries = 0;
    do {
        m1 = mono();
        clock_gettime(CLOCK_REALTIME, &r);
        m2 = mono();
    } while (m2 - m1 > 20e-6 && ++tries < 10);
    if (k < MAX_TRUTH) f->truth[k] = 0.5 * (m1 + m2);
    arv_buffer_set_timestamp(b, (guint64)r.tv_sec * 1000000000ull + (guint64)r.tv_nsec);
}

/* The running fake camera, for the teardown: a failed assertion leaves the test by longjmp, and a
 * camera left serving port 3956 would answer the next test's camera too. */
static fake *running;

static fake *fake_start(void)
{
    fake *f = calloc(1, sizeof *f);
    running = f;
    assert_non_null(f);
    f->gv = arv_gv_fake_camera_new("127.0.0.1", "RIBBONTEST");
    assert_non_null(f->gv);
    assert_true(arv_gv_fake_camera_is_running(f->gv));
    arv_fake_camera_set_fill_pattern(arv_gv_fake_camera_get_fake_camera(f->gv), fill, f);
    return f;
}

static void fake_stop(fake *f)
{
    if (f->gv) g_object_unref(f->gv);
    f->gv = NULL;
}

static void fake_free(fake *f)
{
    fake_stop(f);
    free(f);
    running = NULL;
}

static int teardown(void **state)
{
    (void)state;
    if (running) fake_free(running);
    return 0;
}

static vis_source *open_cam(vis_error *ve)
{
    vis_camera_settings cs = vis_camera_settings_default();
    cs.aravis = 1;
    cs.path = "127.0.0.1";
    cs.width_px = W;
    cs.height_px = H;
    cs.fps = FPS;
    return vis_source_open_camera(&cs, ve);
}

static char dir[64];
static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/test_trial_capture.XXXXXX");
    return mkdtemp(dir) ? 0 : -1;
}

/* Runs the pipeline for `seconds`, consuming in order; returns the counts. */
static void run(fake *f, double seconds, double track_delay_s, double max_loss_fraction, const char *video,
                trial_capture_counts *k, long *consumed, long *skipped_seen)
{
    vis_error ve = {0};
    vis_source *src = open_cam(&ve);
    if (!src) fail_msg("camera: %s", ve.message);
    trial_capture_params p = trial_capture_params_default();
    p.video_path = video;
    p.roi = (trial_roi){0, 0, W, H};
    p.fps = FPS;
    p.track_delay_s = track_delay_s;
    if (max_loss_fraction >= 0.0) p.max_loss_fraction = max_loss_fraction;
    char why[256] = "";
    trial_capture *c = trial_capture_start(src, &p, why, sizeof why);
    if (!c) fail_msg("capture: %s", why);
    vis_frame *fr = vis_frame_alloc(16, 16, 1, &ve);
    double t_end = mono() + seconds;
    long prev = -1;
    *consumed = *skipped_seen = 0;
    while (mono() < t_end) {
        trial_frame_info fi;
        if (trial_capture_next(c, fr, &fi, why, sizeof why)) fail_msg("next: %s", why);
        assert_int_equal(fi.index, prev + 1); /* in order, none missing */
        prev = fi.index;
        (*consumed)++;
        if (fi.skip) (*skipped_seen)++;
        if (!fi.skip && !fi.dropped) {
            /* the pixels are the camera's frame, and its time is the truth's */
            uint64_t id;
            memcpy(&id, vis_frame_data(fr), 8);
            assert_true(id < MAX_TRUTH);
            assert_int_equal(vis_frame_width(fr), W);
        }
    }
    assert_int_equal(trial_capture_stop(c, k, why, sizeof why), 0);
    vis_frame_free(fr);
    vis_source_close(src);
    (void)f;
}

/* Reads the video and its frame-times file back: bit-exact pixels; returns the worst and median
 * |mapped time - truth| over the frames. */
static long check_video(fake *f, const char *video, double *worst, double *median)
{
    char tpath[256];
    snprintf(tpath, sizeof tpath, "%s.frames.csv", video);
    FILE *t = fopen(tpath, "r");
    assert_non_null(t);
    char line[256];
    assert_non_null(fgets(line, sizeof line, t));
    vis_error ve = {0};
    vis_source *v = vis_source_open_video(video, &ve);
    if (!v) fail_msg("video: %s", ve.message);
    vis_frame *fr = vis_frame_alloc(16, 16, 1, &ve);
    long n = 0;
    static double err[MAX_TRUTH];
    for (;;) {
        double ts;
        vis_status st = vis_source_read(v, fr, &ts, &ve);
        if (st == VIS_ERR_END) break;
        assert_int_equal(st, VIS_OK);
        long vf, ci;
        unsigned long long cid;
        double cam, host, mapped;
        assert_non_null(fgets(line, sizeof line, t));
        assert_int_equal(sscanf(line, "%ld,%ld,%llu,%lf,%lf,%lf", &vf, &ci, &cid, &cam, &host, &mapped), 6);
        assert_int_equal(vf, n);
        const uint8_t *p = vis_frame_data(fr);
        uint64_t k;
        memcpy(&k, p, 8);
        assert_true(k < MAX_TRUTH);
        for (size_t i = 8; i < (size_t)W * H; i++)
            if (p[i] != pattern(k, i)) fail_msg("frame %ld pixel %zu: %u, not %u", n, i, p[i], pattern(k, i));
        if (n < MAX_TRUTH) err[n] = fabs(mapped - f->truth[k]);
        n++;
    }
    assert_null(fgets(line, sizeof line, t)); /* one line per frame, no more */
    fclose(t);
    vis_frame_free(fr);
    vis_source_close(v);
    /* Every frame (the clock map warmed up before the first was published). */
    double w = 0.0;
    int m = 0;
    static double sorted[MAX_TRUTH];
    for (long k = 0; k < n; k++) {
        w = fmax(w, err[k]);
        sorted[m++] = err[k];
    }
    for (int a = 1; a < m; a++)
        for (int b = a; b > 0 && sorted[b] < sorted[b - 1]; b--) {
            double x = sorted[b];
            sorted[b] = sorted[b - 1];
            sorted[b - 1] = x;
        }
    *worst = w;
    *median = m ? sorted[m / 2] : NAN;
    return n;
}

static void test_every_frame_recorded_bit_exact_and_stamped(void **state)
{
    (void)state;
    fake *f = fake_start();
    char video[128];
    snprintf(video, sizeof video, "%s/full.avi", dir);
    trial_capture_counts k;
    long consumed, skipped;
    run(f, 3.0, 0.0, -1.0, video, &k, &consumed, &skipped);
    uint64_t sent = __atomic_load_n(&f->counter, __ATOMIC_ACQUIRE);
    fake_stop(f);
    double worst, median;
    long n = check_video(f, video, &worst, &median);
    long accounted = k.warmup + k.captured + k.lost + k.incomplete;
    printf("# %.0f fps: captured %ld lost %ld incomplete %ld dropped %ld recorded %ld skipped %ld; "
           "mapped - truth: median %.3f ms, worst %.3f ms; offset %.6f s drift %.2g\n",
           FPS, k.captured, k.lost, k.incomplete, k.dropped, k.recorded, k.skipped, 1e3 * median, 1e3 * worst,
           k.offset_s, k.drift);
    assert_true(k.captured >= (long)(3.0 * FPS * 0.8));
    assert_int_equal(k.dropped, 0);
    assert_int_equal(k.recorded, k.captured);
    assert_int_equal(n, k.recorded);
    /* The camera here serves from this process, beside the capture, recorder and checker: on 2
     * cores Aravis's receive thread now and then gets a buffer incomplete (1 in 182, in about half
     * the runs on an idle machine, 2026-12-02). Such a buffer is counted, never published, so
     * "every published frame recorded" holds whatever the transport does; the zero-loss rule of
     * issue 13 is asserted end to end, with the camera in ribbon-rigsim's own process, by
     * test_rig_rehearsal and test_rig_rails. Here: no id gap, at most 2% incomplete (2 in 181 once
     * in CI, 2026-12-02), and every frame the camera sent accounted for (published, or counted
     * lost or incomplete; the frames still in flight at the stop are the only ones not). */
    printf("# camera sent %llu, warm-up %ld + captured %ld + lost %ld + incomplete %ld = %ld\n",
           (unsigned long long)sent, k.warmup, k.captured, k.lost, k.incomplete, accounted);
    assert_int_equal(k.lost, 0);
    assert_true(k.incomplete <= (k.captured > 150 ? k.captured / 50 : 3));
    assert_true(accounted <= (long)sent);
    assert_true(accounted >= (long)sent - 4);
    /* A frame's mapped time: the camera's stamp plus the fastest arrival's delay (the leader's
     * trip over loopback, 0.1 ms, which the mapping keeps: the rig's camera_time_offset_s is for
     * such a constant); every frame within 1 ms of the truth in the normal build. */
    assert_true(median < MEDIAN_BOUND_S);
    assert_true(worst < WORST_BOUND_S);
    fake_free(f);
}

static void test_slow_tracker_skips_video_complete(void **state)
{
    (void)state;
    fake *f = fake_start();
    char video[128];
    snprintf(video, sizeof video, "%s/slow.avi", dir);
    trial_capture_counts k;
    long consumed, skipped;
    run(f, 3.0, 3.0 / FPS, -1.0, video, &k, &consumed, &skipped);
    fake_stop(f);
    double worst, median;
    long n = check_video(f, video, &worst, &median);
    printf("# slowed tracker (3 frame periods per frame): captured %ld skipped %ld dropped %ld recorded %ld\n",
           k.captured, k.skipped, k.dropped, k.recorded);
    assert_true(k.skipped > 0);
    assert_int_equal(k.skipped, skipped);
    assert_int_equal(k.dropped, 0);
    assert_int_equal(n, k.captured);
    assert_true(worst < 1.0 / FPS);
    fake_free(f);
}

static void test_camera_stops_is_an_error_soon(void **state)
{
    (void)state;
    fake *f = fake_start();
    vis_error ve = {0};
    vis_source *src = open_cam(&ve);
    if (!src) fail_msg("camera: %s", ve.message);
    trial_capture_params p = trial_capture_params_default();
    p.frame_timeout_s = 0.5;
    char why[256] = "";
    trial_capture *c = trial_capture_start(src, &p, why, sizeof why);
    assert_non_null(c);
    vis_frame *fr = vis_frame_alloc(16, 16, 1, &ve);
    trial_frame_info fi;
    for (int i = 0; i < 10; i++) assert_int_equal(trial_capture_next(c, fr, &fi, why, sizeof why), 0);
    double t_stop = mono();
    fake_stop(f);
    double t_err = NAN;
    for (int i = 0; i < 1000; i++)
        if (trial_capture_next(c, fr, &fi, why, sizeof why)) {
            t_err = mono();
            break;
        }
    printf("# camera stopped: error after %.3f s: %s\n", t_err - t_stop, why);
    assert_true(isfinite(t_err));
    assert_true(t_err - t_stop < STOP_BOUND_S); /* issue 13: within 0.5 s (normal build) */
    assert_non_null(strstr(why, "camera"));
    trial_capture_counts k;
    trial_capture_stop(c, &k, why, sizeof why);
    vis_frame_free(fr);
    vis_source_close(src);
    fake_free(f);
}

/* GVSP packets dropped at random by the camera (Aravis's gvsp-lost-ratio; the fake camera does not
 * resend): every frame the camera sent is accounted for (published, or counted lost or
 * incomplete), the video has every published frame, and the capture goes on. */
static void test_lost_packets_counted(void **state)
{
    (void)state;
    fake *f = fake_start();
    g_object_set(f->gv, "gvsp-lost-ratio", 5e-4, NULL); /* about 1 frame in 10 damaged */
    char video[128];
    snprintf(video, sizeof video, "%s/lossy.avi", dir);
    trial_capture_counts k;
    long consumed, skipped;
    /* No quality limit here: this test is the accounting (test_heavy_loss_ends_capture is the
     * limit's). On a loaded CI machine the transport adds its own losses to the camera's: 46 of 106
     * frames once, over the default 25% limit, and the run stopped before its accounting. */
    run(f, 3.0, 0.0, 0.0, video, &k, &consumed, &skipped);
    uint64_t sent = __atomic_load_n(&f->counter, __ATOMIC_ACQUIRE);
    fake_stop(f);
    long accounted = k.warmup + k.captured + k.lost + k.incomplete;
    printf("# lost packets (5e-4 of them): camera sent %llu, warm-up %ld + captured %ld + lost %ld + incomplete %ld "
           "= %ld; recorded %ld\n",
           (unsigned long long)sent, k.warmup, k.captured, k.lost, k.incomplete, accounted, k.recorded);
    assert_true(k.lost + k.incomplete > 0);
    assert_int_equal(k.recorded, k.captured);
    /* the frames still in flight when the capture stopped are the only ones not accounted */
    assert_true(accounted <= (long)sent);
    assert_true(accounted >= (long)sent - 4);
    fake_free(f);
}

/* Too many damaged frames: the capture ends with a named reason (the runner fails the trial). */
static void test_heavy_loss_ends_capture(void **state)
{
    (void)state;
    fake *f = fake_start();
    vis_error ve = {0};
    vis_source *src = open_cam(&ve);
    if (!src) fail_msg("camera: %s", ve.message);
    trial_capture_params p = trial_capture_params_default();
    p.warmup_s = 0.2;
    /* The damaged frames can starve the in-process stream for over a second (the normal build's
     * CI run on 2026-12-03 ended by "no frame for 1.00 s" before the loss window filled): this
     * test is about the loss limit, so the read waits longer than any such stall. */
    p.frame_timeout_s = 5.0;
    char why[256] = "";
    trial_capture *c = trial_capture_start(src, &p, why, sizeof why);
    if (!c) fail_msg("capture: %s", why);
    g_object_set(f->gv, "gvsp-lost-ratio", 5e-3, NULL); /* 2 frames in 3 damaged */
    vis_frame *fr = vis_frame_alloc(16, 16, 1, &ve);
    trial_frame_info fi;
    int failed = 0;
    for (int i = 0; i < 2000 && !failed; i++) failed = trial_capture_next(c, fr, &fi, why, sizeof why) != 0;
    printf("# heavy loss: %s\n", why);
    assert_true(failed);
#if defined(__SANITIZE_ADDRESS__)
    /* Under the sanitizers at 20 fps the damaged frames can starve the stream for the 1 s read
     * timeout before the window fills (seen in CI, 2026-12-02): a named end either way. */
    assert_true(strstr(why, "lost or incomplete") || strstr(why, "no frame for"));
#else
    assert_non_null(strstr(why, "lost or incomplete"));
#endif
    trial_capture_counts k;
    char w2[256];
    assert_int_equal(trial_capture_stop(c, &k, w2, sizeof w2), 0);
    assert_true(k.lost + k.incomplete > 0);
    vis_frame_free(fr);
    vis_source_close(src);
    fake_stop(f);
    fake_free(f);
}

/* A frozen camera (the same image frame after frame): same_run counts it; before, every frame is new. */
static void test_frozen_image_counted(void **state)
{
    (void)state;
    fake *f = fake_start();
    vis_error ve = {0};
    vis_source *src = open_cam(&ve);
    if (!src) fail_msg("camera: %s", ve.message);
    trial_capture_params p = trial_capture_params_default();
    p.warmup_s = 0.2;
    char why[256] = "";
    trial_capture *c = trial_capture_start(src, &p, why, sizeof why);
    if (!c) fail_msg("capture: %s", why);
    vis_frame *fr = vis_frame_alloc(16, 16, 1, &ve);
    trial_frame_info fi;
    for (int i = 0; i < 30; i++) {
        assert_int_equal(trial_capture_next(c, fr, &fi, why, sizeof why), 0);
        assert_int_equal(fi.same_run, 1);
    }
    __atomic_store_n(&f->frozen, 1, __ATOMIC_RELEASE);
    long run_max = 0;
    for (int i = 0; i < 60; i++) {
        assert_int_equal(trial_capture_next(c, fr, &fi, why, sizeof why), 0);
        if (fi.same_run > run_max) run_max = fi.same_run;
    }
    printf("# frozen image: %ld identical frames in a row seen in 60\n", run_max);
    assert_true(run_max >= TRIAL_FROZEN_FRAMES);
    trial_capture_counts k;
    assert_int_equal(trial_capture_stop(c, &k, why, sizeof why), 0);
    vis_frame_free(fr);
    vis_source_close(src);
    fake_stop(f);
    fake_free(f);
}

/* Frames in another pixel format than Mono8: the capture does not start (named), and no video or
 * frame-times file is left behind. */
static void test_not_mono8_refused_nothing_written(void **state)
{
    (void)state;
    fake *f = fake_start();
    vis_error ve = {0};
    vis_source *src = open_cam(&ve);
    if (!src) fail_msg("camera: %s", ve.message);
    /* the camera switches to Mono16 behind the program's back */
    arv_fake_camera_write_register(arv_gv_fake_camera_get_fake_camera(f->gv), ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT,
                                   ARV_PIXEL_FORMAT_MONO_16);
    char video[128], times[160];
    snprintf(video, sizeof video, "%s/mono16.avi", dir);
    snprintf(times, sizeof times, "%s.frames.csv", video);
    trial_capture_params p = trial_capture_params_default();
    p.video_path = video;
    p.roi = (trial_roi){0, 0, W, H};
    char why[256] = "";
    trial_capture *c = NULL;
    /* frames already in Aravis's pool may still be Mono8: a few tries */
    for (int i = 0; i < 3 && (c = trial_capture_start(src, &p, why, sizeof why)) != NULL; i++) {
        char w2[256];
        trial_capture_stop(c, NULL, w2, sizeof w2);
        c = NULL;
        unlink(video);
        unlink(times);
    }
    printf("# %s\n", why);
    assert_null(c);
    assert_non_null(strstr(why, "Mono8"));
    assert_int_equal(access(video, F_OK), -1);
    assert_int_equal(access(times, F_OK), -1);
    vis_source_close(src);
    fake_stop(f);
    fake_free(f);
}

static void test_named_errors(void **state)
{
    (void)state;
    fake *f = fake_start();
    vis_error ve = {0};
    vis_camera_settings cs = vis_camera_settings_default();
    cs.aravis = 1;
    cs.path = "no-such-camera-4711";
    assert_null(vis_source_open_camera(&cs, &ve));
    printf("# %s\n", ve.message);
    assert_non_null(strstr(ve.message, "no-such-camera-4711"));
    cs.path = "127.0.0.1";
    cs.width_px = 100000; /* the fake sensor is 2048 wide */
    cs.height_px = 480;
    assert_null(vis_source_open_camera(&cs, &ve));
    printf("# %s\n", ve.message);
    assert_non_null(strstr(ve.message, "refused"));
    cs.width_px = W;
    cs.fps = 1e6; /* beyond the camera's AcquisitionFrameRate */
    assert_null(vis_source_open_camera(&cs, &ve));
    printf("# %s\n", ve.message);
    assert_non_null(strstr(ve.message, "AcquisitionFrameRate"));
    fake_stop(f);
    fake_free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_every_frame_recorded_bit_exact_and_stamped, teardown),
        cmocka_unit_test_teardown(test_slow_tracker_skips_video_complete, teardown),
        cmocka_unit_test_teardown(test_camera_stops_is_an_error_soon, teardown),
        cmocka_unit_test_teardown(test_lost_packets_counted, teardown),
        cmocka_unit_test_teardown(test_heavy_loss_ends_capture, teardown),
        cmocka_unit_test_teardown(test_frozen_image_counted, teardown),
        cmocka_unit_test_teardown(test_not_mono8_refused_nothing_written, teardown),
        cmocka_unit_test_teardown(test_named_errors, teardown),
    };
    int failed = cmocka_run_group_tests(tests, setup, NULL);
    test_dir_done(dir, !failed, "the recordings");
    return failed;
}
