/* test_vision_track_robust.c: the tracker under bad frames, other looks, and bad arguments.
 *
 * Black, saturated, noise-only and missing frames are reported with a reason (never measured, never
 * a crash) and the tracker recovers on the next good frame; a light ribbon on a dark background,
 * uneven lighting and background clutter are still measured within the accuracy bar; an occluded
 * ribbon is reported as occluded; black, saturated, noise-only frames and frames without a ribbon
 * get their own named reason and quality zero (issue 14); clamp points outside the image are reported; the overlay draws the
 * tracked centreline; invalid arguments are
 * refused with VIS_ERR_ARG and a message at every entry point.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vis_test_run.h"

static vt_shape shape;

typedef struct scene {
    vis_render_params p;
    vis_calib c;
    vis_track_params tp;
    vis_render_truth truth;
    vis_frame *f;
} scene;

static void scene_make(scene *s, double phi)
{
    vt_arch(&shape, 301, 0.2, 0.16, phi, 0.0);
    s->p = vt_render_params(&shape, 320, 240);
    s->c = vt_calib(&s->p, &shape);
    s->tp = vis_track_params_default();
    s->tp.length_mm = 200.0;
    s->f = vis_frame_alloc(8, 8, 1, NULL);
    assert_non_null(s->f);
}

static void scene_draw(scene *s)
{
    vis_error err;
    vis_renderer *r = vis_renderer_create(&s->p, &err);
    assert_non_null(r);
    assert_int_equal(vis_renderer_draw(r, &shape.view, s->f, &s->truth, &err), VIS_OK);
    vis_renderer_free(r);
}

/* Track the scene's frame with a fresh tracker; returns the Delta Z error in pixels (or 1e9). */
static double scene_track(scene *s, vis_measure *m)
{
    vis_error err;
    vis_tracker *t = vis_tracker_create(&s->tp, &s->c, &err);
    assert_non_null(t);
    assert_int_equal(vis_tracker_process(t, s->f, 0.0, m, &err), VIS_OK);
    vis_tracker_free(t);
    if (m->reason != VIS_REASON_NONE)
        return 1e9;
    const vis_truth *g = &s->truth.truth;
    return fabs(m->dz * s->tp.length_mm * 1e-3 - g->dz_cam * g->length_m) * s->truth.px_per_m;
}

static void fill(vis_frame *f, int v)
{
    for (int y = 0; y < vis_frame_height(f); y++)
        memset(vis_frame_data(f) + y * vis_frame_stride(f), v, (size_t)vis_frame_width(f));
}

static void test_bad_frames_are_reported(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, 0.2);
    scene_draw(&s);
    vis_error err;
    vis_tracker *t = vis_tracker_create(&s.tp, &s.c, &err);
    assert_non_null(t);
    vis_measure m;
    vis_frame *bad = vis_frame_alloc(320, 240, 1, NULL);

    assert_int_equal(vis_tracker_process(t, s.f, 0.0, &m, &err), VIS_OK);
    assert_int_equal(m.reason, VIS_REASON_NONE);

    fill(bad, 0);
    assert_int_equal(vis_tracker_process(t, bad, 0.0, &m, &err), VIS_OK);
    assert_int_equal(m.reason, VIS_REASON_DARK);

    fill(bad, 255);
    assert_int_equal(vis_tracker_process(t, bad, 0.0, &m, &err), VIS_OK);
    assert_int_equal(m.reason, VIS_REASON_SATURATED);

    /* Corrupted: uniform noise over the whole frame, then over the lower half only. */
    unsigned x = 12345u;
    for (int y = 0; y < 240; y++)
        for (int i = 0; i < 320; i++) {
            x = x * 1103515245u + 12345u;
            vis_frame_data(bad)[y * vis_frame_stride(bad) + (size_t)i] = (uint8_t)(x >> 24);
        }
    assert_int_equal(vis_tracker_process(t, bad, 0.0, &m, &err), VIS_OK);
    printf("noise frame: %s\n", vis_reason_str(m.reason));
    assert_int_not_equal(m.reason, VIS_REASON_NONE);
    for (int y = 0; y < 120; y++)
        memcpy(vis_frame_data(bad) + y * vis_frame_stride(bad), vis_frame_data(s.f) + y * vis_frame_stride(s.f), 320);
    assert_int_equal(vis_tracker_process(t, bad, 0.0, &m, &err), VIS_OK);
    printf("half-corrupted frame: %s\n", vis_reason_str(m.reason));
    assert_int_not_equal(m.reason, VIS_REASON_NONE);

    /* Missing frame. */
    assert_int_equal(vis_tracker_process(t, NULL, 0.0, &m, &err), VIS_OK);
    assert_int_equal(m.reason, VIS_REASON_UNREADABLE);
    vis_tracker_skip(t, &m);
    assert_int_equal(m.reason, VIS_REASON_UNREADABLE);

    /* A frame of another size (clamps outside it) and then recovery on a good frame. */
    vis_frame *small = vis_frame_alloc(40, 30, 1, NULL);
    fill(small, 120);
    for (int y = 14; y < 17; y++)
        for (int i = 0; i < 40; i++)
            vis_frame_data(small)[(size_t)y * vis_frame_stride(small) + (size_t)i] = 10;
    assert_int_equal(vis_tracker_process(t, small, 0.0, &m, &err), VIS_OK);
    assert_int_equal(m.reason, VIS_REASON_CLAMP_NOT_FOUND);
    assert_int_equal(vis_tracker_process(t, s.f, 0.0, &m, &err), VIS_OK);
    assert_int_equal(m.reason, VIS_REASON_NONE);

    vis_frame_free(small);
    vis_frame_free(bad);
    vis_frame_free(s.f);
    vis_tracker_free(t);
}

