/* thread_class.h: the scheduling class of ribbond's best-effort threads. Whatever ribbond computes
 * while the rails may move and that no rail waits for (the in-trial fit with its refreshes and
 * bands, the scene's prediction beside a rig trial, the video transcoder with its encoder's slice
 * threads, the phase map, the campaign's boundary trace) runs on a thread that calls
 * thread_class_idle_enter() first. On Linux that thread is put in SCHED_IDLE: it runs only on CPU
 * time that no normal thread wants, and a normal thread that wakes takes the CPU from it at once,
 * so it never delays the threads that watch and stop the rails (the trial's loop, the capture, the
 * rail poller; docs/rig-realtime.md, "Threads and priorities"). Niceness was not enough: a nice-10
 * thread still gets about a tenth of a core beside a nice-0 one, and runs in the slices between.
 * A thread may always lower its own class (no privilege, no unit setting); it does not come back
 * (SCHED_IDLE -> SCHED_OTHER needs CAP_SYS_NICE), so only threads of their own call it. Threads
 * it creates afterwards inherit the class (Linux copies the policy at clone).
 * Why in drivers/: it is OS plumbing (like the drivers' locks and clocks) and knows nothing of
 * trials, and drivers/ is the lowest floor linked by every room that runs such a thread: the trial
 * room, and the campaign room, which does not link the trial room. */
#ifndef RIBBON_DRIVERS_THREAD_CLASS_H
#define RIBBON_DRIVERS_THREAD_CLASS_H

#include <stddef.h>

#define THREAD_CLASS_FALLBACK_NICE 19 /* where SCHED_IDLE is refused: the calling thread's niceness */

/* The calling thread into SCHED_IDLE: 0. Refused (no such class; a seccomp filter): -1 with the
 * reason in why (may be NULL), and the thread at niceness THREAD_CLASS_FALLBACK_NICE instead. */
int thread_class_idle_enter(char *why, size_t why_len);
/* 1 when the thread with Linux thread id tid (0: the caller) runs in SCHED_IDLE, 0 when it runs
 * in another class, -1 when it cannot be read (no such thread). */
int thread_class_is_idle(long tid);
/* The caller's Linux thread id (for thread_class_is_idle from another thread). */
long thread_class_tid(void);

#endif
