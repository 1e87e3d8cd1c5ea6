/* rail_clock.h: the monotonic clock the drivers and simulators read, real or virtual.
 *
 * A clock is a pair of functions and a context, passed by value. The real clock reads
 * CLOCK_MONOTONIC and sleeps with nanosleep; the virtual clock is a counter that sleep advances,
 * so the mock rail and its tests run a minute of motion in microseconds and deterministically.
 * No hidden global: a virtual clock lives in a rail_vclock the caller owns. */
#ifndef RIBBON_DRIVERS_RAIL_CLOCK_H
#define RIBBON_DRIVERS_RAIL_CLOCK_H

typedef struct rail_clock {
    double (*now)(void *ctx);            /* s, monotonic */
    void (*sleep)(void *ctx, double s);  /* s, returns after at least s (virtual: at once) */
    void *ctx;
} rail_clock;

typedef struct rail_vclock {
    double t_s;  /* s, current virtual time */
} rail_vclock;

rail_clock rail_clock_real(void);
rail_clock rail_clock_virtual(rail_vclock *vc);
double rail_clock_now(rail_clock c);
void rail_clock_sleep(rail_clock c, double s);

#endif
