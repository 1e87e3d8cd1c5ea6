/* test_trial_cam_offset.c: the camera's time offset from the shear's start (trial_cam_offset.h),
 * against synthetic series of known offset.
 *
 * The rail: standing at 50 mm, commanded at t = 1 s, accelerating at 200 mm/s^2 to 10 mm/s (the
 * rehearsal's rail), read at 20 Hz with 2 ms of timing jitter and GRBL's 0.001 mm. The camera: 60
 * fps, each frame showing the clamp where the rail was at t_frame + offset, seen through a pinhole
 * D = 1 m away with the clamp 200 px from the image centre (its image moves as D / (D + y): 0.2
 * px/mm, the rehearsal's geometry), plus Gaussian noise of sigma px on each coordinate. Closed
 * form: the offset is the one the series were made with. Checks: the estimate is within 4 standard
 * deviations of the truth for offsets of -30, -15, 0 and +20 ms; over 40 noise seeds the spread of
 * the estimates agrees with the stated standard deviation (their ratio within 0.6..1.6: the
 * uncertainty is honest); an acceleration of 50 mm/s^2 (a longer ramp than the kink model) gives
 * the same offset; a clamp that does not move, a rail that does not, and no standing reading are
 * named refusals. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "trial_cam_offset.h"

static uint64_t rng_s;
static double urand(void)
{
    rng_s ^= rng_s << 13;
    rng_s ^= rng_s >> 7;
    rng_s ^= rng_s << 17;
    return ((double)(rng_s >> 11) + 0.5) / 9007199254740992.0;
}
static double nrand(void) { return sqrt(-2.0 * log(urand())) * cos(2.0 * M_PI * urand()); }

/* The rail's true position at t: standing at s0 until t_cmd, then a constant acceleration to v. */
static double rail_at(double t, double t_cmd, double v, double acc)
{
    const double s0 = 50.0, ta = v / acc;
    if (t <= t_cmd) return s0;
    if (t <= t_cmd + ta) return s0 + 0.5 * acc * (t - t_cmd) * (t - t_cmd);
    return s0 + 0.5 * v * ta + v * (t - t_cmd - ta);
}

typedef struct series {
    double offset, sigma_px, v, acc, moves; /* moves: 1 = the clamp's image follows the rail */
    double t_end;
} series;

static void fill(trial_cam_offset *o, const series *s, uint64_t seed)
{
    rng_s = seed * 2654435761u + 88172645463325252ull;
    trial_cam_offset_clear(o);
    const double t_cmd = 1.0, D = 1000.0, u0 = 320.0, r0 = 200.0;
    for (double t = 0.0; t < s->t_end; t += 0.05) {
        double tr = t + 0.002 * (urand() - 0.5);
        double pos = round(rail_at(tr, t_cmd, s->v, s->acc) * 1000.0) / 1000.0;
        trial_cam_offset_add_reading(o, tr, pos);
    }
    for (double t = 0.0; t < s->t_end; t += 1.0 / 60.0) {
        double y = s->moves * (rail_at(t + s->offset, t_cmd, s->v, s->acc) - 50.0);
        double left[2] = {u0 - r0 + s->sigma_px * nrand(), 240.0 + s->sigma_px * nrand()};
        double right[2] = {u0 + r0 * D / (D + y) + s->sigma_px * nrand(), 240.0 + s->sigma_px * nrand()};
        trial_cam_offset_add_frame(o, t, left, right);
    }
}

