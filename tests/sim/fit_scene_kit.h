/* fit_scene_kit.h: the strips the fit tests (issue 32) are built on: the PET specimen's scene
 * (config/scenes/pet-200x5.ini: gravity on, compliant hinges) at a coarse mesh, and observations
 * of a strip along a compression and a shear as a trial films them. */
#ifndef RIBBON_TESTS_FIT_SCENE_KIT_H
#define RIBBON_TESTS_FIT_SCENE_KIT_H

#include "rod_fit.h"
#include "scene.h"

static inline rod_scene fit_kit_pet(int nodes)
{
    rod_scene sc = rod_scene_default();
    sc.length = 0.2;
    sc.width = 0.005;
    sc.thickness = 0.25e-3;
    sc.youngs_modulus = 4e9;
    sc.shear_modulus = 4e9 / 2.76;
    sc.density = 1380;
    sc.gravity[2] = -9.81;
    sc.fold_angle_deg = -90;
    sc.fold_position = 0.21;
    sc.fold_hinge_stiffness = 3.5e-3;
    sc.fold_angle_rel = 1e-6;
    sc.nodes = nodes;
    sc.compression = 0.3;
    sc.shear_rate = 0.001;
    sc.shear_max = 0.5;
    sc.damping = 0.5;
    return sc;
}

/* Compression at Delta L 0.25 .. 0.3 (n_c states at Delta W 0; below about 0.235 this strip at N = 31
 * has no upper state: gravity takes it), then the shear at Delta L 0.3 to
 * Delta W dw_max (n_s states). */
static inline int fit_kit_states(rod_fit_obs *obs, int n_c, int n_s, double dw_max)
{
    int n = 0;
    for (int k = 0; k < n_c; k++) obs[n++] = (rod_fit_obs){0.25 + 0.05 * k / (n_c - 1), 0.0, 0.0, 0.0};
    for (int k = 1; k <= n_s; k++) obs[n++] = (rod_fit_obs){0.3, dw_max * k / n_s, 0.0, 0.0};
    return n;
}

#endif
