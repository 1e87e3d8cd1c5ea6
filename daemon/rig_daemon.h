/* rig_daemon.h: what ribbond is while it runs: the rig file, the rails (opened once), the store,
 * the current trial session, and the control API's operations on them.
 *
 * Threads: the API's operations run on the API server's thread (api_server.h); a trial runs on
 * its session's thread, which owns the rails while it runs; a replay (replay mode) on its job's
 * thread; main() waits for signals; in rig mode a transcoder's thread encodes each ended trial's
 * raw video to lossless FFV1 beside the next trial (trial_transcoder.h). The daemon's mutex guards `session` and `replay`; the store handle `st` is used by the API thread only (each thread has its
 * own connection). At start-up every trial the store still marks running is marked interrupted:
 * a restart never resumes motion. One daemon per store and per rail device: both are locked
 * (owner_lock.h) for the daemon's life, so a second daemon refuses to start instead of marking
 * the first one's running trial interrupted or opening its controller (issue 33, item 1).
 * ribbonctl --db takes no lock: reading the store beside a running daemon is fine.
 * A trial's final status the store refused (a full disk) is kept and written on the API thread's
 * next operation that finds the store writable again (issue 33, item 3); never "running" for an
 * idle daemon longer than that, and at the latest the next start-up marks it interrupted.
 * The campaign's queue (campaign.h) runs on a thread of its own and starts its trials through
 * the same path as POST /trials; it takes its own lock before the daemon's, never after. */
#ifndef RIBBON_DAEMON_RIG_DAEMON_H
#define RIBBON_DAEMON_RIG_DAEMON_H

#include <pthread.h>
#include <stddef.h>

#include "api.h"
#include "campaign.h"
#include "check.h"
#include "live.h"
#include "owner_lock.h"
#include "rail.h"
#include "rail_lock.h"
#include "rig_config.h"
#include "trial.h"
#include "trial_report.h"
#include "store.h"

#define RIG_DAEMON_MAX_OVERRIDES 64
#define RIG_DAEMON_MAX_UNSTORED 16 /* ended trials whose final status waits for the store */

/* A trial's final status the store refused when it ended (a full disk), written by the API
 * thread on its next operation once the store takes writes again. */
typedef struct rig_unstored {
    int64_t id;
    trial_state final;
    char reason[256];
    double wall_s;   /* when it ended (its ended_at) */
    char why[256];   /* why the store refused it */
} rig_unstored;

typedef struct rig_daemon {
    rig_config cfg;
    char config_path[RIG_PATH_MAX];
    const char *overrides[RIG_DAEMON_MAX_OVERRIDES]; /* from the command line (borrowed) */
    int n_overrides;
    store *st;                 /* API thread's connection */
    rail *compress, *shear;    /* NULL in replay mode */
    rail_vclock vclock;        /* mock mode's virtual clock */
    pthread_mutex_t lock;
    trial_session *session;    /* current or last trial, under lock */
    replay_job *replay;        /* replay mode: the current or last replay, under lock */
    api_server *api;
    live_bus *bus;             /* the live page's: every trial publishes into it */
    live_assets assets;        /* the live page's files */
    phase_map *phase;          /* the predicted phase diagram (GET /phase.png), computed on demand */
    void (*log)(const char *line);
    owner_lock *store_lock;    /* STORE.lock: this daemon owns the store (rig_daemon_open) */
    rail_locks *rails_lock;    /* the rails' devices (rig and mock modes) */
    rig_unstored unstored[RIG_DAEMON_MAX_UNSTORED]; /* under lock */
    int n_unstored;
    trial_transcoder *transcoder; /* rig mode: the trials' raw videos to FFV1, in the background */
    campaign_queue *queue;     /* the campaign's queue (rig and mock modes; rig_daemon_serve) */
    campaign_trace *trace;     /* GET /campaign/phase's predicted boundary, traced off the API
                                  thread (made on its first request; the API thread's) */
    /* The readiness checks (check.h), run at start and by rig_daemon_check; under lock. While
     * one fails, trials are refused (409 with the fails) and GET /status carries them. */
    check_report checks;
    char checked_at[32];       /* when they last ran, UTC ISO 8601 */
    char rails_why[900];       /* rig mode: why the rails could not be opened ("" = open) */
    check_env check_hooks;     /* tests: camera_probe, statvfs_fn; service_user stays NULL
                                  (ribbond runs as its own service user) */
} rig_daemon;

/* Loads the rig file, takes the locks (the store's, STORE_PATH.lock, and in rig and mock modes
 * the rails' devices: rail_lock.h) before touching anything, opens the store (marking interrupted
 * trials) and, in rig and mock modes, both rails, then runs the readiness checks. Returns 0, or -1
 * with why: a store or a device another daemon holds is refused naming the holder (pid, since
 * when). In rig mode rails that do not open (a missing port, a refused controller) do not stop the
 * daemon: it serves status and the page with the reasons, refuses trials, and opens them when the
 * checks run again (rig_daemon_check). */
int rig_daemon_open(rig_daemon *d, const char *config_path, const char *const *overrides, int n_overrides,
                    void (*log)(const char *line), char *why, size_t why_len);
/* Runs the readiness checks again (at start, on SIGHUP, POST /checks): in rig mode rails that could
 * not be opened are opened now (their locks taken again: a port that appeared since has a lock of
 * its own name). Refused (-1, why) while a trial or replay runs: it owns the rails. Holds the
 * daemon's lock while it runs (a missing GenICam camera takes about 3 s to give up). Logs every
 * fail and warning. 0, and *fails (may be NULL) the count of fails. */
int rig_daemon_check(rig_daemon *d, int *fails, char *why, size_t why_len);

/* Starts the control API; *port gets the bound port. */
int rig_daemon_serve(rig_daemon *d, unsigned *port, char *why, size_t why_len);
/* Stops a running trial or replay (aborted with reason), waits for it, stops the API, closes the rails
 * (stopped) and the store. */
void rig_daemon_close(rig_daemon *d, const char *reason);

/* The API operations (api_ops), exposed for tests. */
api_ops rig_daemon_ops(void);

#endif
