/* test_ribbond_e2e: the daemon end to end in mock mode (config/mock.ini: mock rails on a virtual
 * clock, the simulator as the ribbon, synthetic frames measured by the real tracker).
 *   1. A trial started through the HTTP API runs to done; a second start while it runs gets 409;
 *      the measured snap Delta W is within 2% of the prediction made at the same resolution and
 *      the regimes agree; samples, events, the video and the prediction are stored; the calibrated
 *      prediction (the trial's strip fitted to its own frames) is closer to the measurement than
 *      the scene's prediction and inside its own 2-sigma band.
 *   2. Replaying that trial (its video and recorded rail positions) reproduces its measured snap
 *      within one frame's Delta W; so does its video, rails CSV and camera calibration replayed as
 *      an outside recording by ribbond in replay mode (on the replay thread; an abort ends it).
 *      Through the API the trial's samples CSV is the store's export text, and GET /phase.png
 *      answers at once while the predicted map is computed (cancelled by the daemon's close); a
 *      replay in replay mode publishes on the live bus what the page follows.
 *   3. API error cases: unknown trial 404, bad fields 400 (naming the key), abort when idle 409.
 *   4. kill -9 in the middle of a trial, then a restart: integrity_check ok, the trial is marked
 *      interrupted, and the committed samples are all there (contiguous sequence numbers).
 *   5. Long computations before the rails move (issue 17, defects 4 and 5): a start whose
 *      prediction is estimated beyond the bound is refused (400, with the estimate); an abort
 *      while the resolution ladder computes ends the trial aborted within a few seconds; a daemon
 *      killed during the ladder leaves a trial that the restart marks interrupted.
 *   6. The specimen in the prediction (issue 31): a prediction that fails (its ladder's first rung
 *      refuses the specimen's creases) is stored as failed with the reason while the trial runs
 *      to done; the record says what the prediction used and where from; creases that cannot be
 *      simulated at all refuse the start, named. A specimen of unequal creases at unequal
 *      positions (not mirror images) predicts on its own creases and the trial runs to done. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <signal.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>

#include "api.h"
#include "rig_daemon.h"
#include "store.h"
#include "trial.h"
#include "twin.h"
#include "vision.h"

static char dir[64];
static char set_store[256], set_video[256];

static void overrides(const char **ov, int *n)
{
    ov[0] = set_store;
    ov[1] = set_video;
    ov[2] = "api.port=0";
    ov[3] = "sim.nodes=61"; /* the prediction's resolution; the twin has its own (mock.ini [twin]) */
    /* The twin at the rehearsal's resolution, still finer than the prediction's: 2.5 times cheaper
     * than mock.ini's N = 121, dt = 1 ms, which counts under the sanitizers (a trial 112 s there). */
    ov[4] = "twin.mesh.nodes=91";
    ov[5] = "twin.solver.dt=1.5e-3";
    *n = 6;
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/ribbond-e2e-XXXXXX");
    assert_non_null(mkdtemp(dir));
    snprintf(set_store, sizeof set_store, "store.path=%s/trials.db", dir);
    snprintf(set_video, sizeof set_video, "camera.video_dir=%s/videos", dir);
    gsl_set_error_handler_off();
    char why[256];
    assert_int_equal(api_client_global_init(why, sizeof why), 0);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    api_client_global_cleanup();
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static int http(unsigned port, const char *method, const char *path, const char *body_text, json_t **out,
                char *why, size_t why_len)
{
    char url[64];
    snprintf(url, sizeof url, "http://127.0.0.1:%u", port);
    api_client_config c = api_client_config_default();
    c.base_url = url;
    json_t *body = NULL;
    if (body_text) {
        json_error_t je;
        body = json_loads(body_text, 0, &je);
        assert_non_null(body);
    }
    int status = 0;
    unsigned char *bytes = NULL;
    size_t len = 0;
    int rc = api_client_request(&c, method, path, body, &status, out, &bytes, &len, why, why_len);
    json_decref(body);
    free(bytes);
    assert_int_equal(rc, 0);
    return status;
}

static void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* GET path over a plain loopback socket (the reply's headers are wanted): the whole reply,
 * malloc'ed and NUL-terminated, its length in *len. */
static char *raw_get(unsigned port, const char *path, size_t *len)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct timeval tv = {.tv_sec = 60};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    assert_int_equal(connect(fd, (struct sockaddr *)&a, sizeof a), 0);
    char req[256];
    int n = snprintf(req, sizeof req, "GET %s HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n", path);
    assert_int_equal(send(fd, req, (size_t)n, MSG_NOSIGNAL), n);
    size_t cap = 1 << 16, got = 0;
    char *b = malloc(cap);
    assert_non_null(b);
    for (;;) {
        if (got + 1 == cap) {
            b = realloc(b, cap *= 2);
            assert_non_null(b);
        }
        ssize_t r = recv(fd, b + got, cap - 1 - got, 0);
        if (r <= 0) break;
        got += (size_t)r;
    }
    close(fd);
    b[got] = '\0';
    *len = got;
    return b;
}

/* The X-Phase-Map header's value of a reply, into v. */
static void phase_map_header(const char *reply, char *v, size_t n)
{
    const char *h = strstr(reply, "\r\nX-Phase-Map: ");
    assert_non_null(h);
    h += strlen("\r\nX-Phase-Map: ");
    size_t k = strcspn(h, "\r");
    snprintf(v, n, "%.*s", (int)k, h);
}

/* GET /phase.png: a PNG at once (the trials alone while the predicted map is computed, some
 * 10 s of a core in the Release build, minutes under the sanitizers), the map's state in
 * X-Phase-Map; closing the daemon right after cancels the computation (rig_daemon_close returns).
 * The finished map is checked on the page by test_live_page (heavy). */
static void phase_png_route(unsigned port)
{
    size_t len0 = 0;
    char *r0 = raw_get(port, "/phase.png", &len0);
    char state[200];
    phase_map_header(r0, state, sizeof state);
    printf("phase.png: first reply %zu bytes, map %s\n", len0, state);
    assert_non_null(strstr(r0, "\r\nContent-Type: image/png\r\n"));
    assert_true(strstr(r0, "\r\n\r\n\x89PNG") != NULL);
    assert_true(strncmp(state, "computing", 9) == 0);
    free(r0);
}

/* Polls GET /status until the daemon is idle; returns 1 when it became idle in time. */
static int wait_idle(unsigned port, double max_s)
{
    char why[256];
    for (double t = 0; t < max_s; t += 0.1) {
        json_t *s = NULL;
        assert_int_equal(http(port, "GET", "/status", NULL, &s, why, sizeof why), 200);
        int running = !strcmp(json_string_value(json_object_get(s, "state")), "running");
        json_decref(s);
        if (!running) return 1;
        sleep_s(0.1);
    }
    return 0;
}

/* What the replay `nid` published on the live bus (the page follows it so): its trial message
 * (mode replay), the state replaying, then shearing, one sample per stored sample, the result,
 * the state done and the stored message, in that order. */
