/* test_vision_track_video.c: vis_track_video, the whole-video engine (issue 14 part C).
 *
 * A rendered asymmetric sequence is written as FFV1 (.mkv) and as raw Y800 (.avi,
 * vis_video_writer_open_y800); the Y800 file
 * reads back bit-exact; tracking it with the engine on every core gives, frame by frame, exactly
 * what the serial loop (threads = 1) and a hand-written vis_source_read + vis_tracker_process
 * loop give, bit for bit; max_frames stops early; the prefetching source
 * (vis_source_open_video_prefetch) hands out the plain source's frames, times, count, rate and,
 * on a cut file, the same damage after the same frames, in FFV1 and in Y800 (read as its stored
 * packets: the cut frame's short packet is named); a missing file and bad arguments fail
 * with a reason. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "vis_test_run.h"
#include "vis_test_video.h"

#define NF 24

static vt_shape shape;

static void check_format(const char *ext, vis_frame **mem, const vis_calib *c,
                         const vis_track_params *tp)
{
    char path[600];
    snprintf(path, sizeof path, "%s/engine.%s", vt_tmpdir(), ext);
    assert_int_equal(vt_write_frames(path, mem, NF, 30.0), 0);
    vis_error err;
    /* Reference: the plain loop. */
    static vis_measure ref[NF], ser[NF], par[NF];
    vis_source *src = vis_source_open_video(path, &err);
    assert_non_null(src);
    vis_tracker *t = vis_tracker_create(tp, c, &err);
    vis_frame *f = vis_frame_alloc(8, 8, 1, &err);
    int measured = 0;
    for (int i = 0; i < NF; i++) {
        assert_int_equal(vis_source_read(src, f, NULL, &err), VIS_OK);
        assert_int_equal(memcmp(vis_frame_data(f), vis_frame_data(mem[i]),
                                vis_frame_stride(f) * (size_t)vis_frame_height(f)), 0); /* bit-exact */
        assert_int_equal(vis_tracker_process(t, f, 0.0, &ref[i], &err), VIS_OK);
        measured += ref[i].reason == VIS_REASON_NONE;
    }
    vis_source_close(src);
    vis_frame_free(f);
    vis_tracker_free(t);
    assert_int_equal(measured, NF);
    size_t n = 0;
    t = vis_tracker_create(tp, c, &err);
    assert_int_equal(vis_track_video(path, t, NULL, 0, 1, ser, NF, &n, &err), VIS_OK);
    assert_int_equal(n, NF);
    vis_tracker_free(t);
    t = vis_tracker_create(tp, c, &err);
    assert_int_equal(vis_track_video(path, t, NULL, 0, 0, par, NF, &n, &err), VIS_OK);
    assert_int_equal(n, NF);
    vis_tracker_free(t);
    for (int i = 0; i < NF; i++) {
        assert_true(vt_same_measure(&ref[i], &ser[i]));
        assert_true(vt_same_measure(&ref[i], &par[i]));
    }
    /* max_frames stops early; four threads on two cores are fine too. */
    t = vis_tracker_create(tp, c, &err);
    assert_int_equal(vis_track_video(path, t, NULL, 0, 4, par, 5, &n, &err), VIS_OK);
    assert_int_equal(n, 5);
    vis_tracker_free(t);
    printf("%s: %d frames, engine identical to the serial loop\n", ext, NF);
}

static void test_engine_identical(void **state)
{
    (void)state;
    vt_arch(&shape, 301, 0.2, 0.16, 0.0, 0.0);
    vis_render_params p = vt_render_params(&shape, 320, 240);
    vis_calib c = vt_calib(&p, &shape);
    vis_track_params tp = vis_track_params_default();
    tp.length_mm = 200.0;
    vis_renderer *r = vis_renderer_create(&p, NULL);
    assert_non_null(r);
    vis_frame *mem[NF];
    for (int i = 0; i < NF; i++) {
        vt_arch(&shape, 301, 0.2, 0.16, 0.05 * i, 0.0);
        mem[i] = vis_frame_alloc(8, 8, 1, NULL);
        assert_int_equal(vis_renderer_draw(r, &shape.view, mem[i], NULL, NULL), VIS_OK);
    }
    check_format("mkv", mem, &c, &tp);
    check_format("avi", mem, &c, &tp);
    for (int i = 0; i < NF; i++)
        vis_frame_free(mem[i]);
    vis_renderer_free(r);
}

/* The prefetching source hands out what the plain one does, damage included; in FFV1 and in raw
 * Y800 (read as its stored packets, see source_video.cpp), where a file cut inside a frame stops
 * at the frame before the cut with the damage named. */
