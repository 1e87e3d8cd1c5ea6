/* scene.c: defaults for the paper's scene and the cross-field checks that need physics.
 *
 * Single-field bounds (positive lengths, Gamma in (0, 0.5), N >= 5, ...) live in config/'s key
 * table, which knows file lines; the checks here are the ones that involve several fields or the
 * mesh, so any caller that builds a scene by hand gets them too. The per-crease values (angle,
 * position) are resolved here from their own keys or the symmetric pair's, and every crease
 * check uses each crease's own values. */
#include "scene.h"
#include "rod_regime.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

rod_scene rod_scene_default(void)
{
    rod_scene s;
    memset(&s, 0, sizeof s);
    s.length = 1.0;
    s.width = 0.2;
    s.thickness = 1e-3;
    s.youngs_modulus = 1e9;
    s.shear_modulus = 1e9 / 3.0;
    s.density = 1000.0;
    s.fold_angle_deg = -90.0;
    s.fold_position = 0.13;
    s.fold_angle_left_deg = NAN;
    s.fold_angle_right_deg = NAN;
    s.fold_position_left = NAN;
    s.fold_position_right = NAN;
    s.fold_hinge_stiffness = ROD_HINGE_RIGID;
    s.fold_hinge_stiffness_left = NAN;
    s.fold_hinge_stiffness_right = NAN;
    s.fold_stiffness_factor = 1e4;
    s.fold_angle_rel = 1e-6;
    s.nodes = 201;
    s.compression = 0.5;
    s.shear_rate = 0.01;
    s.shear_max = 0.5;
    s.route = ROD_ROUTE_COMPRESS_THEN_FOLD;
    s.dt = 1e-3;
    s.damping = 0.5;
    s.tolerance = 1e-6;
    s.max_iterations = 50;
    s.snap_speed = 1.0;
    s.asym_threshold = ROD_REGIME_ASYM_THRESHOLD;
    return s;
}

static int fail(char *msg, size_t msglen, char *key, size_t keylen, const char *k, const char *text)
{
    if (msg && msglen) snprintf(msg, msglen, "%s", text);
    if (key && keylen) snprintf(key, keylen, "%s", k);
    return 1;
}

double rod_scene_crease_angle_deg(const rod_scene *s, int k)
{
    double own = k == 0 ? s->fold_angle_left_deg : s->fold_angle_right_deg;
    return isnan(own) ? s->fold_angle_deg : own;
}

double rod_scene_crease_position(const rod_scene *s, int k)
{
    double own = k == 0 ? s->fold_position_left : s->fold_position_right;
    if (!isnan(own)) return own;
    return k == 0 ? s->fold_position : 1.0 - s->fold_position;
}

int rod_scene_has_creases(const rod_scene *s)
{
    return rod_scene_crease_angle_deg(s, 0) != 0.0 || rod_scene_crease_angle_deg(s, 1) != 0.0;
}

int rod_scene_hinge_rigid(const rod_scene *s) { return isinf(s->fold_hinge_stiffness) && s->fold_hinge_stiffness > 0; }

double rod_scene_hinge_k(const rod_scene *s, int k)
{
    double own = k == 0 ? s->fold_hinge_stiffness_left : s->fold_hinge_stiffness_right;
    return isnan(own) ? s->fold_hinge_stiffness : own;
}

/* Mean of cos over the tangent angles swept uniformly from x0 to x1. */
static double mean_cos(double x0, double x1)
{
    if (fabs(x1 - x0) < 1e-9) return cos(0.5 * (x0 + x1));
    return (sin(x1) - sin(x0)) / (x1 - x0);
}

/* The per-crease keys: each angle and position finite and in range, the positions in order, off
 * the clamps and at least one edge apart (the mesh puts a node on each, rod_mesh_set_creases). */
