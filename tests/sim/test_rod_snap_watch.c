/* test_rod_snap_watch: a ribbon's own snap found step by step (sim/rod_snap_watch.h), on closed-form
 * input whose onset, detection and peak are known exactly:
 *   Delta Z(t) = 0.3 - 0.3 (1 + tanh u), u = (t - tc) / tau, so |dDeltaZ/dt| = (0.3 / tau) sech^2 u
 *   and the speed falls below a tenth of snap_speed at u_on = -acosh(sqrt(3 / (snap_speed tau)));
 *   A(t) = amp sech u, peaking at amp at the centre.
 * 1. The onset Delta W is the closed form's to within one step's Delta W (the watch keeps the last
 *    step below the slow speed; the finite difference lags the derivative by at most a step).
 * 2. The regime: amp 0.3 rad reads asymmetric, amp 0.02 symmetric (threshold 0.05); the peak is
 *    amp to the step's resolution.
 * 3. A bump of A after the first swing (Delta Z turned round) does not change the regime, but the
 *    peak over the 2 s after detection sees it; the report is final 2 s after detection.
 * 4. Non-finite states are ignored; a state that never moves fast is no snap. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>

#include "rod_snap_watch.h"

#define TC 5.0     /* s, centre of the fall */
#define TAU 0.05   /* s */
#define RATE 0.05  /* 1/s: Delta W = RATE t (10 mm/s on a 200 mm strip) */
#define SPEED 1.0  /* 1/s, snap.speed */

typedef struct bump {
    double amp;      /* rad, A during the fall */
    double late_amp; /* rad, A of a bump at t = TC + 0.5 s, after Delta Z turned round */
} bump;

/* Delta Z falls by 0.6 and then swings back up a little (turning round at TC + 3 tau). */
static void state_at(double t, const bump *b, rod_obs *o)
{
    double u = (t - TC) / TAU;
    o->dz = 0.3 - 0.3 * (1.0 + tanh(u));
    if (u > 3.0) o->dz += 0.02 * (1.0 - exp(-(u - 3.0)));
    o->a = b->amp / cosh(u) + b->late_amp / cosh((t - TC - 0.5) / TAU);
    o->a_cam = 0.9 * o->a;
    o->dz_cam = o->dz;
}

static rod_snap_report run(double h, const bump *b)
{
    rod_snap_watch w;
    rod_snap_watch_init(&w, SPEED, 0.05, 2.0);
    rod_obs o;
    for (long k = 0; k * h <= TC + 3.0; k++) {
        double t = k * h;
        state_at(t, b, &o);
        rod_snap_watch_add(&w, t, RATE * t, &o);
    }
    return w.r;
}

static void onset_matches_closed_form(void **state)
{
    (void)state;
    double u_on = -acosh(sqrt(3.0 / (SPEED * TAU)));
    double dw_exact = RATE * (TC + TAU * u_on);
    const double steps[] = {1e-3, 2e-3, 1.0 / 60.0, 1.0 / 30.0};
    for (int i = 0; i < 4; i++) {
        bump b = {0.3, 0.0};
        rod_snap_report r = run(steps[i], &b);
        printf("h = %.4f s: onset Delta W %.6f, closed form %.6f, difference %.2f steps\n", steps[i], r.snap_dw,
               dw_exact, (r.snap_dw - dw_exact) / (RATE * steps[i]));
        assert_true(r.snapped);
        assert_true(fabs(r.snap_dw - dw_exact) <= RATE * steps[i] + 1e-12);
        assert_true(r.t_detect > r.t_onset);
        assert_true(fabs(r.dt_max - steps[i]) < 1e-9);
    }
}

static void regime_from_peak(void **state)
{
    (void)state;
    bump asym = {0.3, 0.0}, sym = {0.02, 0.0};
    rod_snap_report r = run(1e-3, &asym);
    assert_true(r.asymmetric);
    assert_string_equal(rod_snap_report_regime(&r), "asymmetric");
    assert_true(fabs(r.peak_abs_a - 0.3) < 1e-3);
    assert_true(fabs(r.peak_abs_a_cam - 0.27) < 1e-3);
    r = run(1e-3, &sym);
    assert_false(r.asymmetric);
    assert_string_equal(rod_snap_report_regime(&r), "symmetric");
    assert_true(fabs(r.peak_abs_a - 0.02) < 1e-4);
}

static void after_the_swing_and_final(void **state)
{
    (void)state;
    bump late = {0.02, 0.4};
    rod_snap_report r = run(1e-3, &late);
    printf("late bump: peak over the passage %.4f, over 2 s %.4f, %s\n", r.peak_abs_a, r.peak_abs_a_post,
           rod_snap_report_regime(&r));
    assert_true(r.swing_over);
    assert_false(r.asymmetric);
    assert_true(r.peak_abs_a < 0.03);
    assert_true(fabs(r.peak_abs_a_post - 0.4) < 1e-3);
    assert_true(r.final);
    /* Before 2 s after detection it is not final. */
    rod_snap_watch w;
    rod_snap_watch_init(&w, SPEED, 0.05, 2.0);
    rod_obs o;
    for (double t = 0.0; t <= TC + 1.0; t += 1e-3) {
        state_at(t, &late, &o);
        rod_snap_watch_add(&w, t, RATE * t, &o);
    }
    assert_true(w.r.snapped);
    assert_false(w.r.final);
}

static void ignores_bad_and_quiet(void **state)
{
    (void)state;
    rod_snap_watch w;
    rod_snap_watch_init(&w, SPEED, 0.05, 2.0);
    rod_obs o = {0.3, 0.0, 0.0, 0.3};
    for (int k = 0; k < 1000; k++) {
        o.dz = 0.3 - 1e-4 * k * 1e-3; /* slow drift */
        rod_snap_watch_add(&w, k * 1e-3, RATE * k * 1e-3, &o);
    }
    rod_obs bad = {NAN, 0.0, 0.0, NAN};
    rod_snap_watch_add(&w, 1.0005, RATE, &bad); /* would be a jump of NaN */
    o.dz = 0.3;
    rod_snap_watch_add(&w, INFINITY, RATE, &o);
    assert_false(w.r.snapped);
    assert_string_equal(rod_snap_report_regime(&w.r), "no snap");
    assert_true(isfinite(w.r.snap_dw));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(onset_matches_closed_form),
        cmocka_unit_test(regime_from_peak),
        cmocka_unit_test(after_the_swing_and_final),
        cmocka_unit_test(ignores_bad_and_quiet),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
