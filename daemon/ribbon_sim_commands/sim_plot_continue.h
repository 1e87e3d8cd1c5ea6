/* sim_plot_continue.h: the branch diagram of `ribbon-sim continue --plot FILE.png`, drawn by the
 * plot module (plot.h: plot_branches_panels): Delta Z and A against Delta W, stable segments
 * black, unstable grey and dashed, circles at pitchforks, squares at saddle-nodes (the look of
 * the paper's figures 3a and 4a), the switched branch labelled. */
#ifndef RIBBON_DAEMON_SIM_PLOT_CONTINUE_H
#define RIBBON_DAEMON_SIM_PLOT_CONTINUE_H

#include <stddef.h>

#include "rod_bifurcation.h"

/* Writes the PNG (nothing at path on failure). Returns 0 on success, -1 with a message in err. */
int sim_plot_continue(const char *path, const rod_analysis *a, const char *title, char *why, size_t why_len);

#endif
