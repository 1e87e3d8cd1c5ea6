/* sim_plot_page.h: what ribbon-sim's two PLplot figures (sim_plot_continue, sim_plot_sweep)
 * share: a pngcairo page on a stream of their own, the check that PLplot really wrote the file,
 * and the outlined polygon they draw their markers with. (The daemon's reports use the plot
 * module's plot_session instead, which also contains PLplot's fatal errors.) */
#ifndef RIBBON_DAEMON_SIM_PLOT_PAGE_H
#define RIBBON_DAEMON_SIM_PLOT_PAGE_H

#include <stddef.h>

/* Checks that path can be written, then makes a new PLplot stream current and sets it to write a
 * width_px x height_px pngcairo page to path. The caller sets its palette and calls plinit().
 * Returns 0, or -1 with "cannot write PATH" in err (no stream made). */
int sim_plot_page_open(const char *path, int width_px, int height_px, char *err, size_t errlen);

/* Ends the stream (plend1, which writes the PNG). Returns 1 when path then holds some bytes, 0
 * when it is empty or gone (pngcairo missing); the caller says so in its own words. */
int sim_plot_page_close(const char *path);

/* An outlined regular polygon of n_sides (3..64) around (x, y), rotated by rot (radians), with
 * radius rx in x units and ry in y units (a circle for many sides). */
void sim_plot_polygon(double x, double y, double rx, double ry, int n_sides, double rot);

#endif