static void replay_published(rig_daemon *d, json_int_t nid, json_int_t samples)
{
    uint64_t cursor = live_bus_first(d->bus), seq = 0, missed = 0;
    char buf[1100];
    long n_samples = 0, order = 0;
    int saw_trial = 0, saw_replaying = 0, saw_shearing = 0, saw_result = 0, saw_done = 0, saw_stored = 0;
    int len;
    while ((len = live_bus_read(d->bus, &cursor, buf, sizeof buf, 0, &seq, &missed)) > 0) {
        json_error_t je;
        json_t *m = json_loads(buf, 0, &je);
        if (!m) fail_msg("bus message is not JSON: %s (%s)", buf, je.text);
        const char *type = json_string_value(json_object_get(m, "type"));
        assert_non_null(type);
        if (json_integer_value(json_object_get(m, "trial")) == nid) {
            const char *st = json_string_value(json_object_get(m, "state"));
            order++;
            if (!strcmp(type, "trial")) {
                assert_string_equal(json_string_value(json_object_get(m, "mode")), "replay");
                saw_trial = (int)order;
            } else if (!strcmp(type, "state") && !strcmp(st, "replaying")) {
                saw_replaying = (int)order;
            } else if (!strcmp(type, "state") && !strcmp(st, "shearing")) {
                saw_shearing = (int)order;
            } else if (!strcmp(type, "sample")) {
                n_samples++;
            } else if (!strcmp(type, "result")) {
                assert_string_equal(json_string_value(json_object_get(m, "final")), "done");
                saw_result = (int)order;
            } else if (!strcmp(type, "state") && !strcmp(st, "done")) {
                saw_done = (int)order;
            } else if (!strcmp(type, "stored")) {
                saw_stored = (int)order;
            }
        }
        json_decref(m);
    }
    printf("replay on the live bus: %ld samples (%lld stored), %llu missed; order trial %d, replaying %d, shearing "
           "%d, result %d, done %d, stored %d\n",
           n_samples, (long long)samples, (unsigned long long)missed, saw_trial, saw_replaying, saw_shearing,
           saw_result, saw_done, saw_stored);
    assert_int_equal(missed, 0);
    assert_int_equal(n_samples, samples);
    assert_true(saw_trial == 1 && saw_replaying > saw_trial && saw_shearing > saw_replaying);
    assert_true(saw_result > saw_shearing && saw_done > saw_result && saw_stored > saw_done);
}

/* The stored trial `id` written out as an outside recording would come: its video, a rails CSV
 * (t_s,compress_mm,shear_mm), a camera calibration file in the video's pixels and a replay rig
 * file naming them; ribbond in replay mode replays it on its replay thread (answering the API
 * meanwhile) to the same snap within one frame, and an abort right after a start ends aborted. */
static void replay_outside_recording(store *st, int64_t id, double meas, double frame_dw)
{
    char why[512];
    store_trial src;
    assert_int_equal(store_trial_get(st, id, &src, why, sizeof why), STORE_OK);
    char *config = NULL, *calib = NULL;
    assert_int_equal(store_trial_texts(st, id, &config, &calib, why, sizeof why), STORE_OK);
    trial_record rec;
    assert_int_equal(trial_record_parse(calib, &rec, why, sizeof why), 0);
    assert_non_null(strstr(calib, "\"fold_hinge_stiffness\":\"rigid\"")); /* the crease model it ran */
    free(config);
    free(calib);
    store_sample *smp = NULL;
    size_t ns = 0;
    assert_int_equal(store_samples_get(st, id, &smp, &ns, why, sizeof why), STORE_OK);
    char rails[128], cam[128], ini[128];
    snprintf(rails, sizeof rails, "%s/rails.csv", dir);
    snprintf(cam, sizeof cam, "%s/camera.calib", dir);
    snprintf(ini, sizeof ini, "%s/replay-files.ini", dir);
    FILE *f = fopen(rails, "w");
    assert_non_null(f);
    fprintf(f, "t_s,compress_mm,shear_mm\n");
    double t0 = NAN;
    for (size_t k = 0; k < ns; k++) {
        if (smp[k].kind != STORE_SAMPLE_FRAME) continue;
        if (smp[k].frame == 0) t0 = smp[k].t_s;
        fprintf(f, "%.9f,%.9f,%.9f\n", smp[k].t_s, smp[k].compress_mm, smp[k].shear_mm);
    }
    fclose(f);
    free(smp);
    assert_true(isfinite(t0));
    vis_calib cal; /* in the video's (cropped) pixels */
    trial_record_video_calib(&rec, &cal);
    vis_error ve;
    assert_int_equal(vis_calib_save(&cal, cam, &ve), VIS_OK);
    f = fopen(ini, "w");
    assert_non_null(f);
    fprintf(f,
            "[rig]\nmode = replay\nscene = %s/config/scenes/mock-gamma013.ini\n"
            "[calibration]\ncompress_zero_mm = %.9g\nshear_zero_mm = %.9g\ncompress_sign = %d\nshear_sign = %d\n"
            "camera_side = front\ncamera_time_offset_s = %.9f\n"
            "[camera]\ncalibration = %s\n"
            "[replay]\nvideo = %s\nrails = %s\n"
            "[detect]\ndz_jump = %.9g\nmin_quality = %.9g\n"
            "[store]\npath = %s/trials.db\n[api]\nport = 0\n",
            RIBBON_SOURCE_DIR, rec.calib.compress_zero_mm, rec.calib.shear_zero_mm, rec.calib.compress_sign,
            rec.calib.shear_sign, t0, cam, src.video_path, rails, rec.snap.dz_jump, rec.min_quality, dir);
    fclose(f);

    rig_daemon d;
    assert_int_equal(rig_daemon_open(&d, ini, NULL, 0, NULL, why, sizeof why), 0);
    unsigned port = 0;
    assert_int_equal(rig_daemon_serve(&d, &port, why, sizeof why), 0);
    json_t *t = NULL;
    int code = http(port, "POST", "/trials", "{\"note\": \"outside files\"}", &t, why, sizeof why);
    if (code != 201) fprintf(stderr, "replay of files: %d %s\n", code, why);
    assert_int_equal(code, 201);
    json_int_t nid = json_integer_value(json_object_get(t, "id"));
    json_decref(t);
    assert_true(wait_idle(port, 600));
    char path[64];
    snprintf(path, sizeof path, "/trials/%lld", (long long)nid);
    t = NULL;
    assert_int_equal(http(port, "GET", path, NULL, &t, why, sizeof why), 200);
    const char *status = json_string_value(json_object_get(t, "status"));
    double got = json_number_value(json_object_get(t, "snap_dw_measured"));
    printf("replay of files: trial %lld %s at %.5f (source %.5f)\n", (long long)nid, status, got, meas);
    assert_string_equal(status, "done");
    assert_true(fabs(got - meas) <= frame_dw + 1e-9);
    assert_true(json_is_null(json_object_get(t, "source_trial"))); /* outside files: no source trial */
    json_int_t frames = json_integer_value(json_object_get(t, "samples"));
    json_decref(t);
    replay_published(&d, nid, frames);

    /* An abort right after the start: the replay thread stops, the trial ends aborted. */
    t = NULL;
    assert_int_equal(http(port, "POST", "/trials", NULL, &t, why, sizeof why), 201);
    nid = json_integer_value(json_object_get(t, "id"));
    json_decref(t);
    t = NULL;
    assert_int_equal(http(port, "POST", "/trials/current/abort", NULL, &t, why, sizeof why), 200);
    json_decref(t);
    assert_true(wait_idle(port, 60));
    snprintf(path, sizeof path, "/trials/%lld", (long long)nid);
    t = NULL;
    assert_int_equal(http(port, "GET", path, NULL, &t, why, sizeof why), 200);
    assert_string_equal(json_string_value(json_object_get(t, "status")), "aborted");
    json_decref(t);
    rig_daemon_close(&d, "test done");
}

/* Issue 17: a replay of another video (item 12) is refused up front; a replay of the trial's own
 * video cut short (defects 2 and 7: a full disk, a kill) fails saying so, and stores no result as
 * if the video were whole. */