/* Issue 14: every kind of bad frame gets its own named reason and quality zero, from a fresh
 * tracker and from one that was following the ribbon. */
static void test_bad_input_named_reasons(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, 0.2);
    scene_draw(&s);
    vis_frame *good = s.f;
    /* Jaws but no ribbon: the ribbon drawn in the backdrop's grey. */
    scene s2;
    scene_make(&s2, 0.2);
    s2.p.ribbon = s2.p.background;
    scene_draw(&s2);
    vis_frame *bad = vis_frame_alloc(320, 240, 1, NULL);
    vis_error err;
    for (int following = 0; following < 2; following++) {
        vis_tracker *t = vis_tracker_create(&s.tp, &s.c, &err);
        assert_non_null(t);
        vis_measure m;
        const struct {
            int kind;
            vis_reason want;
        } cases[] = {{0, VIS_REASON_DARK}, {1, VIS_REASON_SATURATED}, {2, VIS_REASON_NOISE},
                     {3, VIS_REASON_NOISE}, {4, VIS_REASON_NO_RIBBON}};
        for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
            if (following) {
                assert_int_equal(vis_tracker_process(t, good, 0.0, &m, &err), VIS_OK);
                assert_int_equal(m.reason, VIS_REASON_NONE);
            }
            unsigned x = 777u + (unsigned)c;
            for (int y = 0; y < 240; y++)
                for (int i = 0; i < 320; i++) {
                    uint8_t *px = vis_frame_data(bad) + y * vis_frame_stride(bad) + (size_t)i;
                    x = x * 1103515245u + 12345u;
                    const double u = (double)(x >> 8) / (1u << 24);
                    switch (cases[c].kind) {
                    case 0: *px = (uint8_t)(u < 0.5 ? 0 : 1); break;            /* black, a little noise */
                    case 1: *px = (uint8_t)(u < 0.5 ? 255 : 254); break;        /* saturated */
                    case 2: *px = (uint8_t)(x >> 24); break;                    /* uniform noise */
                    case 3: {                                                   /* Gaussian-ish, sigma 50 */
                        double g = 0;
                        for (int k = 0; k < 4; k++) {
                            x = x * 1103515245u + 12345u;
                            g += (double)(x >> 8) / (1u << 24) - 0.5;
                        }
                        const double v = 128 + 50 * g * 1.732;
                        *px = (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v);
                        break;
                    }
                    default: *px = vis_frame_data(s2.f)[y * vis_frame_stride(s2.f) + (size_t)i]; break;
                    }
                }
            assert_int_equal(vis_tracker_process(t, bad, 0.0, &m, &err), VIS_OK);
            printf("bad input %d (%s): %s, quality %.3f\n", cases[c].kind, following ? "following" : "fresh",
                   vis_reason_str(m.reason), m.quality);
            assert_int_equal(m.reason, cases[c].want);
            assert_true(m.quality == 0.0);
        }
        /* And the next good frame is measured again. */
        assert_int_equal(vis_tracker_process(t, good, 0.0, &m, &err), VIS_OK);
        assert_int_equal(m.reason, VIS_REASON_NONE);
        vis_tracker_free(t);
    }
    assert_string_equal(vis_reason_str(VIS_REASON_NOISE), "frame is noise");
    assert_string_equal(vis_reason_str(VIS_REASON_NO_RIBBON), "no ribbon in the frame");
    vis_frame_free(bad);
    vis_frame_free(s2.f);
    vis_frame_free(good);
}

