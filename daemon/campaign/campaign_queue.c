/* campaign_queue.c: the queue's thread and its API operations (issue 35, part B).
 *
 * The queue lives in the store (store_queue.c): its items, their history and whether it runs.
 * This file moves it: every CAMPAIGN_TICK_MS (or at once when an operation kicks it) the thread
 * looks at the running item (a trial: has its session ended? then the item ends as its trial
 * did; an operator step: it waits for a confirmation), or, with nothing running and the queue
 * started, begins the next one: a pause stops the queue, an operator step waits, a trial starts
 * through the daemon (campaign_queue_ops). A trial that ends failed, aborted or interrupted
 * stops the queue, saying why: the lab looks at the rig before anything moves again. The queue
 * stops too when it runs out of items. A trial started by hand (POST /trials) while the queue runs
 * makes it wait: its next item begins once that trial has ended.
 *
 * One lock (q->lock) covers the thread's step and every operation, and the queue's own store
 * connection is used under it only, so the queue's rows have one writer. Lock order: q->lock,
 * then the daemon's (start_trial and trial_running take it); the daemon never calls in here
 * holding its own. An item is marked running before its trial starts and names the trial after:
 * a crash in between leaves a running item without a trial, which the next start-up marks
 * unknown (and any trial it created, interrupted). An item that ends the queue (a pause, a
 * trial that did not end done or did not start) ends and stops it in one store transaction. */
#include "campaign_queue.h"

#include <errno.h>
#include <stdarg.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "api.h"
#include "campaign_operator.h"
#include "campaign_specimen.h"

struct campaign_queue {
    store *st;
    campaign_queue_ops ops;
    void *user;
    void (*log)(const char *line);
    pthread_mutex_t lock;
    pthread_cond_t wake;
    pthread_t thread;
    int quit;
    int kicked;
};

