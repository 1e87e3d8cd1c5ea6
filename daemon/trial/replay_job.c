/* replay_job.c: a replay on its own thread (see replay_job.h). */
#include "replay_job.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct replay_job {
    pthread_t thread;
    trial_replay *r;
    store *st; /* the job's own connection */
    int64_t trial_id, source_id;
    atomic_int cancel;
    atomic_long frame;
    long total;
    atomic_int finished;
    trial_result res;
    char why[512];
};

static void job_progress(void *u, long frame, long total)
{
    replay_job *j = u;
    (void)total;
    atomic_store(&j->frame, frame);
}

static void *job_main(void *arg)
{
    replay_job *j = arg;
    trial_replay_execute(j->r, j->st, &j->cancel, job_progress, j, &j->res, j->why, sizeof j->why);
    atomic_store(&j->finished, 1);
    return NULL;
}

int replay_job_start(trial_replay *r, store *st, const char *store_path, const char *note, replay_job **out,
                     int64_t *trial_id, char *why, size_t why_len)
{
    *out = NULL;
    *trial_id = 0;
    replay_job *j = calloc(1, sizeof *j);
    if (!j) {
        snprintf(why, why_len, "out of memory");
        trial_replay_free(r);
        return -1;
    }
    j->r = r;
    j->source_id = trial_replay_source(r);
    j->total = trial_replay_frame_count(r);
    atomic_init(&j->cancel, 0);
    atomic_init(&j->frame, 0);
    atomic_init(&j->finished, 0);
    if (store_open(store_path, &j->st, why, why_len) != STORE_OK) goto fail;
    if (trial_replay_create(r, st, note, &j->trial_id, why, why_len)) goto fail;
    if (pthread_create(&j->thread, NULL, job_main, j) != 0) {
        snprintf(why, why_len, "cannot start the replay thread");
        char w[256];
        store_trial_set_status(st, j->trial_id, STORE_STATUS_FAILED, why, store_wall_now(), w, sizeof w);
        goto fail;
    }
    *trial_id = j->trial_id;
    *out = j;
    return 0;
fail:
    store_close(j->st);
    trial_replay_free(r);
    free(j);
    return -1;
}

void replay_job_status_get(replay_job *j, replay_job_status *out)
{
    out->trial_id = j->trial_id;
    out->source_id = j->source_id;
    out->frame = atomic_load(&j->frame);
    out->total = j->total;
    out->finished = atomic_load(&j->finished);
}

void replay_job_abort(replay_job *j) { atomic_store(&j->cancel, 1); }

void replay_job_join(replay_job *j, trial_result *res)
{
    if (!j) return;
    pthread_join(j->thread, NULL);
    if (res) *res = j->res;
    store_close(j->st);
    trial_replay_free(j->r);
    free(j);
}