static void test_light_ribbon_on_dark_background(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, 0.3);
    s.p.background = 35;
    s.p.ribbon = 225;
    s.p.clamp = 130;
    scene_draw(&s);
    vis_measure m;
    const double e = scene_track(&s, &m);
    printf("light ribbon: %s, Delta Z error %.3f px, A error %.4f rad\n", vis_reason_str(m.reason), e,
           m.a - s.truth.truth.a_cam);
    assert_true(e <= 0.2);
    assert_true(fabs(m.a - s.truth.truth.a_cam) <= 0.03);
    /* Forcing the polarity works too. */
    s.tp.polarity = VIS_POLARITY_LIGHT;
    assert_true(scene_track(&s, &m) <= 0.2);
    vis_frame_free(s.f);
}

static void test_uneven_lighting(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, -0.3);
    s.p.light_gradient = 0.5;
    s.p.vignette = 0.4;
    scene_draw(&s);
    vis_measure m;
    const double e = scene_track(&s, &m);
    printf("uneven lighting: %s, Delta Z error %.3f px, A error %.4f rad\n", vis_reason_str(m.reason), e,
           m.a - s.truth.truth.a_cam);
    assert_true(e <= 0.2);
    assert_true(fabs(m.a - s.truth.truth.a_cam) <= 0.03);
    vis_frame_free(s.f);
}

static void test_background_clutter(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, 0.1);
    s.p.clutter = 8;
    int ok = 0;
    for (uint64_t seed = 1; seed <= 4; seed++) {
        s.p.seed = seed;
        scene_draw(&s);
        vis_measure m;
        const double e = scene_track(&s, &m);
        printf("clutter seed %d: %s, Delta Z error %.3f px, A error %.4f rad\n", (int)seed,
               vis_reason_str(m.reason), e, m.a - s.truth.truth.a_cam);
        ok += e <= 0.3 && fabs(m.a - s.truth.truth.a_cam) <= 0.05;
    }
    assert_int_equal(ok, 4);
    vis_frame_free(s.f);
}

static void test_occluded_ribbon(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, 0.0);
    scene_draw(&s);
    /* A background-coloured card hides the middle third of the arch. */
    const int u0 = (int)(s.c.clamp_left_px[0] + 0.35 * (s.c.clamp_right_px[0] - s.c.clamp_left_px[0]));
    const int u1 = (int)(s.c.clamp_left_px[0] + 0.65 * (s.c.clamp_right_px[0] - s.c.clamp_left_px[0]));
    for (int y = 0; y < 240; y++)
        for (int u = u0; u < u1; u++)
            vis_frame_data(s.f)[y * vis_frame_stride(s.f) + (size_t)u] = (uint8_t)s.p.background;
    vis_measure m;
    scene_track(&s, &m);
    printf("occluded: %s\n", vis_reason_str(m.reason));
    assert_int_equal(m.reason, VIS_REASON_OCCLUDED);
    vis_frame_free(s.f);
}

static void test_clamps_outside_image(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, 0.0);
    scene_draw(&s);
    s.c.clamp_right_px[0] = 900;
    vis_measure m;
    scene_track(&s, &m);
    assert_int_equal(m.reason, VIS_REASON_CLAMP_NOT_FOUND);
    vis_frame_free(s.f);
}