static int check_creases(const rod_scene *s, char *msg, size_t msglen, char *key, size_t keylen)
{
    char buf[256];
    static const char *const angle_key[2] = {"folds.angle_left_deg", "folds.angle_right_deg"};
    static const char *const pos_key[2] = {"folds.position_left", "folds.position_right"};
    for (int k = 0; k < 2; k++) {
        double own = k == 0 ? s->fold_angle_left_deg : s->fold_angle_right_deg;
        if (!isnan(own) && !(fabs(own) < 180.0))
            return fail(msg, msglen, key, keylen, angle_key[k],
                        "a crease of 180 deg or more folds the ribbon flat onto itself; |angle| must be < 180");
    }
    double al = rod_scene_crease_angle_deg(s, 0), ar = rod_scene_crease_angle_deg(s, 1);
    if ((al > 0.0 && ar < 0.0) || (al < 0.0 && ar > 0.0)) {
        snprintf(buf, sizeof buf,
                 "the creases turn opposite ways (%g and %g deg): both must have the sign of the pair "
                 "(a mixed pair is not modelled)",
                 al, ar);
        return fail(msg, msglen, key, keylen, isnan(s->fold_angle_right_deg) ? angle_key[0] : angle_key[1], buf);
    }
    if (!rod_scene_has_creases(s)) return 0;
    if (!(s->fold_hinge_stiffness > 0.0))
        return fail(msg, msglen, key, keylen, "folds.hinge_stiffness",
                    "the hinge stiffness must be a positive number of N m/rad (or rigid); 0, negative "
                    "and NaN are refused");
    /* Each crease's own hinge: a compliant pair's, positive and finite. */
    for (int k = 0; k < 2; k++) {
        double own = k == 0 ? s->fold_hinge_stiffness_left : s->fold_hinge_stiffness_right;
        const char *name = k == 0 ? "folds.hinge_stiffness_left" : "folds.hinge_stiffness_right";
        if (isnan(own)) continue;
        if (rod_scene_hinge_rigid(s))
            return fail(msg, msglen, key, keylen, name,
                        "a crease's own hinge stiffness needs compliant creases: set folds.hinge_stiffness "
                        "to a number of N m/rad too");
        if (!(own > 0.0 && isfinite(own)))
            return fail(msg, msglen, key, keylen, name, "a crease's hinge stiffness must be a positive number of N m/rad");
    }
    /* The free length is meshed with N - 3 edges; a crease closer to the clamp than one edge
     * would sit inside the clamped edge. */
    double h = 1.0 / (double)(s->nodes - 3);
    int own_pos = !isnan(s->fold_position_left) || !isnan(s->fold_position_right);
    if (!own_pos || isnan(s->fold_position_left) || isnan(s->fold_position_right))
        if (!(s->fold_position > 0.0 && s->fold_position < 0.5))
            return fail(msg, msglen, key, keylen, "folds.position", "Gamma must lie in (0, 0.5)");
    double p[2] = {rod_scene_crease_position(s, 0), rod_scene_crease_position(s, 1)};
    const char *blame[2] = {isnan(s->fold_position_left) ? "folds.position" : pos_key[0],
                            isnan(s->fold_position_right) ? "folds.position" : pos_key[1]};
    for (int k = 0; k < 2; k++)
        if (!(p[k] > 0.0 && p[k] < 1.0)) {
            snprintf(buf, sizeof buf, "the %s crease at %g lies outside the free length (0, 1)",
                     k == 0 ? "left" : "right", p[k]);
            return fail(msg, msglen, key, keylen, blame[k], buf);
        }
    if (!(p[0] < p[1])) {
        snprintf(buf, sizeof buf,
                 "the creases cross: the left one (%g) must lie before the right one (%g), both "
                 "measured from the left clamp point",
                 p[0], p[1]);
        return fail(msg, msglen, key, keylen, blame[isnan(s->fold_position_right) ? 0 : 1], buf);
    }
    for (int k = 0; k < 2; k++) {
        double gap = k == 0 ? p[0] : 1.0 - p[1];
        if (gap < h) {
            if (!own_pos)
                snprintf(buf, sizeof buf,
                         "the crease at Gamma = %g lies inside the clamp (closer than one edge, %g, at N = %d)",
                         s->fold_position, h, s->nodes);
            else
                snprintf(buf, sizeof buf,
                         "the %s crease at %g lies inside the clamp (closer than one edge, %g, at N = %d)",
                         k == 0 ? "left" : "right", p[k], h, s->nodes);
            return fail(msg, msglen, key, keylen, blame[k], buf);
        }
    }
    if (p[1] - p[0] < h) {
        snprintf(buf, sizeof buf,
                 "the creases at %g and %g are closer than one edge (%g at N = %d): the mesh cannot "
                 "put a node on each",
                 p[0], p[1], h, s->nodes);
        return fail(msg, msglen, key, keylen, blame[isnan(s->fold_position_right) ? 0 : 1], buf);
    }
    return 0;
}