static void replay_refuses_wrong_or_cut_video(store *st, int64_t id, const char *dir)
{
    char why[512], other[600], cut[600];
    store_trial src;
    assert_int_equal(store_trial_get(st, id, &src, why, sizeof why), STORE_OK);
    /* Another video: 64 x 48 frames. */
    snprintf(other, sizeof other, "%s/other.mkv", dir);
    vis_error ve;
    vis_video_writer *w = vis_video_writer_open(other, 64, 48, 1, 30.0, &ve);
    assert_non_null(w);
    vis_frame *f = vis_frame_alloc(64, 48, 1, &ve);
    for (int i = 0; i < 10; i++) assert_int_equal(vis_video_writer_write(w, f, &ve), VIS_OK);
    vis_frame_free(f);
    vis_video_writer_close(w);
    trial_replay *rep = NULL;
    assert_int_not_equal(trial_replay_prepare(st, NULL, id, other, &rep, why, sizeof why), 0);
    printf("replay of another video: %s\n", why);
    assert_non_null(strstr(why, "not this trial's video"));
    /* The trial's own video, its second half cut off. */
    snprintf(cut, sizeof cut, "%s/cut.mkv", dir);
    FILE *in = fopen(src.video_path, "rb"), *out = fopen(cut, "wb");
    assert_true(in && out);
    fseek(in, 0, SEEK_END);
    long n = ftell(in);
    fseek(in, 0, SEEK_SET);
    char *buf = malloc((size_t)n);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, in), (size_t)n);
    assert_int_equal(fwrite(buf, 1, (size_t)(n / 2), out), (size_t)(n / 2));
    free(buf);
    fclose(in);
    fclose(out);
    int64_t rid = 0;
    trial_result r;
    int rc = trial_replay_prepare(st, NULL, id, cut, &rep, why, sizeof why);
    if (rc == 0) {
        rc = trial_replay_run(rep, st, NULL, NULL, NULL, &rid, &r, why, sizeof why);
        trial_replay_free(rep);
    }
    printf("replay of the cut video: %s\n", why);
    assert_int_not_equal(rc, 0);
    assert_true(strstr(why, "damaged") || strstr(why, "incomplete"));
    if (rid > 0) {
        store_trial t;
        assert_int_equal(store_trial_get(st, rid, &t, why, sizeof why), STORE_OK);
        assert_int_not_equal(t.status, STORE_STATUS_DONE);
        assert_int_equal(t.snapped, -1); /* no result stored */
    }
}

/* No frame of trial `id` is measured with the compress rail away from the trial's compression
 * (Delta L 0.5), where the calibration's clamp points are (more than 0.5 mm: the runner's bound is
 * half a pixel, 0.2 mm here), except in the last 0.05 of Delta L before it, where a mock trial
 * tracks the compression with the clamp point moved to where the rail puts it
 * (trial_comp_track.h: from Delta L = max(0.5 c, c - 0.05)); the earlier compression's frames are
 * there, stored untracked. */
static long none_measured_off_compression(store *st, int64_t id)
{
    char why[256];
    store_sample *smp = NULL;
    size_t n = 0;
    assert_int_equal(store_samples_get(st, id, &smp, &n, why, sizeof why), STORE_OK);
    const double tol_dl = 0.5 / 200.0; /* half a pixel at 1 px/mm or more (the mock's is 2.49), l 200 mm */
    long away = 0, untracked = 0;
    for (size_t k = 0; k < n; k++) {
        if (smp[k].kind != STORE_SAMPLE_FRAME) continue;
        if (isfinite(smp[k].dz) && fabs(smp[k].dl - 0.5) > tol_dl) {
            away++;
            assert_true(smp[k].dl > 0.45 - tol_dl && smp[k].dl < 0.5 + tol_dl); /* the moved-clamp window only */
        }
        if (!isfinite(smp[k].dz) && !strcmp(smp[k].reason, "clamp not found")) untracked++;
    }
    free(smp);
    printf("trial %lld: %ld frames measured off the compression (all within its last 0.05 of Delta L), %ld stored "
           "untracked as clamp not found\n", (long long)id, away, untracked);
    assert_true(untracked > 0);
    return away;
}

/* Issue 32 A/B: a replay of a mock trial tracks the compression window the trial tracked (its last
 * 0.05 of Delta L, trial_comp_track.h), from the recorded video (cropped to the trial's region) and
 * each frame's recorded compression rail position: every frame the source measured there is
 * measured in the replay, its Delta Z within REPLAY_COMP_DZ_TOL of the source's. Before, the
 * replay stored them untracked (clamp not found). */
#define REPLAY_COMP_DZ_TOL 1e-5 /* measured 7.6e-7: the same pixels, cropped losslessly */

static void replay_tracks_compression_window(store *st, int64_t id, int64_t rid)
{
    char why[256];
    store_sample *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    assert_int_equal(store_samples_get(st, id, &a, &na, why, sizeof why), STORE_OK);
    assert_int_equal(store_samples_get(st, rid, &b, &nb, why, sizeof why), STORE_OK);
    const double tol_dl = 0.5 / 200.0;
    long n = 0, same = 0;
    double worst = 0.0, lo = INFINITY, hi = -INFINITY;
    size_t j = 0;
    for (size_t k = 0; k < na; k++) {
        if (a[k].kind != STORE_SAMPLE_FRAME || !isfinite(a[k].dz) || !(a[k].dl < 0.5 - tol_dl)) continue;
        n++;
        while (j < nb && !(b[j].kind == STORE_SAMPLE_FRAME && b[j].frame >= a[k].frame)) j++;
        if (j >= nb || b[j].frame != a[k].frame || !isfinite(b[j].dz)) continue;
        same++;
        worst = fmax(worst, fabs(b[j].dz - a[k].dz));
        lo = fmin(lo, b[j].dl);
        hi = fmax(hi, b[j].dl);
    }
    free(a);
    free(b);
    printf("replay %lld of trial %lld: %ld of the source's %ld compression frames measured again, at Delta L %.4f to "
           "%.4f, |Delta Z - source's| at most %.2g\n", (long long)rid, (long long)id, same, n, lo, hi, worst);
    assert_true(n > 0);
    assert_int_equal(same, n);
    assert_true(worst <= REPLAY_COMP_DZ_TOL);
}

/* The measurement's own error against the twin's truth (docs/trials.md "The twin and its truth"):
 * the camera's onset is the last FRAME whose frame-to-frame Delta Z speed was below a tenth of
 * snap.speed, the twin's the last solver STEP; with the speed rising through the threshold the two
 * differ by less than one frame period of shear (rate / fps: 0.00167 of Delta W at 30 fps) plus one
 * twin step (1 ms: 0.00005); the tracker's noise on Delta Z (sigma 1e-5 during the hold, a speed
 * noise of 4e-4 /s against the 0.1 /s threshold) adds nothing measurable. */
static double onset_error_bound(double fps, double twin_dt)
{
    const double rate = 0.01 / 0.2; /* Delta W per second: 10 mm/s on the 200 mm strip */
    return rate / fps + rate * twin_dt + 1e-9;
}

/* The twin's own snap from the trial's "twin truth" event, and its parameters ("twin: ...").
 * Fails the test when absent. */
static void twin_truth_of(const json_t *t, double *dw, char *regime, size_t regime_len, char *params, size_t plen)
{
    json_t *evs = json_object_get(t, "events");
    int found = 0;
    params[0] = '\0';
    for (size_t k = 0; k < json_array_size(evs); k++) {
        const char *m = json_string_value(json_object_get(json_array_get(evs, k), "message"));
        if (m && !strncmp(m, TWIN_PARAMS_PREFIX, strlen(TWIN_PARAMS_PREFIX))) snprintf(params, plen, "%s", m);
        if (m && twin_truth_parse(m, dw, regime, regime_len)) {
            printf("%s\n", m);
            found = 1;
        }
    }
    assert_true(found);
}

/* The prediction against the twin's truth: the twin is a different strip (mock.ini [twin]:
 * creases relaxed to 86 deg and 2.5% unequal, N = 121, dt = 1 ms, against the scene's 90 deg,
 * equal creases, N = 61; the tests run the twin at N = 91, dt = 1.5 ms), so the prediction is off
 * by more than the measurement's error, by a few
 * percent (issue 31: 4 deg of relaxation and a few percent of inequality move the snap by 5-10%). */
static void score_prediction(double pred, double truth, double bound)
{
    printf("prediction - twin truth: %+.5f (%+.2f%%; the measurement's error bound %.5f)\n", pred - truth,
           100.0 * (pred - truth) / truth, bound);
    assert_true(fabs(pred - truth) > 3.0 * bound);
    assert_true(fabs(pred - truth) < 0.10 * truth);
}

