/* ribbon_sim.c: the `ribbon-sim` program: the embedded simulator from the command line.
 * A table of subcommands, each in its own sim_cmd_<name>.c. GSL's abort-on-error handler is
 * switched off here, once, so every GSL failure comes back as a code with a reason. */
#include "sim_cmd.h"

#include <gsl/gsl_errno.h>
#include <stdio.h>
#include <string.h>

typedef struct sim_command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *help;
} sim_command;

static const sim_command commands[] = {
    {"predict", sim_cmd_predict, "simulate the protocol: snap Delta W, regime, peak |A|"},
    {"equilibrium", sim_cmd_equilibrium, "static equilibrium at (Delta L, Delta W) on a branch"},
    {"trajectory", sim_cmd_trajectory, "the simulated protocol step by step, as CSV"},
    {"convergence", sim_cmd_convergence, "snap Delta W and its error against run time over a ladder of N and dt"},
    {"continue", sim_cmd_continue, "bifurcation analysis: branches in Delta W, pitchfork / saddle-node, regime"},
    {"sweep", sim_cmd_sweep, "phase diagram over (phi, Gamma): regime per point, boundary Gamma*(phi)"},
    {"bench", sim_cmd_bench, "speed and memory on a scene, one machine-readable line"},
#ifdef RIBBON_HAVE_TRUSS
    {"truss", sim_cmd_truss, "the reduced double-mass von Mises truss model (paper section 4)"},
#endif
};

static void usage(FILE *f)
{
    fprintf(f, "usage: ribbon-sim COMMAND [options]   (ribbon-sim COMMAND --help for its options)\n\n");
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(f, "  %-12s %s\n", commands[i].name, commands[i].help);
    fprintf(f, "\nScenes are INI files (config/scenes/); README \"Scene files\" lists every key.\n");
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    if (!strcmp(argv[1], "--version")) {
        printf("ribbon-sim %s\n", RIBBON_VERSION);
        return 0;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name)) return commands[i].run(argc - 1, argv + 1);
    fprintf(stderr, "ribbon-sim: unknown command '%s'\n\n", argv[1]);
    usage(stderr);
    return 2;
}
