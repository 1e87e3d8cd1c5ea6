/* campaign_routes.h: the API's /specimens, /queue, /campaign/phase and /plan routes
 * (campaign_routes.c). */
#ifndef RIBBON_CAMPAIGN_ROUTES_H
#define RIBBON_CAMPAIGN_ROUTES_H

#include <jansson.h>
#include <stddef.h>

#include "campaign_queue.h"
#include "campaign_trace.h"
#include "scene.h"
#include "store.h"

typedef struct campaign_ctx {
    store *st;               /* the API thread's connection (specimens) */
    campaign_queue *q;       /* the queue (its own connection) */
    store_specimen defaults; /* a new specimen's size and material: the rig file's scene */
    const rod_scene *scene;  /* the rig's scene: the predicted boundary (NULL: none) */
    const char *rig_path, *scene_path; /* the files the boundary cache is keyed on */
    const char *boundary_cache; /* the cache file (campaign_predicted.h); NULL: trace every time */
    campaign_trace *trace;      /* ribbond: a cold cache is traced on its thread (503 meanwhile);
                                   NULL: traced on the caller's thread */
    const char *const *sets; /* the daemon's overrides (--set): in the cache's key with the files' */
    int n_sets;                 /* text, as they may change the scene */
} campaign_ctx;

/* A stored proposal as the API and ribbonctl plan --json show it. */
json_t *campaign_proposal_json(const store_plan_proposal *p);

/* Is path one of the campaign's (/specimens, /specimens/..., /queue, /queue/..., /campaign/phase,
 * /plan, /plan/...)? */
int campaign_route_match(const char *path);
/* Serves method ("GET", "POST") on path with body (POST: an object; GET: NULL). 0 with *out and
 * *http (200, 201 for a new specimen or item), or -1 with why and *http (400, 404, 405, 409, 500). */
/* GET /campaign/phase while c->trace traces the predicted boundary: 503 (the API server adds
 * Retry-After), why saying so. */
int campaign_route(const campaign_ctx *c, const char *method, const char *path, const json_t *body, json_t **out,
                   int *http, char *why, size_t why_len);

#endif