/* The calibrated prediction (issue 32 B and D, docs/calibration.md "In every trial"): mock.ini's
 * twin (creases -87.1 and -84.9 deg, compliant hinges of 5e-3 N m/rad, N = 91 here) is another
 * strip than the scene's (-90 deg, equal, rigid; N = 61), and the fit (mock.ini's sim.fit_hinge:
 * both angles and the creases as hinges from the guess 3.5e-3 N m/rad, each with a prior) learns it
 * from the trial's own compression, hold and shear before the snap. It must be stored with a band,
 * closer to the measurement than the scene's prediction and inside its own 2-sigma band. Measured
 * (one run each, loaded 2-core machine): 0.40709 +- 0.02621 against the measured 0.39708 (+2.52%,
 * 0.38 sigma; the scene +6.36%). Before sim.fit_hinge the rigid fit ended at_bound (-70 deg). */
static void score_calibrated(const json_t *t, double meas, double pred, double truth)
{
    json_t *c = json_object_get(t, "snap_dw_calibrated"), *sd = json_object_get(t, "snap_sd_calibrated");
    const char *fail = json_string_value(json_object_get(t, "fit_failure"));
    if (!json_is_number(c) || !json_is_number(sd))
        fail_msg("no calibrated prediction with a band: %s", fail ? fail : "(nothing stored)");
    double cal = json_number_value(c), s = json_number_value(sd);
    printf("calibrated %.5f +- %.5f %s: - measured %+.5f (%+.2f%%, %.2f of the 2-sigma band), - twin truth %+.5f; "
           "scene's - measured %+.5f (%+.2f%%); |calibrated error| / |scene's| %.2f\n",
           cal, s, json_string_value(json_object_get(t, "regime_calibrated")), cal - meas, 100.0 * (cal - meas) / meas,
           fabs(cal - meas) / (2.0 * s), cal - truth, pred - meas, 100.0 * (pred - meas) / meas,
           fabs(cal - meas) / fabs(pred - meas));
    assert_null(fail);
    assert_true(s > 0.0);
    assert_true(fabs(cal - meas) < fabs(pred - meas));
    assert_true(fabs(cal - meas) <= 2.0 * s);
}

static void mock_trial_then_replay(void **state)
{
    (void)state;
    const char *ov[10];
    int nov;
    overrides(ov, &nov);
    ov[nov++] = "detect.torque_witness=on"; /* the twin's shear force as the second witness */
    rig_daemon d;
    char why[512] = "";
    int rc = rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why);
    if (rc) fprintf(stderr, "open: %s\n", why);
    assert_int_equal(rc, 0);
    unsigned port = 0;
    assert_int_equal(rig_daemon_serve(&d, &port, why, sizeof why), 0);

    json_t *t = NULL;
    assert_int_equal(http(port, "POST", "/trials", "{\"note\": \"e2e\"}", &t, why, sizeof why), 201);
    json_int_t id = json_integer_value(json_object_get(t, "id"));
    assert_true(id >= 1);
    json_decref(t);
    /* A second start while it runs. */
    t = NULL;
    assert_int_equal(http(port, "POST", "/trials", NULL, &t, why, sizeof why), 409);
    json_decref(t);
    /* Follow it. */
    int running = 1;
    for (int k = 0; k < 2400 && running; k++) {
        json_t *s = NULL;
        assert_int_equal(http(port, "GET", "/status", NULL, &s, why, sizeof why), 200);
        running = !strcmp(json_string_value(json_object_get(s, "state")), "running");
        json_decref(s);
        if (running) sleep_s(0.25);
    }
    assert_false(running);
    char path[64];
    snprintf(path, sizeof path, "/trials/%lld", (long long)id);
    t = NULL;
    assert_int_equal(http(port, "GET", path, NULL, &t, why, sizeof why), 200);
    const char *status = json_string_value(json_object_get(t, "status"));
    double meas = json_number_value(json_object_get(t, "snap_dw_measured"));
    double pred = json_number_value(json_object_get(t, "snap_dw_predicted"));
    const char *rm = json_string_value(json_object_get(t, "regime_measured"));
    const char *rp = json_string_value(json_object_get(t, "regime_predicted"));
    json_int_t samples = json_integer_value(json_object_get(t, "samples"));
    json_t *pr = json_object_get(t, "prediction");
    printf("trial %lld %s: measured %.5f %s, predicted %.5f %s (N = %lld), difference %.2f%%, %lld samples\n",
           (long long)id, status, meas, rm ? rm : "-", pred, rp ? rp : "-",
           (long long)json_integer_value(json_object_get(pr, "nodes")), 100.0 * (meas - pred) / pred,
           (long long)samples);
    assert_string_equal(status, "done");
    assert_non_null(rm);
    assert_non_null(rp);
    /* Scored against the twin's truth (its own snap), not against the prediction. */
    double truth = NAN;
    char treg[16] = "", tparams[512];
    twin_truth_of(t, &truth, treg, sizeof treg, tparams, sizeof tparams);
    assert_non_null(strstr(tparams, "N = 91, dt = 0.0015 s; [twin] folds.angle_deg=-86"));
    double bound = onset_error_bound(30.0, 1.5e-3);
    printf("measured - twin truth: %+.5f (%.2f frames; bound %.5f)\n", meas - truth, (meas - truth) / (0.05 / 30.0),
           bound);
    assert_true(fabs(meas - truth) <= bound);
    assert_string_equal(treg, "asymmetric"); /* Gamma 0.13: the pitchfork first */
    assert_string_equal(rm, treg);
    assert_string_equal(rp, treg);
    score_prediction(pred, truth, bound);
    score_calibrated(t, meas, pred, truth);
    assert_int_equal(json_integer_value(json_object_get(pr, "nodes")), 61);
    assert_true(samples > 100);
    assert_true(json_array_size(json_object_get(t, "events")) >= 7);
    /* The load witness (the twin's shear force on the mock shear rail) saw the snap too, within a
     * few frames of the camera's onset: 0.01 / 30 / 0.2 of Delta W per frame. */
    {
        double v_dw = NAN, l_dw = NAN;
        json_t *evs = json_object_get(t, "events");
        for (size_t k = 0; k < json_array_size(evs); k++) {
            const char *m = json_string_value(json_object_get(json_array_get(evs, k), "message"));
            const char *b = m ? strstr(m, "vision at Delta W = ") : NULL;
            if (b && strstr(m, "both witnesses"))
                sscanf(b, "vision at Delta W = %lf%*[^=]= %lf", &v_dw, &l_dw);
        }
        printf("witnesses: vision at Delta W = %.5f, load at %.5f (%.1f frames apart)\n", v_dw, l_dw,
               (l_dw - v_dw) / (0.01 / 30.0 / 0.2));
        assert_true(isfinite(v_dw) && isfinite(l_dw));
        assert_true(fabs(v_dw - meas) < 1e-5);
        assert_true(fabs(l_dw - v_dw) <= 3.0 * 0.01 / 30.0 / 0.2 + 1e-9);
    }
    const char *video = json_string_value(json_object_get(t, "video_path"));
    assert_non_null(video);
    struct stat sb;
    assert_int_equal(stat(video, &sb), 0);
    assert_true(sb.st_size > 10000);
    json_decref(t);

    /* Report through the API: PNG bytes. */
    {
        char url[64];
        snprintf(url, sizeof url, "http://127.0.0.1:%u", port);
        api_client_config c = api_client_config_default();
        c.base_url = url;
        int st = 0;
        unsigned char *png = NULL;
        size_t len = 0;
        snprintf(path, sizeof path, "/trials/%lld/report.png", (long long)id);
        assert_int_equal(api_client_request(&c, "GET", path, NULL, &st, NULL, &png, &len, why, sizeof why), 0);
        assert_int_equal(st, 200);
        assert_true(len > 1000 && !memcmp(png, "\x89PNG", 4));
        free(png);
    }

    /* The samples CSV through the API: the text the store's export writes (`ribbonctl export ID
     * --csv` calls the same writer), one row per stored sample; an unknown trial is a 404. */
    {
        char url[64];
        snprintf(url, sizeof url, "http://127.0.0.1:%u", port);
        api_client_config c = api_client_config_default();
        c.base_url = url;
        int st = 0;
        unsigned char *csv = NULL;
        size_t len = 0;
        snprintf(path, sizeof path, "/trials/%lld/samples.csv", (long long)id);
        assert_int_equal(api_client_request(&c, "GET", path, NULL, &st, NULL, &csv, &len, why, sizeof why), 0);
        assert_int_equal(st, 200);
        store *own = NULL;
        char db[128];
        snprintf(db, sizeof db, "%s/trials.db", dir);
        assert_int_equal(store_open(db, &own, why, sizeof why), STORE_OK);
        char *want = NULL;
        size_t want_len = 0;
        assert_int_equal(store_export_trial_csv_text(own, id, &want, &want_len, why, sizeof why), STORE_OK);
        store_close(own);
        long rows = -1; /* the header is not a row */
        for (size_t k = 0; k < len; k++) rows += csv[k] == '\n';
        printf("samples.csv: %zu bytes, %ld rows (%lld samples)\n", len, rows, (long long)samples);
        assert_int_equal(len, want_len);
        assert_memory_equal(csv, want, len);
        assert_true(len > 60 && !memcmp(csv, "seq,t_s,kind,frame,compress_mm,shear_mm,dl,dw,dz,a,quality,reason\n", 60));
        assert_int_equal(rows, samples);
        free(want);
        free(csv);
        csv = NULL;
        assert_int_equal(api_client_request(&c, "GET", "/trials/999/samples.csv", NULL, &st, NULL, &csv, &len, why,
                                            sizeof why), 0);
        assert_int_equal(st, 404);
        assert_non_null(strstr(why, "999"));
        free(csv);
    }

    phase_png_route(port);
    double close_t0 = mono_s();

    /* API errors. */
    t = NULL;
    assert_int_equal(http(port, "GET", "/trials/999", NULL, &t, why, sizeof why), 404);
    json_decref(t);
    t = NULL;
    assert_int_equal(http(port, "POST", "/trials", "{\"bogus\": 1}", &t, why, sizeof why), 400);
    assert_non_null(strstr(why, "bogus"));
    json_decref(t);
    t = NULL;
    assert_int_equal(http(port, "POST", "/trials", "{\"set\": [\"protocol.compression=abc\"]}", &t, why, sizeof why),
                     400);
    assert_non_null(strstr(why, "protocol.compression"));
    json_decref(t);
    t = NULL;
    assert_int_equal(http(port, "POST", "/trials/current/abort", NULL, &t, why, sizeof why), 409);
    json_decref(t);

    /* Replay: the same video and rail positions through the pipeline again. */
    rig_daemon_close(&d, "test done");
    printf("rig_daemon_close with the phase map computing: %.2f s after the request\n", mono_s() - close_t0);
    assert_true(mono_s() - close_t0 < 30); /* the map was cancelled, not finished (30 points) */
    store *st = NULL;
    char db[128];
    snprintf(db, sizeof db, "%s/trials.db", dir);
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    int64_t rid = 0;
    trial_result r;
    trial_replay *rep = NULL;
    rc = trial_replay_prepare(st, NULL, id, NULL, &rep, why, sizeof why);
    if (rc == 0) rc = trial_replay_run(rep, st, NULL, NULL, NULL, &rid, &r, why, sizeof why);
    trial_replay_free(rep);
    if (rc) fprintf(stderr, "replay: %s\n", why);
    assert_int_equal(rc, 0);
    double frame_dw = 0.01 / 30.0 / 0.2; /* shear rate / fps / l */
    printf("replay trial %lld: %s at %.5f (source %.5f, one frame is %.5f)\n", (long long)rid, r.regime, r.snap_dw,
           meas, frame_dw);
    assert_true(r.snapped);
    assert_true(fabs(r.snap_dw - meas) <= frame_dw + 1e-9);
    store_trial rt;
    assert_int_equal(store_trial_get(st, rid, &rt, why, sizeof why), STORE_OK);
    assert_int_equal(rt.source_trial_id, id);
    assert_int_equal(rt.mode, STORE_MODE_REPLAY);
    none_measured_off_compression(st, id);
    none_measured_off_compression(st, rid);
    replay_tracks_compression_window(st, id, rid);
    replay_outside_recording(st, id, meas, frame_dw);
    replay_refuses_wrong_or_cut_video(st, id, dir);
    store_close(st);
}

