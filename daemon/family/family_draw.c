/* family_draw.c: one twin of the family (family.h), drawn from (seed, index) alone.
 *
 * A hand-made strip differs from its scene in every parameter the fit can adjust and the scene
 * cannot know (issue 32 D): each crease's angle (75..95 deg, the two within 5% of each other),
 * each crease's position (within 1% of l), the hinge (its bending length E I1 / k from 1% to 20%
 * of l, log-uniform: the scene's 7.5 mm is 3.75%) and E (-+ 20%). The draws come from a
 * SplitMix64 stream seeded by (seed, index), so a twin does not depend on which core drew the
 * others, and a family is the same on every machine. */
#include "family.h"

#include <math.h>
#include <stdio.h>

static uint64_t splitmix(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Uniform in [lo, hi). */
static double uniform(uint64_t *s, double lo, double hi)
{
    return lo + (hi - lo) * ((double)(splitmix(s) >> 11) / 9007199254740992.0);
}

family_ranges family_ranges_default(void)
{
    return (family_ranges){.angle_lo_deg = 75.0,
                           .angle_hi_deg = 95.0,
                           .angle_diff_rel = 0.05,
                           .hinge_len_lo = 0.01,
                           .hinge_len_hi = 0.20,
                           .youngs_rel = 0.2,
                           .position_rel = 0.01};
}

int family_draw(const rod_scene *sc, const family_ranges *rg, uint64_t seed, int index, rod_scene *twin,
                char *why, size_t why_len)
{
    if (!rod_scene_has_creases(sc) || rod_scene_hinge_rigid(sc)) {
        snprintf(why, why_len, "family: the scene needs compliant creases (folds.hinge_stiffness)");
        return -1;
    }
    if (!(rg->angle_lo_deg > 0 && rg->angle_hi_deg >= rg->angle_lo_deg && rg->angle_hi_deg < 180 &&
          rg->angle_diff_rel >= 0 && rg->angle_diff_rel < 0.5 && rg->hinge_len_lo > 0 &&
          rg->hinge_len_hi >= rg->hinge_len_lo && rg->youngs_rel >= 0 && rg->youngs_rel < 1 &&
          rg->position_rel >= 0 && rg->position_rel < 0.1) || index < 0) {
        snprintf(why, why_len, "family: ranges out of bounds");
        return -1;
    }
    uint64_t s = seed ^ (0xD1B54A32D192ED03ull * (uint64_t)(index + 1));
    splitmix(&s);
    double sign = rod_scene_crease_angle_deg(sc, 0) < 0 ? -1.0 : 1.0;
    /* The pair: a difference within the range, then a mean that keeps both inside the angles'. */
    double d = uniform(&s, -rg->angle_diff_rel, rg->angle_diff_rel);
    double mlo = rg->angle_lo_deg / (1.0 - 0.5 * fabs(d)), mhi = rg->angle_hi_deg / (1.0 + 0.5 * fabs(d));
    double m = mhi > mlo ? uniform(&s, mlo, mhi) : 0.5 * (rg->angle_lo_deg + rg->angle_hi_deg);
    double lg = uniform(&s, log(rg->hinge_len_lo), log(rg->hinge_len_hi));
    double e = uniform(&s, 1.0 - rg->youngs_rel, 1.0 + rg->youngs_rel);
    double pl = uniform(&s, -rg->position_rel, rg->position_rel);
    double pr = uniform(&s, -rg->position_rel, rg->position_rel);

    *twin = *sc;
    twin->fold_angle_left_deg = sign * m * (1.0 + 0.5 * d);
    twin->fold_angle_right_deg = sign * m * (1.0 - 0.5 * d);
    twin->youngs_modulus = sc->youngs_modulus * e;
    twin->shear_modulus = sc->shear_modulus * e;
    twin->fold_position_left = rod_scene_crease_position(sc, 0) + pl;
    twin->fold_position_right = rod_scene_crease_position(sc, 1) + pr;
    /* k = E I1 / L*, I1 = w b^3 / 12 the soft (toward-normal) bending, L* = exp(lg) l. */
    double ei1 = twin->youngs_modulus * sc->width * pow(sc->thickness, 3) / 12.0;
    twin->fold_hinge_stiffness = ei1 / (exp(lg) * sc->length);
    return 0;
}
