/* owner_lock.h: an exclusive lock one process holds on a resource (the store, a serial port, a
 * Modbus drive), so that a second daemon refuses to start instead of driving the same rails or
 * writing the same store (issue 33, item 1).
 *
 * The lock is flock(LOCK_EX | LOCK_NB) on a lock file. flock, not fcntl: an fcntl lock belongs to
 * the process and is dropped when the process closes any descriptor of the file, and two opens in
 * one process do not exclude each other; a flock belongs to the open file description, so two
 * owners in one process (tests) exclude each other too, and the kernel releases it when its holder
 * dies, kill -9 included: a lock file left behind by a dead daemon never blocks the next one. The
 * descriptor is close-on-exec, so a program the holder starts does not inherit the lock.
 * The holder writes one line into the file, "pid PID since ISO-TIME (WHAT)", which a refused
 * process quotes; the file itself stays when the lock is released (unlinking it would let two
 * processes lock two different files of one name). */
#ifndef RIBBON_DRIVERS_OWNER_LOCK_H
#define RIBBON_DRIVERS_OWNER_LOCK_H

#include <stddef.h>

typedef struct owner_lock owner_lock;

/* Takes the lock on path (created if missing, mode 0644), never waiting. what (e.g. "ribbond on
 * rig.ini") goes into the holder's line. Returns the lock, or NULL with why: when another owner
 * holds it, *held = 1 and "PATH is held by pid 1234 since 2026-01-01T00:00:00Z (ribbond on
 * rig.ini)" (the line as its holder wrote it, or "by another process" while it is being
 * written); else *held = 0 and the reason the file could not be created or locked. held may be
 * NULL. */
owner_lock *owner_lock_take(const char *path, const char *what, int *held, char *why, size_t why_len);
/* Whether another owner holds the lock on path, without taking it and without creating the
 * file (a directory this process may not write: a read-only descriptor can still test a flock).
 * 1 with why "PATH is held by pid ..." as above; 0 when it is free or there is no such file. */
int owner_lock_probe(const char *path, char *why, size_t why_len);
/* Releases the lock (the file stays). NULL is a no-op. */
void owner_lock_release(owner_lock *l);

#endif
