/* trial_fit_out.h: the fit beside a trial (trial_calibrate.h) written to the store and the live bus
 * off the trial's loop. The fit's callbacks (its events, each landed result) come on the runner's
 * thread, which watches the rails; a write there waits on SQLite (its commit, a checkpoint, another
 * connection's write lock up to the busy timeout). Measured in a mock trial at N = 31 (30 landings):
 * 0.3-0.5 ms each, but 6 of them 3-17 ms, the store's event append alone up to 24 ms. So the
 * session posts them here (a copy into a queue, never a wait on the store) and one thread of its own
 * writes them on its own connection, in the order posted: an event (store_event_append, then the
 * bus, then the log), a landed result (the trial's calibrated columns, store_trial_set_calibrated,
 * then the bus). A write that fails is said as a warning event. The session drains it before its
 * final status and closes it after the fit is freed. */
#ifndef RIBBON_TRIAL_FIT_OUT_H
#define RIBBON_TRIAL_FIT_OUT_H

#include <stddef.h>
#include <stdint.h>

#include "live.h"
#include "store.h"
#include "trial_calibrate.h"

typedef struct trial_fit_out trial_fit_out;

/* Opens a connection to store_path and starts the writer. log (may be NULL) gets each event's
 * message and each failure, on the writer's thread. NULL with why. */
trial_fit_out *trial_fit_out_open(const char *store_path, int64_t trial_id, live_bus *bus,
                                  void (*log)(void *user, const char *line), void *user, char *why, size_t why_len);
/* Posts an event (its trial_id is the writer's): 0, or -1 when out of memory (nothing posted). */
int trial_fit_out_event(trial_fit_out *o, const store_event *ev);
/* Posts a landed result: 0, or -1 when out of memory (nothing posted). */
int trial_fit_out_calibrated(trial_fit_out *o, const trial_calibrated *r);
/* Returns once everything posted so far is written. */
void trial_fit_out_drain(trial_fit_out *o);
/* Drains, stops the writer and closes its connection (NULL: nothing). */
void trial_fit_out_close(trial_fit_out *o);

#endif
