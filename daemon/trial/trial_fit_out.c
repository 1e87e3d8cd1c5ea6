/* trial_fit_out.c: the fit's events and landed results written on a thread of their own (see
 * trial_fit_out.h). A singly linked queue under one mutex: the poster appends a malloc'ed copy and
 * signals; the writer takes the whole list at once, writes it in order without the lock held, and
 * counts what it wrote, so drain waits for the count to reach what was posted. */
#include "trial_fit_out.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trial_publish.h"

enum { ITEM_EVENT, ITEM_CALIBRATED };

typedef struct item {
    struct item *next;
    int kind;
    union {
        store_event ev;
        trial_calibrated r;
    } u;
} item;

struct trial_fit_out {
    store *st;
    int64_t trial_id;
    live_bus *bus;
    void (*log)(void *user, const char *line);
    void *user;
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t wake, done; /* wake: posted or stopping; done: written went up */
    item *head, *tail;         /* under lock */
    long posted, written;      /* under lock */
    int stop;                  /* under lock */
};

static void say(trial_fit_out *o, const char *line)
{
    if (o->log) o->log(o->user, line);
}

static void write_event(trial_fit_out *o, store_event *ev)
{
    ev->trial_id = o->trial_id;
    trial_publish_event(o->bus, o->trial_id, ev->t_s, store_event_kind_name(ev->kind), ev->message);
    char why[256];
    if (store_event_append(o->st, ev, why, sizeof why) != STORE_OK) {
        char line[400];
        snprintf(line, sizeof line, "event not stored: %s", why);
        say(o, line);
    }
    say(o, ev->message);
}

/* The trial's calibrated columns (a later fit replaces an earlier one; the session posts a
 * failure only when no fit landed ok), then the bus. */
static void write_calibrated(trial_fit_out *o, const trial_calibrated *r)
{
    char fit[2048];
    trial_calibrated_json(r, fit, sizeof fit);
    store_calibrated c = {.snap_dw = r->ok && r->snapped ? r->snap_dw : NAN,
                          .snap_sd = r->ok && r->snapped ? r->snap_sd : NAN,
                          .p_other = r->ok && r->snapped ? r->p_other : NAN,
                          .regime = !r->snapped ? "no snap" : r->asymmetric ? "asymmetric" : "symmetric",
                          .fit_json = fit,
                          .failure = NULL};
    char failure[400];
    if (!r->ok) {
        snprintf(failure, sizeof failure, "%s: %s", r->reason_key, r->reason);
        c.failure = failure;
    }
    store_event w;
    memset(&w, 0, sizeof w);
    if (store_trial_set_calibrated(o->st, o->trial_id, &c, w.message, sizeof w.message) != STORE_OK) {
        w.t_s = r->t_landed;
        w.wall_s = store_wall_now();
        w.kind = STORE_EVENT_WARNING;
        write_event(o, &w);
    }
    trial_publish_calibrated(o->bus, o->trial_id, r);
}

static void *writer_main(void *arg)
{
    trial_fit_out *o = arg;
    pthread_mutex_lock(&o->lock);
    for (;;) {
        while (!o->head && !o->stop) pthread_cond_wait(&o->wake, &o->lock);
        if (!o->head) break; /* stopping, everything written */
        item *list = o->head;
        o->head = o->tail = NULL;
        pthread_mutex_unlock(&o->lock);
        long n = 0;
        while (list) {
            item *next = list->next;
            if (list->kind == ITEM_EVENT) write_event(o, &list->u.ev);
            else write_calibrated(o, &list->u.r);
            free(list);
            list = next;
            n++;
        }
        pthread_mutex_lock(&o->lock);
        o->written += n;
        pthread_cond_broadcast(&o->done);
    }
    pthread_mutex_unlock(&o->lock);
    return NULL;
}

trial_fit_out *trial_fit_out_open(const char *store_path, int64_t trial_id, live_bus *bus,
                                  void (*log)(void *user, const char *line), void *user, char *why, size_t why_len)
{
    trial_fit_out *o = calloc(1, sizeof *o);
    if (!o) {
        snprintf(why, why_len, "out of memory");
        return NULL;
    }
    o->trial_id = trial_id;
    o->bus = bus;
    o->log = log;
    o->user = user;
    if (store_open(store_path, &o->st, why, why_len) != STORE_OK) {
        free(o);
        return NULL;
    }
    pthread_mutex_init(&o->lock, NULL);
    pthread_cond_init(&o->wake, NULL);
    pthread_cond_init(&o->done, NULL);
    if (pthread_create(&o->thread, NULL, writer_main, o) != 0) {
        snprintf(why, why_len, "the fit's writer thread could not start");
        pthread_cond_destroy(&o->done);
        pthread_cond_destroy(&o->wake);
        pthread_mutex_destroy(&o->lock);
        store_close(o->st);
        free(o);
        return NULL;
    }
    return o;
}

static int post(trial_fit_out *o, item *it)
{
    if (!it) return -1;
    it->next = NULL;
    pthread_mutex_lock(&o->lock);
    if (o->tail) o->tail->next = it;
    else o->head = it;
    o->tail = it;
    o->posted++;
    pthread_cond_signal(&o->wake);
    pthread_mutex_unlock(&o->lock);
    return 0;
}

int trial_fit_out_event(trial_fit_out *o, const store_event *ev)
{
    item *it = malloc(sizeof *it);
    if (it) {
        it->kind = ITEM_EVENT;
        it->u.ev = *ev;
    }
    return post(o, it);
}

int trial_fit_out_calibrated(trial_fit_out *o, const trial_calibrated *r)
{
    item *it = malloc(sizeof *it);
    if (it) {
        it->kind = ITEM_CALIBRATED;
        it->u.r = *r;
    }
    return post(o, it);
}

void trial_fit_out_drain(trial_fit_out *o)
{
    if (!o) return;
    pthread_mutex_lock(&o->lock);
    while (o->written < o->posted) pthread_cond_wait(&o->done, &o->lock);
    pthread_mutex_unlock(&o->lock);
}

void trial_fit_out_close(trial_fit_out *o)
{
    if (!o) return;
    pthread_mutex_lock(&o->lock);
    o->stop = 1;
    pthread_cond_signal(&o->wake);
    pthread_mutex_unlock(&o->lock);
    pthread_join(o->thread, NULL);
    pthread_cond_destroy(&o->done);
    pthread_cond_destroy(&o->wake);
    pthread_mutex_destroy(&o->lock);
    store_close(o->st);
    free(o);
}
