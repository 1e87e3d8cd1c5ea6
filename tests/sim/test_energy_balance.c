/* test_energy_balance: the dynamics conserve energy up to what they should lose.
 * Elastic plus kinetic energy changes by the work of the moving clamps minus the damping losses
 * minus the integrator's own dissipation; implicit Euler is first order, so that dissipation
 * must be positive and shrink in proportion to dt (observed order printed, required in
 * [0.8, 1.2]). A fast shear of a coarse creased ribbon gives the ribbon real motion. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "rod_protocol.h"

typedef struct tally {
    rod_sample last;
} tally;

static int record(void *user, const rod_sample *s, const rod *r)
{
    (void)r;
    tally *t = user;
    t->last = *s;
    return 0;
}

/* Returns the integrator's dissipation: work - damping - change of (elastic + kinetic). */
static double dissipation(double dt, double *work, double *damped)
{
    rod_scene s = rod_scene_default();
    s.nodes = 21;
    s.width = 0.05;
    s.fold_stiffness_factor = 10.0;
    s.shear_rate = 0.2;
    s.shear_max = 0.15;
    s.dt = dt;
    s.damping = 0.5;
    s.snap_speed = 1e9; /* no snap detection: a fixed window of motion */
    s.tolerance = 1e-9;
    s.max_iterations = 100;
    tally t;
    memset(&t, 0, sizeof t);
    rod_predict_opts o = rod_predict_opts_default();
    o.on_sample = record;
    o.ramp_time = 0.4; /* a smooth start: a sudden one excites modes implicit Euler kills at O(1) */
    o.user = &t;
    rod_prediction p;
    char err[256] = "";
    assert_int_equal(rod_predict(&s, &o, &p, err, sizeof err), ROD_OK);
    double e_start = p.elastic_upper;
    *work = t.last.work;
    *damped = t.last.damped;
    return t.last.work - t.last.damped - (t.last.elastic + t.last.kinetic - e_start);
}

static void test_dissipation_first_order(void **state)
{
    (void)state;
    double w1, d1, w2, d2, w3, d3;
    double x1 = dissipation(2e-3, &w1, &d1);
    double x2 = dissipation(1e-3, &w2, &d2);
    double x3 = dissipation(5e-4, &w3, &d3);
    print_message("dt 2e-3: work %.6e damped %.6e integrator %.6e\n", w1, d1, x1);
    print_message("dt 1e-3: work %.6e damped %.6e integrator %.6e\n", w2, d2, x2);
    print_message("dt 5e-4: work %.6e damped %.6e integrator %.6e\n", w3, d3, x3);
    double p1 = log2(x1 / x2), p2 = log2(x2 / x3);
    print_message("observed orders of the integrator dissipation: %.3f %.3f\n", p1, p2);
    assert_true(x1 > 0 && x2 > 0 && x3 > 0);
    assert_true(fabs(w3) > 10.0 * fabs(x3)); /* the balance is not trivially small */
    assert_true(p1 > 0.8 && p1 < 1.2);
    assert_true(p2 > 0.8 && p2 < 1.2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dissipation_first_order),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
