/* rod_fit_param.h: the strip parameters a fit may adjust (issue 32 A), their scene keys, the
 * scale each is fitted on, and how a vector of them is put into a rod and into a scene.
 *
 * Owned apart from the fit so that the sensitivities (rod_sensitivity.h) and the fit
 * (rod_fit.h) share one meaning of "parameter j". Values u are in fit units:
 *   folds.angle_left_deg, folds.angle_right_deg  deg, each crease's angle before the
 *                                                imperfection (the scene key's own value)
 *   folds.position_left, folds.position_right    over l from the left clamp point; the mesh
 *                                                moves with them (edge counts held)
 *   folds.hinge_stiffness                        ln(k / (N m/rad)): one k for both creases,
 *                                                compliant creases only
 *   ribbon.youngs_modulus                        ln(E / Pa), the shear modulus scaled with it
 *                                                (G / E held): the elastic stiffness against
 *                                                gravity and the hinges
 *   folds.hinge_stiffness_left, _right           ln(k / (N m/rad)) of each crease's own hinge
 *                                                (compliant creases only): one k each, instead
 *                                                of one for both (not both kinds in one fit);
 *                                                held ones follow folds.hinge_stiffness
 *   view.dz_offset                               over l: a vertical offset of the camera's view,
 *                                                added to the model's Delta Z (the camera's
 *                                                zero height not on the clamps' line). Not a
 *                                                property of the strip: the rod and the scene
 *                                                never see it (0 at the scene's values), and the
 *                                                snap does not depend on it.
 * New keys go at the end, so the values of the ones before stay what callers compiled against.
 */
#ifndef RIBBON_SIM_ROD_FIT_PARAM_H
#define RIBBON_SIM_ROD_FIT_PARAM_H

#include "rod.h"

typedef enum rod_fit_key {
    ROD_FIT_ANGLE_LEFT = 0,
    ROD_FIT_ANGLE_RIGHT,
    ROD_FIT_POSITION_LEFT,
    ROD_FIT_POSITION_RIGHT,
    ROD_FIT_HINGE,
    ROD_FIT_YOUNGS,
    ROD_FIT_DZ_OFFSET,
    ROD_FIT_HINGE_LEFT,
    ROD_FIT_HINGE_RIGHT,
    ROD_FIT_NKEYS
} rod_fit_key;

/* "folds.angle_left_deg", ... as above. */
const char *rod_fit_key_name(rod_fit_key k);
/* The key named name, or -1 when name is not a fit parameter. */
int rod_fit_key_parse(const char *name);
/* 1 when parameter k is on a log scale (its standard error is a relative error). */
int rod_fit_key_log(rod_fit_key k);
/* 1 when parameter k describes the strip (it enters the rod and the scene); 0 for the camera's
 * view.dz_offset, which only shifts what is observed. */
int rod_fit_key_strip(rod_fit_key k);

/* Parameter k's default bounds around the start u0 (fit units): -+ 20 deg on an angle, -+ 0.05
 * (of l) on a position kept inside (0, 1) and on view.dz_offset, -+ ln 100 on a hinge, -+ ln 10
 * on E. */
void rod_fit_key_bounds(rod_fit_key k, double u0, double *lo, double *hi);
/* The step of parameter k in the fits' scaled unknowns (0.01 for the positions and the view's
 * offset, 1 otherwise): so that the solver's unknowns are of like size. */
double rod_fit_key_scale(rod_fit_key k);

/* What the rod was built with, so parameter vectors can be applied and re-applied. */
typedef struct rod_fit_base {
    double EA, EI1, EI2, GJ; /* the scene's stiffnesses (EI1 away from creases) */
    double youngs, length;   /* Pa, m */
    double rel;              /* imperfection fold_angle_rel */
    double ln_k;             /* ln of the scene's folds.hinge_stiffness (0 for rigid creases) */
    int n_left, n_right;     /* mesh edges outside each crease, held as the creases move */
} rod_fit_base;

/* Records the base of a rod just built by rod_alloc from sc. */
void rod_fit_base_init(rod_fit_base *b, const rod *r, const rod_scene *sc);

/* The scene's values in fit units (u[ROD_FIT_HINGE] and the per-crease ones are 0 for rigid
 * creases, where they are not parameters). Each crease's hinge is
 *     k_side = exp(u[ROD_FIT_HINGE] - ln k_scene + u[ROD_FIT_HINGE_side]),
 * so fitting folds.hinge_stiffness scales both, and fitting the per-crease keys sets each. */
void rod_fit_scene_values(const rod_scene *sc, double u[ROD_FIT_NKEYS]);

/* 0 when parameter k can be fitted on scene sc; otherwise non-zero with the reason. */
int rod_fit_key_usable(const rod_scene *sc, rod_fit_key k, char *why, size_t why_len);

/* Puts u into the rod: stiffnesses, hinge stiffness, mesh (when the positions changed) and crease
 * angles. The clamps are not placed: call rod_set_clamps afterwards (the clamped edges' length
 * follows the mesh). q and the frames are not touched. */
void rod_fit_apply(rod *r, const rod_fit_base *b, const double u[ROD_FIT_NKEYS]);

/* Writes u into a scene (per-crease keys, hinge stiffness, E and G). */
void rod_fit_scene_apply(rod_scene *sc, const double u[ROD_FIT_NKEYS]);

#endif
