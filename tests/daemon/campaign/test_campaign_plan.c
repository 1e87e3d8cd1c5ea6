/* test_campaign_plan.c: the planner's beliefs against closed forms and its proposals
 * (campaign_plan.h). With no trials a belief is the prior: Gaussian, mean P_j, sd
 * sqrt(tau^2 + offset_sd^2) (the offset and the model error add), with or without calibration;
 * one specimen goes to the median, two at one phi to its terciles P -+ 0.43073 sd. With a tight
 * bracket at one phi the calibrated planner moves the other phi by the bracket's offset (sd
 * back to about tau); without calibration it does not move them. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include <cmocka.h>

#include "campaign_plan.h"

static void prior_is_the_closed_form(void **s)
{
    (void)s;
    double phi[] = {60, 90, 120}, pred[] = {0.15, 0.175, 0.19};
    campaign_belief b[3];
    campaign_proposal p[3];
    for (int cal = 0; cal <= 1; cal++) {
        campaign_plan_opts o = campaign_plan_opts_default();
        o.calibrate = cal;
        campaign_plan_result r = {.beliefs = b, .proposals = p};
        char why[256];
        assert_int_equal(campaign_plan_run(phi, pred, 3, NULL, 0, &o, 3, &r, why, sizeof why), 0);
        double sd = sqrt(o.tau * o.tau + o.offset_sd * o.offset_sd);
        for (int j = 0; j < 3; j++) {
            assert_true(fabs(b[j].mean - pred[j]) < 1e-5);
            assert_true(fabs(b[j].sd - sd) / sd < 0.01);
            assert_true(fabs(b[j].lo - (pred[j] - 1.96 * sd)) < 1e-3);
            assert_true(fabs(b[j].hi - (pred[j] + 1.96 * sd)) < 1e-3);
        }
        assert_int_equal(r.k, 3); /* equal beliefs: one each, at the median */
        for (int j = 0; j < 3; j++) {
            assert_true(fabs(p[j].gamma - pred[j]) < 3e-4);
        }
    }
}

static void two_at_one_phi_are_terciles(void **s)
{
    (void)s;
    double phi[] = {90}, pred[] = {0.175};
    campaign_belief b[1];
    campaign_proposal p[2];
    campaign_plan_opts o = campaign_plan_opts_default();
    campaign_plan_result r = {.beliefs = b, .proposals = p};
    char why[256];
    assert_int_equal(campaign_plan_run(phi, pred, 1, NULL, 0, &o, 2, &r, why, sizeof why), 0);
    double sd = sqrt(o.tau * o.tau + o.offset_sd * o.offset_sd);
    assert_int_equal(r.k, 2);
    assert_true(fabs(p[0].gamma - (0.175 - 0.430727 * sd)) < 3e-4);
    assert_true(fabs(p[1].gamma - (0.175 + 0.430727 * sd)) < 3e-4);
}

/* Phi 60 bracketed tightly 0.02 above its prediction (noise width small): the offset is about
 * 0.02 and phi 90's belief moves there when calibrated, not otherwise. The next specimen then
 * goes to phi 90 (or 120), near its shifted prediction. */
static void offset_moves_other_phis(void **s)
{
    (void)s;
    double phi[] = {60, 90, 120}, pred[] = {0.15, 0.175, 0.19};
    campaign_obs obs[] = {{60, 0.1695, 2, 0, 0, 2}, {60, 0.1705, 0, 2, 0, 2}};
    campaign_belief b[3];
    campaign_proposal p[1];
    char why[256];
    campaign_plan_opts o = campaign_plan_opts_default();
    o.noise = 2e-4;
    campaign_plan_result r = {.beliefs = b, .proposals = p};
    assert_int_equal(campaign_plan_run(phi, pred, 3, obs, 2, &o, 1, &r, why, sizeof why), 0);
    assert_true(fabs(r.offset_mean - 0.02) < 0.003);
    assert_true(r.offset_sd < 0.004);
    assert_true(fabs(b[0].mean - 0.17) < 5e-4);
    assert_true(fabs(b[1].mean - 0.195) < 0.002);
    assert_true(b[1].sd < 0.0045);
    assert_true(p[0].phi_deg != 60);
    assert_true(fabs(p[0].gamma - (p[0].phi_deg == 90 ? 0.195 : 0.21)) < 0.003);
    o.calibrate = 0;
    assert_int_equal(campaign_plan_run(phi, pred, 3, obs, 2, &o, 1, &r, why, sizeof why), 0);
    assert_true(r.offset_mean == 0);
    assert_true(fabs(b[1].mean - 0.175) < 1e-4);
    assert_true(b[1].sd > 0.025);
}

/* Beliefs equal in exact arithmetic (the prior at every phi) are a tie however the predicted
 * values sit on the grid or differ in their last digits (as two builds' traces do): the next
 * specimen goes to the phi listed first, so a campaign does not depend on round-off. */
static void ties_go_to_the_first_phi(void **s)
{
    (void)s;
    double phi[] = {60, 90, 120};
    double preds[][3] = {{0.15, 0.175, 0.19}, {0.1501, 0.17512, 0.19013}, {0.15, 0.175 + 1e-6, 0.19 - 7e-7},
                         {0.15011, 0.17509, 0.19003}};
    for (int c = 0; c < 4; c++)
        for (int cal = 0; cal <= 1; cal++) {
            campaign_belief b[3];
            campaign_proposal p[1];
            campaign_plan_opts o = campaign_plan_opts_default();
            o.calibrate = cal;
            campaign_plan_result r = {.beliefs = b, .proposals = p};
            char why[256];
            assert_int_equal(campaign_plan_run(phi, preds[c], 3, NULL, 0, &o, 1, &r, why, sizeof why), 0);
            assert_int_equal(r.k, 1);
            assert_true(p[0].phi_deg == 60);
        }
}

static void bad_options_named(void **s)
{
    (void)s;
    double phi[] = {90}, pred[] = {0.6};
    campaign_belief b[1];
    campaign_proposal p[1];
    campaign_plan_opts o = campaign_plan_opts_default();
    campaign_plan_result r = {.beliefs = b, .proposals = p};
    char why[256];
    assert_int_equal(campaign_plan_run(phi, pred, 1, NULL, 0, &o, 1, &r, why, sizeof why), -1);
    assert_non_null(strstr(why, "outside Gamma"));
    pred[0] = 0.17;
    o.noise = 0;
    assert_int_equal(campaign_plan_run(phi, pred, 1, NULL, 0, &o, 1, &r, why, sizeof why), -1);
    assert_non_null(strstr(why, "noise"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(prior_is_the_closed_form),
        cmocka_unit_test(two_at_one_phi_are_terciles),
        cmocka_unit_test(offset_moves_other_phis),
        cmocka_unit_test(ties_go_to_the_first_phi),
        cmocka_unit_test(bad_options_named),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
