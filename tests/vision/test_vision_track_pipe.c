/* test_vision_track_pipe.c: tracking on several cores with the serial results (issue 14 part C).
 *
 * The tracker forgets its previous curve every refresh_frames frames (vis_track_params): frame K is
 * then measured exactly as a new tracker measures it alone, and not as following would (else the
 * refresh would not be one). Cut at those frames, a recording tracks on several cores with every
 * result bit for bit the serial loop's: vis_track_video on raw Y800 (each worker reads the file
 * itself) and on FFV1 (one decoder feeding vis_track_pipe), with 2, 3 and all cores, the tracker
 * left in the serial loop's state; vis_track_pipe taking over a serial loop mid-stretch, with
 * resets pushed anywhere, handing back each frame and its centreline; a full pipe, an empty one and one closed with frames in it; a Y800 file
 * cut inside a frame stops at the same frame with the same message as the serial loop. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vis_test_run.h"
#include "vis_test_video.h"

#define NF 23
#define K 5

static vt_shape shape;
static vis_frame *mem[NF];
static vis_render_params rp;
static vis_calib cal;

static vis_track_params params(int refresh)
{
    vis_track_params tp = vis_track_params_default();
    tp.length_mm = 200.0;
    tp.refresh_frames = refresh;
    return tp;
}

/* Frames of an arch whose asymmetry changes every frame, so that following matters. */
static int setup(void **state)
{
    (void)state;
    vt_arch(&shape, 301, 0.2, 0.16, 0.0, 0.0);
    rp = vt_render_params(&shape, 320, 240);
    cal = vt_calib(&rp, &shape);
    vis_renderer *r = vis_renderer_create(&rp, NULL);
    assert_non_null(r);
    for (int i = 0; i < NF; i++) {
        vt_arch(&shape, 301, 0.2, 0.16, 0.04 * i, 0.0);
        mem[i] = vis_frame_alloc(8, 8, 1, NULL);
        assert_int_equal(vis_renderer_draw(r, &shape.view, mem[i], NULL, NULL), VIS_OK);
    }
    vis_renderer_free(r);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    for (int i = 0; i < NF; i++)
        vis_frame_free(mem[i]);
    return 0;
}

/* The serial reference: one tracker over the frames, vis_tracker_reset where reset[i]. */
static void serial(int refresh, const unsigned char *reset, vis_measure *out, double *uv_last, size_t *n_last)
{
    vis_track_params tp = params(refresh);
    vis_tracker *t = vis_tracker_create(&tp, &cal, NULL);
    assert_non_null(t);
    for (int i = 0; i < NF; i++) {
        if (reset && reset[i])
            vis_tracker_reset(t);
        assert_int_equal(vis_tracker_process(t, mem[i], 0.01 * i, &out[i], NULL), VIS_OK);
        assert_int_equal(out[i].reason, VIS_REASON_NONE);
    }
    if (uv_last)
        *n_last = vis_tracker_curve(t, uv_last, 4096);
    vis_tracker_free(t);
}

static void test_refresh_is_a_fresh_start(void **state)
{
    (void)state;
    static vis_measure with[NF], without[NF];
    serial(K, NULL, with, NULL, NULL);
    serial(0, NULL, without, NULL, NULL);
    int differ = 0, followed = 0;
    for (int i = 0; i < NF; i++) {
        vis_track_params tp = params(K);
        vis_tracker *alone = vis_tracker_create(&tp, &cal, NULL);
        vis_measure m;
        assert_int_equal(vis_tracker_process(alone, mem[i], 0.01 * i, &m, NULL), VIS_OK);
        vis_tracker_free(alone);
        if (i % K == 0)
            assert_true(vt_same_measure(&with[i], &m)); /* a refresh frame: as a new tracker sees it */
        else
            followed += !vt_same_measure(&with[i], &m); /* in between, following is still used */
        if (i < K)
            assert_true(vt_same_measure(&with[i], &without[i])); /* the same start */
        else
            differ += !vt_same_measure(&with[i], &without[i]);
    }
    printf("refresh every %d frames: %d of %d later frames differ from never refreshing, %d followed frames "
           "differ from a new tracker's\n", K, differ, NF - K, followed);
    assert_true(followed > 0);
    assert_true(differ > 0);
    vis_track_params bad = params(-1);
    vis_error err;
    assert_null(vis_tracker_create(&bad, &cal, &err));
    assert_non_null(strstr(err.message, "refresh_frames"));
}

static void write_video(const char *path)
{
    assert_int_equal(vt_write_frames(path, mem, NF, 30.0), 0);
}

/* vis_track_video on 1 (the serial loop), 2, 3 and all cores; then the tracker goes on with the
 * next frame as the serial one does. */
