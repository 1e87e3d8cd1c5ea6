/* test_trial_transcode: a trial's raw Y800 video transcoded to FFV1 after the trial (issue 34,
 * part D). The frames are pseudo-random noise, which no lossy codec reproduces, and the output is
 * read back through the replays' own reader (OpenCV, vis_source_open_video) and compared with
 * the generator's frames, not with the transcoder's own verify. Also: a frame changed before
 * encoding (what a lossy codec does) fails the verify, keeps the raw file and leaves no output;
 * a crop keeps exactly that region; a stopped transcode keeps the raw file; and the worker:
 * a submit returns at once, the next trial's raw video is written while a transcode is held in
 * progress, the store then names each trial's .mkv with its size, and a failed verify leaves the
 * trial's .avi with an event saying why; at start-up the raw videos an earlier run left are queued
 * again, except those kept raw on purpose (a failed transcode, an interrupted trial). While a
 * transcode runs, the worker and every thread of the encoder it opened run in SCHED_IDLE
 * (thread_class.h: the next trial's loop, capture and poller always win the cores), the test's own
 * thread in its normal class. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <dirent.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "store.h"
#include "test_dir.h"
#include "trial_transcode.h"
#include "trial_transcoder.h"
#include "thread_class.h"
#include "vision.h"

#define W 160
#define H 120
#define NF 24

static char dir[] = "/tmp/ribbon-transcode-XXXXXX";

static uint8_t px(int f, int x, int y)
{
    uint32_t s = (uint32_t)(f * 7919 + y * 104729 + x * 1299709) ^ 0x9e3779b9u;
    s ^= s >> 13;
    s *= 0x5bd1e995u;
    s ^= s >> 15;
    return (uint8_t)(s >> 24);
}

static void write_raw(const char *path, int nf)
{
    vis_error ve = {0};
    vis_video_writer *vw = vis_video_writer_open_y800(path, W, H, 60.0, &ve);
    if (!vw) fail_msg("video: %s", ve.message);
    vis_frame *f = vis_frame_alloc(W, H, 1, &ve);
    assert_non_null(f);
    for (int k = 0; k < nf; k++) {
        uint8_t *d = vis_frame_data(f);
        for (int y = 0; y < H; y++)
            for (int x = 0; x < W; x++) d[(size_t)y * vis_frame_stride(f) + (size_t)x] = px(k, x, y);
        assert_int_equal(vis_video_writer_write(vw, f, &ve), VIS_OK);
    }
    vis_video_writer_close(vw);
    vis_frame_free(f);
}

/* Reads path through OpenCV and checks every frame against the generator, cropped. */
static void check_frames(const char *path, int x0, int y0, int w, int h, int nf)
{
    vis_error ve = {0};
    vis_source *src = vis_source_open_video(path, &ve);
    if (!src) fail_msg("%s: %s", path, ve.message);
    vis_frame *f = vis_frame_alloc(8, 8, 1, &ve);
    int k = 0;
    for (;; k++) {
        vis_status s = vis_source_read(src, f, NULL, &ve);
        if (s == VIS_ERR_END) break;
        assert_int_equal(s, VIS_OK);
        assert_int_equal(vis_frame_width(f), w);
        assert_int_equal(vis_frame_height(f), h);
        const uint8_t *d = vis_frame_data(f);
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                if (d[(size_t)y * vis_frame_stride(f) + (size_t)x] != px(k, x0 + x, y0 + y))
                    fail_msg("%s frame %d pixel (%d, %d) differs", path, k, x, y);
    }
    assert_int_equal(k, nf);
    vis_frame_free(f);
    vis_source_close(src);
}

static int exists(const char *p) { return access(p, F_OK) == 0; }

static long long fsize(const char *p)
{
    struct stat sb;
    return stat(p, &sb) == 0 ? (long long)sb.st_size : -1;
}

