/* replay_job.h: a replay running on a thread of its own inside ribbond, so that the control API
 * keeps answering (status, abort, list) while a video is decoded and tracked. The job owns a
 * prepared trial_replay and a store connection of its own; the trial row is created before the
 * thread starts, so the API can answer with its id at once. */
#ifndef RIBBON_DAEMON_REPLAY_JOB_H
#define RIBBON_DAEMON_REPLAY_JOB_H

#include <stddef.h>
#include <stdint.h>

#include "trial_replay.h"

typedef struct replay_job replay_job;

typedef struct replay_job_status {
    int64_t trial_id;  /* the new trial */
    int64_t source_id; /* 0 = outside files */
    long frame, total; /* frames done; total -1 = unknown */
    int finished;
} replay_job_status;

/* Takes r (freed by the job in every case). Creates the trial through st (the caller's
 * connection), opens its own connection to store_path, and starts the thread. */
int replay_job_start(trial_replay *r, store *st, const char *store_path, const char *note, replay_job **out,
                     int64_t *trial_id, char *why, size_t why_len);
void replay_job_status_get(replay_job *j, replay_job_status *out);
void replay_job_abort(replay_job *j);
/* Waits for the thread and frees the job; res (may be NULL) gets the result. */
void replay_job_join(replay_job *j, trial_result *res);

#endif
