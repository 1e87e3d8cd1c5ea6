/* test_vision_depth_profile.c: the centreline's depth from the caller (vis_tracker_set_depth_profile,
 * vis_tracker_set_depth_library), on analytic shapes whose depth is not the default profile's.
 *
 * The shape: an asymmetric arch (vis_test_shapes.h) whose depth follows a smootherstep over its
 * middle third (flat for the first and last thirds, as the DER strip is under shear), 40 mm of
 * shear on 200 mm, filmed from 0.6 m. The tracker's default profile, shear (3 xi^2 - 2 xi^3), puts
 * the middle of the arc at the wrong depth and so at the wrong scale; given the shape's own profile
 * (its 3D arc fraction against depth over shear, mapped by the tracker onto the projected arc it
 * measures) the error is the tracer's alone. The library case gives the tracker three shapes and
 * checks that it takes each frame's depth from the one that frame shows. Bad profiles and
 * libraries are refused with a reason and leave the tracker's depth as it was.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vis_test_shapes.h"

#define NPTS 301
#define SHEAR_M 0.04
#define DISTANCE_M 0.6

static double depth_middle(double xi)
{
    double u = 3.0 * (xi - 1.0 / 3.0);
    u = u < 0 ? 0 : u > 1 ? 1 : u;
    return u * u * u * (u * (6 * u - 15) + 10);
}

static double depth_early(double xi) /* most of the shear in the first half */
{
    return 1.0 - (1.0 - xi) * (1.0 - xi) * (1.0 - xi);
}

typedef struct rig {
    vis_render_params p;
    vis_calib c;
    vis_track_params tp;
    vis_renderer *r;
    vis_frame *f;
} rig;

static vt_shape shape, flat;

/* Camera fitted on the unsheared arch, calibrated at zero shear; the tracker knows the 3D length. */
static void rig_make(rig *g, double phi)
{
    vt_arch_depth(&flat, NPTS, 0.2, 0.16, phi, 0.0, vt_depth_cubic);
    g->p = vis_render_params_default();
    g->p.camera.width_px = 640;
    g->p.camera.height_px = 480;
    g->p.camera.distance_m = DISTANCE_M;
    assert_int_equal(vis_camera_fit(&g->p.camera, -0.03, 0.19, -0.08, 0.08, 0.9, NULL), VIS_OK);
    g->p.noise_sigma = 2.0;
    g->p.blur_sigma_px = 0.8;
    g->c = vt_calib(&g->p, &flat);
    g->tp = vis_track_params_default();
    vis_error err;
    g->r = vis_renderer_create(&g->p, &err);
    assert_non_null(g->r);
    g->f = vis_frame_alloc(8, 8, 1, NULL);
    assert_non_null(g->f);
}

static void rig_free(rig *g)
{
    vis_renderer_free(g->r);
    vis_frame_free(g->f);
}

/* Length of segment i (points i - 1 to i) of the 3D centreline. */
static double seg_len(const vt_shape *s, size_t i)
{
    return sqrt(pow(s->pos[3 * i] - s->pos[3 * i - 3], 2) + pow(s->pos[3 * i + 1] - s->pos[3 * i - 2], 2) +
                pow(s->pos[3 * i + 2] - s->pos[3 * i - 1], 2));
}

static double length_3d(const vt_shape *s)
{
    double l = 0;
    for (size_t i = 1; i < s->n; i++)
        l += seg_len(s, i);
    return l;
}

/* The shape's profile as the tracker takes it: 3D arc fraction, depth over the shear. */
static void profile_of(const vt_shape *s, double *frac, double *rel)
{
    const double l = length_3d(s);
    double c = 0;
    frac[0] = 0;
    rel[0] = 0;
    for (size_t i = 1; i < s->n; i++) {
        c += seg_len(s, i);
        frac[i] = i + 1 == s->n ? 1.0 : c / l;
        rel[i] = s->pos[3 * i + 1] / SHEAR_M;
    }
}

/* The arch of the file's top in `shape`, its rig, the tracker's known length and its profile. */
static void arch_case(rig *g, double *frac, double *rel)
{
    rig_make(g, 0.6);
    vt_arch_depth(&shape, NPTS, 0.2, 0.16, 0.6, SHEAR_M, depth_middle);
    g->tp.length_mm = length_3d(&shape) * 1000.0;
    profile_of(&shape, frac, rel);
}

typedef struct result {
    vis_measure m;
    double edz_px, ea;
} result;

static result measure(rig *g, vis_tracker *t, const vt_shape *s)
{
    vis_render_truth truth;
    vis_error err;
    assert_int_equal(vis_renderer_draw(g->r, &s->view, g->f, &truth, &err), VIS_OK);
    result r;
    assert_int_equal(vis_tracker_process(t, g->f, SHEAR_M * 1000.0, &r.m, &err), VIS_OK);
    assert_int_equal(r.m.reason, VIS_REASON_NONE);
    r.edz_px = (r.m.dz - truth.truth.dz_cam) * truth.truth.length_m * truth.px_per_m;
    r.ea = r.m.a - truth.truth.a_cam;
    return r;
}

