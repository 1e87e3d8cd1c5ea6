/* rigsim_rails.h: the rig simulator's rails: one GRBL 1.1 controller (drivers/grbl_sim.c) on a
 * pseudo-terminal with the rig file's two axes, stepped in real time on its own thread.
 *
 * The pty's path is linked at the port the rig file names for both rails (they must be two axes of
 * one gcode controller), so ribbond opens it as it would open the USB serial port. The axes'
 * ACTUAL positions (a stalled axis where it stalled) are readable from any thread: they are the
 * ribbon's boundary conditions and what the truth log records.
 * Faults: an alarm after a time and a stalled axis are the controller's own (grbl_sim_params);
 * "link lost" stops answering the pty from a time on (the controller is gone: no replies, and the
 * axes halt where they are, as a board that lost power would). */
#ifndef RIBBON_RIGSIM_RAILS_H
#define RIBBON_RIGSIM_RAILS_H

#include <stddef.h>

#include "grbl_sim.h"
#include "rig_config.h"

typedef struct rigsim_rails rigsim_rails;

typedef struct rigsim_rail_faults {
    double alarm_after_s;     /* s after start, < 0 = off */
    double link_lost_after_s; /* s after start, < 0 = off */
    char stall_axis;          /* 'X', 'Y' or 0 = off */
    double stall_at_mm;
} rigsim_rail_faults;

/* Starts the controller for cfg's rails: axis positions start at the compression rail's
 * compress_start_mm and the shear rail's zero. */
int rigsim_rails_start(const rig_config *cfg, double compress_start_mm, const rigsim_rail_faults *f,
                       rigsim_rails **out, char *why, size_t why_len);
/* Actual positions (mm) of the compression and the shear axis, and the host monotonic time of
 * the step they are from. */
void rigsim_rails_positions(rigsim_rails *r, double *compress_mm, double *shear_mm, double *t_s);
const char *rigsim_rails_port(const rigsim_rails *r);
/* Fault on command: the controller stops answering from now on (thread-safe). */
void rigsim_rails_cut_link(rigsim_rails *r);
void rigsim_rails_stop(rigsim_rails *r);

#endif
