/* test_rod_twin: the rail-driven twin is the same physics as the protocol.
 * 1. Compressing a twin mounted at Delta L = 0.3 to the scene's 0.5 (quasi-statically, as a rail
 *    would) and letting it settle ends in the upper state the documented route reaches directly
 *    (an independent path to the same equilibrium).
 * 2. Shearing the twin at the scene's constant rate, one advance per time step, snaps at the
 *    Delta W rod_predict finds (fixed step), with the same pathway: the twin's stepping, clamp
 *    interpolation and energy books add nothing of their own.
 *    The twin's own snap watch (rod_twin_snap) reports that same snap.
 * 3. Bad input is refused with a reason; halving recovers from a too-long advance. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "rod_protocol.h"
#include "rod_twin.h"

static rod_scene coarse(void)
{
    rod_scene s = rod_scene_default();
    s.nodes = 41;
    s.dt = 0.01;
    return s;
}

static void compress_then_settle(void **state)
{
    (void)state;
    rod_scene s = coarse();
    rod_prediction p;
    char err[256] = "";
    rod_predict_opts o = rod_predict_opts_default();
    s.shear_max = 1e-3; /* only the upper state is needed */
    assert_int_equal(rod_predict(&s, &o, &p, err, sizeof err), ROD_OK);

    rod_twin *tw = NULL;
    assert_int_equal(rod_twin_open(&s, 0.3, &tw, err, sizeof err), ROD_OK);
    rod_obs ob;
    rod_twin_observe(tw, &ob);
    assert_true(ob.dz > 0.0);
    /* 0.3 -> 0.5 over 20 s (10 mm/s for a 1 m ribbon), in 0.1 s chunks like camera frames. */
    double t = 0.0;
    for (int k = 1; k <= 200; k++) {
        t = 0.1 * k;
        assert_int_equal(rod_twin_advance(tw, t, 0.3 + 0.2 * k / 200.0, 0.0, err, sizeof err), ROD_OK);
    }
    for (int k = 1; k <= 300; k++) {
        t += 0.1;
        assert_int_equal(rod_twin_advance(tw, t, 0.5, 0.0, err, sizeof err), ROD_OK);
    }
    rod_twin_observe(tw, &ob);
    printf("twin upper state Delta Z %.6f, route %.6f, difference %.2e, kinetic %.2e J\n", ob.dz, p.dz_upper,
           fabs(ob.dz - p.dz_upper), rod_twin_kinetic(tw));
    assert_true(fabs(ob.dz - p.dz_upper) < 1e-4);
    printf("twin upper state A %.3e (imperfection-sized)\n", ob.a);
    assert_true(fabs(ob.a) < 1e-4);
    rod_twin_close(tw);
}

static void shear_snaps_as_predicted(void **state)
{
    (void)state;
    rod_scene s = coarse();
    s.shear_max = 0.6;
    rod_prediction p;
    char err[256] = "";
    rod_predict_opts o = rod_predict_opts_default();
    assert_int_equal(rod_predict(&s, &o, &p, err, sizeof err), ROD_OK);
    assert_true(p.snapped);

    rod_twin *tw = NULL;
    assert_int_equal(rod_twin_open(&s, s.compression, &tw, err, sizeof err), ROD_OK);
    double rate = s.shear_rate / s.length, slow = 0.1 * s.snap_speed;
    rod_obs ob;
    rod_twin_observe(tw, &ob);
    double dz_prev = ob.dz, onset = 0.0, peak = 0.0, snap = -1.0, t_detect = 0.0;
    for (long k = 1; k < 100000; k++) {
        double t = s.dt * (double)k, dw = rate * t;
        assert_int_equal(rod_twin_advance(tw, t, s.compression, dw, err, sizeof err), ROD_OK);
        rod_twin_observe(tw, &ob);
        double speed = fabs(ob.dz - dz_prev) / s.dt;
        dz_prev = ob.dz;
        if (snap < 0.0) {
            if (speed < slow) {
                onset = dw;
                peak = fabs(ob.a);
            } else {
                peak = fmax(peak, fabs(ob.a));
            }
            if (speed > s.snap_speed) {
                snap = onset;
                t_detect = t;
            }
            if (dw > s.shear_max) break;
        } else {
            peak = fmax(peak, fabs(ob.a));
            if (t - t_detect > 2.0) break;
        }
    }
    printf("twin snap Delta W %.6f (peak |A| %.3f), predict %.6f (peak |A| %.3f)\n", snap, peak, p.snap_dw,
           p.peak_abs_a);
    assert_true(snap > 0.0);
    assert_true(fabs(snap - p.snap_dw) < 1e-6 * p.snap_dw + 1e-9);
    assert_int_equal(peak > s.asym_threshold, p.asymmetric);
    /* The twin's own watch (rod_twin_snap, fed every accepted step since the open) finds the same
     * snap and the same peak over 2 s; its regime is decided over the first swing. */
    rod_snap_report tr;
    rod_twin_snap(tw, &tr);
    printf("twin's own watch: Delta W %.6f, peak |A| %.3f over the passage, %.3f over 2 s, %s\n", tr.snap_dw,
           tr.peak_abs_a, tr.peak_abs_a_post, rod_snap_report_regime(&tr));
    assert_true(tr.snapped && tr.final);
    assert_true(fabs(tr.snap_dw - p.snap_dw) < 1e-6 * p.snap_dw + 1e-9);
    assert_true(fabs(tr.peak_abs_a_post - p.peak_abs_a) < 1e-6);
    assert_int_equal(tr.peak_abs_a_post > s.asym_threshold, p.asymmetric);
    assert_true(tr.peak_abs_a <= tr.peak_abs_a_post);
    rod_twin_close(tw);
}

static void refuses_bad_input(void **state)
{
    (void)state;
    rod_scene s = coarse();
    char err[256] = "";
    rod_twin *tw = NULL;
    assert_int_not_equal(rod_twin_open(&s, 1.5, &tw, err, sizeof err), ROD_OK);
    assert_null(tw);
    assert_non_null(strstr(err, "Delta L"));
    assert_int_equal(rod_twin_open(&s, 0.5, &tw, err, sizeof err), ROD_OK);
    assert_int_not_equal(rod_twin_advance(tw, NAN, 0.5, 0.0, err, sizeof err), ROD_OK);
    assert_non_null(strstr(err, "bad advance"));
    assert_int_equal(rod_twin_advance(tw, 1.0, 0.5, 0.0, err, sizeof err), ROD_OK);
    assert_int_not_equal(rod_twin_advance(tw, 0.5, 0.5, 0.0, err, sizeof err), ROD_OK); /* backwards */
    /* A big jump of the clamp in one advance is taken in dt steps (and halvings if needed). */
    assert_int_equal(rod_twin_advance(tw, 3.0, 0.5, 0.05, err, sizeof err), ROD_OK);
    assert_true(fabs(rod_twin_time(tw) - 3.0) < 1e-12);
    rod_obs ob;
    rod_twin_observe(tw, &ob);
    assert_true(isfinite(ob.dz) && ob.dz > 0.0);
    rod_twin_close(tw);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(compress_then_settle),
        cmocka_unit_test(shear_snaps_as_predicted),
        cmocka_unit_test(refuses_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
