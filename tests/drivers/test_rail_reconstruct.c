/* test_rail_reconstruct.c: the front end's reconstruction between device readings (rail.h,
 * "Reconstruction"), on a virtual clock so every run is the same.
 *
 * Against the mock: a "seen" mock rail read through rail_status_get() at its 10 Hz poll rate and
 * a "truth" twin given the same commands and read every millisecond with rail_status_poll().
 * Bounds, derived from rail_axis (the mock's kinematics):
 *   - cruising at the commanded speed s, both the reconstruction and the axis advance exactly
 *     s dt from the reading (the axis's trapezoid rule is exact for a constant velocity), so the
 *     distances travelled since the reading agree to rounding: CRUISE_TOL = 1e-9 mm (the two
 *     mocks integrate their ramps on different sub-step grids, so their positions differ by a
 *     few 1e-6 mm: that offset is in the next bound, not in this one);
 *   - over a whole move, ramps and the braking onto the target included, the axis applies its
 *     velocity law once per integration sub-step (h <= 1 ms) and brakes with a discrete stopping
 *     speed that is at most a h / 2 lower than sqrt(2 a d); each of those shifts its motion by at
 *     most one sub-step in time, so the two differ by at most s h: MOVE_TOL = s * 1 ms.
 * Against a scripted driver (readings set by the test): the target cap when the reading is too
 * fast to stop in time, the stop distance, home's measured velocity, and that a fresh reading
 * replaces whatever was reconstructed. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "rail_mock.h"

#define CRUISE_TOL 1e-9
#define AXIS_SUBSTEP_S 1e-3
#define NEAR(a, b, tol) assert_true(fabs((a) - (b)) <= (tol))

static rail_params params(void)
{
    rail_params p = rail_params_default();
    strcpy(p.name, "shear");
    p.soft_min_mm = 0.0;
    p.soft_max_mm = 100.0;
    p.max_speed_mm_s = 20.0;
    p.accel_mm_s2 = 100.0;
    p.poll_hz = 10.0;
    return p;
}

static rail *open_mock(rail_vclock *vc)
{
    rail_params p = params();
    rail_mock_params m = rail_mock_params_default();
    rail *r = NULL;
    char why[256];
    assert_int_equal(rail_mock_open(&r, &p, &m, rail_clock_virtual(vc), why, sizeof why), RAIL_OK);
    return r;
}

/* Run seen and truth side by side for duration_s in 1 ms steps; returns the largest position
 * difference over all reconstructed statuses, and (in *cruise_err) over those where the reading,
 * the reconstruction and the truth all move at the commanded speed s. Also checks that no status
 * passes target (dir = sign of the move). */
static double track(rail_vclock *vc, rail *seen, rail *truth, double duration_s, double s,
                    double target, double dir, double *cruise_err, int *n_recon)
{
    double worst = 0.0;
    *cruise_err = 0.0;
    *n_recon = 0;
    int steps = (int)lround(duration_s / 1e-3);
    /* The reading the reconstruction starts from, and where the truth was at that time. */
    double read_v = 0.0, read_p = 0.0, truth_p = 0.0;
    for (int i = 0; i < steps; i++) {
        rail_clock_sleep(rail_clock_virtual(vc), 1e-3);
        rail_status a, b;
        assert_int_equal(rail_status_get(seen, &a), RAIL_OK);
        assert_int_equal(rail_status_poll(truth, &b), RAIL_OK);
        assert_true((a.position_mm - target) * dir <= 0.0); /* never past the target */
        /* Fresh readings count too: the two mocks integrate on different sub-step grids. */
        double err = fabs(a.position_mm - b.position_mm);
        worst = fmax(worst, err);
        if (!a.extrapolated) {
            read_v = a.velocity_mm_s;
            read_p = a.position_mm;
            truth_p = b.position_mm;
            continue;
        }
        (*n_recon)++;
        rail_status again;
        assert_int_equal(rail_status_get(seen, &again), RAIL_OK); /* same time: same answer */
        assert_true(again.position_mm == a.position_mm);
        if (fabs(fabs(read_v) - s) < 1e-12 && fabs(fabs(a.velocity_mm_s) - s) < 1e-12 &&
            fabs(fabs(b.velocity_mm_s) - s) < 1e-12)
            *cruise_err = fmax(*cruise_err,
                               fabs((a.position_mm - read_p) - (b.position_mm - truth_p)));
    }
    return worst;
}

