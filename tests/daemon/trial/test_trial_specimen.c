/* test_trial_specimen: the rig file's [specimen] measurements in the trial's prediction
 * (trial_specimen_scene, issue 31). On config/mock.ini (scene folds.angle_deg = -90, Gamma 0.13,
 * fold_angle_rel 1e-6, creases down, rigid):
 *   - nothing measured: the scene unchanged bit for bit, every value from the scene, the hinge
 *     recorded (rigid, or the scene's stiffness);
 *   - each measured angle lands exactly on its crease's own key (folds.angle_left_deg /
 *     angle_right_deg, signed by crease_orientation), the scene's fold_angle_deg and its seed
 *     fold_angle_rel untouched; one measured, the other stays the scene's;
 *   - measured positions land on folds.position_left / position_right, unequal ones included (the
 *     mesh puts a node on each crease), with no warning; one measured, the other the scene's;
 *   - bad input named: creases that cannot be clamped at Delta L = 0.5, a crease inside the clamp,
 *     a measured crease that crosses the scene's other one, no sign to give the measured angles;
 *     a fold date after the trial;
 *   - the crease age is the trial's time minus folded_at. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "trial_specimen.h"

static rig_config cfg; /* large: off the stack */

static void load(const char *const *ovr, int n)
{
    cfg_error err;
    if (rig_config_load(RIBBON_SOURCE_DIR "/config/mock.ini", ovr, n, &cfg, &err) != CFG_OK) {
        char buf[1024];
        print_error("mock.ini: %s\n", cfg_error_format(&err, buf, sizeof buf));
        fail();
    }
}

static void nothing_measured_keeps_the_scene(void **state)
{
    (void)state;
    load(NULL, 0);
    rod_scene sc;
    trial_specimen_use use;
    char why[512] = "";
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), 0);
    assert_memory_equal(&sc, &cfg.scene, sizeof sc);
    for (int k = 0; k < 2; k++) {
        assert_int_equal(use.creases.angle_from[k], STORE_SOURCE_SCENE);
        assert_int_equal(use.creases.position_from[k], STORE_SOURCE_SCENE);
    }
    /* Each crease's own angle, before the seed (the prediction's imperfection). */
    assert_true(use.creases.angle_deg[0] == -90.0 && use.creases.angle_deg[1] == -90.0);
    assert_true(use.creases.position[0] == 0.13 && use.creases.position[1] == 1.0 - 0.13);
    assert_true(isinf(use.creases.hinge_stiffness) && use.creases.hinge_stiffness > 0.0);

    /* A compliant hinge is recorded as the scene's stiffness. */
    const char *hinge[] = {"folds.hinge_stiffness=2.5e-3"};
    load(hinge, 1);
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), 0);
    assert_memory_equal(&sc, &cfg.scene, sizeof sc);
    assert_true(use.creases.hinge_stiffness == 2.5e-3);
}

static void measured_angles_land_on_the_creases(void **state)
{
    (void)state;
    const char *both[] = {"specimen.crease_angle_left_deg=88", "specimen.crease_angle_right_deg=91"};
    load(both, 2);
    rod_scene sc;
    trial_specimen_use use;
    char why[512] = "";
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), 0);
    /* Exactly the measured creases on their own keys, signed down; the pair's angle and the seed
     * stay the scene's. */
    assert_true(sc.fold_angle_left_deg == -88.0 && sc.fold_angle_right_deg == -91.0);
    assert_true(rod_scene_crease_angle_deg(&sc, 0) == -88.0 && rod_scene_crease_angle_deg(&sc, 1) == -91.0);
    assert_true(sc.fold_angle_deg == -90.0 && sc.fold_angle_rel == cfg.scene.fold_angle_rel);
    assert_true(use.creases.angle_deg[0] == -88.0 && use.creases.angle_deg[1] == -91.0);
    assert_int_equal(use.creases.angle_from[0], STORE_SOURCE_SPECIMEN);
    assert_int_equal(use.creases.angle_from[1], STORE_SOURCE_SPECIMEN);
    assert_int_equal(use.creases.position_from[0], STORE_SOURCE_SCENE);
    /* The rest of the scene is the scene's. */
    assert_true(sc.fold_position == cfg.scene.fold_position && isnan(sc.fold_position_left) &&
                isnan(sc.fold_position_right) && sc.compression == cfg.scene.compression &&
                sc.nodes == cfg.scene.nodes && sc.dt == cfg.scene.dt);

    /* One measured: the other crease is the scene's (its key left unset: fold_angle_deg). */
    const char *left[] = {"specimen.crease_angle_left_deg=86"};
    load(left, 1);
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), 0);
    assert_true(sc.fold_angle_left_deg == -86.0 && isnan(sc.fold_angle_right_deg));
    assert_true(rod_scene_crease_angle_deg(&sc, 1) == -90.0 && use.creases.angle_deg[1] == -90.0);
    assert_int_equal(use.creases.angle_from[0], STORE_SOURCE_SPECIMEN);
    assert_int_equal(use.creases.angle_from[1], STORE_SOURCE_SCENE);

    /* Up: the measured magnitudes turn positive (a scene whose creases point up). */
    const char *up[] = {"folds.angle_deg=90", "specimen.crease_orientation=up", "specimen.crease_angle_left_deg=88",
                        "specimen.crease_angle_right_deg=91"};
    load(up, 4);
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), 0);
    assert_true(sc.fold_angle_left_deg == 88.0 && sc.fold_angle_right_deg == 91.0 && sc.fold_angle_deg == 90.0);

    /* Two equal: each crease gets it, the scene's seed stays. */
    const char *equal[] = {"specimen.crease_angle_left_deg=87", "specimen.crease_angle_right_deg=87"};
    load(equal, 2);
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), 0);
    assert_true(sc.fold_angle_left_deg == -87.0 && sc.fold_angle_right_deg == -87.0);
    assert_true(sc.fold_angle_rel == cfg.scene.fold_angle_rel);
}