static void test_known_offsets(void **state)
{
    (void)state;
    trial_cam_offset *o = trial_cam_offset_alloc(1000, 200);
    assert_non_null(o);
    const double offsets[] = {-0.030, -0.015, 0.0, 0.020};
    for (int k = 0; k < 4; k++) {
        series s = {offsets[k], 0.05, 10.0, 200.0, 1.0, 4.0};
        fill(o, &s, (uint64_t)k + 1);
        trial_cam_offset_fit f;
        char why[256] = "";
        int rc = trial_cam_offset_estimate(o, 1.0, NULL, &f, why, sizeof why);
        printf("# offset %+.1f ms: estimate %+.2f +- %.2f ms, rms %.3f px, motion %.2f px, v %.3f mm/s, %d frames "
               "%d readings %s\n",
               1e3 * s.offset, 1e3 * f.offset_s, 1e3 * f.sd_s, f.rms_px, f.motion_px, f.speed_mm_s, f.frames_used,
               f.readings_used, why);
        assert_int_equal(rc, 0);
        assert_true(fabs(f.offset_s - s.offset) < 4.0 * f.sd_s);
        assert_true(fabs(f.speed_mm_s - 10.0) < 0.05);
    }
    trial_cam_offset_free(o);
}

/* The stated standard deviation against the scatter of 40 estimates (noise 0.05 px), and the same
 * offset with a slower ramp (50 mm/s^2: 0.2 s, inside ramp_s). */
static void test_uncertainty_is_honest(void **state)
{
    (void)state;
    trial_cam_offset *o = trial_cam_offset_alloc(1000, 200);
    const int n = 40;
    double sum = 0.0, sum2 = 0.0, sd_mean = 0.0;
    for (int k = 0; k < n; k++) {
        series s = {-0.015, 0.05, 10.0, k % 2 ? 50.0 : 200.0, 1.0, 4.0};
        fill(o, &s, (uint64_t)k + 100);
        trial_cam_offset_fit f;
        char why[256] = "";
        assert_int_equal(trial_cam_offset_estimate(o, 1.0, NULL, &f, why, sizeof why), 0);
        sum += f.offset_s - s.offset;
        sum2 += (f.offset_s - s.offset) * (f.offset_s - s.offset);
        sd_mean += f.sd_s / n;
    }
    double bias = sum / n, spread = sqrt(sum2 / n - bias * bias);
    printf("# 40 seeds: bias %+.3f ms, spread %.3f ms, stated sd %.3f ms (ratio %.2f)\n", 1e3 * bias, 1e3 * spread,
           1e3 * sd_mean, spread / sd_mean);
    assert_true(spread / sd_mean > 0.6 && spread / sd_mean < 1.6);
    assert_true(fabs(bias) < 3.0 * sd_mean / sqrt((double)n) + 1e-4);
    trial_cam_offset_free(o);
}

static void test_refusals(void **state)
{
    (void)state;
    trial_cam_offset *o = trial_cam_offset_alloc(1000, 200);
    trial_cam_offset_fit f;
    char why[256] = "";
    series still = {-0.015, 0.05, 10.0, 200.0, 0.0, 4.0};
    fill(o, &still, 1);
    assert_int_equal(trial_cam_offset_estimate(o, 1.0, NULL, &f, why, sizeof why), -1);
    printf("# %s\n", why);
    assert_non_null(strstr(why, "the shear clamp moved"));
    assert_true(isnan(f.offset_s));
    series parked = {-0.015, 0.05, 0.0, 200.0, 1.0, 4.0};
    fill(o, &parked, 1);
    assert_int_equal(trial_cam_offset_estimate(o, 1.0, NULL, &f, why, sizeof why), -1);
    printf("# %s\n", why);
    assert_non_null(strstr(why, "never left"));
    series ok = {-0.015, 0.05, 10.0, 200.0, 1.0, 4.0};
    fill(o, &ok, 1);
    assert_int_equal(trial_cam_offset_estimate(o, -1.0, NULL, &f, why, sizeof why), -1);
    printf("# %s\n", why);
    assert_non_null(strstr(why, "standing before"));
    /* Too short a shear: no cruise frames. */
    series brief = {-0.015, 0.05, 10.0, 200.0, 1.0, 1.2};
    fill(o, &brief, 1);
    assert_int_equal(trial_cam_offset_estimate(o, 1.0, NULL, &f, why, sizeof why), -1);
    printf("# %s\n", why);
    trial_cam_offset_free(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known_offsets),
        cmocka_unit_test(test_uncertainty_is_honest),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
