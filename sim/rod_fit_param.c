/* rod_fit_param.c: the fit's parameters put into a rod and a scene (rod_fit_param.h). */
#include "rod_fit_param.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const char *const names[ROD_FIT_NKEYS] = {
    "folds.angle_left_deg", "folds.angle_right_deg", "folds.position_left",
    "folds.position_right", "folds.hinge_stiffness", "ribbon.youngs_modulus", "view.dz_offset",
    "folds.hinge_stiffness_left", "folds.hinge_stiffness_right",
};

const char *rod_fit_key_name(rod_fit_key k)
{
    return (k >= 0 && k < ROD_FIT_NKEYS) ? names[k] : "?";
}

int rod_fit_key_parse(const char *name)
{
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (strcmp(name, names[k]) == 0) return k;
    return -1;
}

int rod_fit_key_log(rod_fit_key k)
{
    return k == ROD_FIT_HINGE || k == ROD_FIT_YOUNGS || k == ROD_FIT_HINGE_LEFT || k == ROD_FIT_HINGE_RIGHT;
}

int rod_fit_key_strip(rod_fit_key k)
{
    return k != ROD_FIT_DZ_OFFSET;
}

void rod_fit_key_bounds(rod_fit_key k, double u0, double *lo, double *hi)
{
    switch (k) {
    case ROD_FIT_ANGLE_LEFT:
    case ROD_FIT_ANGLE_RIGHT: *lo = u0 - 20.0; *hi = u0 + 20.0; break;
    case ROD_FIT_POSITION_LEFT:
    case ROD_FIT_POSITION_RIGHT: *lo = fmax(u0 - 0.05, 1e-3); *hi = fmin(u0 + 0.05, 1.0 - 1e-3); break;
    case ROD_FIT_HINGE:
    case ROD_FIT_HINGE_LEFT:
    case ROD_FIT_HINGE_RIGHT: *lo = u0 - log(100.0); *hi = u0 + log(100.0); break;
    case ROD_FIT_DZ_OFFSET: *lo = u0 - 0.05; *hi = u0 + 0.05; break;
    default: *lo = u0 - log(10.0); *hi = u0 + log(10.0); break;
    }
}

double rod_fit_key_scale(rod_fit_key k)
{
    return (k == ROD_FIT_POSITION_LEFT || k == ROD_FIT_POSITION_RIGHT || k == ROD_FIT_DZ_OFFSET) ? 0.01 : 1.0;
}

void rod_fit_base_init(rod_fit_base *b, const rod *r, const rod_scene *sc)
{
    b->EA = r->EA;
    b->EI1 = r->EI1[0];
    b->EI2 = r->EI2;
    b->GJ = r->GJ;
    b->youngs = sc->youngs_modulus;
    b->length = sc->length;
    b->rel = sc->fold_angle_rel;
    b->ln_k = rod_scene_hinge_rigid(sc) ? 0.0 : log(sc->fold_hinge_stiffness);
    b->n_left = r->fold_outer_edges;
    b->n_right = r->fold_outer_right;
}

void rod_fit_scene_values(const rod_scene *sc, double u[ROD_FIT_NKEYS])
{
    u[ROD_FIT_ANGLE_LEFT] = rod_scene_crease_angle_deg(sc, 0);
    u[ROD_FIT_ANGLE_RIGHT] = rod_scene_crease_angle_deg(sc, 1);
    u[ROD_FIT_POSITION_LEFT] = rod_scene_crease_position(sc, 0);
    u[ROD_FIT_POSITION_RIGHT] = rod_scene_crease_position(sc, 1);
    u[ROD_FIT_HINGE] = rod_scene_hinge_rigid(sc) ? 0.0 : log(sc->fold_hinge_stiffness);
    u[ROD_FIT_YOUNGS] = log(sc->youngs_modulus);
    u[ROD_FIT_DZ_OFFSET] = 0.0;
    u[ROD_FIT_HINGE_LEFT] = rod_scene_hinge_rigid(sc) ? 0.0 : log(rod_scene_hinge_k(sc, 0));
    u[ROD_FIT_HINGE_RIGHT] = rod_scene_hinge_rigid(sc) ? 0.0 : log(rod_scene_hinge_k(sc, 1));
}

