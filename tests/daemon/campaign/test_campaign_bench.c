/* test_campaign_bench.c: the simulated campaign (campaign_bench.h) on the mock scene at N = 61:
 * twins whose creases relaxed 6 deg and are softer (stiffness factor 3 against the scene's 1e4),
 * each crease off by up to 1%. Short (the suite):
 *   - the offset-only planner (lab_strip 0) locates the twins' true boundary (rod_boundary on
 *     their mean strip) at phi 60, 90, 120 within 0.005 with at most 15 specimens (at N = 41),
 *     and the truth differs from the model by more than the target at phi 60 (so the test could
 *     fail: a planner that trusted the model there would be off);
 *   - twins with compliant hinges (5e-3 N m/rad, mock.ini's [twin]), at N = 61: the planner given
 *     the twins' calibrations (each fitted from its noisy observables before the snap, pooled into
 *     the lab strip, campaign_strip.h) closes every interval to 0.005 within 15 specimens and
 *     locates the truth within 0.005 (measured 11 specimens, 0.0025, about 12 s of CPU). Before the
 *     lab strip the calibrated planner's single offset could not follow the hinge's
 *     phi-dependent shift (+0.019, +0.008, +0.004): 15 specimens, not closed, 0.0061 off (0.0049
 *     before the planner's tie rule).
 * With the argument "full" (heavy, the normal build): over five seeds the three planners (lab
 * strip, offset only, none) each within 15 specimens and 0.005, the offset-only one never using
 * more specimens than the uncalibrated; the hinge twins without calibration within 0.005 (measured
 * 13, 0.0019; the offset-only one is reported); and the dynamic bench (twins measured by their
 * simulated snap, truth the mean strip's dynamic switch): its truth lies below the static one at
 * every phi (the rate lag, docs/campaign.md "Static and dynamic boundary"), the campaign closes
 * every interval within 15 specimens (measured 11; it lands 0.005-0.018 above that truth, the
 * twins' crease differences: reported, not asserted), and truth = 1 scores a dynamic campaign
 * against the static boundary. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "campaign.h"
#include "scene_file.h"

static rod_scene scene;
static int full;

/* The short version at N = 41 (a third cheaper: 2 s for both campaigns against 3 s; the model is
 * still 0.0066 off at phi 60), the full one at the scene's N = 61. */
static int load(void **state)
{
    (void)state;
    cfg_error ce;
    if (cfg_scene_load(RIBBON_SOURCE_DIR "/config/scenes/mock-gamma013.ini", NULL, 0, &scene, &ce) != CFG_OK) return -1;
    if (!full) scene.nodes = 41;
    return 0;
}

static void report(const char *what, const campaign_bench_result *r)
{
    printf("# %s: %d specimens (%d, %d, %d), max error %.5f, offset %+.5f; truth %.5f %.5f %.5f, located %.5f %.5f "
           "%.5f, model %.5f %.5f %.5f; %.1f s\n",
           what, r->specimens, r->per_phi[0], r->per_phi[1], r->per_phi[2], r->max_error, r->offset_mean, r->truth[0],
           r->truth[1], r->truth[2], r->located[0], r->located[1], r->located[2], r->predicted[0], r->predicted[1],
           r->predicted[2], r->wall_s);
}

static void calibrated_campaign_meets_target(void **state)
{
    (void)state;
    campaign_bench_opts o = campaign_bench_opts_default();
    o.lab_strip = 0; /* the offset alone: the lab strip's campaigns are below */
    static campaign_bench_result r;
    char why[600];
    assert_int_equal(campaign_bench_run(&scene, &o, &r, NULL, NULL, why, sizeof why), 0);
    report("calibrated, seed 1", &r);
    assert_true(fabs(r.truth[0] - r.predicted[0]) > 0.005); /* the model alone misses at phi 60 */
    assert_true(r.converged);
    assert_true(r.specimens <= 15);
    assert_true(r.max_error <= 0.005);
    assert_true(r.offset_mean < 0); /* relaxed creases: the boundary lies below the model's */
}

