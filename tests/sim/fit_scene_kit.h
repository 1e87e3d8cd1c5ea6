/* fit_scene_kit.h: the strips the fit tests (issue 32) are built on: the PET specimen's scene
 * (config/scenes/pet-200x5.ini: gravity on, compliant hinges) at a coarse mesh, and observations
 * of a strip along a compression and a shear as a trial films them. */
#ifndef RIBBON_TESTS_FIT_SCENE_KIT_H
#define RIBBON_TESTS_FIT_SCENE_KIT_H

#include <stdio.h>
#include <stdlib.h>

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

/* The observables of strip `truth` at obs[0..n-1]'s (Delta L, Delta W), exactly: its own model's
 * Delta Z and A into obs[k].dz, .a. ROD_OK, or the model's status with why. */
static inline rod_status fit_kit_observe(const rod_scene *truth, rod_fit_obs *obs, int n, char *why, size_t why_len)
{
    rod_fit_model *m = NULL;
    rod_status st = rod_fit_model_alloc(truth, obs, n, 0, &m, why, why_len);
    if (st != ROD_OK) return st;
    double u[ROD_FIT_NKEYS], *y = malloc(sizeof *y * 2 * (size_t)n);
    if (!y) {
        rod_fit_model_free(m);
        snprintf(why, why_len, "fit_kit_observe: out of memory");
        return ROD_ERR_ALLOC;
    }
    rod_fit_scene_values(truth, u);
    st = rod_fit_model_eval(m, u, NULL, y, NULL, why, why_len);
    for (int k = 0; k < n && st == ROD_OK; k++) {
        obs[k].dz = y[2 * k];
        obs[k].a = y[2 * k + 1];
    }
    free(y);
    rod_fit_model_free(m);
    return st;
}

#endif