static void test_lossless_bit_for_bit_then_raw_removed(void **s)
{
    (void)s;
    char raw[128], out[128], why[512] = "";
    snprintf(raw, sizeof raw, "%s/a.avi", dir);
    snprintf(out, sizeof out, "%s/a.mkv", dir);
    write_raw(raw, NF);
    long long raw_size = fsize(raw);
    trial_transcode_result r;
    trial_transcode_params p = trial_transcode_params_default();
    if (trial_transcode_run(raw, out, &p, &r, why, sizeof why)) fail_msg("%s", why);
    assert_int_equal(r.frames, NF);
    assert_int_equal(r.width, W);
    assert_int_equal(r.height, H);
    assert_true(r.raw_removed);
    assert_false(exists(raw));
    assert_int_equal(r.raw_bytes, raw_size);
    assert_int_equal(r.out_bytes, fsize(out));
    char part[140];
    snprintf(part, sizeof part, "%s.part", out);
    assert_false(exists(part));
    check_frames(out, 0, 0, W, H, NF);
    printf("# noise %dx%dx%d: raw %lld bytes, FFV1 %lld (noise does not compress), encode %.3f s, verify %.3f s\n", W,
           H, NF, raw_size, (long long)r.out_bytes, r.encode_s, r.verify_s);
}

static void test_changed_frame_fails_verify_and_keeps_raw(void **s)
{
    (void)s;
    char raw[128], out[128], why[512] = "";
    snprintf(raw, sizeof raw, "%s/b.avi", dir);
    snprintf(out, sizeof out, "%s/b.mkv", dir);
    write_raw(raw, NF);
    long long raw_size = fsize(raw);
    trial_transcode_params p = trial_transcode_params_default();
    p.corrupt_frame = 7;
    trial_transcode_result r;
    assert_int_equal(trial_transcode_run(raw, out, &p, &r, why, sizeof why), -1);
    printf("# %s\n", why);
    assert_non_null(strstr(why, "frame 7 differs at pixel (0, 0)"));
    assert_false(r.raw_removed);
    assert_int_equal(fsize(raw), raw_size);
    assert_false(exists(out));
    char part[140];
    snprintf(part, sizeof part, "%s.part", out);
    assert_false(exists(part));
    check_frames(raw, 0, 0, W, H, NF); /* the raw file is whole */
}

static void test_crop_keeps_exactly_the_region(void **s)
{
    (void)s;
    char raw[128], out[128], why[512] = "";
    snprintf(raw, sizeof raw, "%s/c.avi", dir);
    snprintf(out, sizeof out, "%s/c.mkv", dir);
    write_raw(raw, NF);
    trial_transcode_params p = trial_transcode_params_default();
    p.crop_x = 13, p.crop_y = 21, p.crop_w = 100, p.crop_h = 80;
    trial_transcode_result r;
    if (trial_transcode_run(raw, out, &p, &r, why, sizeof why)) fail_msg("%s", why);
    assert_int_equal(r.width, 100);
    assert_int_equal(r.height, 80);
    check_frames(out, 13, 21, 100, 80, NF);
    /* a crop outside the frame is refused, the raw file kept */
    snprintf(raw, sizeof raw, "%s/c2.avi", dir);
    snprintf(out, sizeof out, "%s/c2.mkv", dir);
    write_raw(raw, 3);
    p.crop_x = 100;
    assert_int_equal(trial_transcode_run(raw, out, &p, &r, why, sizeof why), -1);
    assert_non_null(strstr(why, "does not fit"));
    assert_true(exists(raw));
    assert_false(exists(out));
}

static void test_stopped_transcode_keeps_raw(void **s)
{
    (void)s;
    char raw[128], out[128], why[512] = "";
    snprintf(raw, sizeof raw, "%s/d.avi", dir);
    snprintf(out, sizeof out, "%s/d.mkv", dir);
    write_raw(raw, NF);
    volatile int cancel = 1;
    trial_transcode_params p = trial_transcode_params_default();
    p.cancel = &cancel;
    assert_int_equal(trial_transcode_run(raw, out, &p, NULL, why, sizeof why), -1);
    assert_non_null(strstr(why, "shutting down"));
    assert_true(exists(raw));
    assert_false(exists(out));
}

