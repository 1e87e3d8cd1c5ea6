/* test_vision_track_accuracy.c: the tracker against projected ground truth on rendered videos.
 *
 * Each case renders an analytic shape sequence (symmetric arch, asymmetric arch under shear, an
 * overhanging arch whose tangent passes vertical, a ribbon with two 90 degree creases, a snap from the up to the down arch) with noise and
 * blur into an FFV1 video, reads it back and tracks it. Bars (issue 5): Delta Z error <= 0.2 px RMS in
 * pixel terms, A error <= 0.01 rad RMS, every frame measured; the snap frame found within one frame.
 * Frames are 640 x 480 (noise sigma 3 grey levels, blur sigma 1 px): the ribbon spans about 580 px.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "vis_test_run.h"

#define DZ_BAR_PX 0.2
#define A_BAR_RAD 0.01

/* Clamp gap 0.16 m for a 0.2 m ribbon: Delta L = 0.2. */
#define L_FREE 0.2
#define X_GAP 0.16

static void gen_sym(vt_shape *s, int i, void *ctx)
{
    (void)ctx;
    /* Symmetric arch while the right clamp shears away from the camera (depth correction). */
    vt_arch(s, 401, L_FREE, X_GAP, 0.0, 0.002 * i);
}

static void gen_asym(vt_shape *s, int i, void *ctx)
{
    (void)ctx;
    /* Asymmetric mode growing under shear. */
    vt_arch(s, 401, L_FREE, X_GAP, 0.06 * i, 0.002 * i);
}

static void gen_overhang(vt_shape *s, int i, void *ctx)
{
    (void)ctx;
    /* Tangent reaches 1.9 rad (beyond vertical) at the quarter points. */
    vt_overhang(s, 401, L_FREE, 1.9, 0.001 * i);
}

/* Folded ribbon: two creases (90 degrees, smoothed over 0.4% of the length) at Gamma = 0.13 and
 * 1 - Gamma, tangent angle theta(s) = 0.6 sin(2 pi s) + 0.2 (1 - cos(2 pi s)) + crease steps - pi s
 * (clamped: theta(0) = theta(1) = 0), sheared progressively. */
static void gen_creased(vt_shape *s, int i, void *ctx)
{
    (void)ctx;
    enum { M = 8192 };
    static double xd[M], zd[M];
    const double ds = L_FREE / (M - 1), G = 0.13, phi = M_PI / 2, w = 0.004;
    xd[0] = zd[0] = 0;
    for (int k = 1; k < M; k++) {
        const double u = (k - 0.5) / (M - 1);
        const double th = 0.6 * sin(2 * M_PI * u) + 0.2 * (1 - cos(2 * M_PI * u)) +
                          phi * (0.5 * (1 + tanh((u - G) / w)) + 0.5 * (1 + tanh((u - 1 + G) / w))) -
                          2 * phi * u;
        xd[k] = xd[k - 1] + ds * cos(th);
        zd[k] = zd[k - 1] + ds * sin(th);
    }
    vt_from_dense(s, 601, xd, zd, M, 0.0015 * i);
}

#define SNAP_AT 8
static void gen_snap(vt_shape *s, int i, void *ctx)
{
    (void)ctx;
    /* Up arch tilting slowly toward the asymmetric mode, then through it to the down arch. */
    double phi;
    if (i < SNAP_AT)
        phi = 0.03 * i;
    else if (i == SNAP_AT)
        phi = M_PI / 2;
    else
        phi = M_PI - 0.03 * (14 - i);
    vt_arch(s, 401, L_FREE, X_GAP, phi, 0.0015 * i);
}

/* A twisted strip in a tight apex: a tall asymmetric arch (Delta L 0.5) under 40 mm of shear, the
 * strip turned about its tangent by psi0 sin(pi s) (edge-on at the clamps, its face toward the
 * camera between; 5 mm wide, 0.25 mm thick as the lab's PET), psi0 from 40 to 70 degrees over the
 * frames. The apex's radius is under
 * twice the face's width and |A| is large, so the bend check refuses the centroids there and the
 * silhouette model (vision/bend_model.cpp) measures the frame. */
