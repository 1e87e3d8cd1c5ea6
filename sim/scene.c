/* scene.c: defaults for the paper's scene and the cross-field checks that need physics.
 *
 * Single-field bounds (positive lengths, Gamma in (0, 0.5), N >= 5, ...) live in config/'s key
 * table, which knows file lines; the checks here are the ones that involve several fields or the
 * mesh, so any caller that builds a scene by hand gets them too. */
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

int rod_scene_check(const rod_scene *s, char *msg, size_t msglen, char *key, size_t keylen)
{
    char buf[256];
    if (s->nodes < 5)
        return fail(msg, msglen, key, keylen, "mesh.nodes", "needs at least 5 nodes");
    if (!(fabs(s->fold_angle_deg) < 180.0))
        return fail(msg, msglen, key, keylen, "folds.angle_deg",
                    "a crease of 180 deg or more folds the ribbon flat onto itself; |angle| must be < 180");
    if (s->fold_angle_deg != 0.0) {
        /* The free length is meshed with N - 3 edges; a crease closer to the clamp than one edge
         * would sit inside the clamped edge. */
        double h = 1.0 / (double)(s->nodes - 3);
        if (!(s->fold_position > 0.0 && s->fold_position < 0.5))
            return fail(msg, msglen, key, keylen, "folds.position", "Gamma must lie in (0, 0.5)");
        if (s->fold_position < h) {
            snprintf(buf, sizeof buf,
                     "the crease at Gamma = %g lies inside the clamp (closer than one edge, %g, at N = %d)",
                     s->fold_position, h, s->nodes);
            return fail(msg, msglen, key, keylen, "folds.position", buf);
        }
        double phi1 = fabs(s->fold_angle_deg) * (1.0 + 0.5 * fabs(s->fold_angle_rel));
        if (!(phi1 < 180.0))
            return fail(msg, msglen, key, keylen, "imperfection.fold_angle_rel",
                        "the imperfection makes one crease reach 180 deg");
        /* Geometric admissibility. The tangent angle starts and ends at 0 and jumps by +phi at
         * each crease, so the smooth pieces must turn back by -2 phi in all. The gentlest way
         * (uniform curvature in each piece, tangent angle within +-phi/2) spans exactly
         * sinc(phi/2) = sin(phi/2) / (phi/2) of the free length, whatever Gamma is. A clamp gap
         * wider than that forces bending sharper than that shape everywhere near the creases;
         * we refuse it rather than let Newton fight an unphysical kink. */
        double half = 0.5 * phi1 * M_PI / 180.0;
        double span_max = sin(half) / half;
        if ((1.0 - s->compression) > span_max) {
            snprintf(buf, sizeof buf,
                     "creases of %g deg cannot be clamped at Delta L = %g: a ribbon with two such "
                     "creases spans at most %.4f l without kinking, so Delta L must be at least %.4f",
                     s->fold_angle_deg, s->compression, span_max, 1.0 - span_max);
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
