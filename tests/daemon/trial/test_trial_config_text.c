/* test_trial_config_text.c: a trial's config text with its overrides (issue 32 C's defect: the
 * start's overrides were not in the record, so a rebuilt scene was the bare scene file's). The
 * overrides line is read back exactly (a value with a newline too), a note that imitates it is
 * not taken for it, a replay's line does not hide it, a text without it (an older row) rebuilds
 * the bare file's scene, and a garbled one is refused with the reason; the in-trial fit's setup
 * (sim.fit_hinge, sim.fit_keys) reads back with its overrides. No simulation: ms. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_file.h"
#include "trial.h"

static rig_config cfg_of_files(void)
{
    static rig_config cfg; /* large: not on the stack */
    memset(&cfg, 0, sizeof cfg);
    snprintf(cfg.path, sizeof cfg.path, "%s/config/mock.ini", RIBBON_SOURCE_DIR);
    snprintf(cfg.scene_path, sizeof cfg.scene_path, "%s/config/scenes/mock-gamma013.ini", RIBBON_SOURCE_DIR);
    return cfg;
}

/* The scene file with overrides, loaded directly: what the trial ran. */
static rod_scene loaded(const char *const *sets, int n)
{
    rig_config c = cfg_of_files();
    rod_scene sc;
    cfg_error ce;
    assert_int_equal(cfg_scene_load(c.scene_path, sets, n, &sc, &ce), CFG_OK);
    return sc;
}

static void overrides_round_trip_and_rebuild(void **state)
{
    (void)state;
    rig_config c = cfg_of_files();
    const char *sets[] = {"folds.angle_deg=-70", "specimen.name=S \"7\"\nline two", "ribbon.thickness=0.3e-3",
                          "folds.angle_deg=-80"};
    const char *note = "a note\n# overrides applied in order after the files: [\"folds.angle_deg=-10\"]";
    char *text = trial_config_text(&c, sets, 4, note);
    assert_non_null(text);
    /* a replay's row: its source's text and one line */
    char *replay = malloc(strlen(text) + 64);
    assert_non_null(replay);
    sprintf(replay, "%s# replay of trial 3\n", text);
    const char *texts[] = {text, replay};
    for (int t = 0; t < 2; t++) {
        json_t *got = trial_config_text_overrides(texts[t]);
        assert_true(json_is_array(got));
        assert_int_equal(json_array_size(got), 4);
        for (size_t k = 0; k < 4; k++) assert_string_equal(json_string_value(json_array_get(got, k)), sets[k]);
        json_decref(got);
        rod_scene sc;
        char why[512];
        if (trial_config_text_scene_load(texts[t], "stored", &sc, why, sizeof why)) fail_msg("%s", why);
        const char *scene_sets[] = {sets[0], sets[2], sets[3]}; /* the rig file's key is not the scene's */
        rod_scene want = loaded(scene_sets, 3);
        assert_true(sc.fold_angle_deg == -80.0); /* in order: the later one wins */
        assert_memory_equal(&sc, &want, sizeof sc);
    }
    free(replay);
    free(text);
}

static void without_the_line_the_bare_file(void **state)
{
    (void)state;
    rig_config c = cfg_of_files();
    char *text = trial_config_text(&c, NULL, 0, "note");
    assert_non_null(text);
    assert_null(strstr(text, "# overrides applied"));
    assert_null(trial_config_text_overrides(text));
    rod_scene sc, want = loaded(NULL, 0);
    char why[512];
    assert_int_equal(trial_config_text_scene_load(text, "stored", &sc, why, sizeof why), 0);
    assert_memory_equal(&sc, &want, sizeof sc);
    free(text);
    /* none given: "[]", not "not recorded" */
    text = trial_config_text(&c, (const char *const[]){NULL}, 0, NULL);
    assert_non_null(text);
    json_t *got = trial_config_text_overrides(text);
    assert_true(json_is_array(got) && json_array_size(got) == 0);
    json_decref(got);
    free(text);
}

/* The in-trial fit's setup read back (for `ribbonctl calibrate`): mock.ini's sim.fit_hinge, the
 * stored overrides of sim.fit_hinge and sim.fit_keys in order (spaces around the dot's key and the
 * value allowed, as rig_config_load takes them), the rig defaults without them, a value the rig
 * loader would refuse named, a text without a rig file refused. */
static void fit_setup_read_back(void **state)
{
    (void)state;
    rig_config c = cfg_of_files();
    double k = -1.0;
    char keys[256], why[320];
    char *text = trial_config_text(&c, (const char *const[]){"folds.angle_deg=-70"}, 1, NULL);
    assert_int_equal(trial_config_text_fit(text, &k, keys, sizeof keys, why, sizeof why), 0);
    assert_true(k == 3.5e-3); /* mock.ini's */
    assert_string_equal(keys, "");
    free(text);
    const char *sets[] = {"sim.fit_hinge=1e-3", "sim.fit_keys=folds.angle_left_deg", " sim.fit_hinge = 0 ",
                          "sim.fit_keys = folds.angle_left_deg,folds.hinge_stiffness"};
    text = trial_config_text(&c, sets, 4, NULL);
    assert_int_equal(trial_config_text_fit(text, &k, keys, sizeof keys, why, sizeof why), 0);
    assert_true(k == 0.0);
    assert_string_equal(keys, "folds.angle_left_deg,folds.hinge_stiffness");
    free(text);
    text = trial_config_text(&c, (const char *const[]){"sim.fit_hinge=-1"}, 1, NULL);
    assert_int_equal(trial_config_text_fit(text, &k, keys, sizeof keys, why, sizeof why), -1);
    printf("refused: %s\n", why);
    assert_non_null(strstr(why, "sim.fit_hinge = -1"));
    free(text);
    assert_int_equal(trial_config_text_fit("# scene file x.ini\n[ribbon]\n", &k, keys, sizeof keys, why, sizeof why),
                     -1);
    assert_non_null(strstr(why, "no readable rig file"));
}

static void garbled_line_refused(void **state)
{
    (void)state;
    rig_config c = cfg_of_files();
    char *text = trial_config_text(&c, NULL, 0, NULL);
    assert_non_null(text);
    char *bad = malloc(strlen(text) + 128);
    assert_non_null(bad);
    sprintf(bad, "%s# overrides applied in order after the files: [\"folds.angle_deg=-70\"\n", text);
    rod_scene sc;
    char why[512] = "";
    assert_int_equal(trial_config_text_scene_load(bad, "stored", &sc, why, sizeof why), -1);
    assert_non_null(strstr(why, "overrides cannot be read"));
    /* a stored override the scene refuses: named */
    sprintf(bad, "%s# overrides applied in order after the files: [\"folds.angle_deg=abc\"]\n", text);
    assert_int_equal(trial_config_text_scene_load(bad, "stored", &sc, why, sizeof why), -1);
    assert_non_null(strstr(why, "folds.angle_deg"));
    free(bad);
    free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(overrides_round_trip_and_rebuild),
        cmocka_unit_test(without_the_line_the_bare_file),
        cmocka_unit_test(garbled_line_refused),
        cmocka_unit_test(fit_setup_read_back),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