static void check_prefetch(const char *ext)
{
    vt_arch(&shape, 301, 0.2, 0.16, 0.3, 0.0);
    vis_render_params p = vt_render_params(&shape, 320, 240);
    p.noise_sigma = 20; /* big FFV1 frames, so the cut falls inside the sequence */
    vis_renderer *r = vis_renderer_create(&p, NULL);
    vis_frame *mem[NF];
    for (int i = 0; i < NF; i++) {
        mem[i] = vis_frame_alloc(8, 8, 1, NULL);
        assert_int_equal(vis_renderer_draw(r, &shape.view, mem[i], NULL, NULL), VIS_OK);
    }
    char path[600], cut[600];
    snprintf(path, sizeof path, "%s/pf.%s", vt_tmpdir(), ext);
    snprintf(cut, sizeof cut, "%s/pf_cut.%s", vt_tmpdir(), ext);
    assert_int_equal(vt_write_frames(path, mem, NF, 30.0), 0);
    assert_int_equal(vt_cut_copy(path, cut, 6, 10), 0);
    const char *files[2] = {path, cut};
    for (int w = 0; w < 2; w++) {
        vis_error e1, e2;
        vis_source *a = vis_source_open_video(files[w], &e1), *b = vis_source_open_video_prefetch(files[w], &e2);
        assert_non_null(a);
        assert_non_null(b);
        assert_int_equal(vis_source_frame_count(a), vis_source_frame_count(b));
        assert_true(vis_source_fps(a) == vis_source_fps(b));
        vis_frame *fa = vis_frame_alloc(8, 8, 1, NULL), *fb = vis_frame_alloc(8, 8, 1, NULL);
        int n = 0;
        for (;; n++) {
            double ta = -1, tb = -2;
            const vis_status sa = vis_source_read(a, fa, &ta, &e1), sb = vis_source_read(b, fb, &tb, &e2);
            assert_int_equal(sa, sb);
            if (sa != VIS_OK) {
                assert_string_equal(e1.message, e2.message);
                printf("%s %s: %d frames, then %s: %s\n", ext, w ? "cut" : "whole", n, vis_status_str(sa),
                       e1.message);
                assert_int_equal(sa, w ? VIS_ERR_FORMAT : VIS_ERR_END);
                if (w)
                    assert_non_null(strstr(e1.message, "damaged"));
                if (w && strcmp(ext, "avi") == 0) /* read as packets: the short one is named */
                    assert_non_null(strstr(e1.message, "frame 14 holds"));
                break;
            }
            assert_true(ta == tb);
            assert_int_equal(memcmp(vis_frame_data(fa), vis_frame_data(fb),
                                    vis_frame_stride(fa) * (size_t)vis_frame_height(fa)), 0);
            if (strcmp(ext, "avi") == 0) /* lossless: the frame written */
                assert_int_equal(memcmp(vis_frame_data(fa), vis_frame_data(mem[n]),
                                        vis_frame_stride(fa) * (size_t)vis_frame_height(fa)), 0);
        }
        assert_int_equal(n > 0, 1);
        if (w == 0)
            assert_int_equal(n, NF);
        else
            assert_true(n < NF);
        vis_frame_free(fa);
        vis_frame_free(fb);
        vis_source_close(a);
        vis_source_close(b);
    }
    /* Closed early, with frames still queued: no hang, no leak. */
    vis_source *b = vis_source_open_video_prefetch(path, NULL);
    assert_non_null(b);
    vis_source_close(b);
    for (int i = 0; i < NF; i++)
        vis_frame_free(mem[i]);
    vis_renderer_free(r);
}

static void test_prefetch_same_as_plain(void **state)
{
    (void)state;
    check_prefetch("mkv");
    check_prefetch("avi");
}

static void test_engine_errors(void **state)
{
    (void)state;
    vt_arch(&shape, 301, 0.2, 0.16, 0.0, 0.0);
    vis_render_params p = vt_render_params(&shape, 320, 240);
    vis_calib c = vt_calib(&p, &shape);
    vis_track_params tp = vis_track_params_default();
    vis_tracker *t = vis_tracker_create(&tp, &c, NULL);
    vis_measure m[4];
    size_t n = 7;
    vis_error err;
    char path[600];
    snprintf(path, sizeof path, "%s/missing.mkv", vt_tmpdir());
    assert_int_not_equal(vis_track_video(path, t, NULL, 0, 0, m, 4, &n, &err), VIS_OK);
    assert_int_equal(n, 0);
    assert_true(strlen(err.message) > 0);
    assert_int_equal(vis_track_video(NULL, t, NULL, 0, 0, m, 4, &n, &err), VIS_ERR_ARG);
    assert_int_equal(vis_track_video(path, t, NULL, 0, -1, m, 4, &n, &err), VIS_ERR_ARG);
    /* The raw writer wants an .avi name. */
    snprintf(path, sizeof path, "%s/raw.mkv", vt_tmpdir());
    assert_null(vis_video_writer_open_y800(path, 64, 48, 30.0, &err));
    assert_int_equal(err.code, VIS_ERR_ARG);
    vis_tracker_free(t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_engine_identical),
        cmocka_unit_test(test_prefetch_same_as_plain),
        cmocka_unit_test(test_engine_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