int rod_scene_check(const rod_scene *s, char *msg, size_t msglen, char *key, size_t keylen)
{
    char buf[256];
    if (s->nodes < 5)
        return fail(msg, msglen, key, keylen, "mesh.nodes", "needs at least 5 nodes");
    if (!(fabs(s->fold_angle_deg) < 180.0))
        return fail(msg, msglen, key, keylen, "folds.angle_deg",
                    "a crease of 180 deg or more folds the ribbon flat onto itself; |angle| must be < 180");
    if (check_creases(s, msg, msglen, key, keylen)) return 1;
    if (rod_scene_has_creases(s)) {
        double rel = s->fold_angle_rel;
        double phi[2] = {rod_scene_crease_angle_deg(s, 0) * (1.0 + 0.5 * rel),
                         rod_scene_crease_angle_deg(s, 1) * (1.0 - 0.5 * rel)};
        if (!(fabs(phi[0]) < 180.0 && fabs(phi[1]) < 180.0))
            return fail(msg, msglen, key, keylen, "imperfection.fold_angle_rel",
                        "the imperfection makes one crease reach 180 deg");
        /* Geometric admissibility. The tangent angle starts and ends at 0 and jumps by +phi_k at
         * each crease, so the smooth pieces must turn back by -(phi_L + phi_R) in all. The
         * gentlest way (uniform curvature in each piece, the tangent angle within +-phi_k / 2
         * around crease k) spans a p_L sinc(phi_L / 2) + (p_R - p_L) <cos> + (1 - p_R)
         * sinc(phi_R / 2) of the free length, <cos> the mean of cos from phi_L / 2 down to
         * -phi_R / 2; for equal creases that is sinc(phi / 2) whatever the positions. A clamp gap
         * wider than that forces bending sharper than that shape everywhere near the creases; we
         * refuse it rather than let Newton fight an unphysical kink. */
        double hl = 0.5 * phi[0] * M_PI / 180.0, hr = 0.5 * phi[1] * M_PI / 180.0;
        double pl = rod_scene_crease_position(s, 0), pr = rod_scene_crease_position(s, 1);
        double span_max = pl * mean_cos(0.0, hl) + (pr - pl) * mean_cos(hl, -hr) + (1.0 - pr) * mean_cos(0.0, hr);
        if ((1.0 - s->compression) > span_max) {
            if (rod_scene_crease_angle_deg(s, 0) == rod_scene_crease_angle_deg(s, 1))
                snprintf(buf, sizeof buf,
                         "creases of %g deg cannot be clamped at Delta L = %g: a ribbon with two such "
                         "creases spans at most %.4f l without kinking, so Delta L must be at least %.4f",
                         s->fold_angle_deg, s->compression, span_max, 1.0 - span_max);
            else
                snprintf(buf, sizeof buf,
                         "creases of %g and %g deg cannot be clamped at Delta L = %g: a ribbon with "
                         "these creases spans at most %.4f l without kinking, so Delta L must be at "
                         "least %.4f",
                         rod_scene_crease_angle_deg(s, 0), rod_scene_crease_angle_deg(s, 1), s->compression,
                         span_max, 1.0 - span_max);
            return fail(msg, msglen, key, keylen, "protocol.compression", buf);
        }
    }
    if (!(s->compression >= 0.0 && s->compression < 1.0))
        return fail(msg, msglen, key, keylen, "protocol.compression", "Delta L must lie in [0, 1)");
    /* The shear ramp at the base step: Delta W_max l / v / dt steps. Counted in double, so a
     * dt of 1e-300 gives a huge count, never an overflow; the key named is the one whose value
     * is further below the paper's (dt = 1 ms, v = 0.01 m/s). */
    double steps = s->shear_max * s->length / s->shear_rate / s->dt;
    if (!(steps <= ROD_SCENE_MAX_STEPS)) {
        int blame_dt = (s->dt / 1e-3) <= (s->shear_rate / 0.01);
        snprintf(buf, sizeof buf,
                 "the shear ramp would take %.3g time steps at %s = %g (more than %.0e; "
                 "Delta W_max l / v / dt)",
                 steps, blame_dt ? "solver.dt" : "protocol.shear_rate",
                 blame_dt ? s->dt : s->shear_rate, ROD_SCENE_MAX_STEPS);
        return fail(msg, msglen, key, keylen, blame_dt ? "solver.dt" : "protocol.shear_rate", buf);
    }
    return 0;
}

int rod_scene_require_symmetric(rod_scene *s, char *msg, size_t msglen, char *key, size_t keylen)
{
    char buf[256];
    double al = rod_scene_crease_angle_deg(s, 0), ar = rod_scene_crease_angle_deg(s, 1);
    double pl = rod_scene_crease_position(s, 0), pr = rod_scene_crease_position(s, 1);
    if (al != ar) {
        snprintf(buf, sizeof buf,
                 "this analysis needs the C2-symmetric scene, but the creases differ (%g and %g deg); "
                 "give the difference as imperfection.fold_angle_rel, or use predict",
                 al, ar);
        return fail(msg, msglen, key, keylen,
                    isnan(s->fold_angle_right_deg) ? "folds.angle_left_deg" : "folds.angle_right_deg", buf);
    }
    if (rod_scene_has_creases(s) && fabs(pl + pr - 1.0) > 1e-12) {
        snprintf(buf, sizeof buf,
                 "this analysis needs the C2-symmetric scene, but the creases sit at %g and %g (not "
                 "p and 1 - p); use predict",
                 pl, pr);
        return fail(msg, msglen, key, keylen,
                    isnan(s->fold_position_right) ? "folds.position_left" : "folds.position_right", buf);
    }
    s->fold_angle_deg = al;
    if (rod_scene_has_creases(s)) s->fold_position = pl;
    s->fold_angle_left_deg = s->fold_angle_right_deg = NAN;
    s->fold_position_left = s->fold_position_right = NAN;
    return 0;
}
