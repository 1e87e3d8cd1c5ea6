/* twin_truth.h: the twin's truth as text: which strip the twin is (its resolution and the [twin]
 * keys it took) and the snap it made by its own state (rod_twin_snap), written into a trial's events
 * by mock mode and onto ribbon-rigsim's output, and read back by `ribbonctl start --wait` and the
 * tests. One format in one place, so writer and readers cannot drift:
 *   twin: N = 121, dt = 0.001 s; [twin] folds.angle_deg=-86 mesh.nodes=121 ...
 *   twin: N = 61, dt = 0.002 s; the trial's scene (no [twin])
 *   twin truth: snap Delta W = 0.41234, regime asymmetric (peak |A| 1.950 rad over the passage,
 *     2.100 over 2 s; the onset known to 0.00010 of Delta W)
 *   twin truth: no snap (Delta W reached 0.60000)
 * The truth line carries the numbers with 5 decimals of Delta W (the measured one's). */
#ifndef RIBBON_DAEMON_TWIN_TRUTH_H
#define RIBBON_DAEMON_TWIN_TRUTH_H

#include <stddef.h>

#include "rod_snap_watch.h"
#include "scene.h"

#define TWIN_TRUTH_PREFIX "twin truth: "
#define TWIN_PARAMS_PREFIX "twin: "

/* The twin's parameters: sc its scene (resolution), keys the n [twin] keys ("section.key=value")
 * it took (n = 0: the trial's scene). Truncated to fit, always terminated. */
void twin_truth_params(const rod_scene *sc, const char *const *keys, int n, char *buf, size_t len);

/* The twin's own snap: r from rod_twin_snap, rate the Delta W per second of the shear (for the
 * onset's resolution, r->dt_max * rate), dw_now the twin's Delta W now (for "no snap"). */
void twin_truth_snap(const rod_snap_report *r, double rate, double dw_now, char *buf, size_t len);

/* Reads a truth line back: 1 with *snap_dw and regime ("asymmetric" / "symmetric") when msg is a
 * twin truth line with a snap; 0 otherwise (regime gets "no snap" when it says so). Either output
 * may be NULL. */
int twin_truth_parse(const char *msg, double *snap_dw, char *regime, size_t regime_len);

#endif
