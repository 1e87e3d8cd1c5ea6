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

/* Positions closer than this to symmetric (left = 1 - right) count as symmetric: far below what
 * a ruler reads, far above the round-off of two decimals written in a file. */
#define SYMMETRIC_TOL 1e-9

/* The sign the measured creases take in the scene's convention (+1 up, -1 down): the specimen's
 * crease_orientation, else the scene's folds.angle_deg; 0 when neither says. */
static int crease_sign(const rig_config *cfg)
{
    if (cfg->specimen.crease_orientation == RIG_CREASE_UP) return 1;
    if (cfg->specimen.crease_orientation == RIG_CREASE_DOWN) return -1;
    return cfg->scene.fold_angle_deg > 0.0 ? 1 : cfg->scene.fold_angle_deg < 0.0 ? -1 : 0;
}

/* The specimen -> scene mapping, all of it.
 *
 * Today's scene has one pair of creases: phi = folds.angle_deg (signed: positive turns the
 * tangent toward the surface normal), split by imperfection.fold_angle_rel into
 *     left = phi (1 + rel/2)  at Gamma,   right = phi (1 - rel/2)  at 1 - Gamma   (sim/scene.h),
 * and Gamma = folds.position. Each crease's angle is taken from the specimen when measured, else
 * from the scene; the two angles (L, R, signed) then give the scene's keys exactly:
 *     phi = (L + R) / 2,   rel = (L - R) / phi     (so phi (1 +- rel/2) = L, R),
 * with the sign of the measured magnitudes from specimen.crease_orientation (up = positive), or
 * the scene's when not recorded. Exception: two measured creases exactly equal give rel = 0, a
 * perfectly symmetric scene that crosses a pitchfork late (DESIGN.md section 3: "symmetry breaking
 * needs a seed"); the scene's fold_angle_rel stays then as the seed. Angles neither measured nor
 * changed leave the scene's phi and rel untouched, bit for bit (the ladder's cache key).
 * Positions: the scene has one Gamma, so measured positions are applied only when symmetric
 * (left = 1 - right); otherwise they are recorded, the scene's Gamma is used and a warning says so.
 *
 * TODO(lead, after merging the per-crease scene keys): set folds.angle_left_deg / angle_right_deg
 * and folds.position_left / position_right directly (L, R and each position as measured), leave
 * fold_angle_rel as the seed, and drop the symmetric-positions restriction and its warning. */
static void map_creases(const rig_config *cfg, rod_scene *sc, trial_specimen_use *use)
{
    const rig_specimen *sp = &cfg->specimen;
    store_creases *c = &use->creases;
    double phi_s = sc->fold_angle_deg, rel_s = sc->fold_angle_rel, gamma_s = sc->fold_position;
    double measured[2] = {sp->crease_angle_left_deg, sp->crease_angle_right_deg};
    double scene_angle[2] = {phi_s * (1.0 + 0.5 * rel_s), phi_s * (1.0 - 0.5 * rel_s)};
    int sign = crease_sign(cfg), any = 0;
    for (int k = 0; k < 2; k++) {
        int from_specimen = isfinite(measured[k]);
        c->angle_deg[k] = from_specimen ? sign * measured[k] : scene_angle[k];
        c->angle_from[k] = from_specimen ? STORE_SOURCE_SPECIMEN : STORE_SOURCE_SCENE;
        any |= from_specimen;
    }
    if (any) {
        double l = c->angle_deg[0], r = c->angle_deg[1], phi = 0.5 * (l + r);
        sc->fold_angle_deg = phi;
        sc->fold_angle_rel = phi != 0.0 ? (l - r) / phi : 0.0;
        if (l == r && isfinite(measured[0]) && isfinite(measured[1])) sc->fold_angle_rel = rel_s;
    }

    double pos[2] = {sp->crease_position_left, sp->crease_position_right};
    double scene_pos[2] = {gamma_s, 1.0 - gamma_s};
    double used[2];
    store_source from[2];
    for (int k = 0; k < 2; k++) {
        used[k] = isfinite(pos[k]) ? pos[k] : scene_pos[k];
        from[k] = isfinite(pos[k]) ? STORE_SOURCE_SPECIMEN : STORE_SOURCE_SCENE;
    }
    int measured_pos = isfinite(pos[0]) || isfinite(pos[1]);
    if (measured_pos && fabs(used[0] - (1.0 - used[1])) <= SYMMETRIC_TOL) {
        sc->fold_position = used[0];
    } else if (measured_pos) {
        snprintf(use->warning, sizeof use->warning,
                 "specimen crease positions %g and %g are not symmetric (crease_position_left is not 1 - "
                 "crease_position_right): the prediction keeps the scene's folds.position = %g (unequal "
                 "positions are not in the model yet)",
                 used[0], used[1], gamma_s);
        for (int k = 0; k < 2; k++) {
            used[k] = scene_pos[k];
            from[k] = STORE_SOURCE_SCENE;
        }
    }
    for (int k = 0; k < 2; k++) {
        c->position[k] = used[k];
        c->position_from[k] = from[k];
    }
}

/* The specimen key to blame for a scene key rod_scene_check named. */
static const char *blame(const trial_specimen_use *use, const char *scene_key)
{
    const store_creases *c = &use->creases;
    if (!strcmp(scene_key, "folds.position"))
        return c->position_from[0] == STORE_SOURCE_SPECIMEN ? "specimen.crease_position_left"
                                                            : "specimen.crease_position_right";
    return c->angle_from[0] == STORE_SOURCE_SPECIMEN ? "specimen.crease_angle_left_deg"
                                                     : "specimen.crease_angle_right_deg";
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
                 "specimen.crease_orientation: not recorded, and the scene has no creases (folds.angle_deg = 0) to "
                 "take the measured creases' sign from: set up or down");
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