static void test_move_matches_mock_kinematics(void **st)
{
    (void)st;
    /* Long trapezoid moves both ways, a short triangle move, a slow one. */
    const double from[] = {0.0, 0.0, 90.0, 10.0, 40.0};
    const double to[] = {90.0, 60.0, 5.0, 10.4, 43.0};
    const double speed[] = {20.0, 13.0, 17.5, 20.0, 0.5};
    for (int k = 0; k < 5; k++) {
        rail_vclock vc = {0};
        rail *seen = open_mock(&vc), *truth = open_mock(&vc);
        if (from[k] > 0.0) {
            assert_int_equal(rail_move_abs(seen, from[k], 20.0), RAIL_OK);
            assert_int_equal(rail_move_abs(truth, from[k], 20.0), RAIL_OK);
            assert_int_equal(rail_wait_idle(seen, 20.0, NULL), RAIL_OK);
            assert_int_equal(rail_wait_idle(truth, 20.0, NULL), RAIL_OK);
        }
        /* Start off the poll grid so readings fall at odd moments of the profile. */
        rail_clock_sleep(rail_clock_virtual(&vc), 0.0137);
        assert_int_equal(rail_move_abs(seen, to[k], speed[k]), RAIL_OK);
        assert_int_equal(rail_move_abs(truth, to[k], speed[k]), RAIL_OK);
        double dir = to[k] > from[k] ? 1.0 : -1.0;
        double dur = fabs(to[k] - from[k]) / speed[k] + speed[k] / 100.0 + 0.3;
        double cruise, worst;
        int n;
        worst = track(&vc, seen, truth, dur, speed[k], to[k], dir, &cruise, &n);
        double move_tol = speed[k] * AXIS_SUBSTEP_S;
        print_message("move %g -> %g at %g: %d reconstructed, worst %.3g mm (bound %.3g), "
                      "cruising %.3g mm (bound %.0e)\n",
                      from[k], to[k], speed[k], n, worst, move_tol, cruise, CRUISE_TOL);
        assert_true(n > 100);
        assert_true(worst <= move_tol);
        assert_true(cruise <= CRUISE_TOL);
        rail_status a;
        assert_int_equal(rail_status_poll(seen, &a), RAIL_OK);
        assert_int_equal(a.state, RAIL_STATE_IDLE);
        assert_true(a.position_mm == to[k]);
        rail_close(seen);
        rail_close(truth);
    }
}

static void test_jog_matches_mock_kinematics(void **st)
{
    (void)st;
    rail_vclock vc = {0};
    rail *seen = open_mock(&vc), *truth = open_mock(&vc);
    assert_int_equal(rail_jog(seen, 0.5), RAIL_OK); /* the slow shear ramp */
    assert_int_equal(rail_jog(truth, 0.5), RAIL_OK);
    double cruise;
    int n;
    double worst = track(&vc, seen, truth, 3.0, 0.5, 100.0, 1.0, &cruise, &n);
    print_message("jog at 0.5 mm/s: worst %.3g mm, cruising %.3g mm\n", worst, cruise);
    assert_true(worst <= 0.5 * AXIS_SUBSTEP_S);
    assert_true(cruise <= CRUISE_TOL);
    rail_close(seen);
    rail_close(truth);
}