int rod_fit_key_usable(const rod_scene *sc, rod_fit_key k, char *why, size_t why_len)
{
    if (k < 0 || k >= ROD_FIT_NKEYS) {
        snprintf(why, why_len, "not a fit parameter");
        return 1;
    }
    int hinge = k == ROD_FIT_HINGE || k == ROD_FIT_HINGE_LEFT || k == ROD_FIT_HINGE_RIGHT;
    if ((k <= ROD_FIT_HINGE || hinge) && !rod_scene_has_creases(sc)) {
        snprintf(why, why_len, "%s: the scene has no creases", names[k]);
        return 1;
    }
    if (hinge && rod_scene_hinge_rigid(sc)) {
        snprintf(why, why_len, "%s: the scene's creases are rigid; give the scene a compliant hinge "
                               "(folds.hinge_stiffness in N m/rad) as the fit's starting point", names[k]);
        return 1;
    }
    return 0;
}

void rod_fit_apply(rod *r, const rod_fit_base *b, const double u[ROD_FIT_NKEYS])
{
    double s = exp(u[ROD_FIT_YOUNGS]) / b->youngs;
    r->EA = b->EA * s;
    r->EI2 = b->EI2 * s;
    r->GJ = b->GJ * s;
    for (int i = 0; i < r->n; i++) r->EI1[i] = b->EI1 * s;
    r->force_scale = b->EI1 * s / (b->length * b->length);
    if (!r->terms.fold && !r->terms.hinge) return;
    if (r->terms.hinge) {
        r->hinge_k = exp(u[ROD_FIT_HINGE]);
        r->hinge_k_side[0] = exp(u[ROD_FIT_HINGE] - b->ln_k + u[ROD_FIT_HINGE_LEFT]);
        r->hinge_k_side[1] = exp(u[ROD_FIT_HINGE] - b->ln_k + u[ROD_FIT_HINGE_RIGHT]);
    }
    if (u[ROD_FIT_POSITION_LEFT] != r->fold_position || u[ROD_FIT_POSITION_RIGHT] != r->fold_position_right)
        rod_mesh_set_creases(r, u[ROD_FIT_POSITION_LEFT], u[ROD_FIT_POSITION_RIGHT], b->n_left, b->n_right);
    /* As rod_alloc: the imperfection on top of each crease's own angle (it also resets the crease
       nodes' stiffness from EI1[0]). */
    rod_set_crease_angles(r, u[ROD_FIT_ANGLE_LEFT] * M_PI / 180.0 * (1.0 + 0.5 * b->rel),
                          u[ROD_FIT_ANGLE_RIGHT] * M_PI / 180.0 * (1.0 - 0.5 * b->rel));
}

void rod_fit_scene_apply(rod_scene *sc, const double u[ROD_FIT_NKEYS])
{
    double e = exp(u[ROD_FIT_YOUNGS]);
    sc->shear_modulus *= e / sc->youngs_modulus;
    sc->youngs_modulus = e;
    if (!rod_scene_has_creases(sc)) return;
    sc->fold_angle_left_deg = u[ROD_FIT_ANGLE_LEFT];
    sc->fold_angle_right_deg = u[ROD_FIT_ANGLE_RIGHT];
    sc->fold_position_left = u[ROD_FIT_POSITION_LEFT];
    sc->fold_position_right = u[ROD_FIT_POSITION_RIGHT];
    if (rod_scene_hinge_rigid(sc)) return;
    /* Each crease's own key is written when the scene had it or the fit made the two differ. A
       value at the scene's own (u as rod_fit_scene_values gives it) is the scene's, bit for bit:
       exp(log(k)) is not always k. */
    double ln_k0 = log(sc->fold_hinge_stiffness);
    int same = u[ROD_FIT_HINGE] == ln_k0;
    double k = same ? sc->fold_hinge_stiffness : exp(u[ROD_FIT_HINGE]);
    double side[2];
    for (int c = 0; c < 2; c++) {
        double us = u[c ? ROD_FIT_HINGE_RIGHT : ROD_FIT_HINGE_LEFT], k_own = rod_scene_hinge_k(sc, c);
        side[c] = same && us == log(k_own) ? k_own : exp(u[ROD_FIT_HINGE] - ln_k0 + us);
    }
    int own = !isnan(sc->fold_hinge_stiffness_left) || !isnan(sc->fold_hinge_stiffness_right) ||
              fabs(side[0] / k - 1.0) > 1e-12 || fabs(side[1] / k - 1.0) > 1e-12;
    sc->fold_hinge_stiffness = k;
    sc->fold_hinge_stiffness_left = own ? side[0] : NAN;
    sc->fold_hinge_stiffness_right = own ? side[1] : NAN;
}
