/* rail_axis.c: trapezoidal single-axis kinematics (see rail_axis.h).
 *
 * Position mode is a bang-bang law on velocity: the desired velocity toward the target is
 * min(speed, sqrt(2 a d)) with d the remaining distance (the fastest speed from which the axis
 * can still stop on the target), and the actual velocity follows it at no more than a per unit
 * time. That gives the trapezoid (or triangle for short moves) without planning phases, and
 * handles a target changed mid-move (decelerate, reverse) for free. */
#include "rail_axis.h"

#include <math.h>

#define AXIS_SUBSTEP_S 1e-3
#define AXIS_MAX_SUBSTEPS 100000

rail_axis rail_axis_make(double pos_mm, double accel_mm_s2, double travel_mm)
{
    rail_axis a = {0};
    a.pos_mm = pos_mm;
    a.target_mm = pos_mm;
    a.accel_mm_s2 = accel_mm_s2 > 0.0 ? accel_mm_s2 : 1.0;
    a.travel_mm = travel_mm;
    a.mode = RAIL_AXIS_IDLE;
    return a;
}

void rail_axis_move_to(rail_axis *a, double target, double speed)
{
    a->target_mm = target;
    a->speed_mm_s = fabs(speed);
    a->mode = RAIL_AXIS_POSITION;
}

void rail_axis_jog(rail_axis *a, double v)
{
    a->speed_mm_s = v;
    a->mode = RAIL_AXIS_VELOCITY;
}

void rail_axis_stop(rail_axis *a)
{
    if (a->mode != RAIL_AXIS_IDLE)
        a->mode = RAIL_AXIS_STOPPING;
}

void rail_axis_halt(rail_axis *a)
{
    a->vel_mm_s = 0.0;
    a->mode = RAIL_AXIS_IDLE;
}

void rail_axis_home(rail_axis *a, double speed)
{
    a->speed_mm_s = -fabs(speed);
    a->mode = RAIL_AXIS_HOMING;
    a->limit_hit = false;
}

bool rail_axis_busy(const rail_axis *a)
{
    return a->mode != RAIL_AXIS_IDLE;
}

static double ramp(double v, double vdes, double dv)
{
    if (vdes > v + dv)
        return v + dv;
    if (vdes < v - dv)
        return v - dv;
    return vdes;
}

static void substep(rail_axis *a, double h)
{
    double dv = a->accel_mm_s2 * h;
    double v0 = a->vel_mm_s, v1;
    switch (a->mode) {
    case RAIL_AXIS_IDLE:
        a->vel_mm_s = 0.0;
        return;
    case RAIL_AXIS_POSITION: {
        double d = a->target_mm - a->pos_mm;
        double dir = d > 0.0 ? 1.0 : -1.0;
        if (fabs(d) < 1e-9 && fabs(v0) <= dv) {
            a->pos_mm = a->target_mm;
            a->vel_mm_s = 0.0;
            a->mode = RAIL_AXIS_IDLE;
            return;
        }
        /* Discrete stopping speed: with velocity steps of a h, a stop from v covers
           v^2 / (2 a) + v h / 2, so v = sqrt((a h / 2)^2 + 2 a d) - a h / 2. */
        double ah2 = 0.5 * dv;
        double vstop = sqrt(ah2 * ah2 + 2.0 * a->accel_mm_s2 * fabs(d)) - ah2;
        double vdes = dir * fmin(a->speed_mm_s, vstop);
        v1 = ramp(v0, vdes, dv);
        a->pos_mm += 0.5 * (v0 + v1) * h;
        a->vel_mm_s = v1;
        if ((a->target_mm - a->pos_mm) * dir <= 0.0) {
            a->pos_mm = a->target_mm;
            a->vel_mm_s = 0.0;
            a->mode = RAIL_AXIS_IDLE;
        }
        break;
    }
    case RAIL_AXIS_VELOCITY:
    case RAIL_AXIS_HOMING:
        v1 = ramp(v0, a->speed_mm_s, dv);
        a->pos_mm += 0.5 * (v0 + v1) * h;
        a->vel_mm_s = v1;
        break;
    case RAIL_AXIS_STOPPING:
        v1 = ramp(v0, 0.0, dv);
        a->pos_mm += 0.5 * (v0 + v1) * h;
        a->vel_mm_s = v1;
        if (v1 == 0.0)
            a->mode = RAIL_AXIS_IDLE;
        break;
    }
    if (a->mode == RAIL_AXIS_HOMING && a->pos_mm <= 0.0) {
        /* Home switch at 0: zero the position, stop there. */
        a->pos_mm = 0.0;
        a->vel_mm_s = 0.0;
        a->mode = RAIL_AXIS_IDLE;
        a->homed = true;
        return;
    }
    if (a->pos_mm < 0.0 || a->pos_mm > a->travel_mm) {
        a->pos_mm = a->pos_mm < 0.0 ? 0.0 : a->travel_mm;
        a->vel_mm_s = 0.0;
        a->mode = RAIL_AXIS_IDLE;
        a->limit_hit = true;
    }
}

void rail_axis_step(rail_axis *a, double dt)
{
    if (!(dt > 0.0) || !isfinite(dt))
        return;
    long n = (long)ceil(dt / AXIS_SUBSTEP_S);
    if (n > AXIS_MAX_SUBSTEPS)
        n = AXIS_MAX_SUBSTEPS;
    double h = dt / (double)n;
    for (long i = 0; i < n && a->mode != RAIL_AXIS_IDLE; i++)
        substep(a, h);
    if (a->mode == RAIL_AXIS_IDLE)
        a->vel_mm_s = 0.0;
}
