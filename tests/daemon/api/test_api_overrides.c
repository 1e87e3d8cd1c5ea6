/* test_api_overrides.c: what an API client may change in a trial (daemon/api/api_overrides.h),
 * issue 33 item 5: POST /trials's "set" reached every key of the rig file, so any local user could
 * point the scene at any file (and read it back in the error), move the video directory, change
 * the API's token or the rails' limits. Now a table allows the scene (physics, protocol, the
 * simulator's settings), the specimen and the trial's timing; the rest is refused naming the key,
 * however it is spelled. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include <jansson.h>

#include "api_overrides.h"
#include "api_start_body.h"
#include "rig_config.h"
#include "scene_file.h"

static void allowed(const char *ovr)
{
    char why[512] = "";
    if (api_override_check(ovr, why, sizeof why) != 0) fail_msg("%s refused: %s", ovr, why);
}

static void refused(const char *ovr, const char *named)
{
    char why[512] = "";
    if (api_override_check(ovr, why, sizeof why) == 0) fail_msg("%s allowed", ovr);
    if (why[0] == '\0') fail_msg("%s refused without a reason", ovr);
    if (named && !strstr(why, named)) fail_msg("%s: the reason does not name %s: %s", ovr, named, why);
    if (named && !strstr(why, "may not be changed through the API")) fail_msg("%s: %s", ovr, why);
}

static void test_what_a_trial_may_change(void **s)
{
    (void)s;
    /* The scene's physics and protocol, whole sections: keys that exist ... */
    allowed("ribbon.length=0.2");
    allowed("ribbon.gravity=0,0,-9.81");
    allowed("folds.angle_deg=90");
    allowed("folds.position=0.13");
    allowed("imperfection.fold_angle_rel=0.01");
    allowed("protocol.compression=0.4");
    allowed("protocol.shear_rate=0.001");
    allowed("snap.speed=2");
    allowed("mesh.nodes=61");   /* the simulator's settings: a start's prediction cost is bounded */
    allowed("solver.dt=5e-4");
    /* ... and keys another branch adds to those sections: no change needed here. */
    allowed("folds.angle_left_deg=88");
    allowed("folds.angle_right_deg=92");
    allowed("folds.position_left=0.13");
    allowed("folds.position_right=0.87");
    allowed("folds.hinge_stiffness=1e-3");
    /* The specimen's record and the trial's timing; blanks around the key as the loaders take. */
    allowed("specimen.name=PET #3");
    allowed("specimen.crease_angle_left_deg=91");
    allowed(" trial.hold_s = 1");
    allowed("trial.post_snap_s=0.5");
    allowed("trial.compress_speed_mm_s=2");
    allowed("trial.return_speed_mm_s=5");
    /* The value is the loader's to judge, however long. */
    char big[2000];
    memset(big, '9', sizeof big);
    memcpy(big, "protocol.compression=", 21);
    big[sizeof big - 1] = '\0';
    allowed(big);
}

static void test_what_is_the_rig_files(void **s)
{
    (void)s;
    /* Paths: nothing the API sends makes the daemon read or create a file. */
    refused("rig.scene=/etc/passwd", "rig.scene");
    refused("camera.video_dir=/tmp/anywhere", "camera.video_dir");
    refused("camera.calibration=/etc/shadow", "camera.calibration");
    refused("camera.source=/dev/video9", "camera.source");
    refused("store.path=/tmp/other.db", "store.path");
    refused("replay.video=/etc/passwd", "replay.video");
    refused("replay.rails=/etc/passwd", "replay.rails");
    refused("rig.outputs=cwd", "rig.outputs");
    refused("rig.mode=rig", "rig.mode");
    /* The API itself. */
    refused("api.token=0123456789abcdef0123", "api.token");
    refused("api.listen=0.0.0.0", "api.listen");
    refused("api.port=80", "api.port");
    /* The rails and their limits, the specimen's clamp gap among them. */
    refused("rail.shear.soft_max_mm=500", "rail.shear.soft_max_mm");
    refused("rail.compress.max_speed_mm_s=100", "rail.compress.max_speed_mm_s");
    refused("rail.compress.port=/dev/ttyS0", "rail.compress.port");
    refused("specimen.min_clamp_gap_mm=0", "a limit of the rails");
    refused("calibration.compress_zero_mm=0", "calibration.compress_zero_mm");
    /* The measurement's and the prediction's settings, the disk margin, the twin. */
    refused("detect.dz_jump=0.5", "detect.dz_jump");
    refused("sim.nodes=100001", "sim.nodes");
    refused("trial.min_free_disk_mb=0", "trial.min_free_disk_mb");
    refused("trial.upper_dz_min=0.001", "trial.upper_dz_min");
    refused("twin.folds_angle_deg=80", "the twin is the bench's");
    refused("twin.anything=1", "twin.anything");
    /* A section no row names, and spellings that are not the allowed key. */
    refused("newsection.key=1", "newsection.key");
    refused("Ribbon.length=1", "Ribbon.length");
    refused("ribbon .length=1", NULL);
    refused("ribbon.length.x=1", NULL);
    refused("protocol.=1", NULL);
    refused(".length=1", NULL);
    refused("ribbon=1", NULL);
    refused("xrig.scene=/etc/passwd", NULL);
    char why[512];
    assert_int_equal(api_override_check("protocol.compression", why, sizeof why), -1); /* no '=' */
    assert_non_null(strstr(why, "section.key=value"));
    assert_int_equal(api_override_check(NULL, why, sizeof why), -1);
    /* The key as shown: printable, no quote, cut. */
    assert_int_equal(api_override_check("rig.\x01\"scene=/x", why, sizeof why), -1);
    assert_null(strchr(why, '"'));
    assert_null(strchr(why, '\x01'));
}

