/* test_fast_predict: the fast prediction (quasi-static start, rod_quasi.h; longer post-snap
 * steps) against the fixed-step prediction of the same scene, on coarsened paper scenes of both
 * regimes: same regime, snap Delta W within 0.5% (the bench's target), the dynamics started
 * on the static branch before the snap, a step budget, and the end after the snap's first
 * swing with that swing's peak |A|. Small enough for the sanitizer build. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>

#include "rod_protocol.h"

static rod_scene coarse_paper(double gamma)
{
    rod_scene s = rod_scene_default();
    s.fold_position = gamma;
    s.nodes = 41;
    s.dt = 5e-3;
    s.shear_max = 0.6;
    return s;
}

/* The fixed run's first swing, from its samples: the snap is detected at the first step faster
 * than snap.speed; the swing ends where Delta Z turns round; the peak |A| of the passage is taken
 * from the onset (the last step slower than a tenth of snap.speed) to that turn. */
typedef struct swing {
    double snap_speed, t_prev, dz_prev, dir, peak, peak_since_slow;
    double t_detect, t_turn;
    int started, detected, over;
} swing;

static int on_fixed_sample(void *user, const rod_sample *smp, const rod *r)
{
    (void)r;
    swing *w = user;
    if (w->started && !w->over) {
        double v = (smp->dz - w->dz_prev) / (smp->t - w->t_prev);
        if (!w->detected) {
            if (fabs(v) < 0.1 * w->snap_speed) w->peak_since_slow = fabs(smp->a);
            else w->peak_since_slow = fmax(w->peak_since_slow, fabs(smp->a));
            if (fabs(v) > w->snap_speed) {
                w->detected = 1;
                w->t_detect = smp->t;
                w->dir = v > 0.0 ? 1.0 : -1.0;
                w->peak = w->peak_since_slow;
            }
        } else if (v * w->dir < 0.0) {
            w->over = 1;
            w->t_turn = smp->t;
        } else {
            w->peak = fmax(w->peak, fabs(smp->a));
        }
    }
    w->started = 1;
    w->t_prev = smp->t;
    w->dz_prev = smp->dz;
    return 0;
}

static void check(double gamma, int asymmetric)
{
    rod_scene s = coarse_paper(gamma);
    rod_predict_opts fixed = rod_predict_opts_default(), fast = rod_predict_opts_fast(&s);
    swing w = {.snap_speed = s.snap_speed};
    fixed.on_sample = on_fixed_sample;
    fixed.user = &w;
    rod_prediction pf, pq;
    char err[256] = "";
    assert_int_equal(rod_predict(&s, &fixed, &pf, err, sizeof err), ROD_OK);
    assert_int_equal(rod_predict(&s, &fast, &pq, err, sizeof err), ROD_OK);
    assert_true(pf.snapped && pq.snapped);
    double rel = fabs(pq.snap_dw - pf.snap_dw) / pf.snap_dw;
    printf("Gamma %.2f: fixed %.5f fast %.5f (rel %.1e), dynamics from %.3f after %d static solves, "
           "steps %ld vs %ld\n", gamma, pf.snap_dw, pq.snap_dw, rel, pq.dw_switch, pq.quasi_solves, pf.steps, pq.steps);
    assert_true(rel < 5e-3);
    assert_int_equal(pf.asymmetric, asymmetric);
    assert_int_equal(pq.asymmetric, asymmetric);
    assert_true(pq.quasi_solves > 0 && pq.dw_switch > 0.0 && pq.dw_switch < pq.snap_dw - 0.01);
    /* The step control: the fast run takes under 5% of the fixed run's steps (the earlier
     * threshold rules took 8% on the Gamma 0.13 scene). */
    assert_true(pq.steps < pf.steps / 20);
    /* The fast run stops at the end of the first swing, where the fixed run's swing ended (to
     * the snap's own shift in time), and its peak |A| is the passage's. */
    assert_true(w.over);
    printf("  first swing: fixed %.3f-%.3f s, peak |A| %.4g; fast ended at %.3f s, peak |A| %.4g "
           "(fixed over 2 s: %.4g)\n", w.t_detect, w.t_turn, w.peak, pq.sim_time, pq.peak_abs_a, pf.peak_abs_a);
    double shift_t = (pq.snap_dw - pf.snap_dw) * s.length / s.shear_rate;
    assert_true(fabs(pq.sim_time - (w.t_turn + shift_t)) < 0.05);
    assert_true(pq.sim_time < pf.sim_time - 1.0);
    if (asymmetric) assert_true(fabs(pq.peak_abs_a - w.peak) < 0.05 * w.peak);
}

static void test_pitchfork_scene(void **st) { (void)st; check(0.13, 1); }
static void test_saddle_node_scene(void **st) { (void)st; check(0.21, 0); }

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pitchfork_scene),
        cmocka_unit_test(test_saddle_node_scene),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
