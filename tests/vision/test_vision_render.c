/* test_vision_render.c: the synthetic renderer, its pinhole camera and the shape ground truth.
 *
 * Ground truth against closed forms (a symmetric arch's midpoint height is its apex, A = 0 for
 * symmetric shapes and odd in the asymmetric mode, the overhanging shape's apex height is the
 * integral of sin theta), the camera against the pinhole formula, and the image: ribbon, clamps and
 * background where the camera puts them, reproducible for a given seed.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "vis_test_run.h"

static vt_shape s;

static void test_truth_closed_forms(void **state)
{
    (void)state;
    vis_truth g, h;
    vis_error err;
    vt_arch(&s, 201, 0.2, 0.16, 0.0, 0.0);
    assert_int_equal(vis_shape_truth(&s.view, &g, &err), VIS_OK);
    assert_true(fabs(g.length_m - 0.2) < 1e-5); /* chords of a 201-point polyline */
    assert_true(fabs(g.dz - s.pos[3 * 100 + 2] / g.length_m) < 1e-9);
    assert_true(fabs(g.a) < 1e-9 && g.dz == g.dz_cam && g.shear_m == 0.0);

    /* A is odd in the asymmetric mode. */
    vt_arch(&s, 201, 0.2, 0.16, 0.3, 0.0);
    assert_int_equal(vis_shape_truth(&s.view, &g, &err), VIS_OK);
    vt_arch(&s, 201, 0.2, 0.16, -0.3, 0.0);
    assert_int_equal(vis_shape_truth(&s.view, &h, &err), VIS_OK);
    assert_true(fabs(g.a) > 0.1 && fabs(g.a + h.a) < 1e-9 && fabs(g.dz - h.dz) < 1e-9);

    /* Overhang: apex height = integral of sin(T sin(2 pi s / l)) over the first half. */
    const double T = 1.9, l = 0.2;
    vt_overhang(&s, 401, l, T, 0.0);
    assert_int_equal(vis_shape_truth(&s.view, &g, &err), VIS_OK);
    double z = 0.0;
    const int m = 20000;
    for (int i = 0; i < m; i++)
        z += sin(T * sin(2 * M_PI * (i + 0.5) * (l / 2) / m / l)) * (l / 2) / m;
    printf("overhang: dz %.6f closed form %.6f, A %.2e\n", g.dz, z / l, g.a);
    assert_true(fabs(g.dz - z / l) < 1e-5);
    assert_true(fabs(g.a) < 1e-6);

    /* Shear: reported; the 3D length grows; the profile y(s) is odd about the midpoint, so the 3D
     * and projected arc-length midpoints are the same point. */
    vt_arch(&s, 201, 0.2, 0.16, 0.0, 0.02);
    assert_int_equal(vis_shape_truth(&s.view, &g, &err), VIS_OK);
    assert_true(fabs(g.shear_m - 0.02) < 1e-12);
    assert_true(g.length_m > 0.2 + 1e-4 && fabs(g.dz_cam - g.dz) < 1e-9);
}

static void test_camera_pinhole(void **state)
{
    (void)state;
    vis_camera c = vis_camera_default();
    const double t[3] = {c.target_x_m, 0.0, c.target_z_m};
    double uv[2];
    assert_int_equal(vis_camera_project(&c, t, uv, NULL), VIS_OK);
    assert_true(fabs(uv[0] - 159.5) < 1e-12 && fabs(uv[1] - 119.5) < 1e-12);
    const double p[3] = {c.target_x_m + 0.01, 0.1, c.target_z_m + 0.02};
    assert_int_equal(vis_camera_project(&c, p, uv, NULL), VIS_OK);
    assert_true(fabs(uv[0] - (159.5 + c.focal_px * 0.01 / 1.1)) < 1e-9);
    assert_true(fabs(uv[1] - (119.5 - c.focal_px * 0.02 / 1.1)) < 1e-9);
    const double behind[3] = {0.0, -2.0, 0.0};
    vis_error err;
    assert_int_equal(vis_camera_project(&c, behind, uv, &err), VIS_ERR_ARG);
    assert_int_equal(vis_camera_fit(&c, 0.0, 0.2, -0.05, 0.05, 0.5, &err), VIS_OK);
    assert_true(fabs(c.focal_px - 0.5 * 320 * c.distance_m / 0.2) < 1e-9);
    assert_int_equal(vis_camera_fit(&c, 0.2, 0.0, 0, 0, 0.5, &err), VIS_ERR_ARG);
}