static void test_profile_puts_the_depth_right(void **state)
{
    (void)state;
    rig g;
    double frac[NPTS], rel[NPTS];
    arch_case(&g, frac, rel);
    vis_error err;
    vis_tracker *t0 = vis_tracker_create(&g.tp, &g.c, &err), *t1 = vis_tracker_create(&g.tp, &g.c, &err);
    assert_non_null(t0);
    assert_non_null(t1);
    assert_int_equal(vis_tracker_set_depth_profile(t1, frac, rel, NPTS, &err), VIS_OK);
    const result r0 = measure(&g, t0, &shape), r1 = measure(&g, t1, &shape);
    printf("default profile: Delta Z off %+.3f px, A off %+.4f rad; the shape's own: %+.3f px, %+.4f rad\n", r0.edz_px,
           r0.ea, r1.edz_px, r1.ea);
    assert_true(fabs(r0.edz_px) > 1.0); /* the case is one the default gets wrong */
    assert_true(fabs(r1.edz_px) < 0.15);
    assert_true(fabs(r1.ea) < 0.01);
    /* The material arc fraction taken as the projected one (no mapping): the depth lands off
     * along the arc where the slope in depth is steep. */
    vis_tracker *t2 = vis_tracker_create(&g.tp, &g.c, &err);
    assert_non_null(t2);
    double planar[NPTS];
    for (int i = 0; i < NPTS; i++)
        planar[i] = (double)i / (NPTS - 1);
    assert_int_equal(vis_tracker_set_depth_profile(t2, planar, rel, NPTS, &err), VIS_OK);
    const result r2 = measure(&g, t2, &shape);
    printf("profile keyed by the projected arc fraction instead: %+.3f px, %+.4f rad\n", r2.edz_px, r2.ea);
    assert_true(fabs(r2.ea) > 0.05); /* the mapping onto the projected arc is what gets it right */
    /* n = 0: back to the default, the same numbers as a tracker that never had a profile (a new
     * renderer of the same seed draws the same frame). */
    assert_int_equal(vis_tracker_set_depth_profile(t1, NULL, NULL, 0, &err), VIS_OK);
    vis_tracker_reset(t1);
    vis_renderer_free(g.r);
    g.r = vis_renderer_create(&g.p, &err);
    const result b0 = measure(&g, t1, &shape);
    vis_renderer_free(g.r);
    g.r = vis_renderer_create(&g.p, &err);
    vis_tracker *t3 = vis_tracker_create(&g.tp, &g.c, &err);
    const result b1 = measure(&g, t3, &shape);
    assert_true(b0.m.dz == b1.m.dz && b0.m.a == b1.m.a);
    vis_tracker_free(t0);
    vis_tracker_free(t1);
    vis_tracker_free(t2);
    vis_tracker_free(t3);
    rig_free(&g);
}

/* Three shapes in the library, each with its own depth: every frame takes the depth of the shape
 * it shows, as if that shape's profile had been set; keyed by Delta Z and A, and by projections. */
static void test_library_takes_the_shape_shown(void **state)
{
    (void)state;
    const double phis[3] = {0.6, -0.5, 0.0};
    double (*depths[3])(double) = {depth_middle, depth_early, vt_depth_cubic};
    static vt_shape s3[3];
    static double xz[3 * NPTS * 2];
    double key[9], frac[3 * NPTS], rel[3 * NPTS];
    rig g;
    rig_make(&g, 0.0);
    vis_error err;
    for (int k = 0; k < 3; k++) {
        vt_arch_depth(&s3[k], NPTS, 0.2, 0.16, phis[k], SHEAR_M, depths[k]);
        profile_of(&s3[k], frac + k * NPTS, rel + k * NPTS);
        for (int j = 0; j < NPTS; j++) {
            xz[2 * (k * NPTS + j)] = (s3[k].pos[3 * j] - s3[k].pos[0]) * 1000.0;
            xz[2 * (k * NPTS + j) + 1] = (s3[k].pos[3 * j + 2] - s3[k].pos[2]) * 1000.0;
        }
        vis_render_truth truth;
        assert_int_equal(vis_renderer_draw(g.r, &s3[k].view, g.f, &truth, &err), VIS_OK);
        key[k] = SHEAR_M * 1000.0;
        key[3 + k] = truth.truth.dz_cam;
        key[6 + k] = truth.truth.a_cam;
    }
    for (int by_curve = 0; by_curve < 2; by_curve++)
    for (int k = 0; k < 3; k++) {
        /* keyed by Delta Z and A, then by the projections */
        const vis_depth_library lib = {3, NPTS, key, key + 3, key + 6, frac, rel, by_curve ? xz : NULL};
        g.tp.length_mm = length_3d(&s3[k]) * 1000.0;
        vis_tracker *tl = vis_tracker_create(&g.tp, &g.c, &err), *tp = vis_tracker_create(&g.tp, &g.c, &err),
                    *td = vis_tracker_create(&g.tp, &g.c, &err);
        assert_non_null(tl);
        assert_non_null(tp);
        assert_non_null(td);
        assert_int_equal(vis_tracker_set_depth_library(tl, &lib, &err), VIS_OK);
        assert_int_equal(vis_tracker_set_depth_profile(tp, frac + k * NPTS, rel + k * NPTS, NPTS, &err), VIS_OK);
        const result rl = measure(&g, tl, &s3[k]), rp = measure(&g, tp, &s3[k]), rd = measure(&g, td, &s3[k]);
        printf("%s shape %d: library %+.3f px %+.4f rad, its own profile %+.3f px %+.4f rad, default %+.3f px %+.4f rad\n",
               by_curve ? "by projection" : "by Delta Z, A", k, rl.edz_px, rl.ea, rp.edz_px, rp.ea, rd.edz_px, rd.ea);
        assert_true(fabs(rl.edz_px) < 0.15);
        assert_true(fabs(rl.ea) < 0.015);
        if (k < 2)
            assert_true(fabs(rd.edz_px) > 0.5); /* the default is wrong for the first two */
        vis_tracker_free(tl);
        vis_tracker_free(tp);
        vis_tracker_free(td);
    }
    rig_free(&g);
}

