/* test_ribbond_api_set.c: ribbond's POST /trials with "set" overrides (issue 33 item 5), through
 * the daemon's own start operation on config/mock.ini. Before, an API client could point the
 * scene at any file and read it back in the error ("'hunter2' is not a number"), have the daemon
 * create and fill any directory (camera.video_dir), and change the API's token, address and port
 * silently. Now such an override is a 400 naming its key, nothing is read or created, and the
 * operator's own --set (ribbond's command line) still changes anything. No trial runs in the
 * first test: every request is refused before one could start.
 *
 * The second (issue 32 C's defect) starts one mock trial with scene overrides and aborts it at
 * once: the overrides applied (ribbond's --set, then the body's, in order) are in its stored
 * record, shown by GET /trials/ID, and the scene rebuilt from the record (what ribbonctl
 * calibrate fits) is the one the trial ran, not the bare scene file's. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "rig_daemon.h"
#include "scene_file.h"
#include "store.h"
#include "trial.h"
#include "test_dir.h"

static char dir[64];
static rig_daemon d;
static int opened;

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/ribbond-api-set-XXXXXX");
    assert_non_null(mkdtemp(dir));
    static char set_store[128], set_video[128];
    snprintf(set_store, sizeof set_store, "store.path=%s/trials.db", dir);
    snprintf(set_video, sizeof set_video, "camera.video_dir=%s/videos", dir); /* the operator's --set */
    const char *ov[] = {set_store, set_video, "api.port=0", "sim.nodes=61", "ribbon.thickness=0.3e-3"};
    char why[512] = "";
    if (rig_daemon_open(&d, RIBBON_SOURCE_DIR "/config/mock.ini", ov, 5, NULL, why, sizeof why) != 0)
        fail_msg("open: %s", why);
    opened = 1;
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    if (opened) rig_daemon_close(&d, "test done");
    opened = 0;
    test_dir_done(dir, 1, "ribbond api set");
    return 0;
}

/* POST /trials with body text: the start op's return, status and reason. */
static int start(const char *body_text, int *status, char *why, size_t why_len)
{
    json_error_t je;
    json_t *body = json_loads(body_text, 0, &je);
    assert_non_null(body);
    api_ops ops = rig_daemon_ops();
    json_t *out = NULL;
    *status = 201;
    why[0] = '\0';
    int rc = ops.start(&d, body, &out, status, why, why_len);
    json_decref(body);
    json_decref(out);
    return rc;
}

static void refused(const char *ovr, const char *key)
{
    char body[512], why[512];
    snprintf(body, sizeof body, "{\"set\": [\"%s\"]}", ovr);
    int status = 0;
    int rc = start(body, &status, why, sizeof why);
    if (rc == 0) {
        api_ops ops = rig_daemon_ops();
        json_t *out = NULL;
        ops.abort_current(&d, &out, &status, why, sizeof why);
        json_decref(out);
        fail_msg("%s started a trial", ovr);
    }
    if (status != 400) fail_msg("%s: %d %s", ovr, status, why);
    if (!strstr(why, key) || !strstr(why, "may not be changed through the API")) fail_msg("%s: %s", ovr, why);
}

static void test_paths_and_api_refused(void **state)
{
    (void)state;
    /* A file the daemon can read, which is not a scene: its content never comes back. */
    char secret[128], body[512], why[512];
    snprintf(secret, sizeof secret, "%s/secret.ini", dir);
    FILE *f = fopen(secret, "w");
    assert_non_null(f);
    fputs("[ribbon]\nlength = hunter2\n", f);
    fclose(f);
    snprintf(body, sizeof body, "{\"set\": [\"rig.scene=%s\"]}", secret);
    int status = 0;
    assert_int_equal(start(body, &status, why, sizeof why), -1);
    printf("# rig.scene: %d %s\n", status, why);
    assert_int_equal(status, 400);
    assert_null(strstr(why, "hunter2"));
    assert_non_null(strstr(why, "rig.scene may not be changed through the API"));

    /* A directory the daemon would create and fill with the trial's video. */
    char elsewhere[128], ovr[192];
    snprintf(elsewhere, sizeof elsewhere, "%s/elsewhere", dir);
    snprintf(ovr, sizeof ovr, "camera.video_dir=%s", elsewhere);
    refused(ovr, "camera.video_dir");
    struct stat sb;
    assert_int_equal(stat(elsewhere, &sb), -1);

    /* The API itself, the store, the rails' limits, the twin. */
    refused("api.token=0123456789abcdef0123", "api.token");
    refused("api.listen=0.0.0.0", "api.listen");
    refused("api.port=1", "api.port");
    snprintf(ovr, sizeof ovr, "store.path=%s/other.db", dir);
    refused(ovr, "store.path");
    refused("rail.shear.soft_max_mm=1000", "rail.shear.soft_max_mm");
    refused("specimen.min_clamp_gap_mm=0", "specimen.min_clamp_gap_mm");
    refused("twin.anything=1", "twin.anything");
    assert_int_equal(stat(elsewhere, &sb), -1);
    snprintf(elsewhere, sizeof elsewhere, "%s/other.db", dir);
    assert_int_equal(stat(elsewhere, &sb), -1);

    /* An allowed key reaches the loader, which judges its value as before. */
    assert_int_equal(start("{\"set\": [\"protocol.compression=abc\"]}", &status, why, sizeof why), -1);
    assert_int_equal(status, 400);
    assert_non_null(strstr(why, "protocol.compression"));
    assert_null(strstr(why, "through the API"));

    /* The operator's --set is not restricted: the video directory came from it. */
    char want[128];
    snprintf(want, sizeof want, "%s/videos", dir);
    assert_string_equal(d.cfg.camera.video_dir, want);
}