/* Gamma 0.21 end to end: the symmetric case (saddle-node first) with the twin's unequal creases.
 * The twin's truth must read symmetric, the prediction (equal creases) too, and the measured snap
 * lies within the measurement's error of the twin's. Mounted at 100 mm (Delta L 0.25): at Gamma
 * 0.21 the route to the upper state does not converge at the shipped 90 mm (Delta L 0.2). */
/* The measured regime: the tracker measures the camera's projected A, which peaks near 0.13 rad
 * here (the twin's own camera's A 0.126) while the twin's 3D A peaks at 0.043 rad; under the old
 * fixed 0.05 rad rule this read "asymmetric". The pathway rule (sim/rod_regime.h, 0.5 rad, derived
 * from symmetric snaps peaking at <= 0.38 and asymmetric ones at >= 0.72) reads it symmetric. */
#define GAMMA021_MEASURED_REGIME "symmetric"

static void mock_trial_gamma021(void **state)
{
    (void)state;
    const char *ov[12];
    int nov;
    overrides(ov, &nov);
    ov[nov++] = "folds.position=0.21";
    ov[nov++] = "rail.compress.start_mm=100";
    rig_daemon d;
    char why[512] = "";
    int rc = rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why);
    if (rc) fprintf(stderr, "open: %s\n", why);
    assert_int_equal(rc, 0);
    unsigned port = 0;
    assert_int_equal(rig_daemon_serve(&d, &port, why, sizeof why), 0);
    json_t *t = NULL;
    assert_int_equal(http(port, "POST", "/trials", "{\"note\": \"e2e gamma 0.21\"}", &t, why, sizeof why), 201);
    json_int_t id = json_integer_value(json_object_get(t, "id"));
    json_decref(t);
    assert_int_equal(wait_idle(port, 600.0), 1);
    char path[64];
    snprintf(path, sizeof path, "/trials/%lld", (long long)id);
    t = NULL;
    assert_int_equal(http(port, "GET", path, NULL, &t, why, sizeof why), 200);
    const char *status = json_string_value(json_object_get(t, "status"));
    double meas = json_number_value(json_object_get(t, "snap_dw_measured"));
    double pred = json_number_value(json_object_get(t, "snap_dw_predicted"));
    const char *rm = json_string_value(json_object_get(t, "regime_measured"));
    const char *rp = json_string_value(json_object_get(t, "regime_predicted"));
    printf("Gamma 0.21 trial %lld %s: measured %.5f %s, predicted %.5f %s\n", (long long)id, status ? status : "-",
           meas, rm ? rm : "-", pred, rp ? rp : "-");
    assert_non_null(status);
    assert_string_equal(status, "done");
    double truth = NAN;
    char treg[16] = "", tparams[512];
    twin_truth_of(t, &truth, treg, sizeof treg, tparams, sizeof tparams);
    double bound = onset_error_bound(30.0, 1.5e-3);
    printf("measured - twin truth: %+.5f (%.2f frames; bound %.5f)\n", meas - truth, (meas - truth) / (0.05 / 30.0),
           bound);
    assert_true(fabs(meas - truth) <= bound);
    assert_string_equal(treg, "symmetric"); /* Gamma 0.21: the saddle-node first */
    assert_non_null(rp);
    assert_string_equal(rp, "symmetric");
    assert_non_null(rm);
    assert_string_equal(rm, GAMMA021_MEASURED_REGIME);
    score_prediction(pred, truth, bound);
    json_decref(t);
    rig_daemon_close(&d, "test done");
}