static void check_video(const char *ext)
{
    char path[600];
    snprintf(path, sizeof path, "%s/pipe.%s", vt_tmpdir(), ext);
    write_video(path);
    double shear[NF];
    for (int i = 0; i < NF; i++)
        shear[i] = 0.01 * i;
    static vis_measure ref[NF], got[NF];
    serial(K, NULL, ref, NULL, NULL);
    const int threads[4] = {1, 2, 3, 0};
    static vis_measure next_ref[K + 2];
    for (int k = 0; k < 4; k++) {
        vis_track_params tp = params(K);
        vis_tracker *t = vis_tracker_create(&tp, &cal, NULL);
        vis_measure dummy;
        assert_int_equal(vis_tracker_process(t, mem[3], 0.0, &dummy, NULL), VIS_OK); /* reset at the start */
        size_t n = 0;
        vis_error err;
        assert_int_equal(vis_track_video(path, t, shear, NF, threads[k], got, NF, &n, &err), VIS_OK);
        assert_int_equal(n, NF);
        for (int i = 0; i < NF; i++)
            assert_true(vt_same_measure(&ref[i], &got[i]));
        /* The tracker goes on as the serial one does: K + 2 more frames (past its next refresh). */
        for (int j = 0; j < K + 2; j++) {
            vis_measure next;
            assert_int_equal(vis_tracker_process(t, mem[(7 + 3 * j) % NF], 0.2, &next, NULL), VIS_OK);
            if (k == 0)
                next_ref[j] = next;
            assert_true(vt_same_measure(&next, &next_ref[j]));
        }
        vis_tracker_free(t);
    }
    printf("%s: %d frames in stretches of %d, identical on 1, 2, 3 and all cores\n", ext, NF, K);
}

static void test_video_every_core(void **state)
{
    (void)state;
    check_video("avi");
    check_video("mkv");
}

static void test_pipe_resets_and_frames(void **state)
{
    (void)state;
    unsigned char reset[NF] = {0};
    reset[7] = reset[8] = reset[16] = 1;
    static vis_measure ref[NF];
    static double uv_ref[8192], uv[8192];
    size_t n_ref = 0, n_uv = 0;
    serial(K, reset, ref, uv_ref, &n_ref);
    vis_track_params tp = params(K);
    vis_tracker *t = vis_tracker_create(&tp, &cal, NULL);
    vis_error err;
    vis_measure m;
    /* The pipe takes over a serial loop three frames in (in the middle of a stretch). */
    enum { HANDOVER = 3 };
    for (int i = 0; i < HANDOVER; i++) {
        assert_int_equal(vis_tracker_process(t, mem[i], 0.01 * i, &m, NULL), VIS_OK);
        assert_true(vt_same_measure(&m, &ref[i]));
    }
    vis_track_pipe *p = vis_track_pipe_create(t, 2, &err);
    assert_non_null(p);
    assert_int_equal(vis_track_pipe_workers(p), 2);
    assert_true(vis_track_pipe_capacity(p) >= 16);
    assert_int_equal(vis_track_pipe_pop(p, 1, &m, NULL, 0, NULL, NULL, &err), VIS_ERR_END);
    vis_frame *in = vis_frame_alloc(8, 8, 1, NULL), *back = vis_frame_alloc(8, 8, 1, NULL);
    int popped = HANDOVER;
    for (int i = HANDOVER; i < NF; i++) {
        assert_int_equal(vis_frame_copy(mem[i], in, NULL), VIS_OK);
        assert_int_equal(vis_track_pipe_push(p, in, 0.01 * i, reset[i], &err), VIS_OK);
        for (;;) {
            const vis_status s = vis_track_pipe_pop(p, i == NF - 1 || i % 6 == 5, &m, uv, 4096, &n_uv, back, &err);
            if (s == VIS_ERR_NOT_FOUND || s == VIS_ERR_END)
                break;
            assert_int_equal(s, VIS_OK);
            assert_true(vt_same_measure(&m, &ref[popped]));
            /* the frame itself comes back */
            assert_int_equal(memcmp(vis_frame_data(back), vis_frame_data(mem[popped]),
                                    vis_frame_stride(back) * (size_t)vis_frame_height(back)), 0);
            popped++;
        }
    }
    while (vis_track_pipe_pop(p, 1, &m, uv, 4096, &n_uv, back, &err) == VIS_OK) {
        assert_true(vt_same_measure(&m, &ref[popped]));
        popped++;
    }
    assert_int_equal(popped, NF);
    assert_int_equal(n_uv, n_ref); /* the last frame's centreline, as the serial tracker has it */
    assert_int_equal(memcmp(uv, uv_ref, 2 * n_ref * sizeof *uv), 0);
    vis_track_pipe_free(p);
    /* The state came back: the caller's tracker has the serial loop's last curve. */
    static double uv_t[8192];
    assert_int_equal(vis_tracker_curve(t, uv_t, 4096), n_ref);
    assert_int_equal(memcmp(uv_t, uv_ref, 2 * n_ref * sizeof *uv), 0);

    /* Full, bad frames, closed with frames inside (no hang; the tracker is reset). */
    p = vis_track_pipe_create(t, 1, &err);
    assert_non_null(p);
    size_t pushed = 0;
    vis_status s;
    for (;;) {
        assert_int_equal(vis_frame_copy(mem[pushed % NF], in, NULL), VIS_OK);
        s = vis_track_pipe_push(p, in, 0.0, 0, &err);
        if (s != VIS_OK)
            break;
        pushed++;
    }
    assert_int_equal(s, VIS_ERR_ARG);
    assert_non_null(strstr(err.message, "full"));
    assert_int_equal(pushed, vis_track_pipe_capacity(p));
    assert_int_equal(vis_track_pipe_held(p), pushed);
    assert_int_equal(vis_track_pipe_push(p, in, 0.0 / 0.0, 0, &err), VIS_ERR_ARG);
    assert_int_equal(vis_track_pipe_push(p, NULL, 0.0, 0, &err), VIS_ERR_ARG);
    assert_int_equal(vis_track_pipe_pop(p, 1, &m, NULL, 0, NULL, NULL, &err), VIS_OK);
    vis_track_pipe_free(p);
    assert_int_equal(vis_tracker_curve(t, NULL, 0), 0);
    assert_null(vis_track_pipe_create(NULL, 1, &err));
    assert_null(vis_track_pipe_create(t, -1, &err));
    vis_frame_free(in);
    vis_frame_free(back);
    vis_tracker_free(t);
}

