/* rail_clock.c: real (CLOCK_MONOTONIC) and virtual clocks for drivers and simulators.
 * See rail_clock.h. Sleeping a negative or NaN time does nothing. */
#include "rail_clock.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <time.h>

static double real_now(void *ctx)
{
    (void)ctx;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void real_sleep(void *ctx, double s)
{
    (void)ctx;
    if (!(s > 0.0))
        return;
    struct timespec ts;
    ts.tv_sec = (time_t)s;
    ts.tv_nsec = (long)((s - (double)ts.tv_sec) * 1e9);
    /* Interrupted sleeps resume with the remaining time; capped so a storm of signals ends. */
    for (int i = 0; i < 64 && nanosleep(&ts, &ts) != 0 && errno == EINTR; i++) {
    }
}

static double virt_now(void *ctx)
{
    return ((rail_vclock *)ctx)->t_s;
}

static void virt_sleep(void *ctx, double s)
{
    if (s > 0.0 && isfinite(s))
        ((rail_vclock *)ctx)->t_s += s;
}

rail_clock rail_clock_real(void)
{
    rail_clock c = {real_now, real_sleep, NULL};
    return c;
}

rail_clock rail_clock_virtual(rail_vclock *vc)
{
    rail_clock c = {virt_now, virt_sleep, vc};
    return c;
}

double rail_clock_now(rail_clock c)
{
    return c.now(c.ctx);
}

void rail_clock_sleep(rail_clock c, double s)
{
    c.sleep(c.ctx, s);
}
