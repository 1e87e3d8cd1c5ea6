/* rail_gcode.h: rails on a GRBL 1.1 controller over serial (G-code driver).
 *
 * One grbl_link is one controller (one serial port); one rail is one axis of it. The two rails
 * of the rig can be two axes of one controller (open the link once, pass it to both rails; the
 * controller runs their moves one after another) or two controllers (each rail opens its own).
 * Every motion goes out as "$J=G53 G21 <axis><mm> F<mm/min>" jog segments of segment_s seconds,
 * (at least min_segment_mm long), at most segments_ahead of them queued past the current
 * position; the front end's polls top the queue up. A process that dies stops feeding, so the
 * rail stops within segments_ahead segments; a jog cancel (0x85) is the decelerating stop;
 * estop is a feed hold ('!') and, once stopped, a soft reset (0x18) that empties the planner.
 * No segment goes out more than 1 / poll_hz + RAIL_CLOCK_JUMP_S after the previous status report
 * (the process was frozen and the controller may have starved): the jog is cancelled instead and
 * the rail faults until reset.
 * Opening a link cancels any motion the controller is still running: nothing resumes by itself.
 * Positions are machine positions: MPos ($10=1, GRBL's default), or WPos plus the last WCO the
 * controller reported (a WPos report before any WCO is refused).
 *
 * Opening reads the controller's settings (`$$`) and refuses what the driver cannot work with,
 * naming the setting, its value and what to set: $13=1 (inches), a max rate $11x below the
 * rail's max_speed_mm_s. It adopts the axis's acceleration $12x as the rail's (the controller
 * decelerates at it) and warns on the rest (grbl_settings.h). A controller that reset (power,
 * USB, reset line, a critical alarm, a reset in motion) lost its position: the rail reports a
 * fault and refuses motion until it is homed ($22=1) or its zero is confirmed. */
#ifndef RIBBON_DRIVERS_RAIL_GCODE_H
#define RIBBON_DRIVERS_RAIL_GCODE_H

#include <stdbool.h>
#include <stddef.h>

#include "rail.h"
#include "rail_gcode_params.h"

typedef struct grbl_link grbl_link; /* one controller (grbl_link.h opens and releases it) */

/* Open one axis as a rail; shared = NULL opens a link of its own, else the link is shared. */
rail_err rail_gcode_open(rail **out, const rail_params *p, const rail_gcode_params *g, grbl_link *shared,
                         rail_clock clock, char *why, size_t why_len);

/* The user says the controller's count is right where the rail stands (after a reset with
 * homing off, $22=0): the rail may move again. Refused without confirmed, on another driver's
 * rail, and when homing is enabled (home it instead). */
rail_err rail_gcode_confirm_zero(rail *r, bool confirmed);
/* One line for a trial's record: the axis, whether the board reset on open, every `$$` setting
 * and the check's warnings. Returns the length written ("" for another driver's rail). */
size_t rail_gcode_describe(const rail *r, char *buf, size_t n);
/* The settings check's warnings ("" = none, or another driver's rail). */
const char *rail_gcode_warnings(const rail *r);

#endif