/* ---- the worker ---- */

typedef struct gate {
    pthread_mutex_t m;
    pthread_cond_t c;
    int held, open;
} gate;

static gate g = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, 0, 0};

static void hold_at_frame_3(void *user, long frame)
{
    gate *x = user;
    if (frame != 3) return;
    pthread_mutex_lock(&x->m);
    x->held = 1;
    pthread_cond_broadcast(&x->c);
    while (!x->open) pthread_cond_wait(&x->c, &x->m);
    pthread_mutex_unlock(&x->m);
}

static double mono(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int64_t new_trial(const char *db, const char *video)
{
    store *st = NULL;
    char why[256];
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_RIG;
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &d, &id, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_video_file(st, id, video, fsize(video), NULL, why, sizeof why), STORE_OK);
    store_close(st);
    return id;
}

static void trial_video_of(const char *db, int64_t id, store_trial *t, char *events, size_t len)
{
    store *st = NULL;
    char why[256];
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_get(st, id, t, why, sizeof why), STORE_OK);
    store_event *ev = NULL;
    size_t n = 0;
    assert_int_equal(store_events_get(st, id, &ev, &n, why, sizeof why), STORE_OK);
    events[0] = '\0';
    for (size_t k = 0; k < n; k++) snprintf(events + strlen(events), len - strlen(events), "%s\n", ev[k].message);
    free(ev);
    store_close(st);
}