static void say(campaign_queue *q, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void say(campaign_queue *q, const char *fmt, ...)
{
    if (!q->log) return;
    char line[700];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    q->log(line);
}

static void stop_queue(campaign_queue *q, const char *reason)
{
    char w[256];
    if (store_queue_state_set(q->st, false, reason, store_wall_now(), w, sizeof w) != STORE_OK)
        say(q, "queue: could not record its stop (%s): %s", reason, w);
    else
        say(q, "queue stopped: %s", reason);
}

static void end_item(campaign_queue *q, const store_queue_item *it, store_queue_status s, const char *reason,
                     const char *values)
{
    char w[256];
    if (store_queue_item_end(q->st, it->id, s, reason, values, store_wall_now(), w, sizeof w) != STORE_OK)
        say(q, "queue: item %lld could not be ended %s: %s", (long long)it->id, store_queue_status_name(s), w);
}

/* The item ends and the queue stops in one transaction: when it cannot be written, neither is,
 * the item stays running and the next step ends it again (never an ended item with the queue
 * still running, which would start the next item). */
static void end_item_stop(campaign_queue *q, const store_queue_item *it, store_queue_status s, const char *reason,
                          const char *stop_reason)
{
    char w[256];
    if (store_queue_item_end_stop(q->st, it->id, s, reason, NULL, stop_reason, store_wall_now(), w, sizeof w) !=
        STORE_OK)
        say(q, "queue: item %lld could not be ended %s and the queue stopped (%s): %s; tried again on the next look",
            (long long)it->id, store_queue_status_name(s), stop_reason, w);
    else
        say(q, "queue stopped: %s", stop_reason);
}

/* A pause item reached (begun): it ends done and stops the queue. */
static void end_pause(campaign_queue *q, const store_queue_item *it)
{
    char why[600];
    snprintf(why, sizeof why, "paused by item %lld%s%.400s: start the queue to go on", (long long)it->id,
             it->note[0] ? ": " : "", it->note);
    end_item_stop(q, it, STORE_QUEUE_DONE, "the queue paused here", why);
}

/* The running trial item: ends as its trial did once the session has ended and the store has its
 * final status. */
static void follow_trial(campaign_queue *q, const store_queue_item *it)
{
    if (!it->trial_id) {
        /* begun, but its trial never started (the start failed and its end could not be written) */
        end_item_stop(q, it, STORE_QUEUE_FAILED, "its trial did not start", "a queue item's trial did not start");
        return;
    }
    if (q->ops.trial_running(q->user, it->trial_id)) return;
    store_trial t;
    char w[256];
    if (store_trial_get(q->st, it->trial_id, &t, w, sizeof w) != STORE_OK) return;
    store_queue_status s;
    switch (t.status) {
    case STORE_STATUS_DONE: s = STORE_QUEUE_DONE; break;
    case STORE_STATUS_FAILED: s = STORE_QUEUE_FAILED; break;
    case STORE_STATUS_ABORTED: s = STORE_QUEUE_ABORTED; break;
    case STORE_STATUS_INTERRUPTED: s = STORE_QUEUE_UNKNOWN; break;
    default: return; /* its final status is not in the store yet (the daemon writes it late) */
    }
    char reason[600];
    snprintf(reason, sizeof reason, "trial %lld ended %s%s%.500s", (long long)t.id, store_status_name(t.status),
             t.reason[0] ? ": " : "", t.reason);
    say(q, "queue item %lld: %s", (long long)it->id, reason);
    if (s != STORE_QUEUE_DONE) {
        char why[700];
        snprintf(why, sizeof why, "item %lld's %.600s; check the rig, then start the queue again", (long long)it->id,
                 reason);
        end_item_stop(q, it, s, reason, why);
    } else {
        end_item(q, it, s, reason, NULL);
    }
}

/* The item's overrides (JSON array text) as strings kept in set_json's parsed copy. */
static int start_trial_item(campaign_queue *q, const store_queue_item *it, char *why, size_t why_len)
{
    store_specimen sp;
    if (campaign_specimen_usable(q->st, it->specimen_name, &sp, why, why_len)) return -1;
    json_error_t je;
    json_t *set = json_loads(it->set_json[0] ? it->set_json : "[]", 0, &je);
    if (!json_is_array(set) || json_array_size(set) > API_START_MAX_SET) {
        json_decref(set);
        snprintf(why, why_len, "its stored overrides are not an array of at most %d strings", API_START_MAX_SET);
        return -1;
    }
    const char *ov[API_START_MAX_SET];
    int n = 0;
    for (size_t k = 0; k < json_array_size(set); k++) ov[n++] = json_string_value(json_array_get(set, k));
    int64_t tid = 0;
    int rc = q->ops.start_trial(q->user, &sp, ov, n, it->note[0] ? it->note : NULL, &tid, why, why_len);
    json_decref(set);
    if (rc) return -1;
    char w[256];
    if (store_queue_item_set_trial(q->st, it->id, tid, w, sizeof w) != STORE_OK)
        say(q, "queue item %lld: trial %lld started but not recorded on the item: %s", (long long)it->id,
            (long long)tid, w);
    say(q, "queue item %lld: trial %lld of %s started", (long long)it->id, (long long)tid, sp.name);
    return 0;
}

/* One look at the queue. Caller holds q->lock. */
static void step(campaign_queue *q)
{
    bool running = false;
    char w[300];
    store_queue_item *it = malloc(sizeof *it);
    if (!it) return;
    if (store_queue_current(q->st, it, w, sizeof w) == STORE_OK) {
        if (it->kind == STORE_QUEUE_TRIAL) follow_trial(q, it);
        if (it->kind == STORE_QUEUE_PAUSE) end_pause(q, it); /* its end could not be written: again */
        /* an operator step waits for campaign_queue_confirm */
        free(it);
        return;
    }
    if (store_queue_state_get(q->st, &running, NULL, 0, NULL, w, sizeof w) != STORE_OK || !running) {
        free(it);
        return;
    }
    if (q->ops.trial_running(q->user, 0)) { /* a trial started by hand: wait for its end */
        free(it);
        return;
    }
    store_err e = store_queue_next(q->st, it, w, sizeof w);
    if (e == STORE_E_NOTFOUND) {
        stop_queue(q, "ran to its end: no item is left");
    } else if (e == STORE_OK && store_queue_item_begin(q->st, it->id, store_wall_now(), w, sizeof w) == STORE_OK) {
        char why[600];
        if (it->kind == STORE_QUEUE_PAUSE) {
            end_pause(q, it);
        } else if (it->kind == STORE_QUEUE_OPERATOR) {
            say(q, "queue item %lld waits for the operator: %s", (long long)it->id, it->prompt);
        } else if (start_trial_item(q, it, why, sizeof why)) {
            char reason[700], stop[700];
            snprintf(reason, sizeof reason, "its trial was not started: %.600s", why);
            snprintf(stop, sizeof stop, "item %lld's trial was not started: %.600s", (long long)it->id, why);
            end_item_stop(q, it, STORE_QUEUE_FAILED, reason, stop);
        }
    } else if (e != STORE_OK) {
        say(q, "queue: %s", w);
    }
    free(it);
}

static void *run(void *arg)
{
    campaign_queue *q = arg;
    pthread_mutex_lock(&q->lock);
    while (!q->quit) {
        step(q);
        if (q->kicked) {
            q->kicked = 0;
            continue;
        }
        struct timespec ts;
        clock_gettime(CLOCK_REALTIME, &ts);
        ts.tv_nsec += CAMPAIGN_TICK_MS * 1000000L;
        ts.tv_sec += ts.tv_nsec / 1000000000L;
        ts.tv_nsec %= 1000000000L;
        while (!q->quit && !q->kicked && pthread_cond_timedwait(&q->wake, &q->lock, &ts) != ETIMEDOUT) {
        }
        q->kicked = 0;
    }
    pthread_mutex_unlock(&q->lock);
    return NULL;
}

int campaign_queue_open(const char *store_path, const campaign_queue_ops *ops, void *user,
                        void (*log)(const char *line), campaign_queue **out, char *why, size_t why_len)
{
    campaign_queue *q = calloc(1, sizeof *q);
    if (!q) {
        snprintf(why, why_len, "out of memory for the queue");
        return -1;
    }
    q->ops = *ops;
    q->user = user;
    q->log = log;
    if (store_open(store_path, &q->st, why, why_len) != STORE_OK) {
        free(q);
        return -1;
    }
    int n = 0;
    char w[300];
    if (store_queue_recover(q->st, store_wall_now(), &n, w, sizeof w) != STORE_OK) {
        snprintf(why, why_len, "the queue could not be recovered: %s", w);
        store_close(q->st);
        free(q);
        return -1;
    }
    if (n) say(q, "queue: an item was found running at start-up and is now 'unknown'; the queue is stopped");
    pthread_mutex_init(&q->lock, NULL);
    pthread_cond_init(&q->wake, NULL);
    if (pthread_create(&q->thread, NULL, run, q) != 0) {
        snprintf(why, why_len, "could not start the queue's thread");
        pthread_cond_destroy(&q->wake);
        pthread_mutex_destroy(&q->lock);
        store_close(q->st);
        free(q);
        return -1;
    }
    *out = q;
    return 0;
}

void campaign_queue_close(campaign_queue *q)
{
    if (!q) return;
    pthread_mutex_lock(&q->lock);
    q->quit = 1;
    pthread_cond_signal(&q->wake);
    pthread_mutex_unlock(&q->lock);
    pthread_join(q->thread, NULL);
    pthread_cond_destroy(&q->wake);
    pthread_mutex_destroy(&q->lock);
    store_close(q->st);
    free(q);
}

static void kick(campaign_queue *q)
{
    q->kicked = 1;
    pthread_cond_signal(&q->wake);
}

/* ---- JSON ---------------------------------------------------------------------------------- */

static json_t *text_or_null(const char *s) { return s && *s ? json_string(s) : json_null(); }

static json_t *parsed_or_null(const char *s)
{
    if (!s || !*s) return json_null();
    json_t *j = json_loads(s, 0, NULL);
    return j ? j : json_null();
}

static json_t *item_json(const store_queue_item *it)
{
    json_t *o = json_object();
    json_object_set_new(o, "id", json_integer(it->id));
    json_object_set_new(o, "kind", json_string(store_queue_kind_name(it->kind)));
    json_object_set_new(o, "status", json_string(store_queue_status_name(it->status)));
    json_object_set_new(o, "position", it->position ? json_integer(it->position) : json_null());
    json_object_set_new(o, "specimen", text_or_null(it->specimen_name));
    if (it->kind == STORE_QUEUE_TRIAL) json_object_set_new(o, "set", parsed_or_null(it->set_json));
    json_object_set_new(o, "note", text_or_null(it->note));
    if (it->kind == STORE_QUEUE_OPERATOR) {
        json_object_set_new(o, "prompt", text_or_null(it->prompt));
        json_object_set_new(o, "fields", parsed_or_null(it->fields_json));
        json_object_set_new(o, "values", parsed_or_null(it->values_json));
        if (it->status == STORE_QUEUE_RUNNING)
            json_object_set_new(o, "waiting", json_string("for the operator's confirmation"));
    }
    json_object_set_new(o, "trial_id", it->trial_id ? json_integer(it->trial_id) : json_null());
    json_object_set_new(o, "reason", text_or_null(it->reason));
    json_object_set_new(o, "created_at", text_or_null(it->created_at));
    json_object_set_new(o, "started_at", text_or_null(it->started_at));
    json_object_set_new(o, "ended_at", text_or_null(it->ended_at));
    return o;
}

/* {running, reason, changed_at}. Caller holds q->lock. */
static json_t *state_json(campaign_queue *q)
{
    bool running = false;
    char reason[600] = "", at[32] = "", w[256];
    if (store_queue_state_get(q->st, &running, reason, sizeof reason, at, w, sizeof w) != STORE_OK)
        return json_pack("{s:b, s:s}", "running", 0, "reason", w);
    return json_pack("{s:b, s:s, s:s}", "running", running, "reason", running ? "" : reason, "changed_at", at);
}

static int store_fail_http(store_err e, const char *w, int *http, char *why, size_t why_len)
{
    *http = e == STORE_E_NOTFOUND ? 404 : e == STORE_E_STATE ? 409 : e == STORE_E_INVALID ? 400 : 500;
    snprintf(why, why_len, "%s", w);
    return -1;
}

/* ---- operations ------------------------------------------------------------------------- */

static int only_fields(const json_t *body, const char *const *keys, size_t n, const char *what, char *why,
                       size_t why_len)
{
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)body, k, v)
    {
        size_t i = 0;
        while (i < n && strcmp(keys[i], k)) i++;
        if (i == n) {
            snprintf(why, why_len, "unknown field \"%.64s\" for %s", k, what);
            return -1;
        }
    }
    return 0;
}

