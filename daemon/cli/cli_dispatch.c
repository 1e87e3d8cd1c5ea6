/* cli_dispatch.c: the subcommand dispatcher of ribbon-sim and ribbonctl (see cli_dispatch.h).
 * It owns only what the two mains had word for word: the usage listing (names padded to 12
 * columns), the --help / --version answers and the exit statuses 0 and 2 of the top level. The
 * table and any global set-up (GSL's error handler) stay in each program's main. */
#include "cli_dispatch.h"

#include <stdio.h>
#include <string.h>

static void usage(const cli_program *p, FILE *f)
{
    fputs(p->usage, f);
    for (size_t i = 0; i < p->ncommands; i++)
        fprintf(f, "  %-12s %s\n", p->commands[i].name, p->commands[i].help);
    if (p->footer)
        fputs(p->footer, f);
}

int cli_dispatch(const cli_program *p, int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(p, argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    if (!strcmp(argv[1], "--version")) {
        printf("%s %s\n", p->name, RIBBON_VERSION);
        return 0;
    }
    for (size_t i = 0; i < p->ncommands; i++)
        if (!strcmp(argv[1], p->commands[i].name))
            return p->commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "%s: unknown command '%s'\n%s", p->name, argv[1], p->blank_line_after_error ? "\n" : "");
    usage(p, stderr);
    return 2;
}
