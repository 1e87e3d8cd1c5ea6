/* trial_specimen.c: the specimen of a trial: the record (store) a rig file describes, its
 * [specimen] section and the scene's geometry and material; and the one place where the
 * specimen's measurements enter the prediction's scene (trial_specimen_scene).
 *
 * Why here: the scene file describes a strip as designed, the [specimen] section the strip on the
 * rig as measured; the trial's prediction should be of the strip on the rig, and the record must
 * say which numbers it used and where each came from (scene or specimen). */
#include "trial_specimen.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void trial_specimen_from_config(const rig_config *cfg, store_specimen *sp)
{
    *sp = store_specimen_default();
    snprintf(sp->name, sizeof sp->name, "%s", cfg->specimen.name[0] ? cfg->specimen.name : "unnamed");
    sp->length_m = cfg->scene.length;
    sp->width_m = cfg->scene.width;
    sp->thickness_m = cfg->scene.thickness;
    sp->youngs_modulus_pa = cfg->scene.youngs_modulus;
    sp->density_kg_m3 = cfg->scene.density;
    snprintf(sp->material, sizeof sp->material, "%.31s", cfg->specimen.material);
    sp->crease_angle_left_deg = cfg->specimen.crease_angle_left_deg;
    sp->crease_angle_right_deg = cfg->specimen.crease_angle_right_deg;
    sp->crease_position_left = cfg->specimen.crease_position_left;
    sp->crease_position_right = cfg->specimen.crease_position_right;
    snprintf(sp->folded_at, sizeof sp->folded_at, "%.39s", cfg->specimen.folded_at);
    sp->fold_position = cfg->scene.fold_position;
    snprintf(sp->crease_orientation, sizeof sp->crease_orientation, "%s",
             cfg->specimen.crease_orientation == RIG_CREASE_UP     ? "up"
             : cfg->specimen.crease_orientation == RIG_CREASE_DOWN ? "down"
                                                                   : "");
}

/* The sign the measured creases take in the scene's convention (+1 up, -1 down): the specimen's
 * crease_orientation, else the scene's creases (folds.angle_deg or the per-crease angles); 0 when
 * neither says. */
static int crease_sign(const rig_config *cfg)
{
    if (cfg->specimen.crease_orientation == RIG_CREASE_UP) return 1;
    if (cfg->specimen.crease_orientation == RIG_CREASE_DOWN) return -1;
    double a = rod_scene_crease_angle_deg(&cfg->scene, 0) + rod_scene_crease_angle_deg(&cfg->scene, 1);
    return a > 0.0 ? 1 : a < 0.0 ? -1 : 0;
}

/* The specimen -> scene mapping, all of it.
 *
 * The scene holds each crease on its own keys (sim/scene.h): folds.angle_left_deg /
 * angle_right_deg (signed: positive turns the tangent toward the surface normal) and
 * folds.position_left / position_right (from the left clamp point, over l). A measured value
 * goes to its crease's key as measured, the angle signed by specimen.crease_orientation (up =
 * positive) or, when not recorded, by the scene's creases. imperfection.fold_angle_rel stays the
 * scene's: a symmetry-breaking seed on top of each crease's own angle (DESIGN.md section 3:
 * "symmetry breaking needs a seed"), so two equal measured creases still cross the pitchfork.
 * Positions need not be symmetric: the mesh puts a node on each crease wherever it is
 * (rod_mesh_set_creases). A crease not measured keeps the scene's value; nothing measured leaves
 * the scene untouched, bit for bit (the ladder's cache key). The record (use->creases) holds each
 * crease's own angle before the seed (the prediction row's imperfection) and its position. */
