/* sim_plot_sweep.h: the figure of `ribbon-sim sweep --plot FILE.png`, drawn by the plot module
 * (plot.h: plot_sweep).
 * With several phi: the (phi, Gamma) phase diagram at one Delta L, circles where the pitchfork
 * comes first (asymmetric snap), squares where the saddle-node does (symmetric), triangles where
 * the upper branch has no instability (no snap), grey diamonds where no stable upper state was
 * found (with a grey bar up to where continuation in Gamma lost it, from the row's note), crosses
 * where the analysis failed, and the located boundaries as lines, one per pair of regimes
 * (asymmetric/symmetric solid, the others dashed), with a legend naming them on the right. With
 * one phi: the first instability's Delta W against Gamma with the same markers and Gamma* as a
 * dashed vertical line. */
#ifndef RIBBON_DAEMON_SIM_PLOT_SWEEP_H
#define RIBBON_DAEMON_SIM_PLOT_SWEEP_H

#include <stddef.h>

#include "sim_sweep_row.h"

/* Rows outside [phi_a, phi_b] x [gamma_a, gamma_b] or of another Delta L than dl are ignored.
 * Returns 0, or -1 with err (nothing at path then). */
int sim_plot_sweep(const char *path, const sweep_table *t, double phi_a, double phi_b, double gamma_a,
                   double gamma_b, double dl, char *why, size_t why_len);

#endif
