/* grblsim_spawn.h: test helper: run a grbl_sim in a child process on a fresh pseudo-terminal.
 * The child is the "controller": killing it (SIGKILL) is a pulled cable. It runs for at most
 * 60 s on its own, so a crashed test cannot leave it behind for long. */
#ifndef RIBBON_TESTS_GRBLSIM_SPAWN_H
#define RIBBON_TESTS_GRBLSIM_SPAWN_H

#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "grbl_sim.h"

__attribute__((unused)) static pid_t grblsim_spawn(const grbl_sim_params *p, char *path, size_t n)
{
    grbl_sim *s = NULL;
    char why[256];
    if (n)
        path[0] = 0;
    if (grbl_sim_open(&s, p, why, sizeof why) != RAIL_OK) {
        fprintf(stderr, "grblsim: %s\n", why);
        return -1;
    }
    snprintf(path, n, "%s", grbl_sim_path(s));
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        grbl_sim_run(s, 60.0, NULL);
        grbl_sim_close(s);
        _exit(0);
    }
    grbl_sim_close(s); /* the parent keeps no end of the pty but the client's */
    return pid;
}

__attribute__((unused)) static void grblsim_kill(pid_t pid)
{
    if (pid > 0) {
        kill(pid, SIGKILL);
        waitpid(pid, NULL, 0);
    }
}

#endif
