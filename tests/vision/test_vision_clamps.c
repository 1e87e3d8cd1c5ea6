/* test_vision_clamps.c: automatic clamp detection (vis_find_clamps) against the renderer's projected
 * clamp points, and tracking with the clamps it finds.
 *
 * Detection: four shapes (up arch, asymmetric arch, down arch, overhanging arch) in both polarities
 * under three picture conditions (noise 3 + blur 1; noise 6 + blur 2; noise, clutter, a 40% lighting
 * gradient and 40% vignetting), 640 x 480, plus a 320 x 240 frame with default tracker parameters.
 * Bar: the found point within 0.5 px of the projected clamp point across the ribbon (v), and along
 * it (u) within 0.5 px of the projected point moved by the perspective of the jaw's depth: the
 * silhouette's inner face is the jaw face nearer the optical axis, |u - u0| w / (2 D + w) px inward
 * (vision.h). Tracking: the sheared symmetric and asymmetric sequences of the accuracy test, tracked
 * with clamp points found on their first frame, meet issue 5's bars (Delta Z <= 0.2 px RMS, A <=
 * 0.01 rad RMS). A frame without jaws, a blank frame and a black frame give VIS_ERR_NOT_FOUND with a
 * message; bad arguments VIS_ERR_ARG.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "vis_test_run.h"

#define L_FREE 0.2
#define X_GAP 0.16
#define CLAMP_BAR_PX 0.5
#define DZ_BAR_PX 0.2
#define A_BAR_RAD 0.01

enum { COND_PLAIN, COND_NOISY, COND_CLUTTER, N_COND };
static const char *cond_name[N_COND] = {"noise3+blur1", "noise6+blur2", "clutter+light"};

static vis_render_params params_for(const vt_shape *s, int width, int light, int cond)
{
    vis_render_params p = vt_render_params(s, width, width * 3 / 4);
    p.noise_sigma = cond == COND_NOISY ? 6.0 : 3.0;
    p.blur_sigma_px = cond == COND_NOISY ? 2.0 : 1.0;
    if (cond == COND_CLUTTER) {
        p.clutter = 8;
        p.light_gradient = 0.4;
        p.vignette = 0.4;
    }
    if (light) {
        p.background = 45.0;
        p.ribbon = 215.0;
        p.clamp = 160.0;
    }
    return p;
}

/* Render `s`, find the clamps; returns the status and fills the errors (found - expected, px). */
static vis_status detect(const vt_shape *s, const vis_render_params *p, const vis_track_params *tp,
                         double du[2], double dv[2], double *q, vis_error *err)
{
    vis_renderer *r = vis_renderer_create(p, NULL);
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    assert_non_null(r);
    assert_non_null(f);
    vis_render_truth t;
    assert_int_equal(vis_renderer_draw(r, &s->view, f, &t, NULL), VIS_OK);
    double lp[2], rp[2];
    const vis_status st = vis_find_clamps(f, tp, lp, rp, q, err);
    if (st == VIS_OK) {
        const double cu = 0.5 * (p->camera.width_px - 1), D = p->camera.distance_m, w = s->view.width_m;
        const double *truth[2] = {t.clamp_left_px, t.clamp_right_px}, *found[2] = {lp, rp};
        for (int k = 0; k < 2; k++) {
            /* The silhouette's inner face moves toward the image centre by the jaw's depth. */
            const double persp = (cu - truth[k][0]) * w / (2 * D + w);
            du[k] = found[k][0] - truth[k][0] - persp;
            dv[k] = found[k][1] - truth[k][1];
        }
    }
    vis_frame_free(f);
    vis_renderer_free(r);
    return st;
}