static void test_stop_stays_within_stop_distance(void **st)
{
    (void)st;
    const double stop_at[] = {0.3, 1.0, 1.05, 2.0};
    for (int k = 0; k < 4; k++) {
        rail_vclock vc = {0};
        rail *seen = open_mock(&vc);
        assert_int_equal(rail_jog(seen, 20.0), RAIL_OK);
        double t = 0.0;
        rail_status a;
        while (t < stop_at[k]) { /* poll as a runner would */
            rail_clock_sleep(rail_clock_virtual(&vc), 1e-3);
            t += 1e-3;
            assert_int_equal(rail_status_get(seen, &a), RAIL_OK);
        }
        /* The last status before the stop (reconstructed or read) is where the runner thinks the
           rail is; what the device does from there is bounded by the stop distance. */
        double p_stop = a.position_mm, v_stop = a.velocity_mm_s;
        assert_true(v_stop > 19.0);
        double d_max = rail_stop_distance_mm(seen, v_stop);
        assert_int_equal(rail_stop(seen), RAIL_OK);
        double prev = p_stop;
        for (int i = 0; i < 600; i++) {
            rail_clock_sleep(rail_clock_virtual(&vc), 1e-3);
            assert_int_equal(rail_status_get(seen, &a), RAIL_OK);
            assert_true(a.position_mm >= prev - 1e-12); /* braking never reverses */
            /* The mock's own last sub-step may add up to 1e-6 mm (test_rail_mock.c). */
            assert_true(a.position_mm - p_stop <= d_max + (a.extrapolated ? 1e-9 : 1e-6));
            prev = a.position_mm;
        }
        assert_int_equal(a.state, RAIL_STATE_IDLE);
        NEAR(a.position_mm - p_stop, d_max, 0.05);
        rail_close(seen);
    }
}

/* A scripted driver: poll returns whatever the test put in `next`. */
typedef struct script {
    rail_status next;
    int moves, stops, homes;
    rail_err fail_move;
} script;

static rail_err sc_poll(rail *r, void *impl, rail_status *out)
{
    (void)r;
    *out = ((script *)impl)->next;
    return RAIL_OK;
}
static rail_err sc_move(rail *r, void *impl, double target, double speed)
{
    script *s = impl;
    s->moves++;
    if (s->fail_move != RAIL_OK)
        return rail_set_error(r, s->fail_move, "scripted failure sending move to %g at %g", target,
                              speed);
    return RAIL_OK;
}
static rail_err sc_stop(rail *r, void *impl)
{
    (void)r;
    ((script *)impl)->stops++;
    return RAIL_OK;
}
static rail_err sc_home(rail *r, void *impl)
{
    (void)r;
    ((script *)impl)->homes++;
    return RAIL_OK;
}

static const rail_ops script_ops = {
    .name = "script", .poll = sc_poll, .move_abs = sc_move, .stop = sc_stop, .estop = sc_stop,
    .home = sc_home, .close = NULL,
};

static rail *open_script(rail_vclock *vc, script *s)
{
    rail_params p = params();
    memset(s, 0, sizeof *s);
    s->next.state = RAIL_STATE_IDLE;
    rail *r = NULL;
    char why[256];
    assert_int_equal(rail_create(&r, &p, rail_clock_virtual(vc), &script_ops, s, why, sizeof why),
                     RAIL_OK);
    return r;
}

static void reading(script *s, rail_state state, double pos, double vel)
{
    s->next.state = state;
    s->next.position_mm = pos;
    s->next.velocity_mm_s = vel;
}

/* Advance to t (s) and read a status through the rate limiter. */
static rail_status at(rail_vclock *vc, rail *r, double t)
{
    vc->t_s = t;
    rail_status st;
    assert_int_equal(rail_status_get(r, &st), RAIL_OK);
    return st;
}

