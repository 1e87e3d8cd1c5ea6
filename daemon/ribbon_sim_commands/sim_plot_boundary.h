/* sim_plot_boundary.h: the two figures of `ribbon-sim boundary --plot FILE.png`, drawn by the plot
 * module (plot.h: plot_boundary): the traced boundary Gamma*(phi), one line per Delta L, over the
 * classified points of a sweep CSV when one is given; or, with --curves, the fold (saddle-node)
 * and pitchfork curves in (Gamma, Delta W) meeting at Gamma*, like the reference paper's figure 5b. */
#ifndef RIBBON_DAEMON_SIM_PLOT_BOUNDARY_H
#define RIBBON_DAEMON_SIM_PLOT_BOUNDARY_H

#include <stddef.h>

#include "rod_boundary.h"
#include "sim_sweep_row.h"

/* curves[k] are the boundaries at dl[k] (ncurves of them, at most PLOT_BOUNDARY_CURVES_MAX);
 * sweep may be NULL. 0, or -1 with err (nothing at path then). */
int sim_plot_boundary(const char *path, const rod_boundary_curve *curves, const double *dl, int ncurves,
                      const sweep_table *sweep, char *why, size_t why_len);

/* The fold and pitchfork curves and the codim-2 point star. 0, or -1 with err. */
int sim_plot_boundary_curves(const char *path, const rod_crit_curve *fold, const rod_crit_curve *pitchfork,
                             const rod_codim2_point *star, char *why, size_t why_len);

#endif
