/* trial_transcoder.c: the background transcode worker (trial_transcoder.h). One thread, a fixed
 * ring of jobs under one mutex; the thread opens its own store connection per job (the store
 * may be busy with the next trial's samples: SQLite's busy timeout covers it). */
#define _GNU_SOURCE
#include "trial_transcoder.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "store.h"
#include "thread_class.h"

typedef struct tx_job {
    int64_t trial_id;
    char raw[1024];
    int crop[4];
    int rec_roi[4];
    int has_crop;
} tx_job;

struct trial_transcoder {
    trial_transcoder_params p;
    char store_path[1024];
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t cond;     /* a job queued, a job done, or stop */
    tx_job q[TRIAL_TRANSCODER_QUEUE];
    int head, count;         /* under lock */
    int busy;                /* under lock: a job in progress */
    int stopping;            /* under lock */
    volatile int cancel;     /* read by the running transcode at each frame */
    atomic_long tid;         /* the worker's Linux thread id, 0 until it runs */
};

trial_transcoder_params trial_transcoder_params_default(void)
{
    trial_transcoder_params p;
    memset(&p, 0, sizeof p);
    p.codec = trial_transcode_params_default();
    p.idle = 1;
    return p;
}

static void tx_log(trial_transcoder *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void tx_log(trial_transcoder *t, const char *fmt, ...)
{
    if (!t->p.log) return;
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    t->p.log(line);
}

/* One event on the trial, on a connection of this thread's; a store that refuses it is logged. */
static void tx_event(trial_transcoder *t, store *st, int64_t id, store_event_kind kind, const char *msg)
{
    store_event ev;
    memset(&ev, 0, sizeof ev);
    ev.trial_id = id;
    ev.t_s = NAN;
    ev.wall_s = store_wall_now();
    ev.kind = kind;
    snprintf(ev.message, sizeof ev.message, "%.511s", msg);
    char w[256] = "";
    if (!st || store_event_append(st, &ev, w, sizeof w) != STORE_OK)
        tx_log(t, "trial %lld: %s (not stored: %s)", (long long)id, msg, st ? w : "no store");
    else
        tx_log(t, "trial %lld: %s", (long long)id, msg);
}

static void out_name(const char *raw, char *out, size_t len)
{
    snprintf(out, len, "%s", raw);
    size_t n = strlen(out);
    if (n >= 4 && strcmp(out + n - 4, ".avi") == 0) out[n - 4] = '\0';
    size_t m = strlen(out);
    if (m + 5 <= len) memcpy(out + m, ".mkv", 5);
}

static void run_job(trial_transcoder *t, const tx_job *j)
{
    store *st = NULL;
    char why[640] = "", w[256] = "";
    if (store_open(t->store_path, &st, w, sizeof w) != STORE_OK) {
        tx_log(t, "trial %lld: video transcode: the store: %s", (long long)j->trial_id, w);
        st = NULL;
    }
    char out[1100];
    out_name(j->raw, out, sizeof out);
    trial_transcode_params cp = t->p.codec;
    cp.cancel = &t->cancel;
    if (j->has_crop) {
        cp.crop_x = j->crop[0], cp.crop_y = j->crop[1], cp.crop_w = j->crop[2], cp.crop_h = j->crop[3];
    }
    trial_transcode_result r;
    char msg[2400];
    if (trial_transcode_run(j->raw, out, &cp, &r, why, sizeof why) == 0) {
        if (st && store_trial_set_video_file(st, j->trial_id, out, r.out_bytes, j->has_crop ? j->rec_roi : NULL, w,
                                                sizeof w) != STORE_OK)
            tx_log(t, "trial %lld: the transcoded video %s not stored as the trial's: %s", (long long)j->trial_id, out,
                   w);
        snprintf(msg, sizeof msg,
                 "video transcoded: FFV1 %s, %ld frames %dx%d verified bit for bit; %lld -> %lld bytes (%.3f of the "
                 "raw); encode %.2f s, verify %.2f s; %s",
                 out, r.frames, r.width, r.height, (long long)r.raw_bytes, (long long)r.out_bytes,
                 r.raw_bytes > 0 ? (double)r.out_bytes / (double)r.raw_bytes : 0.0, r.encode_s, r.verify_s,
                 r.raw_removed ? "raw video removed" : "raw video kept (could not be removed)");
        tx_event(t, st, j->trial_id, STORE_EVENT_INFO, msg);
    } else if (t->cancel) {
        /* Not a failure: ribbond's next start queues it again (trial_transcoder_queue_left). */
        snprintf(msg, sizeof msg, "video transcode stopped (the daemon is stopping): raw video %s kept; the next start "
                 "queues it again", j->raw);
        tx_event(t, st, j->trial_id, STORE_EVENT_WARNING, msg);
    } else {
        snprintf(msg, sizeof msg, "video transcode failed, raw video %s kept: %s", j->raw, why);
        tx_event(t, st, j->trial_id, STORE_EVENT_WARNING, msg);
    }
    store_close(st);
}

static void *tx_main(void *arg)
{
    trial_transcoder *t = arg;
    /* Below the trial's threads: SCHED_IDLE, inherited by the encoder's slice threads (thread_class.h). */
    char why[160];
    if (t->p.idle && thread_class_idle_enter(why, sizeof why)) tx_log(t, "transcoder: %s", why);
    atomic_store(&t->tid, thread_class_tid());
    pthread_mutex_lock(&t->lock);
    for (;;) {
        while (!t->count && !t->stopping) pthread_cond_wait(&t->cond, &t->lock);
        if (t->stopping) break;
        tx_job j = t->q[t->head];
        t->head = (t->head + 1) % TRIAL_TRANSCODER_QUEUE;
        t->count--;
        t->busy = 1;
        pthread_mutex_unlock(&t->lock);
        run_job(t, &j);
        pthread_mutex_lock(&t->lock);
        t->busy = 0;
        pthread_cond_broadcast(&t->cond);
    }
    pthread_mutex_unlock(&t->lock);
    return NULL;
}

trial_transcoder *trial_transcoder_start(const trial_transcoder_params *p, char *why, size_t why_len)
{
    if (!p || !p->store_path || !*p->store_path) {
        snprintf(why, why_len, "transcoder: needs the store's path");
        return NULL;
    }
    trial_transcoder *t = calloc(1, sizeof *t);
    if (!t) {
        snprintf(why, why_len, "transcoder: out of memory");
        return NULL;
    }
    t->p = *p;
    snprintf(t->store_path, sizeof t->store_path, "%s", p->store_path);
    t->p.store_path = t->store_path;
    pthread_mutex_init(&t->lock, NULL);
    pthread_cond_init(&t->cond, NULL);
    int e = pthread_create(&t->thread, NULL, tx_main, t);
    if (e) {
        snprintf(why, why_len, "transcoder: thread: %s", strerror(e));
        pthread_cond_destroy(&t->cond);
        pthread_mutex_destroy(&t->lock);
        free(t);
        return NULL;
    }
    return t;
}

long trial_transcoder_worker_tid(trial_transcoder *t) { return t ? atomic_load(&t->tid) : 0; }

int trial_transcoder_submit(trial_transcoder *t, int64_t trial_id, const char *raw_path, const int crop[4],
                            const int rec_roi[4], char *why, size_t why_len)
{
    if (!t || !raw_path || strlen(raw_path) >= sizeof((tx_job *)0)->raw || (crop && !rec_roi)) {
        snprintf(why, why_len, "video transcode not queued: no transcoder, or the path is too long");
        return -1;
    }
    pthread_mutex_lock(&t->lock);
    int rc = -1;
    if (t->stopping)
        snprintf(why, why_len, "video transcode not queued: the daemon is stopping");
    else if (t->count >= TRIAL_TRANSCODER_QUEUE)
        snprintf(why, why_len, "video transcode not queued: %d videos wait already", t->count);
    else {
        tx_job *j = &t->q[(t->head + t->count) % TRIAL_TRANSCODER_QUEUE];
        memset(j, 0, sizeof *j);
        j->trial_id = trial_id;
        snprintf(j->raw, sizeof j->raw, "%s", raw_path);
        if (crop) {
            memcpy(j->crop, crop, sizeof j->crop);
            memcpy(j->rec_roi, rec_roi, sizeof j->rec_roi);
            j->has_crop = 1;
        }
        t->count++;
        pthread_cond_broadcast(&t->cond);
        rc = 0;
    }
    pthread_mutex_unlock(&t->lock);
    return rc;
}

/* 1 when the trial's events say its raw video stays raw on purpose (or cannot be read). */
static int raw_kept_on_purpose(store *st, int64_t id)
{
    store_event *ev = NULL;
    size_t n = 0;
    char w[256];
    if (store_events_get(st, id, &ev, &n, w, sizeof w) != STORE_OK) return 1;
    int kept = 0;
    for (size_t k = 0; k < n && !kept; k++)
        kept = strncmp(ev[k].message, "video not transcoded", 20) == 0 ||
               strncmp(ev[k].message, "video transcode failed", 22) == 0;
    free(ev);
    return kept;
}

int trial_transcoder_queue_left(trial_transcoder *t, store *st, char *why, size_t why_len)
{
    store_trial *all = NULL;
    size_t n = 0;
    if (store_trial_list(st, &all, &n, why, why_len) != STORE_OK) return -1;
    int queued = 0;
    char w[256];
    for (size_t k = 0; k < n; k++) {
        const store_trial *tr = &all[k];
        size_t l = strlen(tr->video_path);
        if (tr->mode != STORE_MODE_RIG || l < 5 || strcmp(tr->video_path + l - 4, ".avi") != 0 ||
            (tr->status != STORE_STATUS_DONE && tr->status != STORE_STATUS_FAILED &&
             tr->status != STORE_STATUS_ABORTED) ||
            access(tr->video_path, R_OK) != 0 || raw_kept_on_purpose(st, tr->id))
            continue;
        if (trial_transcoder_submit(t, tr->id, tr->video_path, NULL, NULL, w, sizeof w) == 0) queued++;
        else tx_log(t, "trial %lld: %s", (long long)tr->id, w);
    }
    free(all);
    return queued;
}

int trial_transcoder_pending(trial_transcoder *t)
{
    if (!t) return 0;
    pthread_mutex_lock(&t->lock);
    int n = t->count + t->busy;
    pthread_mutex_unlock(&t->lock);
    return n;
}

int trial_transcoder_wait_idle(trial_transcoder *t, double timeout_s)
{
    if (!t) return 0;
    struct timespec dl;
    clock_gettime(CLOCK_REALTIME, &dl);
    double s = (double)dl.tv_sec + 1e-9 * (double)dl.tv_nsec + (timeout_s > 0 ? timeout_s : 0);
    dl.tv_sec = (time_t)s;
    dl.tv_nsec = (long)((s - (double)dl.tv_sec) * 1e9);
    pthread_mutex_lock(&t->lock);
    int rc = 0;
    while ((t->count || t->busy) && rc == 0)
        if (pthread_cond_timedwait(&t->cond, &t->lock, &dl) == ETIMEDOUT) rc = -1;
    if (!t->count && !t->busy) rc = 0;
    pthread_mutex_unlock(&t->lock);
    return rc;
}

void trial_transcoder_stop(trial_transcoder *t)
{
    if (!t) return;
    pthread_mutex_lock(&t->lock);
    t->stopping = 1;
    t->cancel = 1;
    pthread_cond_broadcast(&t->cond);
    pthread_mutex_unlock(&t->lock);
    pthread_join(t->thread, NULL);
    /* What never ran keeps its raw video, and its trial says so. */
    if (t->count) {
        store *st = NULL;
        char w[256];
        if (store_open(t->store_path, &st, w, sizeof w) != STORE_OK) st = NULL;
        for (int k = 0; k < t->count; k++) {
            const tx_job *j = &t->q[(t->head + k) % TRIAL_TRANSCODER_QUEUE];
            char msg[1200];
            snprintf(msg, sizeof msg,
                     "video transcode not run (the daemon stopped first): raw video %s kept; the next start queues it "
                     "again", j->raw);
            tx_event(t, st, j->trial_id, STORE_EVENT_WARNING, msg);
        }
        store_close(st);
    }
    pthread_cond_destroy(&t->cond);
    pthread_mutex_destroy(&t->lock);
    free(t);
}
