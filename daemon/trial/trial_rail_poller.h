/* trial_rail_poller.h: the rails polled on their own thread during a live trial.
 *
 * A real poll is a blocking round trip (Modbus RTU at 19200 baud: 15-25 ms per read; GRBL: a status
 * report), so in rig mode the runner does not poll: this thread calls rail_pair_poll (both rails,
 * rate-limited to each driver's poll_hz, a fault of either stops both) every `period_s` and
 * publishes the latest pair of statuses with the time of the poll (a fault of the first rail is
 * published before the second is read, and the other rail is then emergency-stopped). The runner reads them at once
 * and reconstructs each frame's positions from them at the frame's own time (as before).
 * The rails are not thread-safe: every other call on them (moves, stops) goes through
 * trial_rail_poller_lock/unlock, which waits at most for one poll in flight.
 * After a fault the thread stops polling (rail_pair_poll has already stopped the other rail) and
 * the fault is what every later read returns.
 *
 * A frozen daemon (issue 33, item 2: SIGSTOP / SIGCONT mid-shear; also a suspended machine or a
 * stalled scheduler): while it is frozen a GRBL controller runs out of segments and stops, and on
 * waking the next poll would top them up and carry the move on by itself. So every poll first
 * compares the monotonic clock with the end of the previous poll: more than the period plus
 * TRIAL_CLOCK_JUMP_S since then (or a poll that answered after more than 2 TRIAL_CLOCK_JUMP_S: a
 * freeze inside the poll), and both rails are emergency-stopped before anything else is sent, and
 * the fault "the monotonic clock jumped X s ..." is what every read returns. The reader
 * (trial_rail_poller_latest, the trial's thread) makes the same check against the poller's last
 * poll, so whichever thread wakes first stops the rails. */
#ifndef RIBBON_DAEMON_TRIAL_RAIL_POLLER_H
#define RIBBON_DAEMON_TRIAL_RAIL_POLLER_H

#include <stddef.h>

#include "rail.h"

typedef struct trial_rail_poller trial_rail_poller;

/* s: the longest the clock may run past the poll period between two polls before the daemon
 * counts as having been frozen (the bound on detecting a lost rail link is 0.5 s too). */
#define TRIAL_CLOCK_JUMP_S RAIL_CLOCK_JUMP_S

/* Starts polling (the rails stay the caller's; nothing else may call them unlocked). */
trial_rail_poller *trial_rail_poller_start(rail *compress, rail *shear, double period_s, char *why, size_t why_len);
/* The latest statuses and the rail-clock time of the poll that gave them; RAIL_OK, or the fault
 * (why names the rail). Waits for the first poll. */
rail_err trial_rail_poller_latest(trial_rail_poller *p, rail_status *sc, rail_status *ss, double *t_poll, char *why,
                                  size_t why_len);
/* The rails' lock for a call that may start motion (a move): RAIL_OK with the lock held (release
 * it with trial_rail_poller_unlock after the call), or the poller's fault with the lock released.
 * The freeze check is made again under the lock, so no move goes out between a check and a
 * freeze: a clock jump seen here emergency-stops both rails before the lock is let go. */
rail_err trial_rail_poller_lock_for_move(trial_rail_poller *p, char *why, size_t why_len);
/* s between the shear's fresh readings while a stop is watched (a GRBL status report is about 60
 * bytes, 5 ms at 115200 baud; a Modbus TCP read on a LAN well under that). */
#define TRIAL_STOP_WATCH_PERIOD_S 0.005
/* After a stop of the shear rail (issue 34 F): for the next window_s the shear is read fresh (past
 * its poll_hz rate limit) every TRIAL_STOP_WATCH_PERIOD_S until a reading says it stands, so the
 * rail's rest is seen within a short pass of the end of its deceleration instead of up to a poll
 * period plus the poller's own period later. The compression rail keeps its rate. */
void trial_rail_poller_watch_stop(trial_rail_poller *p, double window_s);
/* The rail-clock time of the fresh reading that ended the last watch standing (the poller's own
 * reading, so it does not wait for the trial's loop to come by), or NaN while none has. */
double trial_rail_poller_stop_seen(trial_rail_poller *p);
void trial_rail_poller_lock(trial_rail_poller *p);
void trial_rail_poller_unlock(trial_rail_poller *p);
/* Longest time one poll took (s), longest gap from one poll's end to the next one's start (s: the
 * period plus any wait for the rails' lock or for the thread to be scheduled), and polls made. */
void trial_rail_poller_stats(trial_rail_poller *p, double *max_poll_s, double *max_gap_s, long *polls);
/* Stops the thread (the rails are left as they are: the runner stops them). NULL is a no-op. */
void trial_rail_poller_stop(trial_rail_poller *p);

#endif
