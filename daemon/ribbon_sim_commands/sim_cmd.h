/* sim_cmd.h: subcommands of the ribbon-sim program. One file per subcommand
 * (sim_cmd_<name>.c), each exporting `int sim_cmd_<name>(int argc, char **argv)` where argv[0]
 * is the subcommand name. Return value is the process exit status (0 on success). Messages go to
 * stderr, machine-readable output (--json) to stdout. */
#ifndef RIBBON_DAEMON_SIM_CMD_H
#define RIBBON_DAEMON_SIM_CMD_H

int sim_cmd_predict(int argc, char **argv);
int sim_cmd_equilibrium(int argc, char **argv);
int sim_cmd_trajectory(int argc, char **argv);
int sim_cmd_convergence(int argc, char **argv);
int sim_cmd_bench(int argc, char **argv);
int sim_cmd_truss(int argc, char **argv);
int sim_cmd_continue(int argc, char **argv);
int sim_cmd_sweep(int argc, char **argv);
int sim_cmd_sweep_merge(int argc, char **argv);
int sim_cmd_boundary(int argc, char **argv);
int sim_cmd_fit(int argc, char **argv);

#endif
