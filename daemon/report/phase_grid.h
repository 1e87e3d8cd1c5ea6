/* phase_grid.h: the predicted phase diagram of a scene: the regime predicted at each (phi, Gamma)
 * of a grid, the scene's crease angle and position replaced by each point's. Computed point by
 * point (one prediction each, at the base scene's resolution); used by the phase report
 * (trial_report.h) and by ribbond's phase map (phase_map.h). */
#ifndef RIBBON_REPORT_PHASE_GRID_H
#define RIBBON_REPORT_PHASE_GRID_H

#include <stdatomic.h>
#include <stddef.h>

#include "scene.h"

/* Regime codes ("asymmetric", ...) of scene `base` with its crease angle and position replaced
 * by each (phi_deg[i], gamma[j]); grid[i * n_gamma + j]. */
typedef struct phase_grid {
    size_t n_phi, n_gamma;
    double *phi_deg, *gamma;
    int *regime;   /* plot_regime codes */
} phase_grid;

/* progress (may be NULL) is told each point. cancel (may be NULL): once non-zero, the point being
 * computed stops at its next time step and the computation fails with "cancelled". Returns 0, or
 * -1 with why (and *out empty). */
int phase_grid_compute(const rod_scene *base, double phi0, double phi1, size_t n_phi, double g0, double g1,
                       size_t n_gamma, phase_grid *out, void (*progress)(void *u, size_t done, size_t total),
                       void *u, const atomic_int *cancel, char *why, size_t why_len);
void phase_grid_free(phase_grid *g);

#endif