static void test_worker_next_trial_records_while_transcode_runs(void **s)
{
    (void)s;
    char db[128], raw1[128], raw2[128], raw3[128], why[512] = "";
    snprintf(db, sizeof db, "%s/trials.db", dir);
    snprintf(raw1, sizeof raw1, "%s/trial-1.avi", dir);
    snprintf(raw2, sizeof raw2, "%s/trial-2.avi", dir);
    snprintf(raw3, sizeof raw3, "%s/trial-3.avi", dir);
    write_raw(raw1, NF);
    int64_t id1 = new_trial(db, raw1);
    trial_transcoder_params tp = trial_transcoder_params_default();
    tp.store_path = db;
    tp.codec.on_frame = hold_at_frame_3;
    tp.codec.on_frame_user = &g;
    trial_transcoder *t = trial_transcoder_start(&tp, why, sizeof why);
    if (!t) fail_msg("%s", why);
    double t0 = mono();
    assert_int_equal(trial_transcoder_submit(t, id1, raw1, NULL, NULL, why, sizeof why), 0);
    double submit_s = mono() - t0;
    /* the transcode is now held in progress at frame 3 */
    pthread_mutex_lock(&g.m);
    while (!g.held) pthread_cond_wait(&g.c, &g.m);
    pthread_mutex_unlock(&g.m);
    assert_int_equal(trial_transcoder_pending(t), 1);
    assert_true(exists(raw1)); /* not removed while the transcode runs */
    /* The worker and the encoder's slice threads (open now, held mid-video) in SCHED_IDLE; this
     * thread, which stands for the next trial's, in its normal class. */
    long worker = trial_transcoder_worker_tid(t);
    assert_true(worker > 0);
    assert_int_equal(thread_class_is_idle(worker), 1);
    assert_int_equal(thread_class_is_idle(0), 0);
    int others = 0, idle = 0;
    DIR *tasks = opendir("/proc/self/task");
    assert_non_null(tasks);
    for (struct dirent *e; (e = readdir(tasks));) {
        long tid = atol(e->d_name);
        if (tid <= 0 || tid == thread_class_tid()) continue;
        int k = thread_class_is_idle(tid);
        if (k < 0) continue; /* ended meanwhile */
        others++;
        idle += k;
    }
    closedir(tasks);
    printf("# while a transcode runs: %d other thread(s), %d of them in SCHED_IDLE\n", others, idle);
    assert_true(others >= 2); /* the worker and at least one encoder thread (camera.transcode_threads 2) */
    assert_int_equal(idle, others);
    /* the next trial records its video meanwhile, and queues it */
    write_raw(raw2, NF);
    int64_t id2 = new_trial(db, raw2);
    t0 = mono();
    assert_int_equal(trial_transcoder_submit(t, id2, raw2, NULL, NULL, why, sizeof why), 0);
    submit_s = submit_s > mono() - t0 ? submit_s : mono() - t0;
    printf("# submit took at most %.6f s while a transcode was in progress\n", submit_s);
    assert_true(submit_s < 0.05);
    assert_int_equal(trial_transcoder_pending(t), 2);
    pthread_mutex_lock(&g.m);
    g.open = 1;
    pthread_cond_broadcast(&g.c);
    pthread_mutex_unlock(&g.m);
    assert_int_equal(trial_transcoder_wait_idle(t, 60.0), 0);
    trial_transcoder_stop(t);

    char ev[4096];
    store_trial tr;
    int64_t ids[2] = {id1, id2};
    for (int k = 0; k < 2; k++) {
        trial_video_of(db, ids[k], &tr, ev, sizeof ev);
        char mkv[128];
        snprintf(mkv, sizeof mkv, "%s/trial-%d.mkv", dir, k + 1);
        assert_string_equal(tr.video_path, mkv);
        assert_int_equal(tr.video_bytes, fsize(mkv));
        assert_non_null(strstr(ev, "video transcoded: FFV1"));
        assert_non_null(strstr(ev, "verified bit for bit"));
        check_frames(mkv, 0, 0, W, H, NF);
    }
    assert_false(exists(raw1));
    assert_false(exists(raw2));

    /* a transcode that does not verify: the trial keeps its raw video and says why */
    write_raw(raw3, NF);
    int64_t id3 = new_trial(db, raw3);
    tp.codec.on_frame = NULL;
    tp.codec.corrupt_frame = 5;
    t = trial_transcoder_start(&tp, why, sizeof why);
    assert_non_null(t);
    assert_int_equal(trial_transcoder_submit(t, id3, raw3, NULL, NULL, why, sizeof why), 0);
    assert_int_equal(trial_transcoder_wait_idle(t, 60.0), 0);
    trial_transcoder_stop(t);
    trial_video_of(db, id3, &tr, ev, sizeof ev);
    printf("# %s", ev);
    assert_string_equal(tr.video_path, raw3);
    assert_int_equal(tr.video_bytes, fsize(raw3));
    assert_non_null(strstr(ev, "video transcode failed, raw video"));
    assert_non_null(strstr(ev, "frame 5 differs"));
    assert_true(exists(raw3));
}

/* A rig trial with raw video path, ended with status (running first), optionally an event. */
static int64_t ended_trial(const char *db, const char *video, store_status status, const char *event)
{
    int64_t id = new_trial(db, video);
    store *st = NULL;
    char why[256];
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, store_wall_now(), why, sizeof why),
                     STORE_OK);
    if (status == STORE_STATUS_INTERRUPTED) {
        int count = 0;
        assert_int_equal(store_trial_mark_interrupted(st, store_wall_now(), &count, why, sizeof why), STORE_OK);
        assert_int_equal(count, 1);
    } else {
        assert_int_equal(store_trial_set_status(st, id, status, NULL, store_wall_now(), why, sizeof why), STORE_OK);
    }
    if (event) {
        store_event ev;
        memset(&ev, 0, sizeof ev);
        ev.trial_id = id;
        ev.t_s = NAN;
        ev.wall_s = store_wall_now();
        ev.kind = STORE_EVENT_WARNING;
        snprintf(ev.message, sizeof ev.message, "%s", event);
        assert_int_equal(store_event_append(st, &ev, why, sizeof why), STORE_OK);
    }
    store_close(st);
    return id;
}