/* Every row names a section and a key, and says what it covers; a row refusing a key inside an
 * allowed section comes before the section's row (first match wins). */
static void test_table(void **s)
{
    (void)s;
    size_t n = 0;
    const api_override_rule *r = api_override_rules(&n);
    assert_true(n > 10);
    for (size_t i = 0; i < n; i++) {
        assert_true(r[i].section && r[i].section[0] && r[i].key && r[i].key[0] && r[i].what && r[i].what[0]);
        if (strcmp(r[i].key, "*") == 0)
            for (size_t j = i + 1; j < n; j++)
                if (strcmp(r[j].section, r[i].section) == 0)
                    fail_msg("row %zu (%s.%s) is hidden by row %zu (%s.*)", j, r[j].section, r[j].key, i, r[i].section);
    }
}

/* Against the loaders' own key tables, so a key added later is judged too: every scene key is
 * allowed (the scene is a trial's, by section), and every rig key that names a file, a directory
 * or a device (PATH, the camera's SOURCE), the API's, the store's, the rails' limits via the
 * specimen, is refused. A path key added to an allowed section fails here. */
static void test_loader_tables(void **s)
{
    (void)s;
    char ovr[160], why[512];
    size_t n = 0;
    const cfg_scene_key *sk = cfg_scene_keys(&n);
    for (size_t i = 0; i < n; i++) {
        snprintf(ovr, sizeof ovr, "%s.%s=1", sk[i].section, sk[i].name);
        allowed(ovr);
    }
    const rig_key *rk = rig_config_keys(&n);
    int paths = 0;
    for (size_t i = 0; i < n; i++) {
        snprintf(ovr, sizeof ovr, "%s.%s=/etc/passwd", rk[i].section, rk[i].name);
        int ok = api_override_check(ovr, why, sizeof why) == 0;
        if (rk[i].type == RIG_KEY_PATH || rk[i].type == RIG_KEY_SOURCE) {
            paths++;
            if (ok) fail_msg("%s (a path) allowed through the API", ovr);
        }
        if (ok && (!strcmp(rk[i].section, "api") || !strcmp(rk[i].section, "store") || !strcmp(rk[i].section, "rig")))
            fail_msg("%s allowed through the API", ovr);
    }
    printf("# %zu rig keys, %d of them paths or devices, all refused\n", n, paths);
    assert_true(paths >= 6); /* rig.scene, camera.source, camera.calibration, camera.video_dir, store.path, replay.* */
}

/* Through POST /trials's body check: the first refused override is named by its index. */
static void test_start_body_refuses(void **s)
{
    (void)s;
    char why[512];
    api_start_body b;
    json_t *body = json_pack("{s:[s,s,s]}", "set", "protocol.compression=0.4", "trial.hold_s=1",
                             "camera.video_dir=/tmp/x");
    assert_int_equal(api_start_body_parse(body, 0, &b, why, sizeof why), -1);
    assert_non_null(strstr(why, "\"set\"[2]: camera.video_dir may not be changed through the API"));
    json_decref(body);
    body = json_pack("{s:[s,s]}", "set", "protocol.compression=0.4", "folds.hinge_stiffness=2");
    assert_int_equal(api_start_body_parse(body, 0, &b, why, sizeof why), 0);
    assert_int_equal(b.n_set, 2);
    json_decref(body);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_what_a_trial_may_change),
        cmocka_unit_test(test_what_is_the_rig_files),
        cmocka_unit_test(test_table),
        cmocka_unit_test(test_loader_tables),
        cmocka_unit_test(test_start_body_refuses),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
