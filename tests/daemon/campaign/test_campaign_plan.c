/* test_campaign_plan.c: the planner's beliefs against closed forms and its proposals
 * (campaign_plan.h). With no trials a belief is the prior: mean P_j; without calibration, or
 * with one offset for every phi, Gaussian of sd sqrt(tau^2 + offset_sd^2) (the offset and the
 * model error add); with the per-phi offsets pooled, the scale mixture of Gaussians over the
 * spread's grid (its sd and quantiles in closed form); one specimen goes to the median, two at
 * one phi to its terciles (P -+ 0.43073 sd for the Gaussian). With a tight
 * bracket at one phi the calibrated planner moves the other phi by the bracket's offset (sd
 * back to about tau); without calibration it does not move them. An undecided trial is a band
 * about its Gamma (sd in closed form), so the next specimen goes to a phi the planner knows less. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "campaign_edge.h"
#include "campaign_plan.h"

/* The prior of Gamma*_j: delta ~ N(0, offset_sd^2) plus e_j ~ N(0, s^2) with s on
 * PLAN_MAX_SPREAD log-spaced values from tau to spread_max, equally likely (calibrated), or one
 * Gaussian of sd sqrt(tau^2 + offset_sd^2) (not): a scale mixture of Gaussians. Its variance, and
 * its CDF at x (a sum of normal CDFs), in closed form. */
static double prior_var(const campaign_plan_opts *o, double x, double *cdf)
{
    double v = 0, c = 0;
    int ns = o->calibrate && o->spread_max > o->tau ? PLAN_MAX_SPREAD : 1;
    for (int m = 0; m < ns; m++) {
        double sm = !o->calibrate ? o->tau : ns == 1 ? o->tau : o->tau * pow(o->spread_max / o->tau, m / (ns - 1.0));
        double var = sm * sm + o->offset_sd * o->offset_sd;
        v += var / ns;
        c += 0.5 * erfc(-x / sqrt(2 * var)) / ns;
    }
    if (cdf) *cdf = c;
    return v;
}