/* A Y800 file cut inside a frame: every core stops where the serial loop does, saying the same. */
static void test_cut_file(void **state)
{
    (void)state;
    char path[600], cut[600];
    snprintf(path, sizeof path, "%s/whole.avi", vt_tmpdir());
    snprintf(cut, sizeof cut, "%s/cut.avi", vt_tmpdir());
    write_video(path);
    assert_int_equal(vt_cut_copy(path, cut, 7, 10), 0);
    static vis_measure a[NF], b[NF];
    vis_track_params tp = params(K);
    vis_tracker *t = vis_tracker_create(&tp, &cal, NULL);
    size_t na = 0, nb = 0;
    vis_error ea, eb;
    const vis_status sa = vis_track_video(cut, t, NULL, 0, 1, a, NF, &na, &ea);
    const vis_status sb = vis_track_video(cut, t, NULL, 0, 2, b, NF, &nb, &eb); /* one reader each */
    printf("cut Y800: serial %zu frames then %s; all cores %zu frames then %s\n", na, ea.message, nb, eb.message);
    assert_int_equal(sa, VIS_ERR_FORMAT);
    assert_int_equal(sb, sa);
    assert_int_equal(nb, na);
    assert_true(na > (size_t)K && na < NF);
    assert_string_equal(ea.message, eb.message);
    for (size_t i = 0; i < na; i++)
        assert_true(vt_same_measure(&a[i], &b[i]));
    /* Fewer frames asked for than there are: the same first ones. */
    assert_int_equal(vis_track_video(path, t, NULL, 0, 0, b, 12, &nb, &eb), VIS_OK);
    assert_int_equal(nb, 12);
    for (size_t i = 0; i < 12; i++)
        assert_true(vt_same_measure(&a[i], &b[i]));
    vis_tracker_free(t);
}

/* The tracker's error on frame 12 (a shear that puts the clamp behind the camera) ends the run
 * there on every core, as in the serial loop: the 12 frames before it, the same message, and no
 * later frame's result handed out in its place (repeated: the workers run ahead by a varying
 * number of frames). */
static void test_tracker_error_mid_stream(void **state)
{
    (void)state;
    enum { BAD = 12 };
    double shear[NF];
    for (int i = 0; i < NF; i++)
        shear[i] = i == BAD ? -1e9 : 0.01 * i;
    const char *ext[2] = {"avi", "mkv"};
    for (int e = 0; e < 2; e++) {
        char path[600];
        snprintf(path, sizeof path, "%s/bad_shear.%s", vt_tmpdir(), ext[e]);
        write_video(path);
        static vis_measure a[NF], b[NF];
        vis_track_params tp = params(K);
        vis_tracker *t = vis_tracker_create(&tp, &cal, NULL);
        size_t na = 0, nb = 0;
        vis_error ea, eb;
        assert_int_equal(vis_track_video(path, t, shear, NF, 1, a, NF, &na, &ea), VIS_ERR_ARG);
        assert_int_equal(na, BAD);
        for (int rep = 0; rep < 6; rep++) {
            memset(b, 0, sizeof b);
            assert_int_equal(vis_track_video(path, t, shear, NF, rep % 2 ? 2 : 0, b, NF, &nb, &eb), VIS_ERR_ARG);
            assert_int_equal(nb, na);
            assert_string_equal(eb.message, ea.message);
            for (size_t i = 0; i < na; i++)
                assert_true(vt_same_measure(&a[i], &b[i]));
            assert_int_equal(vis_tracker_curve(t, NULL, 0), 0); /* reset after the failure */
        }
        printf("%s: the tracker's error on frame %d ends every run there: %s\n", ext[e], BAD, ea.message);
        vis_tracker_free(t);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_refresh_is_a_fresh_start),
        cmocka_unit_test(test_video_every_core),
        cmocka_unit_test(test_pipe_resets_and_frames),
        cmocka_unit_test(test_cut_file),
        cmocka_unit_test(test_tracker_error_mid_stream),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
