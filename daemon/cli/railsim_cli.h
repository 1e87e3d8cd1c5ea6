/* railsim_cli.h: the command-line plumbing the rail protocol simulators' programs share
 * (ribbon-grblsim in grblsim_main.c, ribbon-mbsim in mbsim_main.c): a number option checked
 * against its range with the message both print, and the stop flag their SIGINT/SIGTERM
 * handler sets. The options themselves, the --help texts and what a program prints stay in
 * its own main. */
#ifndef RIBBON_DAEMON_RAILSIM_CLI_H
#define RIBBON_DAEMON_RAILSIM_CLI_H

#include <signal.h>

/* v as a number in [lo, hi] into *out and 0; otherwise -1 after printing
 * "PROG: OPT needs a number in [lo, hi], got 'V'" on stderr (v NULL: a missing value). */
int railsim_cli_num(const char *prog, const char *opt, const char *v, double lo, double hi, double *out);

/* Installs a SIGINT and SIGTERM handler that only sets the flag returned (the process has one:
 * a handler reaches it only through a file-scope variable); the simulator's run loop polls it
 * and the main shuts down when it returns. */
volatile sig_atomic_t *railsim_cli_catch_stop(void);

#endif