static void test_never_passes_target(void **st)
{
    (void)st;
    rail_vclock vc = {0};
    script s;
    rail *r = open_script(&vc, &s);
    /* Commanded to 10 mm; the reading says 9.9 mm at 20 mm/s toward it: 2 mm of braking needed
       for 0.1 mm left. The reconstruction brakes and stops on 10, never beyond. */
    reading(&s, RAIL_STATE_IDLE, 9.0, 0.0);
    assert_int_equal(rail_move_abs(r, 10.0, 20.0), RAIL_OK);
    reading(&s, RAIL_STATE_MOVING, 9.9, 20.0);
    rail_status a = at(&vc, r, 0.0);
    assert_false(a.extrapolated);
    double prev = a.position_mm;
    for (int i = 1; i < 100; i++) {
        a = at(&vc, r, i * 1e-3);
        assert_true(a.extrapolated);
        assert_true(a.position_mm <= 10.0);
        assert_true(a.position_mm >= prev);
        prev = a.position_mm;
    }
    assert_true(a.position_mm == 10.0);
    assert_true(a.velocity_mm_s == 0.0);
    /* The same, moving down, from a reading at the far side moving away (it came back). */
    vc.t_s = 1.0;
    reading(&s, RAIL_STATE_IDLE, 50.0, 0.0);
    assert_int_equal(rail_move_abs(r, 40.0, 15.0), RAIL_OK);
    reading(&s, RAIL_STATE_MOVING, 39.0, -5.0);
    a = at(&vc, r, 1.0);
    for (int i = 1; i < 100; i++) {
        a = at(&vc, r, 1.0 + i * 1e-3);
        assert_true(a.position_mm <= 40.0); /* heading back up to 40, never above */
    }
    /* A reading moving toward the target at cruise: the reconstruction reaches it, stops there. */
    vc.t_s = 2.0;
    reading(&s, RAIL_STATE_IDLE, 40.0, 0.0);
    assert_int_equal(rail_move_abs(r, 41.0, 20.0), RAIL_OK);
    reading(&s, RAIL_STATE_MOVING, 40.0, 0.0);
    a = at(&vc, r, 2.0);
    for (int i = 1; i < 100; i++) {
        a = at(&vc, r, 2.0 + i * 1e-3);
        assert_true(a.position_mm <= 41.0);
    }
    /* Triangle: peak sqrt(a L) = 10 mm/s after 0.1 s, at rest on 41 after 0.2 s. */
    NEAR(a.position_mm, 40.0 + 0.5 * 100.0 * 0.099 * 0.099, 1e-9);
    rail_close(r);
}

static void test_stop_from_reading(void **st)
{
    (void)st;
    rail_vclock vc = {0};
    script s;
    rail *r = open_script(&vc, &s);
    assert_int_equal(rail_jog(r, -20.0), RAIL_E_LIMIT); /* at 0: refused, nothing recorded */
    assert_int_equal(rail_jog(r, 20.0), RAIL_OK);
    reading(&s, RAIL_STATE_MOVING, 30.0, 20.0);
    rail_status a = at(&vc, r, 0.0);
    a = at(&vc, r, 0.05);
    NEAR(a.position_mm, 31.0, 1e-12); /* cruising toward the jog's end at 100 */
    assert_int_equal(rail_stop(r), RAIL_OK);
    reading(&s, RAIL_STATE_MOVING, 31.0, 20.0);
    a = at(&vc, r, 0.05);
    assert_false(a.extrapolated);
    double d = 20.0 * 20.0 / (2.0 * 100.0);
    NEAR(d, rail_stop_distance_mm(r, 20.0), 1e-12);
    a = at(&vc, r, 0.10);
    NEAR(a.position_mm, 31.0 + 20.0 * 0.05 - 50.0 * 0.05 * 0.05, 1e-12);
    NEAR(a.velocity_mm_s, 15.0, 1e-12);
    for (double t = 0.06; t < 0.149; t += 1e-3) {
        a = at(&vc, r, t);
        assert_true(a.position_mm <= 31.0 + d + 1e-12);
    }
    /* At rest after v/a = 0.2 s; the poll period (0.1 s) ends first, then a reading is taken. */
    assert_true(a.extrapolated);
    /* estop is modelled the same way. */
    reading(&s, RAIL_STATE_MOVING, 33.0, -8.0);
    assert_int_equal(rail_estop(r), RAIL_OK);
    a = at(&vc, r, 0.2);
    a = at(&vc, r, 0.29);
    NEAR(a.position_mm, 33.0 - 0.32, 1e-12); /* 8^2 / 200, at rest after 0.08 s */
    assert_true(a.velocity_mm_s == 0.0);
    rail_close(r);
}