static void test_overlay_draws_the_curve(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, 0.3);
    scene_draw(&s);
    vis_error err;
    vis_tracker *t = vis_tracker_create(&s.tp, &s.c, &err);
    assert_non_null(t);
    vis_measure m;
    assert_int_equal(vis_tracker_process(t, s.f, 0.0, &m, &err), VIS_OK);
    assert_int_equal(m.reason, VIS_REASON_NONE);
    vis_frame *o = vis_frame_alloc(8, 8, 1, NULL);
    assert_int_equal(vis_overlay_draw(s.f, t, &m, 3, o, &err), VIS_OK);
    assert_int_equal(vis_frame_channels(o), 3);
    /* Green pixels along the tracked curve, none in a plain grey frame. */
    double uv[2 * 400];
    const size_t n = vis_tracker_curve(t, uv, 400);
    assert_true(n >= 16);
    int green = 0;
    for (size_t i = 0; i < n && i < 400; i += 4) {
        const int x = (int)lround(uv[2 * i]), y = (int)lround(uv[2 * i + 1]);
        const uint8_t *px = vis_frame_data(o) + (size_t)y * vis_frame_stride(o) + 3 * (size_t)x;
        green += px[1] > px[0] + 40 && px[1] > px[2] + 40; /* BGR */
    }
    printf("overlay: %d of %zu curve samples green\n", green, (n + 3) / 4);
    assert_true(green * 2 > (int)((n + 3) / 4));
    char path[600];
    snprintf(path, sizeof path, "%s/overlay.png", vt_tmpdir());
    assert_int_equal(vis_frame_save(o, path, &err), VIS_OK);
    vis_frame_free(o);
    vis_tracker_free(t);
    vis_frame_free(s.f);
}

static void test_invalid_arguments(void **state)
{
    (void)state;
    scene s;
    scene_make(&s, 0.0);
    scene_draw(&s);
    vis_error err;
    vis_measure m;
    vis_track_params tp = s.tp;
    tp.band_px = 0;
    assert_null(vis_tracker_create(&tp, &s.c, &err));
    assert_int_equal(err.code, VIS_ERR_ARG);
    assert_non_null(strstr(err.message, "band_px"));
    tp = s.tp;
    tp.fit_window = NAN;
    assert_null(vis_tracker_create(&tp, &s.c, &err));
    vis_calib c = s.c;
    c.px_per_mm = 0;
    assert_null(vis_tracker_create(&s.tp, &c, &err));
    assert_non_null(strstr(err.message, "px_per_mm"));
    assert_null(vis_tracker_create(NULL, &s.c, &err));
    vis_tracker *t = vis_tracker_create(&s.tp, &s.c, &err);
    assert_non_null(t);
    assert_int_equal(vis_tracker_process(t, s.f, NAN, &m, &err), VIS_ERR_ARG);
    assert_int_equal(vis_tracker_process(NULL, s.f, 0.0, &m, &err), VIS_ERR_ARG);
    assert_int_equal(vis_tracker_process(t, s.f, 0.0, NULL, &err), VIS_ERR_ARG);
    vis_tracker_free(t);

    vis_render_params p = s.p;
    p.supersample = 0;
    assert_null(vis_renderer_create(&p, &err));
    p = s.p;
    p.camera.focal_px = -1;
    assert_null(vis_renderer_create(&p, &err));
    vis_renderer *r = vis_renderer_create(&s.p, &err);
    assert_non_null(r);
    vis_shape bad = shape.view;
    bad.n = 2;
    assert_int_equal(vis_renderer_draw(r, &bad, s.f, NULL, &err), VIS_ERR_ARG);
    double pos[9] = {0, 0, 0, 0.1, 0, NAN, 0.2, 0, 0}, nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    bad.n = 3;
    bad.pos = pos;
    bad.normal = nrm;
    assert_int_equal(vis_renderer_draw(r, &bad, s.f, NULL, &err), VIS_ERR_ARG);
    assert_non_null(strstr(err.message, "point 1"));
    pos[5] = 0;
    pos[3] = 0; /* coincident points */
    assert_int_equal(vis_renderer_draw(r, &bad, s.f, NULL, &err), VIS_ERR_ARG);
    vis_truth g;
    assert_int_equal(vis_shape_truth(NULL, &g, &err), VIS_ERR_ARG);
    vis_renderer_free(r);
    assert_null(vis_frame_alloc(0, 10, 1, &err));
    assert_null(vis_frame_alloc(10, 10, 2, &err));
    vis_frame_free(s.f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bad_frames_are_reported),
        cmocka_unit_test(test_bad_input_named_reasons),
        cmocka_unit_test(test_light_ribbon_on_dark_background),
        cmocka_unit_test(test_uneven_lighting),
        cmocka_unit_test(test_background_clutter),
        cmocka_unit_test(test_occluded_ribbon),
        cmocka_unit_test(test_clamps_outside_image),
        cmocka_unit_test(test_overlay_draws_the_curve),
        cmocka_unit_test(test_invalid_arguments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
