/* test_campaign_bench.c: the simulated campaign (campaign_bench.h) on the mock scene at N = 61:
 * twins whose creases relaxed 6 deg and are softer (stiffness factor 3 against the scene's 1e4),
 * each crease off by up to 1%. Short (the suite, a few seconds): the calibrated planner locates
 * the twins' true boundary (rod_boundary on their mean strip) at phi 60, 90, 120 within 0.005 with
 * at most 15 specimens (at N = 41), and the truth differs from the model by more than the target at phi 60
 * (so the test could fail: a planner that trusted the model there would be off). With the
 * argument "full" (heavy, the normal build): the same and the uncalibrated campaign over five
 * seeds, each within 15 specimens and 0.005, the calibrated one never using more specimens; and
 * twins with compliant hinges (twin_hinge 5e-3 N m/rad, the mock rig's [twin]) instead of the
 * stiffness factor: the truth is traced (rod_boundary found no codim-2 point with a hinge before
 * rod_params_apply moved hinged creases) and the uncalibrated campaign locates it within 0.005 with
 * at most 15 specimens (measured 13, 0.0019); the calibrated one's single offset does not fit the
 * hinge's phi-dependent shift (+0.019, +0.008, +0.004): it uses all 15 and is only reported
 * (max error 0.0025 in one run, 0.0049 in another, same seed). And the dynamic bench (twins measured
 * by their simulated snap, truth the mean strip's dynamic switch): its truth lies below the static
 * one at every phi (the rate lag, docs/campaign.md "Static and dynamic boundary"), and the
 * calibrated campaign closes every interval within 15 specimens (measured 11; it lands 0.005-0.018
 * above that truth, the twins' crease differences: reported, not asserted). */
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
    campaign_bench_result r;
    char why[600];
    assert_int_equal(campaign_bench_run(&scene, &o, &r, NULL, NULL, why, sizeof why), 0);
    report("calibrated, seed 1", &r);
    assert_true(fabs(r.truth[0] - r.predicted[0]) > 0.005); /* the model alone misses at phi 60 */
    assert_true(r.converged);
    assert_true(r.specimens <= 15);
    assert_true(r.max_error <= 0.005);
    assert_true(r.offset_mean < 0); /* relaxed creases: the boundary lies below the model's */
}

static void both_campaigns_over_seeds(void **state)
{
    (void)state;
    for (unsigned seed = 1; seed <= 5; seed++) {
        campaign_bench_result r[2];
        char why[600];
        for (int cal = 0; cal <= 1; cal++) {
            campaign_bench_opts o = campaign_bench_opts_default();
            o.seed = seed;
            o.calibrate = cal;
            assert_int_equal(campaign_bench_run(&scene, &o, &r[cal], NULL, NULL, why, sizeof why), 0);
            char what[64];
            snprintf(what, sizeof what, "%s, seed %u", cal ? "calibrated" : "without calibration", seed);
            report(what, &r[cal]);
            assert_true(r[cal].specimens <= 15 && r[cal].max_error <= 0.005);
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
        campaign_bench_result r;
        char why[600] = "";
        int rc = campaign_bench_run(&scene, &o, &r, NULL, NULL, why, sizeof why);
        if (rc) print_error("%s\n", why);
        assert_int_equal(rc, 0);
        report(cal ? "hinge twins, calibrated" : "hinge twins, without calibration", &r);
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
    campaign_bench_result r, rs;
    char why[600] = "";
    int rc = campaign_bench_run(&scene, &o, &r, NULL, NULL, why, sizeof why);
    if (rc) print_error("%s\n", why);
    assert_int_equal(rc, 0);
    report("dynamic, calibrated", &r);
    assert_int_equal(campaign_bench_run(&scene, &s, &rs, NULL, NULL, why, sizeof why), 0);
    for (int j = 0; j < 3; j++) assert_true(r.truth[j] < rs.truth[j] - 0.002);
    assert_true(r.converged && r.specimens <= 15);
}

int main(int argc, char **argv)
{
    full = argc > 1 && !strcmp(argv[1], "full");
    const struct CMUnitTest shortt[] = {cmocka_unit_test(calibrated_campaign_meets_target)};
    const struct CMUnitTest fullt[] = {cmocka_unit_test(calibrated_campaign_meets_target),
                                       cmocka_unit_test(both_campaigns_over_seeds),
                                       cmocka_unit_test(hinge_twins), cmocka_unit_test(dynamic_bench)};
    return full ? cmocka_run_group_tests(fullt, load, NULL) : cmocka_run_group_tests(shortt, load, NULL);
}
