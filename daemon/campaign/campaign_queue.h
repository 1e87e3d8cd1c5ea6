/* campaign_queue.h: the queue that runs a campaign's items one after another: trials of named
 * specimens, operator steps that wait for a confirmation, pauses (campaign_queue.c). */
#ifndef RIBBON_CAMPAIGN_QUEUE_H
#define RIBBON_CAMPAIGN_QUEUE_H

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "store.h"

#define CAMPAIGN_TICK_MS 200 /* how often the queue looks at its running item */

/* What the queue asks of the daemon. */
typedef struct campaign_queue_ops {
    /* Start a trial of sp (usable: checked) with the item's overrides (after the specimen's) and
     * note: 0 and *trial_id, or -1 with why (nothing started). Called on the queue's thread. */
    int (*start_trial)(void *user, const store_specimen *sp, const char *const *set, int n_set, const char *note,
                       int64_t *trial_id, char *why, size_t why_len);
    /* 1 while trial_id's session runs, 0 once it has ended (or is not the daemon's); trial_id 0:
     * 1 while any trial runs (one started by hand: the queue waits for it). */
    int (*trial_running)(void *user, int64_t trial_id);
} campaign_queue_ops;

typedef struct campaign_queue campaign_queue;

/* Opens the queue's own connection to the store, recovers it (store_queue_recover: an item found
 * running becomes unknown, the queue stopped, saying why; log gets a line) and starts the
 * queue's thread. The queue never starts by itself. 0, or -1 with why. */
int campaign_queue_open(const char *store_path, const campaign_queue_ops *ops, void *user,
                        void (*log)(const char *line), campaign_queue **out, char *why, size_t why_len);
/* Stops the queue's thread (a running trial is the daemon's to stop) and closes. NULL: no-op. */
void campaign_queue_close(campaign_queue *q);

/* The API's operations. Each returns 0 with *out (a new reference), or -1 with why and an HTTP
 * status in *http (400 bad body, 404 no such item, 409 not in that state). */
int campaign_queue_add(campaign_queue *q, const json_t *body, json_t **out, int *http, char *why, size_t why_len);
int campaign_queue_list(campaign_queue *q, json_t **out, int *http, char *why, size_t why_len);
/* One item's whole status: the item, its specimen, its trial (with events) and the queue's state. */
int campaign_queue_show(campaign_queue *q, int64_t id, json_t **out, int *http, char *why, size_t why_len);
int campaign_queue_remove(campaign_queue *q, int64_t id, json_t **out, int *http, char *why, size_t why_len);
/* A plan proposal's approval (POST /plan/ID/approve), on the queue's connection under its lock, in
 * one store transaction (store_plan_approve_new): the new specimen sp, the operator step op and the
 * trial item trial for it, the proposal approved; all or nothing. 0 with *out, or -1 with why and
 * *http: 409 a specimen of that name exists (the store's UNIQUE constraint) or the proposal is not
 * proposed, 404 no such proposal, 500 the store refused. */
int campaign_queue_approve(campaign_queue *q, int64_t proposal_id, const store_specimen *sp,
                           const store_queue_item *op, const store_queue_item *trial, store_plan_approval *out,
                           int *http, char *why, size_t why_len);
int campaign_queue_move(campaign_queue *q, int64_t id, const json_t *body, json_t **out, int *http, char *why,
                        size_t why_len);
/* start: the queue runs from its next item; stop: it starts no further item (a running trial
 * runs to its end: abort it to stop the rails). */
int campaign_queue_set_running(campaign_queue *q, bool run, json_t **out, int *http, char *why, size_t why_len);
/* Confirms the running operator step id with body {"values": {...}} (its fields). */
int campaign_queue_confirm(campaign_queue *q, int64_t id, const json_t *body, json_t **out, int *http, char *why,
                           size_t why_len);
/* The queue's state and its items for the status and live page: {running, reason, current,
 * queued}. */
json_t *campaign_queue_summary(campaign_queue *q);

#endif
