/* ribbon_sim.c: the `ribbon-sim` program: the embedded simulator from the command line.
 * A table of subcommands, each in its own sim_cmd_<name>.c, run by cli_dispatch. GSL's
 * abort-on-error handler is switched off here, once, so every GSL failure comes back as a code
 * with a reason. */
#include "cli.h"
#include "sim_cmd.h"

#include <gsl/gsl_errno.h>

static const cli_command commands[] = {
    {"predict", sim_cmd_predict, "simulate the protocol: snap Delta W, regime, peak |A|"},
    {"equilibrium", sim_cmd_equilibrium, "static equilibrium at (Delta L, Delta W) on a branch"},
    {"trajectory", sim_cmd_trajectory, "the simulated protocol step by step, as CSV"},
    {"convergence", sim_cmd_convergence, "snap Delta W and its error against run time over a ladder of N and dt"},
    {"continue", sim_cmd_continue, "bifurcation analysis: branches in Delta W, pitchfork / saddle-node, regime"},
    {"sweep", sim_cmd_sweep, "phase diagram over (phi, Gamma): regime per point, boundary Gamma*(phi)"},
    {"sweep-merge", sim_cmd_sweep_merge, "join the shard files of `sweep --shard i/N` into one sweep file"},
    {"boundary", sim_cmd_boundary, "regime boundary Gamma*(phi) traced directly (pitchfork meets saddle-node)"},
    {"fit", sim_cmd_fit, "fit a scene's strip to observed (Delta L, Delta W, Delta Z, A) samples, with errors"},
    {"bench", sim_cmd_bench, "speed and memory on a scene, one machine-readable line"},
    {"truss", sim_cmd_truss, "the reduced double-mass von Mises truss model (paper section 4)"},
};

static const cli_program program = {
    .name = "ribbon-sim",
    .usage = "usage: ribbon-sim COMMAND [options]   (ribbon-sim COMMAND --help for its options)\n\n",
    .footer = "\nScenes are INI files (config/scenes/); README \"Scene files\" lists every key.\n",
    .commands = commands,
    .ncommands = sizeof commands / sizeof commands[0],
    .blank_line_after_error = true,
};

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    return cli_dispatch(&program, argc, argv);
}