static int text_field(const json_t *body, const char *key, char *dst, size_t cap, char *why, size_t why_len)
{
    json_t *j = json_object_get(body, key);
    if (!j || json_is_null(j)) return 0;
    if (!json_is_string(j) || json_string_length(j) >= cap) {
        snprintf(why, why_len, "field \"%s\" must be a string of at most %zu bytes", key, cap - 1);
        return -1;
    }
    snprintf(dst, cap, "%s", json_string_value(j));
    return 0;
}

/* The item a body describes; 400 naming the field otherwise. Caller holds q->lock. */
static int item_from_body(campaign_queue *q, const json_t *body, store_queue_item *it, char *why, size_t why_len)
{
    *it = store_queue_item_default();
    json_t *kind = json_object_get(body, "kind");
    store_queue_kind k;
    if (!json_is_string(kind) || !store_queue_kind_parse(json_string_value(kind), &k)) {
        snprintf(why, why_len, "field \"kind\" must be \"trial\", \"operator\" or \"pause\"");
        return -1;
    }
    it->kind = k;
    static const char *const trial_keys[] = {"kind", "specimen", "set", "note"};
    static const char *const op_keys[] = {"kind", "specimen", "prompt", "fields", "note"};
    static const char *const pause_keys[] = {"kind", "note"};
    if (k == STORE_QUEUE_TRIAL ? only_fields(body, trial_keys, 4, "a trial item", why, why_len)
        : k == STORE_QUEUE_OPERATOR ? only_fields(body, op_keys, 5, "an operator step", why, why_len)
                                    : only_fields(body, pause_keys, 2, "a pause", why, why_len))
        return -1;
    if (text_field(body, "note", it->note, sizeof it->note, why, why_len) ||
        text_field(body, "prompt", it->prompt, sizeof it->prompt, why, why_len) ||
        text_field(body, "specimen", it->specimen_name, sizeof it->specimen_name, why, why_len))
        return -1;
    if (k == STORE_QUEUE_TRIAL && !it->specimen_name[0]) {
        snprintf(why, why_len, "a trial item names its specimen (field \"specimen\")");
        return -1;
    }
    if (k == STORE_QUEUE_OPERATOR && !it->prompt[0]) {
        snprintf(why, why_len, "an operator step needs its \"prompt\" (what the operator is to do)");
        return -1;
    }
    if (it->specimen_name[0]) {
        store_specimen sp;
        if (campaign_specimen_usable(q->st, it->specimen_name, &sp, why, why_len)) return -1;
        it->specimen_id = sp.id;
    }
    json_t *set = json_object_get(body, "set");
    if (set) {
        if (!json_is_array(set) || json_array_size(set) > API_START_MAX_SET) {
            snprintf(why, why_len, "field \"set\" must be an array of at most %d \"section.key=value\" strings",
                     API_START_MAX_SET);
            return -1;
        }
        for (size_t i = 0; i < json_array_size(set); i++) {
            json_t *s = json_array_get(set, i);
            char w[400];
            if (!json_is_string(s)) {
                snprintf(why, why_len, "set[%zu] must be a string", i);
                return -1;
            }
            if (api_override_check(json_string_value(s), w, sizeof w)) {
                snprintf(why, why_len, "set[%zu]: %s", i, w);
                return -1;
            }
        }
        char *t = json_dumps(set, JSON_COMPACT);
        if (!t || strlen(t) >= sizeof it->set_json) {
            free(t);
            snprintf(why, why_len, "field \"set\" is longer than %d bytes", STORE_QUEUE_JSON_MAX - 1);
            return -1;
        }
        snprintf(it->set_json, sizeof it->set_json, "%s", t);
        free(t);
    }
    json_t *fields = json_object_get(body, "fields");
    if (fields) {
        if (campaign_operator_fields_check(fields, it->specimen_id != 0, why, why_len)) return -1;
        char *t = json_dumps(fields, JSON_COMPACT);
        snprintf(it->fields_json, sizeof it->fields_json, "%s", t ? t : "[]");
        free(t);
    }
    return 0;
}

