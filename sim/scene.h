/* scene.h: the physical scene a prediction runs on (ribbon, folds, imperfection, mesh,
 * protocol, solver), as plain typed parameters in SI units.
 *
 * Owned here because the simulator is the only consumer of its meaning; config/ fills it from
 * INI files and `--set section.key=value` overrides, and names file, line and key on errors.
 * Frame convention (DESIGN.md section 3): x is the compression axis (clamps at x = 0 and
 * x = l - dl), y is the width / shear direction, z is up. The clamps hold the ribbon flat with
 * its surface normal along +z. rod_scene_check() does the cross-field checks that need physics
 * (a fold inside a clamp, an impossible crease) and names the offending key. */
#ifndef RIBBON_SIM_SCENE_H
#define RIBBON_SIM_SCENE_H

#include <math.h>
#include <stddef.h>

/* How the simulator reaches the upper state at Delta L (DESIGN.md section 3). */
typedef enum rod_route {
    ROD_ROUTE_COMPRESS_THEN_FOLD = 0, /* compress the flat ribbon with an upward bias, then ramp
                                         the crease angle and stiffness at fixed Delta L */
    ROD_ROUTE_TOGETHER = 1            /* ramp compression and crease together, same bias */
} rod_route;

typedef struct rod_scene {
    /* [ribbon] */
    double length;          /* m, free length l between the two clamp points */
    double width;           /* m */
    double thickness;       /* m */
    double youngs_modulus;  /* Pa */
    double shear_modulus;   /* Pa */
    double density;         /* kg/m^3 */
    double gravity[3];      /* m/s^2, (x, y, z); default 0 0 0 (off) */

    /* [folds] two creases, "left" near the x = 0 clamp and "right" near the other. The pair is
     * symmetric (angle_deg at Gamma and 1 - Gamma) unless the per-crease keys say otherwise;
     * read them through rod_scene_crease_angle_deg / rod_scene_crease_position. */
    double fold_angle_deg;        /* deg, 0 means no folds; |angle| < 180; positive turns the
                                     tangent toward the surface normal (up when clamped flat) */
    double fold_position;         /* Gamma, in (0, 0.5), fraction of the free length */
    double fold_angle_left_deg;   /* deg, the left crease's own angle; NaN: fold_angle_deg */
    double fold_angle_right_deg;  /* deg, the right crease's own angle; NaN: fold_angle_deg */
    double fold_position_left;    /* left crease from the left clamp point, over l; NaN: Gamma */
    double fold_position_right;   /* right crease from the left clamp point, over l;
                                     NaN: 1 - Gamma */
    double fold_hinge_stiffness;  /* N m/rad, the creases' rotational stiffness k (a compliant
                                     hinge, sim/rod_hinge.c); ROD_HINGE_RIGID: rigid creases */
    double fold_hinge_stiffness_left;  /* N m/rad, the left crease's own k (compliant creases
                                          only); NaN: fold_hinge_stiffness */
    double fold_hinge_stiffness_right; /* N m/rad, the right crease's own k; NaN: the pair's */
    double fold_stiffness_factor; /* >= 1, rigid creases only: multiplies the soft bending
                                     stiffness at a fold node (the penalty that holds the angle) */

    /* [imperfection] */
    double fold_angle_rel;  /* relative difference between the two crease angles, applied on top
                               of each crease's own angle as a symmetry-breaking seed: the left
                               crease gets phi_L (1 + rel/2), the right one phi_R (1 - rel/2) */

    /* [mesh] */
    int nodes;              /* N, total nodes including the two clamped edges, >= 5 */

    /* [protocol] */
    double compression;     /* Delta L = dl / l, in [0, 1) */
    double shear_rate;      /* m/s, rate of the shear clamp along y, > 0 */
    double shear_max;       /* Delta W = dw / l at which the protocol stops without a snap */
    rod_route route;        /* route to the upper state */

    /* [solver] */
    double dt;              /* s, time step of the dynamics */
    double damping;         /* 1/s, mass-proportional damping mu (C = mu M) */
    double tolerance;       /* Newton tolerance on the force residual, relative to the
                               scene's force scale EI1 / l^2 */
    int max_iterations;     /* Newton iteration cap per solve */

    /* [snap] detection (README: "Snap") */
    double snap_speed;      /* 1/s, |d(Delta Z)/dt| above which the ribbon is snapping */
    double asym_threshold;  /* rad, peak |A| during the snap above which it is asymmetric */
} rod_scene;

/* fold_hinge_stiffness of a rigid crease (the default: today's model, EI1 times
 * fold_stiffness_factor at the crease node). */
#define ROD_HINGE_RIGID INFINITY

/* The paper's simulation scene (l = 1 m, w = 0.2 m, b = 1 mm, E = 1 GPa, G = E/3,
 * rho = 1000 kg/m^3, N = 201, dt = 1 ms, 0.01 m/s, Delta L = 0.5, phi = 90 deg, Gamma = 0.13). */
rod_scene rod_scene_default(void);

/* Crease k (0 left, 1 right) as the scene resolves it: its own angle (deg, before the
 * imperfection) or fold_angle_deg, its position (from the left clamp point, over l) or Gamma /
 * 1 - Gamma. */
double rod_scene_crease_angle_deg(const rod_scene *s, int k);
double rod_scene_crease_position(const rod_scene *s, int k);

/* 1 when the scene has creases (either resolved angle non-zero). */
int rod_scene_has_creases(const rod_scene *s);

/* 1 when the creases are rigid (fold_hinge_stiffness is ROD_HINGE_RIGID). */
int rod_scene_hinge_rigid(const rod_scene *s);
/* Crease k's hinge stiffness (0 left, 1 right): its own key when set, else the pair's. */
double rod_scene_hinge_k(const rod_scene *s, int k);

/* Tools that rely on the C2 symmetry of the perfect scene (continuation's classification,
 * sweeps, the boundary) call this: 0 when the resolved creases are a symmetric pair (equal
 * angles, positions p and 1 - p), after which the per-crease keys are cleared (NaN) so that
 * later changes of fold_angle_deg / fold_position move both creases; otherwise non-zero with a
 * message and the key to blame, as rod_scene_check. */
int rod_scene_require_symmetric(rod_scene *s, char *msg, size_t msglen, char *key, size_t keylen);

/* Most time steps a scene's shear ramp may need (shear_max * length / shear_rate / dt):
 * rod_scene_check refuses more, naming solver.dt or protocol.shear_rate and the count. 10^12 steps
 * would already take weeks; the point is that no count reaches the range of a long. */
#define ROD_SCENE_MAX_STEPS 1e12

/* Cross-field checks. Returns 0 when the scene is usable; otherwise non-zero, writes a message
 * to msg and the "section.key" most to blame to key (both may be NULL). */
int rod_scene_check(const rod_scene *s, char *msg, size_t msglen, char *key, size_t keylen);

#endif