static void kill9_then_restart(void **state)
{
    (void)state;
    /* A store of its own, so the trial watched is the one killed. */
    char db[128];
    snprintf(db, sizeof db, "%s/killed.db", dir);
    snprintf(set_store, sizeof set_store, "store.path=%s", db);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        const char *ov[8];
        int nov;
        overrides(ov, &nov);
        rig_daemon d;
        char why[512];
        if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why)) _exit(3);
        trial_session *s;
        int64_t id;
        if (trial_session_start(&d.cfg, d.compress, d.shear, "to be killed", NULL, NULL, &s, &id, why, sizeof why)) _exit(4);
        for (;;) pause();
    }
    /* Wait until the trial is well under way, then kill it without warning. */
    int64_t trial = 0, seen = 0;
    for (int k = 0; k < 1200 && seen < 300; k++) {
        sleep_s(0.1);
        sqlite3 *h = NULL;
        if (sqlite3_open_v2(db, &h, SQLITE_OPEN_READONLY, NULL) != SQLITE_OK) {
            sqlite3_close(h);
            continue;
        }
        sqlite3_busy_timeout(h, 1000);
        sqlite3_stmt *q = NULL;
        if (sqlite3_prepare_v2(h, "SELECT trial_id, count(*) FROM samples GROUP BY trial_id ORDER BY trial_id DESC LIMIT 1",
                               -1, &q, NULL) == SQLITE_OK &&
            sqlite3_step(q) == SQLITE_ROW) {
            trial = sqlite3_column_int64(q, 0);
            seen = sqlite3_column_int64(q, 1);
        }
        sqlite3_finalize(q);
        sqlite3_close(h);
    }
    kill(pid, SIGKILL);
    int ws;
    waitpid(pid, &ws, 0);
    assert_true(WIFSIGNALED(ws));
    assert_true(seen >= 300);

    /* Restart: the daemon marks it interrupted and never moves. */
    const char *ov[8];
    int nov;
    overrides(ov, &nov);
    rig_daemon d;
    char why[512];
    assert_int_equal(rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why), 0);
    store_trial tr;
    assert_int_equal(store_trial_get(d.st, trial, &tr, why, sizeof why), STORE_OK);
    assert_int_equal(tr.status, STORE_STATUS_INTERRUPTED);
    sqlite3 *h = store_handle(d.st);
    sqlite3_stmt *q = NULL;
    assert_int_equal(sqlite3_prepare_v2(h, "PRAGMA integrity_check", -1, &q, NULL), SQLITE_OK);
    assert_int_equal(sqlite3_step(q), SQLITE_ROW);
    assert_string_equal((const char *)sqlite3_column_text(q, 0), "ok");
    sqlite3_finalize(q);
    assert_int_equal(sqlite3_prepare_v2(h, "SELECT count(*), min(seq), max(seq) FROM samples WHERE trial_id = ?", -1, &q,
                                        NULL),
                     SQLITE_OK);
    sqlite3_bind_int64(q, 1, trial);
    assert_int_equal(sqlite3_step(q), SQLITE_ROW);
    int64_t n = sqlite3_column_int64(q, 0), lo = sqlite3_column_int64(q, 1), hi = sqlite3_column_int64(q, 2);
    sqlite3_finalize(q);
    printf("killed trial %lld: %lld samples seen before the kill, %lld stored (seq %lld..%lld), status %s\n",
           (long long)trial, (long long)seen, (long long)n, (long long)lo, (long long)hi, store_status_name(tr.status));
    assert_true(n >= seen);
    assert_int_equal(lo, 0);
    assert_int_equal(hi, n - 1);
    rig_daemon_close(&d, "test done");
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Overrides for a trial whose ladder is slow (fixed steps at 0.5 ms: tens of seconds uncancelled,
 * estimated well inside the bound), on a store of its own. */
static void slow_ladder_overrides(const char *db, char *set_db, size_t len, const char **ov, int *n)
{
    snprintf(set_db, len, "store.path=%s", db);
    ov[0] = set_db;
    ov[1] = set_video;
    ov[2] = "api.port=0";
    ov[3] = "sim.fast=off";
    ov[4] = "solver.dt=5e-4";
    *n = 5;
}

static void long_computations_cancel(void **state)
{
    (void)state;
    char db[128], set_db[200], why[512] = "";
    snprintf(db, sizeof db, "%s/ladder.db", dir);
    const char *ov[8];
    int nov;
    slow_ladder_overrides(db, set_db, sizeof set_db, ov, &nov);
    rig_daemon d;
    int rc = rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why);
    if (rc) fprintf(stderr, "open: %s\n", why);
    assert_int_equal(rc, 0);
    unsigned port = 0;
    assert_int_equal(rig_daemon_serve(&d, &port, why, sizeof why), 0);

    /* Refused up front, with the estimate; nothing recorded. */
    json_t *t = NULL;
    assert_int_equal(http(port, "POST", "/trials", "{\"set\": [\"solver.dt=1e-6\"]}", &t, why, sizeof why), 400);
    printf("refused: %s\n", why);
    assert_non_null(strstr(why, "would take about"));
    json_decref(t);

    /* An abort while the ladder computes. */
    t = NULL;
    assert_int_equal(http(port, "POST", "/trials", "{\"note\": \"abort in the ladder\"}", &t, why, sizeof why), 201);
    json_int_t id = json_integer_value(json_object_get(t, "id"));
    json_decref(t);
    sleep_s(0.5);
    t = NULL;
    double t0 = now_s();
    assert_int_equal(http(port, "POST", "/trials/current/abort", NULL, &t, why, sizeof why), 200);
    json_decref(t);
    int idle = wait_idle(port, 30.0);
    double took = now_s() - t0;
    printf("abort during the ladder: idle after %.2f s\n", took);
    assert_true(idle);
    assert_true(took < 5.0); /* uncancelled, this ladder takes tens of seconds */
    store_trial tr;
    assert_int_equal(store_trial_get(d.st, id, &tr, why, sizeof why), STORE_OK);
    assert_int_equal(tr.status, STORE_STATUS_ABORTED);
    rig_daemon_close(&d, "test done");
}

static void kill9_during_ladder(void **state)
{
    (void)state;
    char db[128], set_db[200];
    snprintf(db, sizeof db, "%s/killed-ladder.db", dir);
    const char *ov[8];
    int nov;
    slow_ladder_overrides(db, set_db, sizeof set_db, ov, &nov);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        rig_daemon d;
        char why[512];
        if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why)) _exit(3);
        trial_session *s;
        int64_t id;
        if (trial_session_start(&d.cfg, d.compress, d.shear, "to be killed", NULL, NULL, &s, &id, why, sizeof why)) _exit(4);
        for (;;) pause();
    }
    /* Wait for the trial row, then kill while the ladder computes. */
    int have = 0;
    for (int k = 0; k < 300 && !have; k++) {
        sleep_s(0.1);
        sqlite3 *h = NULL;
        if (sqlite3_open_v2(db, &h, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK) {
            sqlite3_busy_timeout(h, 1000);
            sqlite3_stmt *q = NULL;
            if (sqlite3_prepare_v2(h, "SELECT count(*) FROM trials WHERE status = 'created'", -1, &q, NULL) ==
                    SQLITE_OK &&
                sqlite3_step(q) == SQLITE_ROW)
                have = sqlite3_column_int(q, 0) > 0;
            sqlite3_finalize(q);
        }
        sqlite3_close(h);
    }
    sleep_s(0.3);
    kill(pid, SIGKILL);
    int ws;
    waitpid(pid, &ws, 0);
    assert_true(have);
    rig_daemon d;
    char why[512];
    assert_int_equal(rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, nov, NULL, why, sizeof why), 0);
    store_trial *list = NULL;
    size_t n = 0;
    assert_int_equal(store_trial_list(d.st, &list, &n, why, sizeof why), STORE_OK);
    assert_int_equal(n, 1);
    printf("trial killed during the ladder: %s (%s)\n", store_status_name(list[0].status), list[0].reason);
    assert_int_equal(list[0].status, STORE_STATUS_INTERRUPTED);
    free(list);
    rig_daemon_close(&d, "test done");
}