static double twist_sine(double xi, void *ctx) { return *(const double *)ctx * sin(M_PI * xi); }

static void gen_twisted(vt_shape *s, int i, void *ctx)
{
    (void)ctx;
    vt_arch(s, 401, L_FREE, 0.1, 0.5, 0.04);
    s->view.thickness_m = 0.00025;
    double psi0 = (40.0 + 10.0 * i) * M_PI / 180.0; /* edge-on at the clamps */
    vt_twist(s, twist_sine, &psi0);
}

static vis_render_params params_for(vt_gen_fn gen, int frames, int width)
{
    /* A fixed camera framing every frame of the sequence. */
    static vt_shape s;
    double x0 = 1e9, x1 = -1e9, z0 = 1e9, z1 = -1e9;
    for (int i = 0; i < frames; i++) {
        gen(&s, i, NULL);
        for (size_t k = 0; k < s.n; k++) {
            x0 = fmin(x0, s.pos[3 * k]);
            x1 = fmax(x1, s.pos[3 * k]);
            z0 = fmin(z0, s.pos[3 * k + 2]);
            z1 = fmax(z1, s.pos[3 * k + 2]);
        }
    }
    vis_render_params p = vis_render_params_default();
    /* 640 x 480: at 320 x 240 the end tangents carry about 0.012 rad of noise (pixel quantisation
     * over a short one-sided window), above the 0.01 rad bar for A. */
    p.camera.width_px = width;
    p.camera.height_px = width * 3 / 4;
    assert_int_equal(vis_camera_fit(&p.camera, x0 - 0.02, x1 + 0.02, z0 - 0.01, z1 + 0.01, 0.9, NULL),
                     VIS_OK);
    p.noise_sigma = 3.0;
    p.blur_sigma_px = 1.0;
    return p;
}

static void run_case_p(const char *name, vt_gen_fn gen, int frames, int width, int clutter, double gradient,
                       double tilt, vt_result *r)
{
    static vt_shape s;
    vis_render_params p = params_for(gen, frames, width);
    p.camera.tilt_rad = tilt;
    p.clutter = clutter;
    p.light_gradient = gradient;
    p.vignette = gradient;
    gen(&s, 0, NULL);
    vis_calib c = vt_calib(&p, &s);
    vis_track_params tp = vis_track_params_default();
    vis_truth g;
    assert_int_equal(vis_shape_truth(&s.view, &g, NULL), VIS_OK);
    tp.length_mm = g.length_m * 1000.0;
    tp.ribbon_max_px = 12.0; /* the 2 mm ribbon looks up to 8 px thick at this scale */
    assert_int_equal(vt_run(name, gen, NULL, frames, &p, &c, &tp, r), 0);
}

static void run_case(const char *name, vt_gen_fn gen, int frames, int width, vt_result *r)
{
    run_case_p(name, gen, frames, width, 0, 0.0, 0.0, r);
}

static void check(const vt_result *r)
{
    assert_int_equal(r->measured, r->frames);
    assert_true(r->dz_rms_px <= DZ_BAR_PX);
    assert_true(r->a_rms <= A_BAR_RAD);
}

static void test_symmetric_arch(void **state)
{
    (void)state;
    vt_result r;
    run_case("sym", gen_sym, 10, 640, &r);
    check(&r);
}

static void test_asymmetric_sheared_arch(void **state)
{
    (void)state;
    vt_result r;
    run_case("asym", gen_asym, 10, 640, &r);
    check(&r);
}

static void test_overhanging_arch(void **state)
{
    (void)state;
    vt_result r;
    run_case("overhang", gen_overhang, 8, 640, &r);
    check(&r);
}