static void test_home_and_unknown_use_measured_velocity(void **st)
{
    (void)st;
    rail_vclock vc = {0};
    script s;
    rail *r = open_script(&vc, &s);
    assert_int_equal(rail_home(r, true), RAIL_OK);
    reading(&s, RAIL_STATE_HOMING, 20.0, -5.0);
    rail_status a = at(&vc, r, 1.0);
    a = at(&vc, r, 1.08);
    assert_true(a.extrapolated);
    NEAR(a.position_mm, 20.0 - 5.0 * 0.08, 1e-12);
    /* A move the driver failed to send: the device's motion is unknown, so measured velocity. */
    reading(&s, RAIL_STATE_IDLE, 20.0, 0.0);
    s.fail_move = RAIL_E_IO;
    assert_int_equal(rail_move_abs(r, 80.0, 10.0), RAIL_E_IO);
    assert_non_null(strstr(rail_last_error(r), "scripted failure"));
    reading(&s, RAIL_STATE_MOVING, 20.0, 3.0);
    a = at(&vc, r, 2.0);
    a = at(&vc, r, 2.05);
    NEAR(a.position_mm, 20.15, 1e-12);
    /* A move refused by the front end sends nothing and keeps the standing command. */
    s.fail_move = RAIL_OK;
    assert_int_equal(rail_move_abs(r, 30.0, 10.0), RAIL_OK);
    int sent = s.moves;
    assert_int_equal(rail_move_abs(r, 130.0, 10.0), RAIL_E_LIMIT);
    assert_int_equal(s.moves, sent);
    reading(&s, RAIL_STATE_MOVING, 29.9, 10.0);
    a = at(&vc, r, 3.0);
    a = at(&vc, r, 3.09);
    assert_true(a.position_mm <= 30.0);
    NEAR(a.position_mm, 30.0, 1e-12);
    rail_close(r);
}

static void test_fresh_reading_replaces_reconstruction(void **st)
{
    (void)st;
    rail_vclock vc = {0};
    script s;
    rail *r = open_script(&vc, &s);
    assert_int_equal(rail_move_abs(r, 50.0, 10.0), RAIL_OK);
    reading(&s, RAIL_STATE_MOVING, 0.0, 10.0);
    rail_status a = at(&vc, r, 0.0);
    a = at(&vc, r, 0.05);
    assert_true(a.extrapolated);
    NEAR(a.position_mm, 0.5, 1e-12);
    /* The device disagrees (a slip, a blocked carriage): the next reading wins entirely. */
    reading(&s, RAIL_STATE_MOVING, 0.2, 0.0);
    s.next.code = 7;
    a = at(&vc, r, 0.1);
    assert_false(a.extrapolated);
    assert_true(a.t_s == 0.1);
    assert_true(a.position_mm == 0.2 && a.velocity_mm_s == 0.0 && a.code == 7);
    a = at(&vc, r, 0.12); /* reconstructed from the new reading: ramping up from rest */
    assert_true(a.extrapolated && a.t_s == 0.1);
    NEAR(a.position_mm, 0.2 + 0.5 * 100.0 * 0.02 * 0.02, 1e-12);
    /* rail_status_poll reads at once, inside the poll period too. */
    reading(&s, RAIL_STATE_MOVING, 7.0, 1.0);
    vc.t_s = 0.13;
    assert_int_equal(rail_status_poll(r, &a), RAIL_OK);
    assert_true(a.position_mm == 7.0 && !a.extrapolated && a.t_s == 0.13);
    a = at(&vc, r, 0.14);
    assert_true(a.t_s == 0.13 && a.extrapolated);
    /* A reading that is not moving is never reconstructed. */
    reading(&s, RAIL_STATE_FAULT, 7.5, 4.0);
    assert_int_equal(rail_status_poll(r, &a), RAIL_OK);
    a = at(&vc, r, 0.2);
    assert_false(a.extrapolated);
    assert_true(a.position_mm == 7.5);
    rail_close(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_move_matches_mock_kinematics),
        cmocka_unit_test(test_jog_matches_mock_kinematics),
        cmocka_unit_test(test_stop_stays_within_stop_distance),
        cmocka_unit_test(test_never_passes_target),
        cmocka_unit_test(test_stop_from_reading),
        cmocka_unit_test(test_home_and_unknown_use_measured_velocity),
        cmocka_unit_test(test_fresh_reading_replaces_reconstruction),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
