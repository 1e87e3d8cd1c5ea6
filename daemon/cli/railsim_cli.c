/* railsim_cli.c: the simulators' shared command-line plumbing (see railsim_cli.h). The stop
 * flag is the only state, file-scope because a signal handler can reach nothing else; it is
 * handed out by railsim_cli_catch_stop() rather than read by name elsewhere. */
#include "railsim_cli.h"
#include "cfg_number.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static volatile sig_atomic_t g_stop; /* set by the signal handler only */

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

int railsim_cli_num(const char *prog, const char *opt, const char *v, double lo, double hi, double *out)
{
    char *end = NULL;
    double x = v ? cfg_number_strtod(v, &end) : NAN;
    if (!v || end == v || *end || !(x >= lo && x <= hi)) {
        fprintf(stderr, "%s: %s needs a number in [%g, %g], got '%s'\n", prog, opt, lo, hi, v ? v : "");
        return -1;
    }
    *out = x;
    return 0;
}

volatile sig_atomic_t *railsim_cli_catch_stop(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    return &g_stop;
}
