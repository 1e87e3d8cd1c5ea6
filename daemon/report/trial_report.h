/* trial_report.h: the figures made from the store: a trial's report (Delta Z and A against
 * Delta W, measured and predicted, snaps marked) and the phase report (every trial's measured
 * regime on the predicted (Gamma, phi) phase diagram). Used by the API (report.png) and by
 * ribbonctl (report, phase-report), with or without a daemon. Plotting itself is plot.h's. The
 * report room's face. */
#ifndef RIBBON_REPORT_TRIAL_REPORT_H
#define RIBBON_REPORT_TRIAL_REPORT_H

#include <stddef.h>
#include <stdint.h>

#include "scene.h"
#include "store.h"
#include "trial.h"

/* Writes the report of trial id to png_path: TRIAL_E_NOTFOUND when there is no such trial,
 * TRIAL_E_FAILED when the store or the plot failed (why says which). */
trial_err trial_report_png(store *st, int64_t id, const char *png_path, char *why, size_t why_len);
/* The same as malloc'ed PNG bytes. */
trial_err trial_report_png_bytes(store *st, int64_t id, unsigned char **png, size_t *len, char *why, size_t why_len);

/* The predicted phase diagram: regime codes ("asymmetric", ...) of scene `base` with its crease
 * angle and position replaced by each (phi_deg[i], gamma[j]); grid[i * n_gamma + j]. Each point is
 * a prediction at the base scene's resolution; progress (may be NULL) is told each point. */
typedef struct phase_grid {
    size_t n_phi, n_gamma;
    double *phi_deg, *gamma;
    int *regime;   /* plot_regime codes */
} phase_grid;
int phase_grid_compute(const rod_scene *base, double phi0, double phi1, size_t n_phi, double g0, double g1,
                       size_t n_gamma, phase_grid *out, void (*progress)(void *u, size_t done, size_t total),
                       void *u, char *why, size_t why_len);
void phase_grid_free(phase_grid *g);

/* Draws every trial of the store (measured regime at its crease angle and position) over grid
 * (may be NULL: trials only). */
int trial_phase_report_png(store *st, const phase_grid *grid, const char *png_path, char *why, size_t why_len);

#endif