static int at(vis_frame *f, double u, double v)
{
    const int x = (int)lround(u), y = (int)lround(v);
    return vis_frame_data(f)[(size_t)y * vis_frame_stride(f) + (size_t)x];
}

static void test_image_content_and_seed(void **state)
{
    (void)state;
    vt_arch(&s, 201, 0.2, 0.16, 0.0, 0.0);
    vis_render_params p = vt_render_params(&s, 320, 240);
    vis_render_truth tr;
    vis_frame *a = vis_frame_alloc(8, 8, 1, NULL), *b = vis_frame_alloc(8, 8, 1, NULL);
    vis_renderer *r = vis_renderer_create(&p, NULL);
    assert_int_equal(vis_renderer_draw(r, &s.view, a, &tr, NULL), VIS_OK);
    assert_int_equal(vis_frame_width(a), 320);
    assert_int_equal(vis_frame_height(a), 240);
    assert_true(fabs(at(a, tr.mid_px[0], tr.mid_px[1]) - p.ribbon) < 25);        /* ribbon */
    assert_true(fabs(at(a, tr.mid_px[0], tr.mid_px[1] + 20) - p.background) < 12); /* backdrop */
    assert_true(fabs(at(a, tr.clamp_left_px[0] - 8, tr.clamp_left_px[1] + 5) - p.clamp) < 12);
    assert_true(fabs(at(a, tr.clamp_right_px[0] + 8, tr.clamp_right_px[1] - 5) - p.clamp) < 12);
    assert_true(fabs(tr.px_per_m - p.camera.focal_px / p.camera.distance_m) < 1e-9);
    /* Same seed, same frames; the noise differs from frame to frame of one renderer. */
    vis_renderer *r2 = vis_renderer_create(&p, NULL);
    assert_int_equal(vis_renderer_draw(r2, &s.view, b, NULL, NULL), VIS_OK);
    assert_memory_equal(vis_frame_data(a), vis_frame_data(b), vis_frame_stride(a) * 240);
    assert_int_equal(vis_renderer_draw(r2, &s.view, b, NULL, NULL), VIS_OK);
    assert_memory_not_equal(vis_frame_data(a), vis_frame_data(b), vis_frame_stride(a) * 240);
    vis_renderer_free(r2);
    vis_renderer_free(r);
    vis_frame_free(a);
    vis_frame_free(b);
}

static void test_ground_truth_csv(void **state)
{
    (void)state;
    vt_arch(&s, 201, 0.2, 0.16, 0.2, 0.0);
    vis_render_params p = vt_render_params(&s, 160, 120);
    char video[600], csv[600];
    snprintf(video, sizeof video, "%s/gt.mkv", vt_tmpdir());
    snprintf(csv, sizeof csv, "%s/gt.csv", vt_tmpdir());
    vis_error err;
    vis_synth_writer *w = vis_synth_writer_open(video, csv, &p, 30.0, &err);
    assert_non_null(w);
    vis_render_truth tr;
    for (int i = 0; i < 3; i++)
        assert_int_equal(vis_synth_writer_add(w, &s.view, &tr, &err), VIS_OK);
    assert_int_equal(vis_synth_writer_close(w, &err), VIS_OK);
    FILE *f = fopen(csv, "r");
    assert_non_null(f);
    char line[1024];
    assert_non_null(fgets(line, sizeof line, f));
    assert_non_null(strstr(line, "dz_cam"));
    int rows = 0, frame = -1;
    double t = -1, shear, len, dz, a;
    while (fgets(line, sizeof line, f)) {
        assert_int_equal(sscanf(line, "%d,%lf,%lf,%lf,%lf,%lf", &frame, &t, &shear, &len, &dz, &a), 6);
        assert_int_equal(frame, rows);
        assert_true(dz == tr.truth.dz && a == tr.truth.a); /* %.17g round-trips */
        rows++;
    }
    fclose(f);
    assert_int_equal(rows, 3);
    assert_true(fabs(t - 2.0 / 30.0) < 1e-12);
    assert_null(vis_synth_writer_open(video, "/nonexistent/dir/gt.csv", &p, 30.0, &err));
    assert_int_equal(err.code, VIS_ERR_IO);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_truth_closed_forms),
        cmocka_unit_test(test_camera_pinhole),
        cmocka_unit_test(test_image_content_and_seed),
        cmocka_unit_test(test_ground_truth_csv),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