int campaign_queue_add(campaign_queue *q, const json_t *body, json_t **out, int *http, char *why, size_t why_len)
{
    store_queue_item *it = malloc(sizeof *it);
    if (!it) {
        *http = 500;
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    pthread_mutex_lock(&q->lock);
    int rc = -1;
    char w[400];
    int64_t id = 0;
    if (item_from_body(q, body, it, why, why_len)) {
        *http = 400;
    } else {
        store_err e = store_queue_add(q->st, it, store_wall_now(), &id, w, sizeof w);
        if (e != STORE_OK) store_fail_http(e, w, http, why, why_len);
        else if ((e = store_queue_get(q->st, id, it, w, sizeof w)) != STORE_OK) store_fail_http(e, w, http, why, why_len);
        else {
            *out = item_json(it);
            rc = 0;
            kick(q);
        }
    }
    pthread_mutex_unlock(&q->lock);
    free(it);
    return rc;
}

int campaign_queue_approve(campaign_queue *q, int64_t proposal_id, const store_specimen *sp,
                           const store_queue_item *op, const store_queue_item *trial, store_plan_approval *out,
                           int *http, char *why, size_t why_len)
{
    char w[512];
    pthread_mutex_lock(&q->lock);
    store_err e = store_plan_approve_new(q->st, proposal_id, sp, op, trial, store_wall_now(), out, w, sizeof w);
    if (e == STORE_OK) kick(q);
    pthread_mutex_unlock(&q->lock);
    if (e == STORE_OK) return 0;
    if (e == STORE_E_EXISTS) {
        *http = 409;
        snprintf(why, why_len, "%s", w);
        return -1;
    }
    return store_fail_http(e, w, http, why, why_len);
}

int campaign_queue_list(campaign_queue *q, json_t **out, int *http, char *why, size_t why_len)
{
    store_queue_item *v = NULL;
    size_t n = 0;
    char w[300];
    pthread_mutex_lock(&q->lock);
    store_err e = store_queue_list(q->st, &v, &n, w, sizeof w);
    json_t *o = e == STORE_OK ? state_json(q) : NULL;
    pthread_mutex_unlock(&q->lock);
    if (e != STORE_OK) return store_fail_http(e, w, http, why, why_len);
    json_t *current = json_null(), *queued = json_array(), *history = json_array();
    for (size_t k = 0; k < n; k++) {
        if (v[k].status == STORE_QUEUE_RUNNING) {
            json_decref(current);
            current = item_json(&v[k]);
        } else {
            json_array_append_new(v[k].status == STORE_QUEUE_QUEUED ? queued : history, item_json(&v[k]));
        }
    }
    free(v);
    json_object_set_new(o, "current", current);
    json_object_set_new(o, "queued", queued);
    json_object_set_new(o, "history", history);
    *out = o;
    return 0;
}

json_t *campaign_queue_summary(campaign_queue *q)
{
    store_queue_item *it = malloc(sizeof *it);
    char w[300];
    pthread_mutex_lock(&q->lock);
    json_t *o = state_json(q);
    json_object_set_new(o, "current",
                        it && store_queue_current(q->st, it, w, sizeof w) == STORE_OK ? item_json(it) : json_null());
    pthread_mutex_unlock(&q->lock);
    free(it);
    return o;
}

int campaign_queue_show(campaign_queue *q, int64_t id, json_t **out, int *http, char *why, size_t why_len)
{
    store_queue_item *it = malloc(sizeof *it);
    char w[300];
    if (!it) {
        *http = 500;
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    pthread_mutex_lock(&q->lock);
    store_err e = store_queue_get(q->st, id, it, w, sizeof w);
    json_t *o = NULL;
    if (e == STORE_OK) {
        o = item_json(it);
        json_t *t = NULL;
        if (it->trial_id && store_trial_json(q->st, it->trial_id, &t, w, sizeof w) == STORE_OK)
            json_object_set_new(o, "trial", t);
        else
            json_object_set_new(o, "trial", json_null());
        store_specimen sp;
        if (it->specimen_id && store_specimen_get(q->st, it->specimen_id, &sp, w, sizeof w) == STORE_OK)
            json_object_set_new(o, "specimen_record", campaign_specimen_json(&sp));
        else
            json_object_set_new(o, "specimen_record", json_null());
        json_object_set_new(o, "queue", state_json(q));
    }
    pthread_mutex_unlock(&q->lock);
    free(it);
    if (e != STORE_OK) return store_fail_http(e, w, http, why, why_len);
    *out = o;
    return 0;
}

/* Reply with the item as it is now. Caller holds q->lock. */
static int reply_item(campaign_queue *q, int64_t id, json_t **out, int *http, char *why, size_t why_len)
{
    store_queue_item *it = malloc(sizeof *it);
    char w[300];
    store_err e = it ? store_queue_get(q->st, id, it, w, sizeof w) : STORE_E_NOMEM;
    if (e == STORE_OK) *out = item_json(it);
    free(it);
    if (e != STORE_OK) return store_fail_http(e, it ? w : "out of memory", http, why, why_len);
    return 0;
}

int campaign_queue_remove(campaign_queue *q, int64_t id, json_t **out, int *http, char *why, size_t why_len)
{
    char w[400];
    pthread_mutex_lock(&q->lock);
    store_err e = store_queue_remove(q->st, id, "removed from the queue before it ran", store_wall_now(), w, sizeof w);
    int rc = e == STORE_OK ? reply_item(q, id, out, http, why, why_len) : store_fail_http(e, w, http, why, why_len);
    pthread_mutex_unlock(&q->lock);
    return rc;
}

int campaign_queue_move(campaign_queue *q, int64_t id, const json_t *body, json_t **out, int *http, char *why,
                        size_t why_len)
{
    static const char *const keys[] = {"position"};
    json_t *p = json_object_get(body, "position");
    if (only_fields(body, keys, 1, "a move", why, why_len)) {
        *http = 400;
        return -1;
    }
    if (!json_is_integer(p) || json_integer_value(p) < 1) {
        snprintf(why, why_len, "field \"position\" must be an integer >= 1 (1 = next)");
        *http = 400;
        return -1;
    }
    char w[400];
    pthread_mutex_lock(&q->lock);
    store_err e = store_queue_move(q->st, id, (int64_t)json_integer_value(p), w, sizeof w);
    int rc = e == STORE_OK ? reply_item(q, id, out, http, why, why_len) : store_fail_http(e, w, http, why, why_len);
    pthread_mutex_unlock(&q->lock);
    return rc;
}

int campaign_queue_set_running(campaign_queue *q, bool running, json_t **out, int *http, char *why, size_t why_len)
{
    char w[300];
    pthread_mutex_lock(&q->lock);
    store_err e = store_queue_state_set(q->st, running,
                                        running ? "started" : "stopped by the operator (a running trial runs to its end)",
                                        store_wall_now(), w, sizeof w);
    if (e == STORE_OK) {
        say(q, "queue %s through the API", running ? "started" : "stopped");
        *out = state_json(q);
        kick(q);
    }
    pthread_mutex_unlock(&q->lock);
    if (e != STORE_OK) return store_fail_http(e, w, http, why, why_len);
    return 0;
}

int campaign_queue_confirm(campaign_queue *q, int64_t id, const json_t *body, json_t **out, int *http, char *why,
                           size_t why_len)
{
    static const char *const keys[] = {"values"};
    if (only_fields(body, keys, 1, "a confirmation", why, why_len)) {
        *http = 400;
        return -1;
    }
    json_t *values = json_object_get(body, "values");
    json_t *empty = NULL;
    if (!values) values = empty = json_object();
    store_queue_item *it = malloc(sizeof *it);
    char w[400];
    int rc = -1;
    pthread_mutex_lock(&q->lock);
    store_err e = it ? store_queue_get(q->st, id, it, w, sizeof w) : STORE_E_NOMEM;
    if (e != STORE_OK) {
        store_fail_http(e, it ? w : "out of memory", http, why, why_len);
    } else if (it->kind != STORE_QUEUE_OPERATOR || it->status != STORE_QUEUE_RUNNING) {
        *http = 409;
        snprintf(why, why_len, "queue item %lld is %s %s: only the operator step the queue waits for can be confirmed",
                 (long long)id, it->kind == STORE_QUEUE_OPERATOR ? "an operator step," : "a",
                 it->kind == STORE_QUEUE_OPERATOR ? store_queue_status_name(it->status) : store_queue_kind_name(it->kind));
    } else {
        store_specimen sp = store_specimen_default();
        int have = it->specimen_id && store_specimen_get(q->st, it->specimen_id, &sp, w, sizeof w) == STORE_OK;
        if (campaign_operator_values_check(it, values, &sp, why, why_len)) {
            *http = 400;
        } else if (have && json_object_size(values) &&
                   (e = store_specimen_upsert(q->st, &sp, NULL, w, sizeof w)) != STORE_OK) {
            store_fail_http(e, w, http, why, why_len);
        } else {
            char *vt = json_dumps(values, JSON_COMPACT);
            e = store_queue_item_end(q->st, id, STORE_QUEUE_DONE, "confirmed by the operator", vt, store_wall_now(), w,
                                     sizeof w);
            free(vt);
            if (e != STORE_OK) store_fail_http(e, w, http, why, why_len);
            else {
                say(q, "queue item %lld confirmed", (long long)id);
                rc = reply_item(q, id, out, http, why, why_len);
                kick(q);
            }
        }
    }
    pthread_mutex_unlock(&q->lock);
    free(it);
    json_decref(empty);
    return rc;
}
