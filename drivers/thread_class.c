/* thread_class.c: the best-effort threads' scheduling class (see thread_class.h). Linux only calls:
 * sched_setscheduler and sched_getscheduler take a thread id (0: the calling thread), which is how
 * one thread of a process gets a class of its own. */
#define _GNU_SOURCE /* SCHED_IDLE, gettid through syscall */
#include "thread_class.h"

#include <errno.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

long thread_class_tid(void) { return (long)syscall(SYS_gettid); }

int thread_class_idle_enter(char *why, size_t why_len)
{
    struct sched_param sp = {.sched_priority = 0}; /* SCHED_IDLE's only priority */
    if (sched_setscheduler(0, SCHED_IDLE, &sp) == 0) return 0;
    int e = errno;
    (void)setpriority(PRIO_PROCESS, (id_t)thread_class_tid(), THREAD_CLASS_FALLBACK_NICE);
    if (why && why_len)
        snprintf(why, why_len, "SCHED_IDLE refused (%s): the thread runs at niceness %d instead", strerror(e),
                 THREAD_CLASS_FALLBACK_NICE);
    return -1;
}

int thread_class_is_idle(long tid)
{
    int p = sched_getscheduler((pid_t)tid);
    if (p < 0) return -1;
    return (p & ~SCHED_RESET_ON_FORK) == SCHED_IDLE;
}
