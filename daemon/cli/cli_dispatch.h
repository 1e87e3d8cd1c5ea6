/* cli_dispatch.h: the top level shared by the rig's multi-command programs (ribbon-sim,
 * ribbonctl): a table of subcommands {name, function, one-line help} and one main-level
 * dispatcher for it, so both programs answer --help, --version and a bad command the same way.
 * Each program keeps its own table and whatever it must set up before dispatching. */
#ifndef RIBBON_DAEMON_CLI_DISPATCH_H
#define RIBBON_DAEMON_CLI_DISPATCH_H

#include <stdbool.h>
#include <stddef.h>

/* run gets argv shifted by one (argv[0] is the subcommand's name) and returns the exit status. */
typedef struct cli_command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *help;
} cli_command;

typedef struct cli_program {
    const char *name;              /* "ribbon-sim": in --version and in error messages */
    const char *usage;             /* the usage text before the table, e.g. "usage: P COMMAND ...\n\n" */
    const char *footer;            /* printed after the table; NULL for none */
    const cli_command *commands;
    size_t ncommands;
    bool blank_line_after_error;   /* an empty line between "unknown command" and the usage */
} cli_program;

/* The whole of main after the program's own set-up. No argument: usage on stderr, 2.
 * --help, -h, help: usage on stdout, 0. --version: "NAME VERSION", 0. A command in the table:
 * its run's status. Anything else: "NAME: unknown command 'X'" and the usage on stderr, 2. */
int cli_dispatch(const cli_program *p, int argc, char **argv);

#endif