/* The prior's q-quantile about its mean, by bisection on the closed-form CDF. */
static double prior_quantile(const campaign_plan_opts *o, double q)
{
    double lo = -0.5, hi = 0.5;
    for (int it = 0; it < 200; it++) {
        double mid = 0.5 * (lo + hi), c;
        prior_var(o, mid, &c);
        if (c < q) lo = mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

static void prior_is_the_closed_form(void **s)
{
    (void)s;
    double phi[] = {60, 90, 120}, pred[] = {0.15, 0.175, 0.19};
    campaign_belief b[3];
    campaign_proposal p[3];
    for (int c = 0; c < 3; c++) {
        campaign_plan_opts o = campaign_plan_opts_default();
        o.calibrate = c != 0;
        if (c == 2) o.spread_max = o.tau; /* one offset: the planner before, a single Gaussian */
        campaign_plan_result r = {.beliefs = b, .proposals = p};
        char why[256];
        assert_int_equal(campaign_plan_run(phi, pred, 3, NULL, 0, &o, 3, &r, why, sizeof why), 0);
        double sd = sqrt(prior_var(&o, 0, NULL)), lo = prior_quantile(&o, 0.025), hi = prior_quantile(&o, 0.975);
        if (c != 1) assert_true(fabs(sd - sqrt(o.tau * o.tau + o.offset_sd * o.offset_sd)) < 1e-12);
        for (int j = 0; j < 3; j++) {
            assert_true(fabs(b[j].mean - pred[j]) < 1e-5);
            assert_true(fabs(b[j].offset_mean) < 1e-5);
            assert_true(fabs(b[j].sd - sd) / sd < 0.01);
            assert_true(fabs(b[j].lo - (pred[j] + lo)) < 1e-3);
            assert_true(fabs(b[j].hi - (pred[j] + hi)) < 1e-3);
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
    for (int c = 0; c < 2; c++) {
        campaign_plan_opts o = campaign_plan_opts_default();
        if (c) o.spread_max = o.tau; /* a Gaussian: P -+ 0.430727 sd */
        campaign_plan_result r = {.beliefs = b, .proposals = p};
        char why[256];
        assert_int_equal(campaign_plan_run(phi, pred, 1, NULL, 0, &o, 2, &r, why, sizeof why), 0);
        double t = prior_quantile(&o, 2.0 / 3);
        if (c) assert_true(fabs(t - 0.430727 * sqrt(o.tau * o.tau + o.offset_sd * o.offset_sd)) < 1e-6);
        assert_int_equal(r.k, 2);
        assert_true(fabs(p[0].gamma - (0.175 - t)) < 3e-4);
        assert_true(fabs(p[1].gamma - (0.175 + t)) < 3e-4);
    }
}

/* Phi 60 bracketed tightly 0.02 above its prediction (noise width small): the offset is about
 * 0.02 and phi 90's belief moves there when calibrated, not otherwise. The next specimen then
 * goes to phi 90 (or 120), near its shifted prediction. With one offset for every phi (spread_max
 * = tau, the planner before) phi 90 follows phi 60 to within tau; with the per-phi offsets pooled
 * (the default) one phi's bracket says less about the others: the shared offset comes out shrunk
 * (0.018) and wider, phi 90's belief moves most of the way but stays wide (measured: 0.193 +-
 * 0.0144, against the prior's 0.033 and 0.0042 with one offset). */
static void offset_moves_other_phis(void **s)
{
    (void)s;
    double phi[] = {60, 90, 120}, pred[] = {0.15, 0.175, 0.19};
    campaign_obs obs[] = {{60, 0.1695, 2, 0, 0, 2, 0}, {60, 0.1705, 0, 2, 0, 2, 0}};
    campaign_belief b[3];
    campaign_proposal p[1];
    char why[256];
    campaign_plan_opts o = campaign_plan_opts_default();
    o.noise = 2e-4;
    o.spread_max = o.tau;
    campaign_plan_result r = {.beliefs = b, .proposals = p};
    assert_int_equal(campaign_plan_run(phi, pred, 3, obs, 2, &o, 1, &r, why, sizeof why), 0);
    assert_true(fabs(r.offset_mean - 0.02) < 0.003);
    assert_true(r.offset_sd < 0.004);
    assert_true(fabs(b[0].mean - 0.17) < 5e-4);
    assert_true(fabs(b[0].offset_mean - 0.02) < 5e-4);
    assert_true(fabs(b[1].mean - 0.195) < 0.002);
    assert_true(b[1].sd < 0.0045);
    assert_true(p[0].phi_deg != 60);
    assert_true(fabs(p[0].gamma - (p[0].phi_deg == 90 ? 0.195 : 0.21)) < 0.003);
    o.spread_max = campaign_plan_opts_default().spread_max;
    assert_int_equal(campaign_plan_run(phi, pred, 3, obs, 2, &o, 1, &r, why, sizeof why), 0);
    assert_true(fabs(r.offset_mean - 0.018) < 0.003);
    assert_true(r.offset_sd > 0.005 && r.offset_sd < 0.012);
    assert_true(r.spread_mean > o.tau && r.spread_mean < o.spread_max);
    assert_true(fabs(b[0].mean - 0.17) < 5e-4);
    assert_true(fabs(b[1].mean - 0.193) < 0.003);
    assert_true(b[1].sd > 0.01 && b[1].sd < 0.018);
    assert_true(p[0].phi_deg != 60);
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

/* A synthetic lab whose boundary differs from the model by an offset that varies with phi: the
 * compliant hinge's +0.0187, +0.0075, +0.0040 at 60, 90, 120 deg (docs/campaign.md), each trial's
 * regime the truth's (asymmetric below it, symmetric above). The campaign: one specimen at a time
 * where the planner proposes, until every phi's bracket is at most 0.005 wide or 15 specimens.
 * One offset for every phi cannot fit: the planner before kept proposing at phi 60 under its
 * edge (15 specimens, phi 60 not closed, its median 0.006 off); per-phi offsets pooled toward
 * the common one locate all three within 0.005. */
static int synthetic_campaign(const double *off, int *used, double *err)
{
    double phi[] = {60, 90, 120}, pred[] = {0.15110, 0.17625, 0.18575}, truth[3];
    for (int j = 0; j < 3; j++) truth[j] = pred[j] + off[j];
    campaign_obs obs[16];
    size_t nobs = 0;
    campaign_belief b[3];
    campaign_proposal p[1];
    campaign_plan_opts o = campaign_plan_opts_default();
    campaign_plan_result r = {.beliefs = b, .proposals = p};
    char why[256];
    int closed = 0;
    for (;;) {
        closed = 1;
        for (int j = 0; j < 3; j++) {
            campaign_edge e;
            campaign_edge_fit(obs, nobs, phi[j], &e);
            if (!(e.method == CAMPAIGN_EDGE_BRACKET && e.hi - e.lo <= 0.005)) closed = 0;
        }
        if (closed || nobs >= 15) break;
        assert_int_equal(campaign_plan_run(phi, pred, 3, obs, nobs, &o, 1, &r, why, sizeof why), 0);
        int j = p[0].phi_deg == 60 ? 0 : p[0].phi_deg == 90 ? 1 : 2;
        int asym = p[0].gamma < truth[j];
        obs[nobs++] = (campaign_obs){p[0].phi_deg, p[0].gamma, asym, !asym, 0, 1, 0};
    }
    assert_int_equal(campaign_plan_run(phi, pred, 3, obs, nobs, &o, 0, &r, why, sizeof why), 0);
    *used = (int)nobs;
    *err = 0;
    for (int j = 0; j < 3; j++) {
        campaign_edge e;
        campaign_edge_fit(obs, nobs, phi[j], &e);
        double located = isfinite(e.gamma) ? e.gamma : b[j].median;
        *err = fmax(*err, fabs(located - truth[j]));
    }
    return closed;
}

static void offsets_that_differ_by_phi_are_located(void **s)
{
    (void)s;
    double hinge[] = {0.0187, 0.0075, 0.0040}, even[] = {0.008, 0.008, 0.008};
    int used;
    double err;
    int closed = synthetic_campaign(hinge, &used, &err);
    print_message("offsets +0.0187, +0.0075, +0.0040: %d specimens, closed %d, max |located - truth| %.5f\n", used,
                  closed, err);
    assert_true(closed);
    assert_true(used <= 15);
    assert_true(err <= 0.005);
    /* one offset for all: still found (the pooling does not cost the case one offset explains) */
    closed = synthetic_campaign(even, &used, &err);
    print_message("offset +0.008 at every phi: %d specimens, closed %d, max |located - truth| %.5f\n", used, closed,
                  err);
    assert_true(closed);
    assert_true(used <= 12);
    assert_true(err <= 0.005);
}

/* An undecided trial (the ordered probit, campaign_plan.h): its likelihood in Gamma* is the
 * density of U + eps, U uniform on [-h, h], eps ~ N(0, noise^2), scaled, so under a prior much
 * wider than it the belief's sd is sqrt(h^2 / 3 + noise^2) (closed form) about the trial's Gamma.
 * Before, an undecided trial said nothing (the belief stayed the prior's, sd 0.030). */
static void undecided_trial_is_a_band_about_its_gamma(void **s)
{
    (void)s;
    double phi[] = {60}, pred[] = {0.17};
    campaign_belief b[1];
    campaign_proposal p[1];
    campaign_plan_opts o = campaign_plan_opts_default();
    o.calibrate = 0;
    o.offset_sd = 0.05; /* a prior ~20 times wider than the band */
    campaign_plan_result r = {.beliefs = b, .proposals = p};
    char why[256];
    campaign_obs obs[] = {{60, 0.17, 0, 0, 1, 1, 1}};
    assert_int_equal(campaign_plan_run(phi, pred, 1, obs, 1, &o, 1, &r, why, sizeof why), 0);
    double want = sqrt(o.undecided * o.undecided / 3 + o.noise * o.noise);
    printf("# one undecided trial: belief sd %.6f, closed form %.6f\n", b[0].sd, want);
    assert_true(fabs(b[0].mean - 0.17) < 1e-4);
    assert_true(fabs(b[0].sd - want) / want < 0.02);
    o.undecided = 0; /* two outcomes: ignored */
    assert_int_equal(campaign_plan_run(phi, pred, 1, obs, 1, &o, 1, &r, why, sizeof why), 0);
    assert_true(b[0].sd > 0.04);
}

/* An undecided trial narrows its phi's belief, so the next specimen goes where the planner knows
 * less. Phi 60 bracketed by (0.160, 0.180), phi 90 by (0.178, 0.190): phi 60 is the wider, and
 * its median gets the next specimen. That specimen reads undecided: the two-outcome planner
 * (undecided trials ignored) proposes phi 60 at the same Gamma again (the camera campaign spent 3
 * of 14 specimens so); with the third outcome phi 60's belief is narrower than phi 90's and the
 * next specimen goes to phi 90. */
static void undecided_trial_sends_the_next_specimen_elsewhere(void **s)
{
    (void)s;
    double phi[] = {60, 90}, pred[] = {0.17, 0.184};
    campaign_belief b[2];
    campaign_proposal p[1];
    campaign_plan_opts o = campaign_plan_opts_default();
    o.calibrate = 0;
    campaign_plan_result r = {.beliefs = b, .proposals = p};
    char why[256];
    campaign_obs obs[] = {{60, 0.160, 1, 0, 0, 1, 0}, {60, 0.180, 0, 1, 0, 1, 0}, {90, 0.178, 1, 0, 0, 1, 0},
                          {90, 0.190, 0, 1, 0, 1, 0}, {60, 0.0, 0, 0, 1, 1, 1}};
    assert_int_equal(campaign_plan_run(phi, pred, 2, obs, 4, &o, 1, &r, why, sizeof why), 0);
    assert_true(p[0].phi_deg == 60);
    double median = p[0].gamma;
    obs[4].gamma = median;
    campaign_plan_opts two = o;
    two.undecided = 0;
    assert_int_equal(campaign_plan_run(phi, pred, 2, obs, 5, &two, 1, &r, why, sizeof why), 0);
    printf("# undecided at phi 60 Gamma %.5f: two outcomes propose phi %g Gamma %.5f", median, p[0].phi_deg,
           p[0].gamma);
    assert_true(p[0].phi_deg == 60 && fabs(p[0].gamma - median) < 5e-4); /* the same again */
    assert_int_equal(campaign_plan_run(phi, pred, 2, obs, 5, &o, 1, &r, why, sizeof why), 0);
    printf("; three: phi %g Gamma %.5f (belief sd at 60 %.5f, at 90 %.5f)\n", p[0].phi_deg, p[0].gamma, b[0].sd,
           b[1].sd);
    assert_true(b[0].sd < b[1].sd);
    assert_true(p[0].phi_deg == 90);
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
        cmocka_unit_test(offsets_that_differ_by_phi_are_located),
        cmocka_unit_test(undecided_trial_is_a_band_about_its_gamma),
        cmocka_unit_test(undecided_trial_sends_the_next_specimen_elsewhere),
        cmocka_unit_test(bad_options_named),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
