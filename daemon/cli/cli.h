/* cli.h: the command-line room's face: what the programs' mains share.
 *   cli_dispatch.h   the subcommand dispatcher (usage listing, --help/--version, unknown command)
 *   railsim_cli.h    the rail simulators' number options and SIGINT/SIGTERM stop flag */
#ifndef RIBBON_CLI_H
#define RIBBON_CLI_H

#include "cli_dispatch.h"
#include "railsim_cli.h"

#endif