static void expect_refused(vis_status st, const vis_error *err)
{
    assert_int_equal(st, VIS_ERR_ARG);
    assert_true(strlen(err->message) > 10);
    printf("  refused: %s\n", err->message);
}

static void test_bad_profiles_are_refused(void **state)
{
    (void)state;
    rig g;
    double frac[NPTS], rel[NPTS], bad[NPTS];
    arch_case(&g, frac, rel);
    vis_error err;
    vis_tracker *t = vis_tracker_create(&g.tp, &g.c, &err);
    assert_non_null(t);
    assert_int_equal(vis_tracker_set_depth_profile(t, frac, rel, NPTS, &err), VIS_OK);
    expect_refused(vis_tracker_set_depth_profile(NULL, frac, rel, NPTS, &err), &err);
    expect_refused(vis_tracker_set_depth_profile(t, NULL, rel, NPTS, &err), &err);
    expect_refused(vis_tracker_set_depth_profile(t, frac, rel, 1, &err), &err);
    memcpy(bad, frac, sizeof bad);
    bad[10] = bad[9]; /* not increasing */
    expect_refused(vis_tracker_set_depth_profile(t, bad, rel, NPTS, &err), &err);
    memcpy(bad, frac, sizeof bad);
    bad[NPTS - 1] = 0.9 + 0.1 * bad[NPTS - 2]; /* does not end at 1 */
    expect_refused(vis_tracker_set_depth_profile(t, bad, rel, NPTS, &err), &err);
    memcpy(bad, rel, sizeof bad);
    bad[5] = NAN;
    expect_refused(vis_tracker_set_depth_profile(t, frac, bad, NPTS, &err), &err);
    bad[5] = 11.0; /* beyond +-10 shears */
    expect_refused(vis_tracker_set_depth_profile(t, frac, bad, NPTS, &err), &err);
    double key[3] = {40.0, 0.1, 0.0};
    static double xz[2 * NPTS];
    vis_depth_library lib = {1, NPTS, key, key + 1, key + 2, frac, rel, NULL};
    lib.xz_mm = xz;
    xz[7] = NAN;
    expect_refused(vis_tracker_set_depth_library(t, &lib, &err), &err);
    lib.xz_mm = NULL;
    lib.n_points = 1;
    expect_refused(vis_tracker_set_depth_library(t, &lib, &err), &err);
    lib.n_points = NPTS;
    lib.frac = NULL;
    expect_refused(vis_tracker_set_depth_library(t, &lib, &err), &err);
    lib.frac = frac;
    key[1] = INFINITY;
    expect_refused(vis_tracker_set_depth_library(t, &lib, &err), &err);
    key[1] = 0.1;
    lib.depth_rel = bad;
    expect_refused(vis_tracker_set_depth_library(t, &lib, &err), &err);
    /* The profile set first is still the one used. */
    const result r = measure(&g, t, &shape);
    assert_true(fabs(r.edz_px) < 0.15);
    /* No shapes: no library (accepted). */
    assert_int_equal(vis_tracker_set_depth_library(t, NULL, &err), VIS_OK);
    vis_tracker_free(t);
    rig_free(&g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_profile_puts_the_depth_right),
        cmocka_unit_test(test_library_takes_the_shape_shown),
        cmocka_unit_test(test_bad_profiles_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
