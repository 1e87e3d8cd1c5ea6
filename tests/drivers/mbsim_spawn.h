/* mbsim_spawn.h: test helper: run an mb_sim in a child process on 127.0.0.1, any free port.
 * The parent learns the port before the fork; killing the child is a drive losing power.
 * The child runs for at most 60 s on its own. */
#ifndef RIBBON_TESTS_MBSIM_SPAWN_H
#define RIBBON_TESTS_MBSIM_SPAWN_H

#include <signal.h>
#include <stdio.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "mb_sim.h"

__attribute__((unused)) static pid_t mbsim_spawn(mb_sim_params p, int *port)
{
    mb_sim *s = NULL;
    char why[256];
    *port = 0;
    snprintf(p.host, sizeof p.host, "127.0.0.1");
    p.port = 0;
    if (mb_sim_open(&s, &p, why, sizeof why) != RAIL_OK) {
        fprintf(stderr, "mbsim: %s\n", why);
        return -1;
    }
    *port = mb_sim_port(s);
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        mb_sim_run(s, 60.0, NULL);
        mb_sim_close(s);
        _exit(0);
    }
    mb_sim_close(s);
    return pid;
}

/* The same on RTU: path gets the pseudo-terminal a client opens as its serial line. */
__attribute__((unused)) static pid_t mbsim_spawn_rtu(mb_sim_params p, char *path, size_t n)
{
    mb_sim *s = NULL;
    char why[256];
    if (n)
        path[0] = 0;
    p.rtu = true;
    if (mb_sim_open(&s, &p, why, sizeof why) != RAIL_OK) {
        fprintf(stderr, "mbsim: %s\n", why);
        return -1;
    }
    snprintf(path, n, "%s", mb_sim_path(s));
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0) {
        mb_sim_run(s, 60.0, NULL);
        mb_sim_close(s);
        _exit(0);
    }
    mb_sim_close(s);
    return pid;
}

__attribute__((unused)) static void mbsim_kill(pid_t pid)
{
    if (pid > 0) {
        kill(pid, SIGKILL);
        waitpid(pid, NULL, 0);
    }
}

#endif
