/* trial_report.h: the figures made from the store: a trial's report (Delta Z and A against
 * Delta W, measured and predicted, snaps marked) and the phase report (every trial's measured
 * regime on the predicted (Gamma, phi) phase diagram). Used by the API (report.png, phase.png)
 * and by ribbonctl (report, phase-report), with or without a daemon. Plotting itself is plot.h's.
 * The report room's face: it brings phase_grid.h (the predicted map, point by point) and
 * phase_map.h (ribbond's map, computed once on a thread of its own). */
#ifndef RIBBON_REPORT_TRIAL_REPORT_H
#define RIBBON_REPORT_TRIAL_REPORT_H

#include <stddef.h>
#include <stdint.h>

#include "phase_grid.h"
#include "phase_map.h"
#include "scene.h"
#include "store.h"
#include "trial.h"

/* Writes the report of trial id to png_path: TRIAL_E_NOTFOUND when there is no such trial,
 * TRIAL_E_FAILED when the store or the plot failed (why says which). */
trial_err trial_report_png(store *st, int64_t id, const char *png_path, char *why, size_t why_len);
/* The same as malloc'ed PNG bytes. */
trial_err trial_report_png_bytes(store *st, int64_t id, unsigned char **png, size_t *len, char *why, size_t why_len);

/* Draws every trial of the store (measured regime at its crease angle and position) over grid
 * (may be NULL: trials only). */
int trial_phase_report_png(store *st, const phase_grid *grid, const char *png_path, char *why, size_t why_len);
/* The same as malloc'ed PNG bytes (the API's GET /phase.png). */
int trial_phase_report_png_bytes(store *st, const phase_grid *grid, unsigned char **png, size_t *len, char *why,
                                 size_t why_len);

#endif