/* Compliant-hinge twins, the planner calibrated by their fits (the lab strip and the offset). */
static void hinge_twins_lab_strip(void **state)
{
    (void)state;
    rod_scene sc = scene;
    sc.nodes = 61; /* at N = 41 and 51 the hinged boundary is not the regime boundary at every phi */
    campaign_bench_opts o = campaign_bench_opts_default();
    o.twin_hinge = 5e-3;
    static campaign_bench_result r;
    char why[600] = "";
    int rc = campaign_bench_run(&sc, &o, &r, NULL, NULL, why, sizeof why);
    if (rc) print_error("%s\n", why);
    assert_int_equal(rc, 0);
    report("hinge twins, lab strip", &r);
    printf("# lab strip: relaxed %.3f +- %.3f deg, hinge %.3g +- %.1f%% from %d calibrations (%d failed); %d traces "
           "(%d failed); fits %.1f s, traces %.1f s\n",
           r.strip.relax_deg, r.strip.relax_se, r.strip.hinge, 100 * r.strip.hinge_se_rel, r.calibrations,
           r.calibration_failures, r.traces, r.trace_failures, r.fit_s, r.trace_s);
    assert_true(r.calibrations >= 3 && isfinite(r.strip.hinge)); /* the hinge came from the fits */
    assert_true(r.converged);
    assert_true(r.specimens <= 15);
    assert_true(r.max_error <= 0.005);
}

static void three_planners_over_seeds(void **state)
{
    (void)state;
    for (unsigned seed = 1; seed <= 5; seed++) {
        static campaign_bench_result r[3];
        char why[600];
        for (int m = 0; m <= 2; m++) {
            campaign_bench_opts o = campaign_bench_opts_default();
            o.seed = seed;
            o.calibrate = m > 0;
            o.lab_strip = m == 2;
            assert_int_equal(campaign_bench_run(&scene, &o, &r[m], NULL, NULL, why, sizeof why), 0);
            char what[64];
            snprintf(what, sizeof what, "%s, seed %u", m == 2 ? "lab strip" : m ? "offset only" : "without calibration",
                     seed);
            report(what, &r[m]);
            assert_true(r[m].specimens <= 15 && r[m].max_error <= 0.005);
        }
        assert_true(r[1].specimens <= r[0].specimens);
    }
}

static void hinge_twins(void **state)
{
    (void)state;
    for (int cal = 1; cal >= 0; cal--) {
        campaign_bench_opts o = campaign_bench_opts_default();
        o.twin_hinge = 5e-3;
        o.calibrate = cal;
        o.lab_strip = 0;
        static campaign_bench_result r;
        char why[600] = "";
        int rc = campaign_bench_run(&scene, &o, &r, NULL, NULL, why, sizeof why);
        if (rc) print_error("%s\n", why);
        assert_int_equal(rc, 0);
        report(cal ? "hinge twins, offset only" : "hinge twins, without calibration", &r);
        assert_true(r.truth[1] > r.predicted[1]); /* the compliant hinge raises the boundary */
        assert_true(r.specimens <= 15);
        if (!cal) assert_true(r.converged && r.max_error <= 0.005);
    }
}

static void dynamic_bench(void **state)
{
    (void)state;
    campaign_bench_opts o = campaign_bench_opts_default(), s = o;
    o.dynamic = 1;
    o.lab_strip = s.lab_strip = 0;
    static campaign_bench_result r, rs, rt;
    char why[600] = "";
    int rc = campaign_bench_run(&scene, &o, &r, NULL, NULL, why, sizeof why);
    if (rc) print_error("%s\n", why);
    assert_int_equal(rc, 0);
    report("dynamic, offset only", &r);
    assert_int_equal(campaign_bench_run(&scene, &s, &rs, NULL, NULL, why, sizeof why), 0);
    for (int j = 0; j < 3; j++) {
        assert_true(r.truth[j] < rs.truth[j] - 0.002);
        assert_true(r.truth[j] == r.truth_dynamic[j] && r.truth_static[j] == rs.truth[j]); /* scored dynamic */
        assert_true(isnan(rs.truth_dynamic[j]));
    }
    assert_true(r.converged && r.specimens <= 15);
    /* The same dynamic campaign scored against the static boundary. */
    o.truth = 1;
    assert_int_equal(campaign_bench_run(&scene, &o, &rt, NULL, NULL, why, sizeof why), 0);
    report("dynamic, scored against the static truth", &rt);
    for (int j = 0; j < 3; j++) assert_true(rt.truth[j] == rs.truth[j] && rt.located[j] == r.located[j]);
}

int main(int argc, char **argv)
{
    full = argc > 1 && !strcmp(argv[1], "full");
    const struct CMUnitTest shortt[] = {cmocka_unit_test(calibrated_campaign_meets_target),
                                        cmocka_unit_test(hinge_twins_lab_strip)};
    const struct CMUnitTest fullt[] = {cmocka_unit_test(calibrated_campaign_meets_target),
                                       cmocka_unit_test(hinge_twins_lab_strip),
                                       cmocka_unit_test(three_planners_over_seeds),
                                       cmocka_unit_test(hinge_twins), cmocka_unit_test(dynamic_bench)};
    return full ? cmocka_run_group_tests(fullt, load, NULL) : cmocka_run_group_tests(shortt, load, NULL);
}