static void positions_land_on_the_creases(void **state)
{
    (void)state;
    /* Unequal (not mirror images): each on its own key, from the specimen. */
    const char *asym[] = {"specimen.crease_position_left=0.12", "specimen.crease_position_right=0.86"};
    load(asym, 2);
    rod_scene sc;
    trial_specimen_use use;
    char why[512] = "";
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), 0);
    assert_true(sc.fold_position_left == 0.12 && sc.fold_position_right == 0.86);
    assert_true(sc.fold_position == cfg.scene.fold_position);
    assert_true(use.creases.position[0] == 0.12 && use.creases.position[1] == 0.86);
    assert_int_equal(use.creases.position_from[0], STORE_SOURCE_SPECIMEN);
    assert_int_equal(use.creases.position_from[1], STORE_SOURCE_SPECIMEN);
    assert_int_equal(use.creases.angle_from[0], STORE_SOURCE_SCENE);

    /* One measured: the other crease stays where the scene puts it (1 - Gamma). */
    const char *one[] = {"specimen.crease_position_left=0.15"};
    load(one, 1);
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), 0);
    assert_true(sc.fold_position_left == 0.15 && isnan(sc.fold_position_right));
    assert_true(use.creases.position[1] == 1.0 - 0.13);
    assert_int_equal(use.creases.position_from[0], STORE_SOURCE_SPECIMEN);
    assert_int_equal(use.creases.position_from[1], STORE_SOURCE_SCENE);
}

static void bad_input_named(void **state)
{
    (void)state;
    rod_scene sc;
    trial_specimen_use use;
    char why[512] = "";
    /* At Delta L = 0.2 the strip must span 0.8 l; two creases of 150 and 160 deg span at most
     * sinc(155/2 deg (1 + 1/31)) = 0.69 l (sim/scene.c), so they cannot be clamped. */
    const char *wide[] = {"protocol.compression=0.2", "specimen.crease_angle_left_deg=150",
                          "specimen.crease_angle_right_deg=160"};
    load(wide, 3);
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), -1);
    printf("unclampable: %s\n", why);
    assert_true(strncmp(why, "specimen.crease_angle_left_deg:", 31) == 0);
    assert_non_null(strstr(why, "cannot be clamped"));

    const char *clamp[] = {"specimen.crease_position_left=0.01", "specimen.crease_position_right=0.99"};
    load(clamp, 2);
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), -1);
    printf("inside the clamp: %s\n", why);
    assert_true(strncmp(why, "specimen.crease_position_left:", 30) == 0);
    assert_non_null(strstr(why, "inside the clamp"));

    /* One measured crease beyond the scene's other one: they cross. */
    const char *cross[] = {"specimen.crease_position_left=0.9"};
    load(cross, 1);
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), -1);
    printf("crossing: %s\n", why);
    assert_true(strncmp(why, "specimen.crease_position_left:", 30) == 0);
    assert_non_null(strstr(why, "cross"));

    /* A scene without creases and no crease_orientation: no sign for the measured angles. */
    const char *nosign[] = {"folds.angle_deg=0", "specimen.crease_angle_left_deg=80"};
    load(nosign, 2);
    cfg.specimen.crease_orientation = RIG_CREASE_UNSET;
    assert_int_equal(trial_specimen_scene(&cfg, &sc, &use, why, sizeof why), -1);
    printf("no sign: %s\n", why);
    assert_true(strncmp(why, "specimen.crease_orientation:", 28) == 0);
}

static void crease_age(void **state)
{
    (void)state;
    const char *at[] = {"specimen.folded_at=2026-11-30T12:00Z"};
    load(at, 1);
    double t0 = 20787.0 * 86400.0 + 12.0 * 3600.0, age = 0.0;
    char why[256] = "";
    assert_int_equal(trial_specimen_crease_age(&cfg, t0 + 5400.0, &age, why, sizeof why), 0);
    assert_true(age == 5400.0);
    assert_int_equal(trial_specimen_crease_age(&cfg, t0 - 10.0, &age, why, sizeof why), -1);
    printf("folded after the trial: %s\n", why);
    assert_true(strncmp(why, "specimen.folded_at:", 19) == 0);
    load(NULL, 0);
    assert_int_equal(trial_specimen_crease_age(&cfg, t0, &age, why, sizeof why), 0);
    assert_true(isnan(age));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(nothing_measured_keeps_the_scene),
        cmocka_unit_test(measured_angles_land_on_the_creases),
        cmocka_unit_test(positions_land_on_the_creases),
        cmocka_unit_test(bad_input_named),
        cmocka_unit_test(crease_age),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