static void map_creases(const rig_config *cfg, rod_scene *sc, trial_specimen_use *use)
{
    const rig_specimen *sp = &cfg->specimen;
    store_creases *c = &use->creases;
    const double measured[2] = {sp->crease_angle_left_deg, sp->crease_angle_right_deg};
    const double pos[2] = {sp->crease_position_left, sp->crease_position_right};
    double *angle_key[2] = {&sc->fold_angle_left_deg, &sc->fold_angle_right_deg};
    double *pos_key[2] = {&sc->fold_position_left, &sc->fold_position_right};
    int sign = crease_sign(cfg);
    for (int k = 0; k < 2; k++) {
        if (isfinite(measured[k])) *angle_key[k] = sign * measured[k];
        if (isfinite(pos[k])) *pos_key[k] = pos[k];
    }
    for (int k = 0; k < 2; k++) {
        c->angle_deg[k] = rod_scene_crease_angle_deg(sc, k);
        c->angle_from[k] = isfinite(measured[k]) ? STORE_SOURCE_SPECIMEN : STORE_SOURCE_SCENE;
        c->position[k] = rod_scene_crease_position(sc, k);
        c->position_from[k] = isfinite(pos[k]) ? STORE_SOURCE_SPECIMEN : STORE_SOURCE_SCENE;
    }
    c->hinge_stiffness = sc->fold_hinge_stiffness;
}

/* The specimen key to blame for a scene key rod_scene_check named: the same crease's measurement
 * of the same kind (a position key blames a position, anything else an angle) when the specimen
 * gave it, else the other crease's, else a measurement of the other kind. */
static const char *blame(const trial_specimen_use *use, const char *scene_key)
{
    static const char *const angle_name[2] = {"specimen.crease_angle_left_deg", "specimen.crease_angle_right_deg"};
    static const char *const pos_name[2] = {"specimen.crease_position_left", "specimen.crease_position_right"};
    const store_creases *c = &use->creases;
    int side = strstr(scene_key, "right") != NULL, pos = strstr(scene_key, "position") != NULL;
    for (int kind = 0; kind < 2; kind++, pos = !pos) {
        const store_source *from = pos ? c->position_from : c->angle_from;
        const char *const *name = pos ? pos_name : angle_name;
        if (from[side] == STORE_SOURCE_SPECIMEN) return name[side];
        if (from[!side] == STORE_SOURCE_SPECIMEN) return name[!side];
    }
    return pos ? pos_name[side] : angle_name[side];
}

int trial_specimen_scene(const rig_config *cfg, rod_scene *out, trial_specimen_use *use, char *why, size_t why_len)
{
    memset(use, 0, sizeof *use);
    use->creases = store_creases_unknown();
    rod_scene sc = cfg->scene;
    const rig_specimen *sp = &cfg->specimen;
    int measured = isfinite(sp->crease_angle_left_deg) || isfinite(sp->crease_angle_right_deg);
    if (measured && crease_sign(cfg) == 0) {
        snprintf(why, why_len,
                 "specimen.crease_orientation: not recorded, and the scene has no creases (folds.angle_deg and the "
                 "per-crease angles 0) to take the measured creases' sign from: set up or down");
        return -1;
    }
    map_creases(cfg, &sc, use);
    if (cfg->sim.explicit_resolution && cfg->sim.nodes > 0) sc.nodes = cfg->sim.nodes;
    char msg[256], key[64];
    if (rod_scene_check(&sc, msg, sizeof msg, key, sizeof key)) {
        const store_creases *c = &use->creases;
        snprintf(why, why_len,
                 "%s: the specimen's creases (%g and %g deg at %g and %g) cannot be simulated: %s (%s, N = %d)",
                 blame(use, key), c->angle_deg[0], c->angle_deg[1], c->position[0], c->position[1], msg, key, sc.nodes);
        return -1;
    }
    sc.nodes = cfg->scene.nodes;
    *out = sc;
    return 0;
}

int trial_specimen_crease_age(const rig_config *cfg, double wall_s, double *age_s, char *why, size_t why_len)
{
    *age_s = NAN;
    double t = cfg->specimen.folded_at_s;
    if (!isfinite(t)) return 0;
    if (wall_s < t) {
        snprintf(why, why_len, "specimen.folded_at: %s lies after this trial's start (%.0f s later)",
                 cfg->specimen.folded_at, t - wall_s);
        return -1;
    }
    *age_s = wall_s - t;
    return 0;
}
