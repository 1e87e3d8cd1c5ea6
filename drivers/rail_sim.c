/* rail_sim.c: the protocol simulators' shared plumbing (see rail_sim.h): fault stream, stall
 * test, the held-open raw pseudo-terminal, the run loop. Nothing protocol-specific lives here:
 * each simulator's own file decides what a fault or a stall does to its replies. */
#define _XOPEN_SOURCE 700
#include "rail_sim.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

double rail_sim_rand(unsigned *state)
{
    /* xorshift32: a private stream so fault runs replay with their seed. */
    unsigned x = *state ? *state : 1u;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *state = x;
    return (double)(x >> 8) / 16777216.0;
}

unsigned rail_sim_seed(unsigned seed)
{
    /* splitmix64's finaliser: neighbouring small seeds (1, 2, 3...) land far apart, so the first
       draws of their streams are spread over [0, 1) instead of all tiny (xorshift32 from a state
       of a few bits needs many steps to fill its high bits). */
    unsigned long long z = (unsigned long long)seed + 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    unsigned x = (unsigned)(z ^ (z >> 32));
    return x ? x : 0x6a09e667u; /* xorshift's state must not be 0 */
}

bool rail_sim_crossed(double before_mm, double after_mm, double at_mm)
{
    return (before_mm < at_mm && after_mm >= at_mm) || (before_mm > at_mm && after_mm <= at_mm);
}

rail_sim_pty_err rail_sim_pty_open(int *master, int *slave, char *path, size_t path_len)
{
    *slave = -1;
    *master = posix_openpt(O_RDWR | O_NOCTTY);
    if (*master < 0 || grantpt(*master) != 0 || unlockpt(*master) != 0) {
        int e = errno;
        if (*master >= 0)
            close(*master);
        *master = -1;
        errno = e;
        return RAIL_SIM_PTY_MASTER;
    }
    const char *name = ptsname(*master);
    rail_text_copy(path, path_len, name ? name : "");
    *slave = open(path, O_RDWR | O_NOCTTY);
    struct termios tio;
    if (*slave < 0 || tcgetattr(*slave, &tio) != 0) {
        int e = errno;
        if (*slave >= 0)
            close(*slave);
        close(*master);
        *master = *slave = -1;
        errno = e;
        return RAIL_SIM_PTY_SLAVE;
    }
    cfmakeraw(&tio);
    tcsetattr(*slave, TCSANOW, &tio);
    fcntl(*master, F_SETFD, FD_CLOEXEC);
    fcntl(*slave, F_SETFD, FD_CLOEXEC);
    return RAIL_SIM_PTY_OK;
}

rail_err rail_sim_run(rail_sim_step_fn step, void *sim, rail_clock clock, double duration_s,
                      volatile sig_atomic_t *stop)
{
    double t0 = rail_clock_now(clock);
    for (unsigned long it = 0; duration_s < 0.0 || it < (unsigned long)(duration_s * 2000.0) + 10; it++) {
        if (stop && *stop)
            break;
        if (duration_s >= 0.0 && rail_clock_now(clock) - t0 >= duration_s)
            break;
        step(sim, 0.002);
    }
    return RAIL_OK;
}