static void test_start_up_queues_what_an_earlier_run_left(void **s)
{
    (void)s;
    char db[128], v[4][128], why[512] = "";
    snprintf(db, sizeof db, "%s/left.db", dir);
    for (int k = 0; k < 4; k++) {
        snprintf(v[k], sizeof v[k], "%s/left-%d.avi", dir, k + 1);
        write_raw(v[k], 4);
    }
    int64_t done = ended_trial(db, v[0], STORE_STATUS_DONE, NULL);
    int64_t failed_tx = ended_trial(db, v[1], STORE_STATUS_DONE, "video transcode failed, raw video kept: verify: x");
    int64_t interrupted = ended_trial(db, v[2], STORE_STATUS_INTERRUPTED, NULL);
    int64_t aborted = ended_trial(db, v[3], STORE_STATUS_ABORTED, NULL);
    trial_transcoder_params tp = trial_transcoder_params_default();
    tp.store_path = db;
    trial_transcoder *t = trial_transcoder_start(&tp, why, sizeof why);
    assert_non_null(t);
    store *st = NULL;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    assert_int_equal(trial_transcoder_queue_left(t, st, why, sizeof why), 2);
    store_close(st);
    assert_int_equal(trial_transcoder_wait_idle(t, 60.0), 0);
    trial_transcoder_stop(t);
    char ev[4096];
    store_trial tr;
    const int64_t ids[4] = {done, failed_tx, interrupted, aborted};
    const int transcoded[4] = {1, 0, 0, 1};
    for (int k = 0; k < 4; k++) {
        trial_video_of(db, ids[k], &tr, ev, sizeof ev);
        size_t l = strlen(tr.video_path);
        assert_string_equal(tr.video_path + l - 4, transcoded[k] ? ".mkv" : ".avi");
        assert_int_equal(exists(v[k]), !transcoded[k]);
    }
}

static gate g2 = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, 0, 0};

static void *open_gate_later(void *arg)
{
    gate *x = arg;
    struct timespec ts = {0, 100000000};
    nanosleep(&ts, NULL);
    pthread_mutex_lock(&x->m);
    x->open = 1;
    pthread_cond_broadcast(&x->c);
    pthread_mutex_unlock(&x->m);
    return NULL;
}

/* A daemon stopping mid-transcode: the transcode stops at its next frame, the raw video stays the
 * trial's with an event that is not a failure, and the next start queues it again. */
static void test_stop_mid_transcode_then_next_start(void **s)
{
    (void)s;
    char db[128], raw[128], why[512] = "";
    snprintf(db, sizeof db, "%s/stop.db", dir);
    snprintf(raw, sizeof raw, "%s/stop-1.avi", dir);
    write_raw(raw, NF);
    int64_t id = ended_trial(db, raw, STORE_STATUS_DONE, NULL);
    trial_transcoder_params tp = trial_transcoder_params_default();
    tp.store_path = db;
    tp.codec.on_frame = hold_at_frame_3;
    tp.codec.on_frame_user = &g2;
    trial_transcoder *t = trial_transcoder_start(&tp, why, sizeof why);
    assert_non_null(t);
    assert_int_equal(trial_transcoder_submit(t, id, raw, NULL, NULL, why, sizeof why), 0);
    pthread_mutex_lock(&g2.m);
    while (!g2.held) pthread_cond_wait(&g2.c, &g2.m);
    pthread_mutex_unlock(&g2.m);
    pthread_t opener;
    assert_int_equal(pthread_create(&opener, NULL, open_gate_later, &g2), 0);
    trial_transcoder_stop(t); /* cancels, then waits for the frame in progress */
    pthread_join(opener, NULL);
    char ev[4096];
    store_trial tr;
    trial_video_of(db, id, &tr, ev, sizeof ev);
    printf("# %s", ev);
    assert_string_equal(tr.video_path, raw);
    assert_true(exists(raw));
    assert_non_null(strstr(ev, "video transcode stopped (the daemon is stopping)"));
    assert_null(strstr(ev, "video transcode failed"));
    char part[140];
    snprintf(part, sizeof part, "%s/stop-1.mkv.part", dir);
    assert_false(exists(part));
    /* the next start */
    tp.codec.on_frame = NULL;
    t = trial_transcoder_start(&tp, why, sizeof why);
    assert_non_null(t);
    store *st = NULL;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    assert_int_equal(trial_transcoder_queue_left(t, st, why, sizeof why), 1);
    store_close(st);
    assert_int_equal(trial_transcoder_wait_idle(t, 60.0), 0);
    trial_transcoder_stop(t);
    trial_video_of(db, id, &tr, ev, sizeof ev);
    assert_non_null(strstr(tr.video_path, "stop-1.mkv"));
    assert_false(exists(raw));
}

