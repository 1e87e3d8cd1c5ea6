/* campaign_trace.c: the predicted boundary traced on a thread of its own (see campaign_trace.h).
 *
 * One trace at a time: a request for another key while one runs is told to come back (1) and
 * starts its own once that one has landed. State under t->lock: the running trace's key and
 * start, and the last landed one's key with its curve or its failure. The thread works on its own
 * copies (scene, key text, cache path) and writes only the landed result, so the caller's
 * configuration may change or go meanwhile. */
#include "campaign_trace.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "thread_class.h"

struct campaign_trace {
    pthread_mutex_t lock;
    pthread_t thread;
    int started;         /* a thread exists and is not joined yet */
    int running;         /* it has not landed yet */
    uint64_t run_key;
    double run_t0;
    /* the job the thread works on (its own copies) */
    rod_scene sc;
    char *key_text, *cache_path;
    double lo, hi;
    /* the last landed trace */
    int landed;          /* 0 none, 1 curve, -1 failure */
    uint64_t landed_key;
    char landed_cache[1024];
    campaign_predicted curve;
    char why[600];
};

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* A deep copy (arrays malloc'ed): 0, or -1 when out of memory (dst freed). */
static int predicted_copy(const campaign_predicted *src, campaign_predicted *dst)
{
    *dst = *src;
    dst->phi_deg = malloc((src->n ? src->n : 1) * sizeof *dst->phi_deg);
    dst->gamma = malloc((src->n ? src->n : 1) * sizeof *dst->gamma);
    if (!dst->phi_deg || !dst->gamma) {
        free(dst->phi_deg);
        free(dst->gamma);
        memset(dst, 0, sizeof *dst);
        return -1;
    }
    if (src->n) {
        memcpy(dst->phi_deg, src->phi_deg, src->n * sizeof *dst->phi_deg);
        memcpy(dst->gamma, src->gamma, src->n * sizeof *dst->gamma);
    }
    return 0;
}

campaign_trace *campaign_trace_new(void)
{
    campaign_trace *t = calloc(1, sizeof *t);
    if (!t) return NULL;
    if (pthread_mutex_init(&t->lock, NULL) != 0) {
        free(t);
        return NULL;
    }
    return t;
}

static void job_clear(campaign_trace *t)
{
    free(t->key_text);
    free(t->cache_path);
    t->key_text = t->cache_path = NULL;
}

void campaign_trace_free(campaign_trace *t)
{
    if (!t) return;
    if (t->started) pthread_join(t->thread, NULL);
    job_clear(t);
    campaign_predicted_free(&t->curve);
    pthread_mutex_destroy(&t->lock);
    free(t);
}

static void *run(void *arg)
{
    campaign_trace *t = arg;
    /* SCHED_IDLE, as every best-effort thread of ribbond (thread_class.h): a trial's rails may be
     * moving. Refused: nice 19, the trace merely slower. */
    thread_class_idle_enter(NULL, 0);
    campaign_predicted res;
    char why[600] = "";
    int rc = campaign_predicted_cached(&t->sc, t->key_text, t->lo, t->hi, t->cache_path, &res, why, sizeof why);
    pthread_mutex_lock(&t->lock);
    campaign_predicted_free(&t->curve);
    if (rc == 0) t->curve = res;
    else memset(&t->curve, 0, sizeof t->curve);
    snprintf(t->why, sizeof t->why, "%s", why);
    t->landed = rc == 0 ? 1 : -1;
    t->landed_key = t->run_key;
    snprintf(t->landed_cache, sizeof t->landed_cache, "%s", t->cache_path ? t->cache_path : "");
    t->running = 0;
    pthread_mutex_unlock(&t->lock);
    return NULL;
}

/* The landed result of key (and cache path): 0 copied into out, -1 its failure, 2 none. Caller
 * holds lock. */
static int landed_for(campaign_trace *t, uint64_t key, const char *cache, campaign_predicted *out, char *why,
                      size_t why_len)
{
    if (!t->landed || t->landed_key != key || strcmp(t->landed_cache, cache ? cache : "")) return 2;
    if (t->landed < 0) {
        snprintf(why, why_len, "%s", t->why);
        return -1;
    }
    if (predicted_copy(&t->curve, out)) {
        snprintf(why, why_len, "predicted boundary: out of memory");
        return -1;
    }
    return 0;
}

int campaign_trace_get(campaign_trace *t, const rod_scene *sc, const char *key_text, double phi_lo, double phi_hi,
                       const char *cache_path, campaign_predicted *out, double *running_s, char *why, size_t why_len)
{
    uint64_t key = campaign_predicted_key(key_text);
    memset(out, 0, sizeof *out);
    pthread_mutex_lock(&t->lock);
    int rc = landed_for(t, key, cache_path, out, why, why_len);
    if (rc != 2) {
        pthread_mutex_unlock(&t->lock);
        return rc;
    }
    if (t->running) { /* this key's trace, or another's: come back once it has landed */
        if (running_s) *running_s = now_s() - t->run_t0;
        pthread_mutex_unlock(&t->lock);
        return 1;
    }
    pthread_mutex_unlock(&t->lock);
    /* the cache file, on this thread: a hit costs a file read */
    if (campaign_predicted_cache_read(key_text, phi_lo, phi_hi, cache_path, out) == 0) return 0;
    pthread_mutex_lock(&t->lock);
    if (t->running) { /* started by another caller meanwhile (ops run one at a time: not in ribbond) */
        if (running_s) *running_s = now_s() - t->run_t0;
        pthread_mutex_unlock(&t->lock);
        return 1;
    }
    if (t->started) pthread_join(t->thread, NULL); /* landed: its thread has returned or is returning */
    t->started = 0;
    job_clear(t);
    t->sc = *sc;
    t->key_text = strdup(key_text);
    t->cache_path = cache_path ? strdup(cache_path) : NULL;
    t->lo = phi_lo;
    t->hi = phi_hi;
    t->run_key = key;
    t->run_t0 = now_s();
    t->running = 1;
    if (!t->key_text || (cache_path && !t->cache_path) || pthread_create(&t->thread, NULL, run, t) != 0) {
        t->running = 0;
        job_clear(t);
        pthread_mutex_unlock(&t->lock);
        snprintf(why, why_len, "predicted boundary: its trace could not be started (out of memory or threads)");
        return -1;
    }
    t->started = 1;
    if (running_s) *running_s = 0.0;
    pthread_mutex_unlock(&t->lock);
    return 1;
}