static void test_creased_ribbon(void **state)
{
    (void)state;
    vt_result r;
    /* The creased ribbon is tall: 800 x 600 keeps it about as long in pixels as the others. */
    run_case("creased", gen_creased, 8, 800, &r);
    check(&r);
}

static void test_clutter_and_uneven_light(void **state)
{
    (void)state;
    /* The asymmetric sequence in front of 8 fixed background shapes under a lighting gradient and
     * vignetting (both 40%): frames after the first follow the previous curve. */
    vt_result r;
    run_case_p("clutter", gen_asym, 10, 640, 8, 0.4, 0.0, &r);
    check(&r);
}

static void test_tilted_camera(void **state)
{
    (void)state;
    /* The asymmetric sequence under shear seen by a camera pitched down by 0.15 rad (8.6 degrees):
     * without the tilt in the model the height would be off by about 2 px. */
    vt_result r;
    run_case_p("tilted", gen_asym, 10, 640, 0, 0.0, 0.15, &r);
    check(&r);
}

static void test_twisted_tight_apex(void **state)
{
    (void)state;
    static vt_shape s;
    const int frames = 4;
    vis_render_params p = params_for(gen_twisted, frames, 640);
    p.camera.focal_px *= 10.0 / p.camera.distance_m; /* 10 m away, same framing */
    p.camera.distance_m = 10.0;
    gen_twisted(&s, 0, NULL);
    vis_calib c = vt_calib(&p, &s);
    vis_truth g;
    assert_int_equal(vis_shape_truth(&s.view, &g, NULL), VIS_OK);
    vis_track_params tp = vis_track_params_default();
    tp.length_mm = g.length_m * 1000.0;
    tp.ribbon_max_px = ceil(s.view.width_m * 1000.0 * c.px_per_mm + 2.0);
    tp.band_px = fmax(12.0, 1.5 * tp.ribbon_max_px);
    tp.refresh_frames = 1; /* every frame from scratch */
    vt_result r;
    assert_int_equal(vt_run("twisted", gen_twisted, NULL, frames, &p, &c, &tp, &r), 0);
    printf("twisted tight apex: %d/%d measured, Delta Z error %.3f px RMS (max %.3f), A error %.4f rad RMS (max %.4f)\n",
           r.measured, r.frames, r.dz_rms_px, r.dz_max_px, r.a_rms, r.a_max);
    /* Every frame measured (the bend check alone loses all four). Bars: issue 14's 0.02 rad for A;
     * Delta Z within 1 px, not issue 5's 0.2: the apex's radius (about 20 px) is small against the
     * local fit's window (8% of the length either side, about 65 px), and the fit cuts it by 0.75 px
     * whatever traced it (with the bend check off the centroids measure 0.755 px RMS, A 0.0047;
     * the model 0.82 px, A 0.011: these sections are nearly square to the curve, so the centroids
     * are not biased here and the model only measures what the check would refuse). */
    assert_int_equal(r.measured, r.frames);
    assert_true(r.dz_rms_px <= 1.0);
    assert_true(r.a_rms <= 0.02);
}

static void test_snap_sequence(void **state)
{
    (void)state;
    vt_result r;
    run_case("snap", gen_snap, 14, 640, &r);
    check(&r);
    const int snap = vis_snap_find(r.dz, r.valid, (size_t)r.frames, 0.02, 0.3);
    printf("snap: found at frame %d, rendered at frame %d\n", snap, SNAP_AT);
    assert_true(abs(snap - SNAP_AT) <= 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_symmetric_arch),
        cmocka_unit_test(test_asymmetric_sheared_arch),
        cmocka_unit_test(test_overhanging_arch),
        cmocka_unit_test(test_creased_ribbon),
        cmocka_unit_test(test_clutter_and_uneven_light),
        cmocka_unit_test(test_tilted_camera),
        cmocka_unit_test(test_snap_sequence),
        cmocka_unit_test(test_twisted_tight_apex),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