/* The stdout of `ribbonctl ARGS` (RIBBON_BIN_DIR), malloc'ed; the exit status in *rc. */
static char *ribbonctl_out(const char *args, int *rc)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "%s/ribbonctl %s 2>&1", RIBBON_BIN_DIR, args);
    FILE *f = popen(cmd, "r");
    assert_non_null(f);
    size_t cap = 1 << 16, n = 0;
    char *b = malloc(cap);
    assert_non_null(b);
    size_t got;
    while ((got = fread(b + n, 1, cap - 1 - n, f)) > 0) n += got;
    b[n] = '\0';
    *rc = pclose(f);
    return b;
}

/* The first prediction message of trial `id` on bus b, as JSON (a new reference), or NULL. */
static json_t *bus_prediction(live_bus *b, json_int_t id)
{
    uint64_t cursor = live_bus_first(b), seq = 0, missed = 0;
    char buf[1100];
    int len;
    json_t *found = NULL;
    while (!found && (len = live_bus_read(b, &cursor, buf, sizeof buf, 0, &seq, &missed)) > 0) {
        json_t *m = json_loads(buf, 0, NULL);
        if (m && !strcmp(json_string_value(json_object_get(m, "type")), "prediction") &&
            json_integer_value(json_object_get(m, "trial")) == id)
            found = json_incref(m);
        json_decref(m);
    }
    return found;
}

/* Issue 31: the specimen in the prediction, and a prediction that fails does not stop the trial.
 * The specimen's creases at 0.03 and 0.97 (each on its own crease key) lie in
 * the clamp of the ladder's first rung (N = 31: one edge is 1/28 of l) but not at the scene's
 * N = 61: the ladder fails, the prediction is stored as failed with that reason, and the trial
 * (the twin is the scene, Gamma 0.13) runs to done with its measured snap. The record says which
 * crease values the prediction used and where each came from, and the creases' age; ribbonctl
 * show and list say the prediction failed. Creases in the clamp at N = 61 already are bad input:
 * the start is refused naming the specimen key, nothing recorded. */
static void prediction_fails_trial_runs(void **state)
{
    (void)state;
    char db[128], set_db[200], why[512] = "";
    snprintf(db, sizeof db, "%s/specimen.db", dir);
    snprintf(set_db, sizeof set_db, "store.path=%s", db);
    /* sim.fit_hinge=0: the fit beside the trial is not this test's; with the scene's rigid creases
     * it ends at once (at_bound) instead of a three-parameter fit the trial's end waits for. */
    const char *ov[] = {set_db, set_video, "api.port=0", "specimen.crease_angle_left_deg=88",
                        "specimen.folded_at=2020-01-01T00:00Z", "sim.fit_hinge=0"};
    rig_daemon d;
    int rc = rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, 6, NULL, why, sizeof why);
    if (rc) fprintf(stderr, "open: %s\n", why);
    assert_int_equal(rc, 0);
    unsigned port = 0;
    assert_int_equal(rig_daemon_serve(&d, &port, why, sizeof why), 0);

    /* Bad input: refused, named, nothing recorded. */
    json_t *t = NULL;
    assert_int_equal(http(port, "POST", "/trials",
                          "{\"set\": [\"specimen.crease_position_left=0.01\", \"specimen.crease_position_right=0.99\"]}",
                          &t, why, sizeof why),
                     400);
    printf("refused: %s\n", why);
    assert_non_null(strstr(why, "specimen.crease_position_left"));
    assert_non_null(strstr(why, "inside the clamp"));
    json_decref(t);
    store_trial *list = NULL;
    size_t n = 0;
    assert_int_equal(store_trial_list(d.st, &list, &n, why, sizeof why), STORE_OK);
    free(list);
    assert_int_equal(n, 0);

    t = NULL;
    assert_int_equal(http(port, "POST", "/trials",
                          "{\"set\": [\"specimen.crease_position_left=0.03\", \"specimen.crease_position_right=0.97\"],"
                          " \"note\": \"prediction fails\"}",
                          &t, why, sizeof why),
                     201);
    json_int_t id = json_integer_value(json_object_get(t, "id"));
    json_decref(t);
    assert_true(wait_idle(port, 600));
    char path[64];
    snprintf(path, sizeof path, "/trials/%lld", (long long)id);
    t = NULL;
    assert_int_equal(http(port, "GET", path, NULL, &t, why, sizeof why), 200);
    const char *status = json_string_value(json_object_get(t, "status"));
    double meas = json_number_value(json_object_get(t, "snap_dw_measured"));
    json_t *pr = json_object_get(t, "prediction"), *cr = json_object_get(pr, "creases");
    const char *failure = json_string_value(json_object_get(pr, "failure"));
    printf("trial %lld %s: measured %.5f %s; prediction %s: %s\n", (long long)id, status, meas,
           json_string_value(json_object_get(t, "regime_measured")),
           json_string_value(json_object_get(pr, "status")), failure ? failure : "-");
    assert_string_equal(status, "done");
    assert_true(json_is_true(json_object_get(t, "snapped")) && meas > 0.3 && meas < 0.6);
    assert_string_equal(json_string_value(json_object_get(pr, "status")), "failed");
    assert_non_null(failure);
    assert_non_null(strstr(failure, "ladder rung N = 31"));
    assert_non_null(strstr(failure, "inside the clamp"));
    assert_true(json_is_null(json_object_get(t, "snap_dw_predicted")));
    /* What it was to use: the left angle measured (88 deg, down), the right the scene's; the
     * symmetric positions the specimen's. */
    assert_true(json_number_value(json_object_get(cr, "angle_left_deg")) == -88.0);
    assert_string_equal(json_string_value(json_object_get(cr, "angle_left_from")), "specimen");
    assert_string_equal(json_string_value(json_object_get(cr, "angle_right_from")), "scene");
    assert_true(json_number_value(json_object_get(cr, "position_left")) == 0.03);
    assert_string_equal(json_string_value(json_object_get(cr, "position_left_from")), "specimen");
    assert_string_equal(json_string_value(json_object_get(cr, "hinge_stiffness")), "rigid");
    assert_true(json_number_value(json_object_get(t, "crease_age_s")) > 6.0 * 365.0 * 86400.0);
    int warned = 0;
    json_t *evs = json_object_get(t, "events");
    for (size_t k = 0; k < json_array_size(evs); k++) {
        json_t *e = json_array_get(evs, k);
        const char *m = json_string_value(json_object_get(e, "message"));
        if (m && !strncmp(m, "prediction failed: ", 19) &&
            !strcmp(json_string_value(json_object_get(e, "kind")), "warning"))
            warned = 1;
    }
    assert_true(warned);
    json_decref(t);
    /* The live page heard it: the prediction not ok, with the reason. */
    json_t *m = bus_prediction(d.bus, id);
    assert_non_null(m);
    assert_true(json_is_false(json_object_get(m, "ok")));
    assert_non_null(strstr(json_string_value(json_object_get(m, "why")), "ladder rung N = 31"));
    json_decref(m);
    rig_daemon_close(&d, "test done");

    /* A replay of the trial shows the page the source's prediction as failed, with its reason. */
    store *st = NULL;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    live_bus *bus = live_bus_create();
    assert_non_null(bus);
    trial_replay *rep = NULL;
    int64_t rid = 0;
    trial_result r;
    rc = trial_replay_prepare(st, NULL, id, NULL, &rep, why, sizeof why);
    if (rc == 0) {
        trial_replay_set_bus(rep, bus);
        rc = trial_replay_run(rep, st, NULL, NULL, NULL, &rid, &r, why, sizeof why);
    }
    trial_replay_free(rep);
    if (rc) fprintf(stderr, "replay: %s\n", why);
    assert_int_equal(rc, 0);
    m = bus_prediction(bus, rid);
    assert_non_null(m);
    printf("replay %lld: source prediction ok %s, why %s\n", (long long)rid,
           json_is_true(json_object_get(m, "ok")) ? "true" : "false", json_string_value(json_object_get(m, "why")));
    assert_true(json_is_false(json_object_get(m, "ok")));
    assert_non_null(strstr(json_string_value(json_object_get(m, "why")), "ladder rung N = 31"));
    json_decref(m);
    live_bus_free(bus);
    store_close(st);

    /* ribbonctl show and list say so (from the store file). */
    char args[300];
    snprintf(args, sizeof args, "show %lld --db %s", (long long)id, db);
    char *out = ribbonctl_out(args, &rc);
    printf("%s", out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "  predicted  failed: no prediction resolution: ladder rung N = 31"));
    assert_non_null(strstr(out, "prediction's creases: left -88 deg (specimen) at 0.03 (specimen)"));
    assert_non_null(strstr(out, "prediction's crease hinges: rigid"));
    assert_non_null(strstr(out, "creases folded"));
    free(out);
    snprintf(args, sizeof args, "list --db %s", db);
    out = ribbonctl_out(args, &rc);
    printf("%s", out);
    assert_int_equal(rc, 0);
    assert_non_null(strstr(out, "failed  "));
    free(out);
}