static void test_overrides_stored_with_the_trial(void **state)
{
    (void)state;
    char why[512];
    int status = 0;
    api_ops ops = rig_daemon_ops();
    json_error_t je;
    json_t *body = json_loads("{\"set\": [\"folds.angle_deg=-75\", \"trial.hold_s=0.5\", "
                              "\"imperfection.fold_angle_rel=0.02\"]}", 0, &je);
    assert_non_null(body);
    json_t *out = NULL;
    why[0] = '\0';
    if (ops.start(&d, body, &out, &status, why, sizeof why) != 0) fail_msg("start: %d %s", status, why);
    json_decref(body);
    int64_t id = (int64_t)json_integer_value(json_object_get(out, "id"));
    json_decref(out);
    assert_true(id > 0);
    out = NULL;
    ops.abort_current(&d, &out, &status, why, sizeof why);
    json_decref(out);

    /* GET /trials/ID: the overrides, the daemon's first, in order. */
    out = NULL;
    if (ops.show(&d, id, &out, &status, why, sizeof why) != 0) fail_msg("show: %d %s", status, why);
    json_t *got = json_object_get(out, "overrides");
    assert_true(json_is_array(got));
    const char *want[] = {"store.path=", "camera.video_dir=", "api.port=0", "sim.nodes=61",
                          "ribbon.thickness=0.3e-3", "folds.angle_deg=-75", "trial.hold_s=0.5",
                          "imperfection.fold_angle_rel=0.02"};
    assert_int_equal(json_array_size(got), 8);
    for (size_t k = 0; k < 8; k++)
        if (strncmp(json_string_value(json_array_get(got, k)), want[k], strlen(want[k])) != 0)
            fail_msg("override %zu: %s, expected %s", k, json_string_value(json_array_get(got, k)), want[k]);
    json_decref(out);

    /* The scene rebuilt from the stored record equals the one the trial was loaded with. */
    char dbp[128];
    snprintf(dbp, sizeof dbp, "%s/trials.db", dir);
    store *st;
    assert_int_equal(store_open(dbp, &st, why, sizeof why), STORE_OK);
    char *text = NULL;
    assert_int_equal(store_trial_texts(st, id, &text, NULL, why, sizeof why), STORE_OK);
    store_close(st);
    rod_scene rebuilt;
    if (trial_config_text_scene_load(text, "stored", &rebuilt, why, sizeof why)) fail_msg("rebuild: %s", why);
    assert_true(rebuilt.fold_angle_deg == -75.0);
    assert_true(rebuilt.thickness == 0.3e-3);
    assert_true(rebuilt.fold_angle_rel == 0.02);
    rig_config cfg;
    cfg_error ce;
    const char *ran[] = {"sim.nodes=61", "ribbon.thickness=0.3e-3", "folds.angle_deg=-75", "trial.hold_s=0.5",
                         "imperfection.fold_angle_rel=0.02"};
    assert_int_equal(rig_config_load(RIBBON_SOURCE_DIR "/config/mock.ini", ran, 5, &cfg, &ce), CFG_OK);
    assert_memory_equal(&rebuilt, &cfg.scene, sizeof rebuilt);
    /* The bare scene file (all a trial's record kept before) is another strip. */
    const char *begin;
    size_t len;
    assert_int_equal(trial_config_text_scene(text, &begin, &len), 0);
    rod_scene bare;
    assert_int_equal(cfg_scene_parse("bare", begin, len, NULL, 0, &bare, &ce), CFG_OK);
    assert_true(bare.fold_angle_deg == -90.0);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_paths_and_api_refused, setup, teardown),
        cmocka_unit_test_setup_teardown(test_overrides_stored_with_the_trial, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
