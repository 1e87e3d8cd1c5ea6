/* test_ctl_calibrate_trial.c: `ribbonctl calibrate` on a stored mock trial reproduces that trial's
 * own in-trial fit (issue 32 C; docs/calibration.md "Stored trials").
 *
 * One mock trial through ribbond's API operations in process (config/mock.ini: rigid creases in
 * the scene, sim.fit_hinge = 3.5e-3; its twin's creases compliant, -87.1 and -84.9 deg; everything
 * at N = 31 for speed, refreshes off so the stored fit is fit 0, from the compression and hold).
 * Then the program, as a user runs it, on the trial's frames before the shear (--dw-max 0, the
 * compression from its first tracked frame, at most 40 frames as the in-trial fit thins them).
 * The offline fit must be set up as the in-trial one was (the trial's sim.fit_hinge making the
 * rigid creases hinges, its keys, the priors, the tracker's common mode): the same three
 * parameters, each value within a tenth of the in-trial fit's standard error of it, and the
 * standard errors within 2% of each other (the frames thinned the same way but for rounding).
 * Before the offline fit shared the setup it fitted the rigid angles alone, without priors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../mock_daemon.h"

static mock_daemon md;

/* The parameter named key in a "parameters" array (NULL: none). */
static const json_t *param(const json_t *ps, const char *key)
{
    for (size_t k = 0; k < json_array_size(ps); k++)
        if (!strcmp(json_string_value(json_object_get(json_array_get(ps, k), "key")), key))
            return json_array_get(ps, k);
    return NULL;
}

/* ribbonctl's stdout as JSON; its exit status in *status. */
static json_t *ribbonctl(const char *args, int *status)
{
    char cmd[1024], out[160], err[160];
    snprintf(out, sizeof out, "%s/out.json", md.dir);
    snprintf(err, sizeof err, "%s/err.txt", md.dir);
    snprintf(cmd, sizeof cmd, "%s calibrate %s > %s 2> %s", RIBBONCTL_PATH, args, out, err);
    int rc = system(cmd);
    *status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
    printf("$ ribbonctl calibrate %s\nexit %d\n", args, *status);
    char line[1024];
    FILE *f = fopen(err, "r");
    while (f && fgets(line, sizeof line, f)) printf("  stderr: %s", line);
    if (f) fclose(f);
    return json_load_file(out, 0, NULL);
}

static void offline_fit_reproduces_the_in_trial_fit(void **state)
{
    (void)state;
    int64_t id = mock_daemon_trial(&md, NULL);
    json_t *t = mock_daemon_show(&md, id);
    assert_string_equal(json_string_value(json_object_get(t, "status")), "done");
    const json_t *fit = json_object_get(t, "fit");
    assert_true(json_is_object(fit));
    assert_true(json_is_true(json_object_get(fit, "ok")));
    assert_int_equal(json_integer_value(json_object_get(fit, "refresh")), 0);
    int frames = (int)json_integer_value(json_object_get(fit, "frames_before"));
    const json_t *in = json_object_get(fit, "parameters");
    printf("in-trial fit 0 of trial %lld: %d frames, residual %.3g\n", (long long)id, frames,
           json_number_value(json_object_get(fit, "rms")));

    /* The frames the in-trial fit had: those before the shear, from the first tracked one. */
    char path[128], args[512];
    snprintf(path, sizeof path, "%s/trials.db", md.dir);
    snprintf(args, sizeof args, "%lld --db %s --json --no-snap --dw-max 0 --dl-min 1e-6 --max-samples 40",
             (long long)id, path);
    int status;
    json_t *j = ribbonctl(args, &status);
    assert_int_equal(status, 0);
    assert_non_null(j);
    assert_int_equal(json_integer_value(json_object_get(j, "samples")), frames);
    const json_t *off = json_object_get(j, "parameters");
    assert_int_equal(json_array_size(off), json_array_size(in));
    assert_int_equal(json_array_size(in), 3); /* both angles and the hinge: sim.fit_hinge made one */
    for (size_t k = 0; k < json_array_size(in); k++) {
        const json_t *a = json_array_get(in, k);
        const char *key = json_string_value(json_object_get(a, "key"));
        const json_t *b = param(off, key);
        assert_non_null(b);
        double va = json_number_value(json_object_get(a, "fitted")), vb = json_number_value(json_object_get(b, "fitted"));
        double sa = json_number_value(json_object_get(a, "se")), sb = json_number_value(json_object_get(b, "se"));
        double s0a = json_number_value(json_object_get(a, "scene")), s0b = json_number_value(json_object_get(b, "scene"));
        int lg = !strcmp(json_string_value(json_object_get(a, "se_kind")), "relative");
        double dist = lg ? fabs(log(vb / va)) : fabs(vb - va); /* a relative se is one of ln k */
        printf("  %-24s start %g / %g, in-trial %.6g +- %.4g, offline %.6g +- %.4g: %.3f se apart\n", key, s0a, s0b,
               va, sa, vb, sb, dist / sa);
        assert_true(s0a == s0b);
        assert_true(isfinite(sa) && sa > 0.0);
        assert_true(dist < 0.1 * sa);
        assert_true(fabs(sb / sa - 1.0) < 0.02);
    }
    json_decref(j);
    json_decref(t);
}

static int setup(void **state)
{
    (void)state;
    /* fit 0 from Delta Z and A alone: a trial's centrelines (sim.fit_shape, on by default) are not
       stored with it, so the offline fit cannot have them (docs/calibration.md "Stored trials") */
    const char *sets[] = {"sim.fit_refresh_s=0", "sim.fit_shape=off"};
    mock_daemon_open(&md, "ctl-calib-trial", sets, 2);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    mock_daemon_close(&md, "ribbonctl calibrate of a mock trial");
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(offline_fit_reproduces_the_in_trial_fit, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
