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

#include "rig_daemon.h"

#include "../test_dir.h"

static char dir[64];
static rig_daemon d;

/* The trial, run to its end. Returns its id. */
static int64_t run_trial(void)
{
    api_ops ops = rig_daemon_ops();
    json_t *body = json_loads("{}", 0, NULL), *out = NULL;
    int http = 201;
    char why[512] = "";
    if (ops.start(&d, body, &out, &http, why, sizeof why)) fail_msg("start: %d %s", http, why);
    int64_t id = json_integer_value(json_object_get(out, "id"));
    json_decref(body);
    json_decref(out);
    for (int k = 0;; k++) {
        json_t *st = NULL;
        assert_int_equal(ops.status(&d, &st, why, sizeof why), 0);
        int idle = !strcmp(json_string_value(json_object_get(st, "state")), "idle");
        json_decref(st);
        if (idle) break;
        if (k > 6000) fail_msg("trial %lld did not end in 300 s", (long long)id);
        usleep(50000);
    }
    return id;
}

static json_t *trial_json(int64_t id)
{
    api_ops ops = rig_daemon_ops();
    json_t *out = NULL;
    int http = 200;
    char why[256];
    if (ops.show(&d, id, &out, &http, why, sizeof why)) fail_msg("show %lld: %s", (long long)id, why);
    return out;
}

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
    snprintf(out, sizeof out, "%s/out.json", dir);
    snprintf(err, sizeof err, "%s/err.txt", dir);
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
    int64_t id = run_trial();
    json_t *t = trial_json(id);
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
    snprintf(path, sizeof path, "%s/trials.db", dir);
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
    snprintf(dir, sizeof dir, "/tmp/ctl-calib-trial-XXXXXX");
    assert_non_null(mkdtemp(dir));
    static char set_store[128], set_video[128];
    snprintf(set_store, sizeof set_store, "store.path=%s/trials.db", dir);
    snprintf(set_video, sizeof set_video, "camera.video_dir=%s/videos", dir);
    const char *ov[] = {set_store, set_video, "api.port=0", "mesh.nodes=31", "sim.nodes=31", "sim.dt=2e-3",
                        "twin.mesh.nodes=31", "twin.solver.dt=2e-3", "sim.fit_refresh_s=0"};
    char why[512] = "";
    if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, 9, NULL, why, sizeof why))
        fail_msg("open: %s", why);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    rig_daemon_close(&d, "test done");
    test_dir_done(dir, 1, "ribbonctl calibrate of a mock trial");
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(offline_fit_reproduces_the_in_trial_fit, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
