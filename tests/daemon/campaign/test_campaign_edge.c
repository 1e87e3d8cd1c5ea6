/* test_campaign_edge.c: the experimental regime boundary at one phi (campaign_edge.h): the
 * bracket of separated regimes, the probit fit of overlapping ones against counts drawn from a
 * known boundary and width, the open sides, and the distinct phi values. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "campaign_edge.h"

static void bracket_lands_between(void **s)
{
    (void)s;
    campaign_obs obs[] = {
        {90, 0.15, 1, 0, 0, 1, 0}, {90, 0.16, 2, 0, 0, 1, 0}, {90, 0.17, 0, 1, 0, 1, 0}, {90, 0.18, 0, 3, 1, 1, 0},
        {60, 0.10, 0, 1, 0, 1, 0}, /* another phi: ignored */
    };
    campaign_edge e;
    campaign_edge_fit(obs, 5, 90, &e);
    assert_int_equal(e.method, CAMPAIGN_EDGE_BRACKET);
    assert_true(fabs(e.lo - 0.16) < 1e-12 && fabs(e.hi - 0.17) < 1e-12);
    assert_true(fabs(e.gamma - 0.165) < 1e-12);
    assert_int_equal(e.n_asym, 3);
    assert_int_equal(e.n_sym, 4);
    assert_int_equal(e.n_points, 4);
    assert_string_equal(campaign_edge_method_name(e.method), "bracket");
}

static void open_sides_and_none(void **s)
{
    (void)s;
    campaign_obs obs[] = {{90, 0.17, 0, 2, 0, 1, 0}, {90, 0.19, 0, 1, 0, 1, 0}, {60, 0.12, 1, 0, 0, 1, 0},
                          {120, 0.2, 0, 0, 2, 1, 0}};
    campaign_edge e;
    campaign_edge_fit(obs, 4, 90, &e);
    assert_int_equal(e.method, CAMPAIGN_EDGE_BELOW);
    assert_true(fabs(e.hi - 0.17) < 1e-12 && isnan(e.lo) && isnan(e.gamma));
    campaign_edge_fit(obs, 4, 60, &e);
    assert_int_equal(e.method, CAMPAIGN_EDGE_ABOVE);
    assert_true(fabs(e.lo - 0.12) < 1e-12 && isnan(e.hi));
    campaign_edge_fit(obs, 4, 120, &e); /* no snaps only */
    assert_int_equal(e.method, CAMPAIGN_EDGE_NONE);
    double phis[8];
    assert_int_equal(campaign_edge_phis(obs, 4, phis, 8), 3);
    assert_true(phis[0] == 60 && phis[1] == 90 && phis[2] == 120);
}

/* Counts at the expected proportions of a probit with Gamma* = 0.172, w = 0.004 (400 trials
 * a point, rounded): the fit must find both to within its grid and a fraction of the width,
 * and its 95% interval must hold the truth and be narrow. */
static void probit_recovers_known_boundary(void **s)
{
    (void)s;
    const double gs = 0.172, w = 0.004;
    campaign_obs obs[9];
    for (int i = 0; i < 9; i++) {
        double g = 0.164 + 0.002 * i;
        double p = 0.5 * erfc(-((gs - g) / w) / M_SQRT2);
        int na = (int)lround(400 * p);
        obs[i] = (campaign_obs){120, g, na, 400 - na, 0, 1, 0};
    }
    campaign_edge e;
    campaign_edge_fit(obs, 9, 120, &e);
    assert_int_equal(e.method, CAMPAIGN_EDGE_PROBIT);
    assert_true(fabs(e.gamma - gs) < 2e-4);
    assert_true(e.width > 0.003 && e.width < 0.005);
    assert_true(e.lo <= gs && e.hi >= gs);
    assert_true(e.hi - e.lo < 0.002);
}

/* Few overlapping trials: a wide interval that still holds the overlap. */
static void probit_few_points(void **s)
{
    (void)s;
    campaign_obs obs[] = {{90, 0.16, 1, 0, 0, 1, 0}, {90, 0.17, 1, 1, 0, 2, 0}, {90, 0.18, 0, 1, 0, 1, 0}};
    campaign_edge e;
    campaign_edge_fit(obs, 3, 90, &e);
    assert_int_equal(e.method, CAMPAIGN_EDGE_PROBIT);
    assert_true(fabs(e.gamma - 0.17) < 1e-3);
    assert_true(e.lo < 0.17 && e.hi > 0.17 && e.lo >= 0.14 && e.hi <= 0.20);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(bracket_lands_between),
        cmocka_unit_test(open_sides_and_none),
        cmocka_unit_test(probit_recovers_known_boundary),
        cmocka_unit_test(probit_few_points),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