/* camera.transcode_keep = tracker: the worker keeps the crop, and the trial's record names the
 * kept region (in the full frame) with the new file, so a replay places the clamps. */
static void test_worker_crop_moves_the_record_region(void **s)
{
    (void)s;
    char db[128], raw[128], mkv[128], why[512] = "";
    snprintf(db, sizeof db, "%s/crop.db", dir);
    snprintf(raw, sizeof raw, "%s/crop-1.avi", dir);
    snprintf(mkv, sizeof mkv, "%s/crop-1.mkv", dir);
    write_raw(raw, 6);
    store *st = NULL;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_RIG;
    d.calibration_json = "{\"fps\":60,\"roi\":[10,20,160,120]}";
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &d, &id, why, sizeof why), STORE_OK);
    store_close(st);
    trial_transcoder_params tp = trial_transcoder_params_default();
    tp.store_path = db;
    trial_transcoder *t = trial_transcoder_start(&tp, why, sizeof why);
    assert_non_null(t);
    const int crop[4] = {13, 21, 100, 80}, rec[4] = {23, 41, 100, 80};
    assert_int_equal(trial_transcoder_submit(t, id, raw, crop, rec, why, sizeof why), 0);
    assert_int_equal(trial_transcoder_wait_idle(t, 60.0), 0);
    trial_transcoder_stop(t);
    check_frames(mkv, 13, 21, 100, 80, 6);
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    char *cfg = NULL, *cal = NULL;
    assert_int_equal(store_trial_texts(st, id, &cfg, &cal, why, sizeof why), STORE_OK);
    printf("# record after the cropped transcode: %s\n", cal);
    assert_non_null(strstr(cal, "\"roi\":[23,41,100,80]"));
    assert_non_null(strstr(cal, "\"fps\":60"));
    free(cfg);
    free(cal);
    store_trial tr;
    assert_int_equal(store_trial_get(st, id, &tr, why, sizeof why), STORE_OK);
    assert_string_equal(tr.video_path, mkv);
    store_close(st);
}

int main(void)
{
    if (!mkdtemp(dir)) return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lossless_bit_for_bit_then_raw_removed),
        cmocka_unit_test(test_changed_frame_fails_verify_and_keeps_raw),
        cmocka_unit_test(test_crop_keeps_exactly_the_region),
        cmocka_unit_test(test_stopped_transcode_keeps_raw),
        cmocka_unit_test(test_worker_next_trial_records_while_transcode_runs),
        cmocka_unit_test(test_start_up_queues_what_an_earlier_run_left),
        cmocka_unit_test(test_worker_crop_moves_the_record_region),
        cmocka_unit_test(test_stop_mid_transcode_then_next_start),
    };
    int failed = cmocka_run_group_tests(tests, NULL, NULL);
    test_dir_done(dir, failed == 0, "transcode");
    return failed ? 1 : 0;
}
