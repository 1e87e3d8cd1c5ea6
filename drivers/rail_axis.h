/* rail_axis.h: one simulated linear axis with a trapezoidal velocity profile.
 *
 * Shared by the mock driver and both protocol simulators, so "the hardware" behaves the same
 * everywhere: acceleration-limited ramps to a commanded speed, a deceleration that ends exactly
 * on the target, constant-velocity jogs, decelerating stops, instant halts (e-stop, stall) and a
 * hard travel range [0, travel] that raises a limit alarm if crossed.
 * Time advances by rail_axis_step(dt) in fixed sub-steps of at most 1 ms (at most 100000 per
 * call), integrating velocity with the trapezoid rule; a target crossed inside a sub-step snaps
 * the axis onto it. Units: mm, mm/s, mm/s^2, s. */
#ifndef RIBBON_DRIVERS_RAIL_AXIS_H
#define RIBBON_DRIVERS_RAIL_AXIS_H

#include <stdbool.h>

typedef enum rail_axis_mode {
    RAIL_AXIS_IDLE = 0,
    RAIL_AXIS_POSITION,  /* moving to target at up to speed */
    RAIL_AXIS_VELOCITY,  /* constant velocity (jog) */
    RAIL_AXIS_STOPPING,  /* decelerating to rest */
    RAIL_AXIS_HOMING     /* moving to 0 at speed, then zeroed (position set to 0) */
} rail_axis_mode;

typedef struct rail_axis {
    double pos_mm;        /* mm, current position */
    double vel_mm_s;      /* mm/s, current signed velocity */
    double target_mm;     /* mm, target of a position move */
    double speed_mm_s;    /* mm/s, commanded speed (position mode) or signed jog velocity */
    double accel_mm_s2;   /* mm/s^2, acceleration and deceleration */
    double travel_mm;     /* mm, hard travel: leaving [0, travel] raises limit_hit */
    rail_axis_mode mode;
    bool limit_hit;       /* set when the axis touched a hard end; axis halted there */
    bool homed;
} rail_axis;

/* An axis at rest at pos_mm with the given acceleration and travel. */
rail_axis rail_axis_make(double pos_mm, double accel_mm_s2, double travel_mm);
void rail_axis_move_to(rail_axis *a, double target_mm, double speed_mm_s);
void rail_axis_jog(rail_axis *a, double velocity_mm_s);
void rail_axis_stop(rail_axis *a);   /* decelerate to rest */
void rail_axis_halt(rail_axis *a);   /* velocity to zero at once */
void rail_axis_home(rail_axis *a, double speed_mm_s);
void rail_axis_step(rail_axis *a, double dt_s);
bool rail_axis_busy(const rail_axis *a);

#endif