/* The specimen's unequal creases (88 and 91 deg) at unequal positions (0.12 and 0.86, not mirror
 * images) are the prediction's own: it runs at sim.nodes = 61 (a node on each crease), snaps, and
 * the record keeps each value from the specimen and the rigid hinge; the trial (its twin the
 * scene) runs to done. No warning: unequal positions are used, not set aside. */
static void specimen_unequal_predicts(void **state)
{
    (void)state;
    char db[128], set_db[200], why[512] = "";
    snprintf(db, sizeof db, "%s/unequal.db", dir);
    snprintf(set_db, sizeof set_db, "store.path=%s", db);
    /* (sim.specimen_fit=off: the refit after the trial is test_campaign_specimen_calib's; here it
     * would only add a fit's cost, 5-10x under the sanitizers) */
    const char *ov[] = {set_db, set_video, "api.port=0", "sim.nodes=61", "sim.fit_hinge=0", "sim.specimen_fit=off"};
    rig_daemon d;
    int rc = rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, 5, NULL, why, sizeof why);
    if (rc) fprintf(stderr, "open: %s\n", why);
    assert_int_equal(rc, 0);
    unsigned port = 0;
    assert_int_equal(rig_daemon_serve(&d, &port, why, sizeof why), 0);
    json_t *t = NULL;
    assert_int_equal(http(port, "POST", "/trials",
                          "{\"set\": [\"specimen.crease_angle_left_deg=88\", \"specimen.crease_angle_right_deg=91\","
                          " \"specimen.crease_position_left=0.12\", \"specimen.crease_position_right=0.86\"]}",
                          &t, why, sizeof why),
                     201);
    json_int_t id = json_integer_value(json_object_get(t, "id"));
    json_decref(t);
    assert_true(wait_idle(port, 600));
    char path[64];
    snprintf(path, sizeof path, "/trials/%lld", (long long)id);
    t = NULL;
    assert_int_equal(http(port, "GET", path, NULL, &t, why, sizeof why), 200);
    json_t *pr = json_object_get(t, "prediction"), *cr = json_object_get(pr, "creases");
    double meas = json_number_value(json_object_get(t, "snap_dw_measured"));
    double pred = json_number_value(json_object_get(t, "snap_dw_predicted"));
    const char *failure = json_string_value(json_object_get(pr, "failure"));
    printf("trial %lld %s: measured %.5f %s (twin: the scene); predicted %.5f %s (specimen: 88, 91 deg at 0.12, "
           "0.86)%s%s\n",
           (long long)id, json_string_value(json_object_get(t, "status")), meas,
           json_string_value(json_object_get(t, "regime_measured")), pred,
           json_string_value(json_object_get(t, "regime_predicted")), failure ? "; failed: " : "",
           failure ? failure : "");
    assert_string_equal(json_string_value(json_object_get(t, "status")), "done");
    assert_true(json_is_true(json_object_get(t, "snapped")) && meas > 0.3 && meas < 0.6);
    assert_string_equal(json_string_value(json_object_get(pr, "status")), "done");
    assert_true(json_is_number(json_object_get(t, "snap_dw_predicted")) && pred > 0.2 && pred < 0.6);
    assert_int_equal(json_integer_value(json_object_get(pr, "nodes")), 61);
    static const char *const keys[4] = {"angle_left_deg", "angle_right_deg", "position_left", "position_right"};
    static const double want[4] = {-88.0, -91.0, 0.12, 0.86};
    for (int k = 0; k < 4; k++) {
        char from[40];
        snprintf(from, sizeof from, "%.*s_from", (int)(strlen(keys[k]) - (k < 2 ? 4 : 0)), keys[k]);
        assert_true(json_number_value(json_object_get(cr, keys[k])) == want[k]);
        assert_string_equal(json_string_value(json_object_get(cr, from)), "specimen");
    }
    assert_string_equal(json_string_value(json_object_get(cr, "hinge_stiffness")), "rigid");
    json_t *evs = json_object_get(t, "events");
    for (size_t k = 0; k < json_array_size(evs); k++) {
        json_t *e = json_array_get(evs, k);
        const char *kind = json_string_value(json_object_get(e, "kind"));
        const char *msg = json_string_value(json_object_get(e, "message"));
        /* The fit beside the trial (issue 32 B) is not this test's: its outcome is printed (the
         * twin here is the rig's scene, not the specimen's creases the fit starts from). */
        if (msg && (!strncmp(msg, "calibration", 11) || !strncmp(msg, "no calibrated prediction", 24))) {
            printf("fit: %s: %s\n", kind ? kind : "-", msg);
            continue;
        }
        if (kind && (!strcmp(kind, "warning") || !strcmp(kind, "fault")))
            fprintf(stderr, "unexpected %s: %s\n", kind, json_string_value(json_object_get(e, "message")));
        assert_false(kind && (!strcmp(kind, "warning") || !strcmp(kind, "fault")));
    }
    json_decref(t);
    rig_daemon_close(&d, "test done");
}

/* `test_ribbond_e2e gamma021` runs only the Gamma 0.21 trial and `specimen` only the specimen's
 * unequal creases (each its own ctest, so the mock trials run side by side: under the sanitizers
 * the whole file took over 600 s at load 13 once the in-trial fit also fits the hinge); without an
 * argument, everything else. */
int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "gamma021")) {
        const struct CMUnitTest only[] = {cmocka_unit_test(mock_trial_gamma021)};
        return cmocka_run_group_tests(only, setup, teardown);
    }
    if (argc > 1 && !strcmp(argv[1], "specimen")) {
        const struct CMUnitTest only[] = {cmocka_unit_test(specimen_unequal_predicts)};
        return cmocka_run_group_tests(only, setup, teardown);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(mock_trial_then_replay),
        cmocka_unit_test(kill9_then_restart),
        cmocka_unit_test(long_computations_cancel),
        cmocka_unit_test(kill9_during_ladder),
        cmocka_unit_test(prediction_fails_trial_runs),
    };
    if (getenv("RIBBON_TEST_ONLY")) cmocka_set_test_filter(getenv("RIBBON_TEST_ONLY")); /* one case by name */
    return cmocka_run_group_tests(tests, setup, teardown);
}