static void test_detection_accuracy(void **state)
{
    (void)state;
    static vt_shape s;
    vis_track_params tp = vis_track_params_default();
    tp.ribbon_max_px = 12.0; /* as the accuracy test: the 2 mm ribbon looks up to 8 px thick */
    double worst_u = 0, worst_v = 0, sum2 = 0;
    int n = 0;
    for (int shape = 0; shape < 4; shape++) {
        if (shape == 3)
            vt_overhang(&s, 401, L_FREE, 1.9, 0.0);
        else
            vt_arch(&s, 401, L_FREE, X_GAP, shape == 0 ? 0.0 : shape == 1 ? 0.6 : M_PI, 0.0);
        for (int light = 0; light < 2; light++)
            for (int cond = 0; cond < N_COND; cond++) {
                vis_render_params p = params_for(&s, 640, light, cond);
                p.seed = (uint64_t)(1 + shape * 7 + light * 3 + cond);
                double du[2], dv[2], q = 0;
                vis_error err;
                const vis_status st = detect(&s, &p, &tp, du, dv, &q, &err);
                if (st != VIS_OK)
                    printf("shape %d %s %s: %s\n", shape, light ? "light" : "dark", cond_name[cond],
                           err.message);
                assert_int_equal(st, VIS_OK);
                printf("shape %d %-5s %-13s: left du %+.3f dv %+.3f, right du %+.3f dv %+.3f px, "
                       "quality %.3f\n",
                       shape, light ? "light" : "dark", cond_name[cond], du[0], dv[0], du[1], dv[1], q);
                for (int k = 0; k < 2; k++) {
                    worst_u = fmax(worst_u, fabs(du[k]));
                    worst_v = fmax(worst_v, fabs(dv[k]));
                    sum2 += du[k] * du[k] + dv[k] * dv[k];
                    n++;
                }
                assert_true(q > 0.3);
            }
    }
    printf("clamp points: worst |du| %.3f px (perspective removed), worst |dv| %.3f px, RMS %.3f px "
           "over %d points\n",
           worst_u, worst_v, sqrt(sum2 / n), n);
    assert_true(worst_u <= CLAMP_BAR_PX);
    assert_true(worst_v <= CLAMP_BAR_PX);
}

static void test_detection_small_default_params(void **state)
{
    (void)state;
    /* 320 x 240 (jaws about 22 x 17 px), the tracker's default parameters, both polarities. */
    static vt_shape s;
    vt_arch(&s, 301, L_FREE, X_GAP, 0.3, 0.0);
    for (int light = 0; light < 2; light++) {
        vis_render_params p = params_for(&s, 320, light, COND_PLAIN);
        double du[2], dv[2], q;
        vis_error err;
        const vis_status st = detect(&s, &p, NULL, du, dv, &q, &err);
        if (st != VIS_OK)
            printf("320x240 %s: %s\n", light ? "light" : "dark", err.message);
        assert_int_equal(st, VIS_OK);
        printf("320x240 %-5s: left du %+.3f dv %+.3f, right du %+.3f dv %+.3f px\n", light ? "light" : "dark",
               du[0], dv[0], du[1], dv[1]);
        for (int k = 0; k < 2; k++) {
            assert_true(fabs(du[k]) <= CLAMP_BAR_PX);
            assert_true(fabs(dv[k]) <= CLAMP_BAR_PX);
        }
    }
}

static void gen_sym(vt_shape *s, int i, void *ctx)
{
    (void)ctx;
    vt_arch(s, 401, L_FREE, X_GAP, 0.0, 0.002 * i);
}

static void gen_asym(vt_shape *s, int i, void *ctx)
{
    (void)ctx;
    vt_arch(s, 401, L_FREE, X_GAP, 0.06 * i, 0.002 * i);
}

