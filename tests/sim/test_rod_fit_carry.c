/* test_rod_fit_carry: a refresh's prior on the crease positions from fit 0's (sim/rod_fit_carry.h,
 * issue 32 A/B/D): the width is fit 0's standard error between the floor and the tolerance, the
 * centre fit 0's values, the other priors' centres the specimen's, the model at fit 0's strip; and
 * the fit takes a prior's centre apart from the scene (rod_fit_opts.prior_centre), in closed form. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "fit_scene_kit.h"
#include "rod_fit_carry.h"

/* The width: se itself inside [floor, cap], clipped outside it, the cap where se is unknown. */
static void sigma_between_floor_and_cap(void **state)
{
    (void)state;
    assert_true(rod_fit_carry_sigma(0.0003, 0.001, 0.006) == 0.001);
    assert_true(rod_fit_carry_sigma(0.0026, 0.001, 0.006) == 0.0026);
    assert_true(rod_fit_carry_sigma(0.02, 0.001, 0.006) == 0.006);
    assert_true(rod_fit_carry_sigma(INFINITY, 0.001, 0.006) == 0.006);
    assert_true(rod_fit_carry_sigma(NAN, 0.001, 0.006) == 0.006);
}

#define NEAR(a, b) assert_true(fabs((a) - (b)) < 1e-12)

/* Both positions: fitted with their carried widths around fit 0's values; the scene becomes fit
 * 0's strip (every value); the other priors keep their widths and their centres on the
 * specimen's values; the default bounds are the specimen's (fit 0's). */
static void positions_carried(void **state)
{
    (void)state;
    rod_scene sc = fit_kit_pet(31);
    double spec[ROD_FIT_NKEYS], v[ROD_FIT_NKEYS], u0[ROD_FIT_NKEYS], se0[ROD_FIT_NKEYS], centre[ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, spec);
    memcpy(u0, spec, sizeof u0);
    u0[ROD_FIT_ANGLE_LEFT] += 3.0; /* fit 0 moved an angle and both positions */
    u0[ROD_FIT_POSITION_LEFT] += 0.002;
    u0[ROD_FIT_POSITION_RIGHT] -= 0.003;
    for (int k = 0; k < ROD_FIT_NKEYS; k++) se0[k] = INFINITY;
    se0[ROD_FIT_POSITION_LEFT] = 0.0003;
    se0[ROD_FIT_POSITION_RIGHT] = 0.0025;
    rod_fit_opts o = rod_fit_opts_default(), before;
    o.fit[ROD_FIT_ANGLE_LEFT] = 1;
    o.prior_sigma[ROD_FIT_ANGLE_LEFT] = 7.6;
    before = o;
    assert_int_equal(rod_fit_carry_positions(u0, se0, ROD_FIT_CARRY_FLOOR, 0.006, &sc, &o, centre), 1);
    rod_fit_scene_values(&sc, v);
    for (int k = 0; k < ROD_FIT_NKEYS; k++) NEAR(v[k], u0[k]);
    assert_true(o.prior_centre == centre);
    assert_true(o.fit[ROD_FIT_POSITION_LEFT] && o.fit[ROD_FIT_POSITION_RIGHT]);
    assert_true(o.prior_sigma[ROD_FIT_POSITION_LEFT] == ROD_FIT_CARRY_FLOOR);
    assert_true(o.prior_sigma[ROD_FIT_POSITION_RIGHT] == 0.0025);
    NEAR(centre[ROD_FIT_POSITION_LEFT], u0[ROD_FIT_POSITION_LEFT]);
    NEAR(centre[ROD_FIT_POSITION_RIGHT], u0[ROD_FIT_POSITION_RIGHT]);
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        if (k == ROD_FIT_POSITION_LEFT || k == ROD_FIT_POSITION_RIGHT) continue;
        NEAR(centre[k], spec[k]);
        assert_int_equal(o.fit[k], before.fit[k]);
        assert_true(o.prior_sigma[k] == before.prior_sigma[k]);
    }
    /* bounds around the specimen's values, as fit 0 had them */
    NEAR(o.lo[ROD_FIT_ANGLE_LEFT], spec[ROD_FIT_ANGLE_LEFT] - 20.0);
    NEAR(o.hi[ROD_FIT_ANGLE_LEFT], spec[ROD_FIT_ANGLE_LEFT] + 20.0);
    NEAR(o.lo[ROD_FIT_POSITION_RIGHT], fmax(spec[ROD_FIT_POSITION_RIGHT] - 0.05, 1e-3));
    NEAR(o.hi[ROD_FIT_POSITION_RIGHT], fmin(spec[ROD_FIT_POSITION_RIGHT] + 0.05, 1.0 - 1e-3));
}

