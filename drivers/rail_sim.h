/* rail_sim.h: what the two protocol simulators (grbl_sim.c, mb_sim.c) share around their
 * protocols: the fault random stream, the stall test, a pseudo-terminal whose slave end the
 * simulator holds open, and the serve-until-stopped loop their programs and tests run.
 * Kept apart from the protocols so both simulators replay faults, treat their pty and stop on
 * a signal or a duration in the same way. It owns no state: the caller owns the random state,
 * the descriptors, the clock and the stop flag. */
#ifndef RIBBON_DRIVERS_RAIL_SIM_H
#define RIBBON_DRIVERS_RAIL_SIM_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>

#include "rail.h"
#include "rail_clock.h"

/* The next number in [0, 1) of a fault stream: xorshift32 over *state (0 counts as 1). Each
 * simulator keeps its own state, seeded from its params, so a fault run replays with its seed. */
double rail_sim_rand(unsigned *state);

/* The fault stream's starting state for a user's seed: the seed mixed (splitmix64), never 0, so
 * every seed, small ones included, starts a well-spread stream. */
unsigned rail_sim_seed(unsigned seed);

/* Whether a step from before_mm to after_mm reached or passed at_mm, from either side (a stall
 * position; false when at_mm is NaN). */
bool rail_sim_crossed(double before_mm, double after_mm, double at_mm);

typedef enum rail_sim_pty_err {
    RAIL_SIM_PTY_OK = 0,
    RAIL_SIM_PTY_MASTER,  /* no pseudo-terminal master could be made */
    RAIL_SIM_PTY_SLAVE    /* the slave (path[] says which) could not be opened or set raw */
} rail_sim_pty_err;

/* Opens a pseudo-terminal: its master in *master, the slave's path in path[path_len], and the
 * slave itself in *slave, held open in raw mode so nothing echoes back into the master's input
 * and clients that come and go never hang the pty up. Both are close-on-exec; the master
 * blocks (the caller may set O_NONBLOCK). On failure it closes what it opened and sets both to
 * -1; errno tells why. */
rail_sim_pty_err rail_sim_pty_open(int *master, int *slave, char *path, size_t path_len);

/* One iteration of a simulator: wait up to max_wait_s for input, serve it, advance the axes. */
typedef rail_err (*rail_sim_step_fn)(void *sim, double max_wait_s);

/* Calls step(sim, 2 ms) until *stop becomes non-zero (a flag a signal handler sets; stop may be
 * NULL) or duration_s has passed on clock (negative: forever). Capped at one iteration per 2 ms
 * of the duration (plus 10), so a clock that stands still cannot keep it running. */
rail_err rail_sim_run(rail_sim_step_fn step, void *sim, rail_clock clock, double duration_s,
                      volatile sig_atomic_t *stop);

#endif
