/* test_protocol_step_cap.c: the shear protocol's step count when it does not fit in a long
 * (issue 17, defect 6: dt = 1e-300 loaded, then failed with "step cap of -9223372036854774808").
 * rod_scene_check (so the loaders and rod_predict) refuses a scene whose ramp needs more than
 * ROD_SCENE_MAX_STEPS steps, naming the key and the count; rod_predict counts its cap in double
 * and saturates it, so no huge double is ever converted to long (UB; UBSan's float-cast-overflow
 * is on in the sanitizer build). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "rod_protocol.h"
#include "scene.h"

static int stop_after_three(void *user, const rod_sample *s, const rod *r)
{
    (void)s;
    (void)r;
    int *n = user;
    return ++*n >= 3;
}

static rod_scene small_scene(void)
{
    rod_scene s = rod_scene_default();
    s.nodes = 21;
    s.fold_angle_deg = 0.0;
    s.fold_position = 0.13;
    return s;
}

/* A scene whose ramp needs too many steps is refused by rod_predict itself (rod_scene_check),
 * with the key and the count, before any step. */
static void refused_up_front(double dt, double rate, const char *key)
{
    rod_scene s = small_scene();
    s.dt = dt;
    s.shear_rate = rate;
    rod_predict_opts o = rod_predict_opts_default();
    rod_prediction p;
    char err[256] = "";
    rod_status st = rod_predict(&s, &o, &p, err, sizeof err);
    print_message("  dt %g rate %g: status %d, \"%s\"\n", dt, rate, (int)st, err);
    /* Before the fix: "step cap of -9223372036854774808 reached" at Delta W = 0. */
    assert_null(strstr(err, "step cap"));
    assert_int_not_equal(st, ROD_OK);
    assert_non_null(strstr(err, key));
    assert_non_null(strstr(err, "time steps"));
}

static void test_tiny_dt_is_refused_with_key_and_count(void **state)
{
    (void)state;
    refused_up_front(1e-300, 0.01, "solver.dt");
}

static void test_tiny_rate_is_refused_with_key_and_count(void **state)
{
    (void)state;
    refused_up_front(1e-3, 1e-300, "protocol.shear_rate");
}

/* The options are not the scene's to check: post_snap_time = 1e300 s makes the cap's count
 * 1e303, which the cap saturates (before the fix: a double-to-long overflow, UB, caught by
 * UBSan's float-cast-overflow in the sanitizer build; on x86 a negative cap, reached at once). */
static void test_huge_post_snap_time_saturates_the_cap(void **state)
{
    (void)state;
    rod_scene s = small_scene();
    rod_predict_opts o = rod_predict_opts_default();
    o.post_snap_time = 1e300;
    int n = 0;
    o.on_sample = stop_after_three;
    o.user = &n;
    rod_prediction p;
    char err[256] = "";
    rod_status st = rod_predict(&s, &o, &p, err, sizeof err);
    print_message("  post_snap_time 1e300: status %d, %d samples, \"%s\"\n", (int)st, n, err);
    assert_null(strstr(err, "step cap"));
    assert_int_not_equal(st, ROD_ERR_TIME_LIMIT);
    assert_int_equal(n, 3);
}

static void test_scene_check_names_key_and_count(void **state)
{
    (void)state;
    char msg[256], key[64];
    rod_scene s = small_scene();
    s.dt = 1e-300;
    assert_int_not_equal(rod_scene_check(&s, msg, sizeof msg, key, sizeof key), 0);
    assert_string_equal(key, "solver.dt");
    assert_non_null(strstr(msg, "time steps"));
    assert_non_null(strstr(msg, "5e+301")); /* 0.5 * 1 m / 0.01 m/s / 1e-300 s */
    s = small_scene();
    s.shear_rate = 1e-300;
    assert_int_not_equal(rod_scene_check(&s, msg, sizeof msg, key, sizeof key), 0);
    assert_string_equal(key, "protocol.shear_rate");
    s = small_scene();
    assert_int_equal(rod_scene_check(&s, msg, sizeof msg, key, sizeof key), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tiny_dt_is_refused_with_key_and_count),
        cmocka_unit_test(test_tiny_rate_is_refused_with_key_and_count),
        cmocka_unit_test(test_huge_post_snap_time_saturates_the_cap),
        cmocka_unit_test(test_scene_check_names_key_and_count),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