/* Positions fit 0 did not give (NaN): nothing carried, nothing touched. */
static void nothing_without_positions(void **state)
{
    (void)state;
    rod_scene sc = fit_kit_pet(31), sc0 = sc;
    rod_fit_opts o = rod_fit_opts_default(), o0 = o;
    double u0[ROD_FIT_NKEYS], se0[ROD_FIT_NKEYS], centre[ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, u0);
    for (int k = 0; k < ROD_FIT_NKEYS; k++) se0[k] = 0.0003;
    u0[ROD_FIT_POSITION_LEFT] = NAN;
    assert_int_equal(rod_fit_carry_positions(u0, se0, ROD_FIT_CARRY_FLOOR, 0.006, &sc, &o, centre), 0);
    assert_memory_equal(&sc, &sc0, sizeof sc);
    assert_memory_equal(&o, &o0, sizeof o);
}

/* The fit honours a prior's centre apart from the scene (rod_fit_opts.prior_centre): E alone,
 * noise-free frames of the scene's own strip, a prior of width sp centred dc away. The linearised
 * estimate moves by dc se^2 / sp^2 (se the fit's standard error: 1 / se^2 = J^T J + 1 / sp^2);
 * with the centre at the scene's it stays there. */
static void fit_takes_the_prior_centre(void **state)
{
    (void)state;
    rod_scene sc = fit_kit_pet(31);
    enum { NC = 6, NS = 6 };
    rod_fit_obs obs[NC + NS];
    int n = fit_kit_states(obs, NC, NS, 0.1);
    char why[256];
    assert_int_equal(fit_kit_observe(&sc, obs, n, why, sizeof why), ROD_OK);
    double u[ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, u);
    const double sp = 0.05, dc = 0.05;
    double centre[ROD_FIT_NKEYS];
    for (int k = 0; k < ROD_FIT_NKEYS; k++) centre[k] = NAN; /* the scene's */
    centre[ROD_FIT_YOUNGS] = u[ROD_FIT_YOUNGS] + dc;
    rod_fit_opts o = rod_fit_opts_default();
    o.fit[ROD_FIT_YOUNGS] = 1;
    o.prior_sigma[ROD_FIT_YOUNGS] = sp;
    o.stop_sd = 0.0;
    rod_fit_result r;
    assert_int_equal(rod_fit_run(&sc, obs, n, &o, &r, why, sizeof why), ROD_OK);
    double moved0 = r.u[ROD_FIT_YOUNGS] - u[ROD_FIT_YOUNGS];
    o.prior_centre = centre;
    assert_int_equal(rod_fit_run(&sc, obs, n, &o, &r, why, sizeof why), ROD_OK);
    double moved = r.u[ROD_FIT_YOUNGS] - u[ROD_FIT_YOUNGS], expect = dc * r.se[ROD_FIT_YOUNGS] * r.se[ROD_FIT_YOUNGS] / (sp * sp);
    printf("ln E moved %.3g with the centre at the scene's, %.6g with it %.3g away (linearised %.6g, se %.4g)\n",
           moved0, moved, dc, expect, r.se[ROD_FIT_YOUNGS]);
    assert_true(fabs(moved0) < 1e-8);
    assert_true(expect > 0.05 * dc && expect < 0.95 * dc); /* the data and the prior both count */
    assert_true(fabs(moved - expect) < 0.02 * expect);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sigma_between_floor_and_cap),
        cmocka_unit_test(positions_carried),
        cmocka_unit_test(nothing_without_positions),
        cmocka_unit_test(fit_takes_the_prior_centre),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