static void track_auto(const char *name, vt_gen_fn gen, int light)
{
    static vt_shape s;
    enum { FRAMES = 10 };
    double x0 = 1e9, x1 = -1e9, z0 = 1e9, z1 = -1e9;
    for (int i = 0; i < FRAMES; i++) {
        gen(&s, i, NULL);
        for (size_t k = 0; k < s.n; k++) {
            x0 = fmin(x0, s.pos[3 * k]);
            x1 = fmax(x1, s.pos[3 * k]);
            z0 = fmin(z0, s.pos[3 * k + 2]);
            z1 = fmax(z1, s.pos[3 * k + 2]);
        }
    }
    vis_render_params p = params_for(&s, 640, light, COND_PLAIN);
    assert_int_equal(vis_camera_fit(&p.camera, x0 - 0.02, x1 + 0.02, z0 - 0.01, z1 + 0.01, 0.9, NULL), VIS_OK);
    gen(&s, 0, NULL);
    vis_track_params tp = vis_track_params_default();
    tp.ribbon_max_px = 12.0;
    vis_truth g;
    assert_int_equal(vis_shape_truth(&s.view, &g, NULL), VIS_OK);
    tp.length_mm = g.length_m * 1000.0;

    /* Clamp points from the first frame; scale and camera distance as the rig would know them. */
    vis_renderer *r = vis_renderer_create(&p, NULL);
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    assert_int_equal(vis_renderer_draw(r, &s.view, f, NULL, NULL), VIS_OK);
    vis_calib c = vt_calib(&p, &s);
    vis_error err;
    const vis_status st = vis_find_clamps(f, &tp, c.clamp_left_px, c.clamp_right_px, NULL, &err);
    if (st != VIS_OK)
        printf("%s: %s\n", name, err.message);
    assert_int_equal(st, VIS_OK);
    vis_frame_free(f);
    vis_renderer_free(r);

    vt_result res;
    assert_int_equal(vt_run(name, gen, NULL, FRAMES, &p, &c, &tp, &res), 0);
    assert_int_equal(res.measured, res.frames);
    assert_true(res.dz_rms_px <= DZ_BAR_PX);
    assert_true(res.a_rms <= A_BAR_RAD);
}

static void test_track_with_found_clamps(void **state)
{
    (void)state;
    track_auto("auto_sym", gen_sym, 0);
    track_auto("auto_asym_light", gen_asym, 1);
}

static void test_no_clamps(void **state)
{
    (void)state;
    static vt_shape s;
    vt_arch(&s, 301, L_FREE, X_GAP, 0.3, 0.0);
    vis_render_params p = params_for(&s, 320, 0, COND_PLAIN);
    p.clamp_length_m = 0.0; /* the ribbon alone */
    double du[2], dv[2], q = -1;
    vis_error err;
    memset(&err, 0, sizeof err);
    assert_int_equal(detect(&s, &p, NULL, du, dv, &q, &err), VIS_ERR_NOT_FOUND);
    assert_int_equal(err.code, VIS_ERR_NOT_FOUND);
    printf("no jaws: %s\n", err.message);
    assert_true(strlen(err.message) > 10);

    vis_frame *f = vis_frame_alloc(320, 240, 1, NULL);
    double lp[2], rp[2];
    memset(vis_frame_data(f), 200, vis_frame_stride(f) * 240);
    assert_int_equal(vis_find_clamps(f, NULL, lp, rp, NULL, &err), VIS_ERR_NOT_FOUND);
    printf("blank: %s\n", err.message);
    memset(vis_frame_data(f), 0, vis_frame_stride(f) * 240);
    assert_int_equal(vis_find_clamps(f, NULL, lp, rp, NULL, &err), VIS_ERR_NOT_FOUND);
    printf("black: %s\n", err.message);

    assert_int_equal(vis_find_clamps(NULL, NULL, lp, rp, NULL, &err), VIS_ERR_ARG);
    assert_int_equal(vis_find_clamps(f, NULL, NULL, rp, NULL, &err), VIS_ERR_ARG);
    vis_track_params tp = vis_track_params_default();
    tp.ribbon_max_px = NAN;
    assert_int_equal(vis_find_clamps(f, &tp, lp, rp, NULL, &err), VIS_ERR_ARG);
    vis_frame_free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_detection_accuracy),
        cmocka_unit_test(test_detection_small_default_params),
        cmocka_unit_test(test_track_with_found_clamps),
        cmocka_unit_test(test_no_clamps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
