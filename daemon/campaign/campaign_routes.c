/* campaign_routes.c: the campaign's routes, one table of (method, pattern) -> function:
 *
 *   GET  /specimens                 every specimen
 *   POST /specimens                 add one (campaign_specimen_from_json)       201; 409 exists
 *   GET  /specimens/NAME            one, with its trials
 *   POST /specimens/NAME/retire     {"reason": "...", "broken": false}          409 already
 *   GET  /queue                     {running, reason, current, queued, history}
 *   POST /queue                     add an item                                 201
 *   POST /queue/start | /queue/stop
 *   GET  /queue/ID                  the item's whole status
 *   POST /queue/ID/remove | /queue/ID/move {"position": N} | /queue/ID/confirm {"values": {...}}
 *   GET  /campaign/phase            the lab's phase diagram's data (campaign_phase_json); with
 *                                   nothing to draw yet, empty lists and "empty": why; 503 while
 *                                   the predicted boundary is traced (ribbond: campaign_trace.h)
 *   GET  /plan                      every proposal, newest first
 *   POST /plan/ID/approve           {"name": "..."}: the proposal's specimen, an operator step
 *                                   and a trial in the queue                    409 not proposed
 *
 * The API server hands every path under /specimens and /queue here (it checks the path's bytes
 * and the token; the methods are checked here, 405 naming the allowed one). */
#include "campaign_routes.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "campaign_phase.h"
#include "campaign_plan.h"
#include "campaign_specimen.h"

int campaign_route_match(const char *path)
{
    return path && (!strcmp(path, "/specimens") || !strncmp(path, "/specimens/", 11) || !strcmp(path, "/queue") ||
                    !strncmp(path, "/queue/", 7) || !strcmp(path, "/campaign/phase") || !strcmp(path, "/plan") ||
                    !strncmp(path, "/plan/", 6));
}

static int fail(int *http, int status, char *why, size_t why_len, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static int fail(int *http, int status, char *why, size_t why_len, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(why, why_len, fmt, ap);
    va_end(ap);
    *http = status;
    return -1;
}

static int need(const char *method, const char *want, int *http, char *why, size_t why_len)
{
    if (!strcmp(method, want)) return 0;
    return fail(http, 405, why, why_len, "method %s not allowed here (allowed: %s)", method, want);
}

static int specimens_list(const campaign_ctx *c, json_t **out, int *http, char *why, size_t why_len)
{
    store_specimen *v = NULL;
    size_t n = 0;
    char w[300];
    if (store_specimen_list(c->st, &v, &n, w, sizeof w) != STORE_OK) return fail(http, 500, why, why_len, "%s", w);
    json_t *a = json_array();
    for (size_t k = 0; k < n; k++) json_array_append_new(a, campaign_specimen_json(&v[k]));
    free(v);
    *out = a;
    return 0;
}

static int specimen_add(const campaign_ctx *c, const json_t *body, json_t **out, int *http, char *why, size_t why_len)
{
    store_specimen sp, old;
    char w[300];
    if (campaign_specimen_from_json(body, &c->defaults, &sp, why, why_len)) return (*http = 400, -1);
    if (store_specimen_get_by_name(c->st, sp.name, &old, w, sizeof w) == STORE_OK)
        return fail(http, 409, why, why_len, "specimen %s exists (id %lld, %s): a specimen is added once", sp.name,
                    (long long)old.id, store_specimen_state_name(old.state));
    /* the look above names the one there; the insert decides (the name's UNIQUE constraint), so
       two adds of one name at once cannot both pass it */
    int64_t id = 0;
    store_err e = store_specimen_insert(c->st, &sp, &id, w, sizeof w);
    if (e == STORE_OK) e = store_specimen_get(c->st, id, &sp, w, sizeof w);
    if (e != STORE_OK)
        return fail(http, e == STORE_E_EXISTS ? 409 : e == STORE_E_INVALID ? 400 : 500, why, why_len, "%s", w);
    *out = campaign_specimen_json(&sp);
    *http = 201;
    return 0;
}

static int specimen_get(const campaign_ctx *c, const char *name, store_specimen *sp, int *http, char *why,
                        size_t why_len)
{
    char w[300];
    if (!campaign_specimen_name_ok(name, why, why_len)) return (*http = 400, -1);
    store_err e = store_specimen_get_by_name(c->st, name, sp, w, sizeof w);
    if (e == STORE_E_NOTFOUND) return fail(http, 404, why, why_len, "unknown specimen '%s'", name);
    if (e != STORE_OK) return fail(http, 500, why, why_len, "%s", w);
    return 0;
}

static int specimen_show(const campaign_ctx *c, const char *name, json_t **out, int *http, char *why, size_t why_len)
{
    store_specimen sp;
    if (specimen_get(c, name, &sp, http, why, why_len)) return -1;
    store_trial *t = NULL;
    size_t n = 0;
    char w[300];
    if (store_trial_list(c->st, &t, &n, w, sizeof w) != STORE_OK) return fail(http, 500, why, why_len, "%s", w);
    json_t *o = campaign_specimen_json(&sp), *a = json_array();
    for (size_t k = 0; k < n; k++) {
        if (t[k].specimen_id != sp.id) continue;
        const char *reg = store_regime_name(t[k].regime_measured);
        json_array_append_new(a, json_pack("{s:I, s:s, s:s, s:o, s:o, s:s}", "id", (json_int_t)t[k].id, "mode",
                                           store_mode_name(t[k].mode), "status", store_status_name(t[k].status),
                                           "regime_measured", reg ? json_string(reg) : json_null(), "snap_dw_measured",
                                           t[k].snap_dw_measured == t[k].snap_dw_measured ? json_real(t[k].snap_dw_measured)
                                                                                          : json_null(),
                                           "created_at", t[k].created_at));
    }
    free(t);
    json_object_set_new(o, "trials", a);
    *out = o;
    return 0;
}

static int specimen_retire(const campaign_ctx *c, const char *name, const json_t *body, json_t **out, int *http,
                           char *why, size_t why_len)
{
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)body, k, v)
    {
        if (strcmp(k, "reason") && strcmp(k, "broken"))
            return fail(http, 400, why, why_len, "unknown field \"%.64s\" (a retirement has: reason, broken)", k);
    }
    json_t *reason = json_object_get(body, "reason"), *broken = json_object_get(body, "broken");
    if (!json_is_string(reason) || !json_string_length(reason))
        return fail(http, 400, why, why_len, "field \"reason\" (why the specimen is retired) is required");
    if (broken && !json_is_boolean(broken))
        return fail(http, 400, why, why_len, "field \"broken\" must be true or false");
    store_specimen sp;
    if (specimen_get(c, name, &sp, http, why, why_len)) return -1;
    char w[300];
    store_err e = store_specimen_retire(c->st, sp.id, json_is_true(broken) ? STORE_SPECIMEN_BROKEN : STORE_SPECIMEN_RETIRED,
                                        json_string_value(reason), store_wall_now(), w, sizeof w);
    if (e == STORE_OK) e = store_specimen_get(c->st, sp.id, &sp, w, sizeof w);
    if (e != STORE_OK)
        return fail(http, e == STORE_E_STATE ? 409 : e == STORE_E_INVALID ? 400 : 500, why, why_len, "%s", w);
    *out = campaign_specimen_json(&sp);
    return 0;
}

/* GET /campaign/phase: the measured points, the experimental boundary and the predicted one (from
 * the cache; traced on the first request after the rig or scene file changed, about a second: with
 * c->trace on a thread of its own, and 503 until it has landed). */
static int phase_data(const campaign_ctx *c, json_t **out, int *http, char *why, size_t why_len)
{
    campaign_phase ph;
    char w[1024];
    int rc = campaign_phase_collect(c->st, &ph, w, sizeof w);
    if (rc == -2) {
        /* nothing to draw yet is a state, not a failure: 200 with the reason (the page polls this) */
        *out = json_pack("{s:[],s:[],s:n,s:i,s:i,s:s}", "points", "edges", "predicted", "specimens", 0, "trials", 0,
                         "empty", w);
        return 0;
    }
    if (rc) return fail(http, 500, why, why_len, "%s", w);
    campaign_predicted pred = {0};
    int have = 0;
    if (c->scene) {
        char *key = campaign_predicted_key_text(c->rig_path, c->scene_path);
        /* the daemon's --set may change the scene the files give: a cache traced without them
           (ribbonctl phase / plan) is not this scene's, nor is this one theirs */
        for (int k = 0; key && k < c->n_sets; k++) {
            size_t len = strlen(key), add = strlen(c->sets[k]) + 8;
            char *t = realloc(key, len + add);
            if (!t) free(key);
            key = t;
            if (key) snprintf(key + len, add, "\n--set %s", c->sets[k]);
        }
        if (c->trace) {
            /* off the API thread: a cold cache answers 503 until the trace has landed */
            double age = 0.0;
            int rc2 = campaign_trace_get(c->trace, c->scene, key ? key : "", CAMPAIGN_PHI_TRACE_LO,
                                         CAMPAIGN_PHI_TRACE_HI, c->boundary_cache, &pred, &age, w, sizeof w);
            free(key);
            if (rc2 == 1) {
                campaign_phase_free(&ph);
                return fail(http, 503, why, why_len,
                            "the predicted boundary is being traced in the background (%.1f s so far; about a "
                            "second on an idle core): ask again shortly", age);
            }
            have = rc2 == 0;
        } else {
            have = campaign_predicted_cached(c->scene, key ? key : "", CAMPAIGN_PHI_TRACE_LO, CAMPAIGN_PHI_TRACE_HI,
                                             c->boundary_cache, &pred, w, sizeof w) == 0;
            free(key);
        }
    }
    json_t *o = campaign_phase_json(&ph, have ? &pred : NULL);
    if (c->scene && !have) json_object_set_new(o, "predicted_error", json_string(w));
    campaign_predicted_free(&pred);
    campaign_phase_free(&ph);
    *out = o;
    return 0;
}

json_t *campaign_proposal_json(const store_plan_proposal *p)
{
    return json_pack("{s:I,s:I,s:f,s:f,s:f,s:f,s:f,s:f,s:b,s:s,s:o,s:o,s:o,s:s,s:o}", "id", (json_int_t)p->id, "batch",
                     (json_int_t)p->batch, "phi_deg", p->phi_deg, "gamma", p->gamma, "sd_before", p->sd_before,
                     "predicted_gamma", p->predicted_gamma, "offset_mean", p->offset_mean, "offset_sd", p->offset_sd,
                     "calibrated", p->calibrated, "status", store_plan_status_name(p->status), "specimen",
                     p->specimen_name[0] ? json_string(p->specimen_name) : json_null(), "operator_item",
                     p->operator_item_id ? json_integer(p->operator_item_id) : json_null(), "trial_item",
                     p->trial_item_id ? json_integer(p->trial_item_id) : json_null(), "created_at", p->created_at,
                     "approved_at", p->approved_at[0] ? json_string(p->approved_at) : json_null());
}

static int plan_list(const campaign_ctx *c, json_t **out, int *http, char *why, size_t why_len)
{
    store_plan_proposal *v = NULL;
    size_t n = 0;
    char w[300];
    if (store_plan_list(c->st, &v, &n, w, sizeof w) != STORE_OK) return fail(http, 500, why, why_len, "%s", w);
    json_t *a = json_array();
    for (size_t k = 0; k < n; k++) json_array_append_new(a, campaign_proposal_json(&v[k]));
    free(v);
    *out = a;
    return 0;
}

/* POST /plan/ID/approve: the specimen (name from the body, default plan-ID; the design from the
 * proposal, the rest from the rig's defaults), an operator step (fold and mount it, its measured
 * angles) and a trial of it at the end of the queue, and the proposal approved: all in one store
 * transaction (campaign_queue_approve), all or nothing. */
static int plan_approve(const campaign_ctx *c, int64_t id, const json_t *body, json_t **out, int *http, char *why,
                        size_t why_len)
{
    if (!c->q) return fail(http, 409, why, why_len, "this daemon has no queue: a proposal goes into the queue");
    const char *k;
    json_t *v;
    json_object_foreach((json_t *)body, k, v)
    {
        if (strcmp(k, "name")) return fail(http, 400, why, why_len, "unknown field \"%.64s\" (an approval has: name)", k);
    }
    json_t *jn = json_object_get(body, "name");
    if (jn && !json_is_string(jn)) return fail(http, 400, why, why_len, "field \"name\" must be a specimen name");
    store_plan_proposal p;
    char w[512];
    store_err e = store_plan_get(c->st, id, &p, w, sizeof w);
    if (e == STORE_E_NOTFOUND) return fail(http, 404, why, why_len, "no proposal %lld (ribbonctl plan --list)", (long long)id);
    if (e != STORE_OK) return fail(http, 500, why, why_len, "%s", w);
    if (p.status != STORE_PLAN_PROPOSED)
        return fail(http, 409, why, why_len, "proposal %lld is %s: only a proposed one can be approved", (long long)id,
                    store_plan_status_name(p.status));
    char name[64];
    snprintf(name, sizeof name, "%s", jn ? json_string_value(jn) : "");
    if (!name[0]) snprintf(name, sizeof name, "plan-%lld", (long long)id);
    store_specimen sp;
    json_t *sb = json_pack("{s:s,s:f,s:f}", "name", name, "phi_deg", p.phi_deg, "gamma", p.gamma);
    int rc = campaign_specimen_from_json(sb, &c->defaults, &sp, why, why_len);
    json_decref(sb);
    if (rc) return (*http = 400, -1);
    store_queue_item *it = malloc(2 * sizeof *it); /* two 13 kB items: off the API thread's stack */
    if (!it) return fail(http, 500, why, why_len, "approving proposal %lld: out of memory", (long long)id);
    it[0] = store_queue_item_default();
    it[0].kind = STORE_QUEUE_OPERATOR;
    snprintf(it[0].prompt, sizeof it[0].prompt,
             "fold and mount %s: phi %g deg, Gamma %.4f (plan proposal %lld); measured angles?", name, p.phi_deg,
             p.gamma, (long long)id);
    snprintf(it[0].fields_json, sizeof it[0].fields_json,
             "[\"crease_angle_left_deg\",\"crease_angle_right_deg\",\"folded_at\"]");
    it[1] = store_queue_item_default();
    it[1].kind = STORE_QUEUE_TRIAL;
    snprintf(it[1].note, sizeof it[1].note, "plan proposal %lld", (long long)id);
    /* specimen, operator step, trial item and the proposal approved: one transaction, so a failure
     * leaves none of them, and a name taken meanwhile is the store's UNIQUE constraint (409) */
    store_plan_approval a;
    rc = campaign_queue_approve(c->q, id, &sp, &it[0], &it[1], &a, http, why, why_len);
    free(it);
    if (rc) return -1;
    store_plan_get(c->st, id, &p, w, sizeof w);
    *out = json_pack("{s:o}", "proposal", campaign_proposal_json(&p));
    *http = 201;
    return 0;
}

/* "/queue/ID[/verb]": the id (decimal, >= 1) and the verb ("" when none). */
static int queue_path(const char *rest, int64_t *id, const char **verb, int *http, char *why, size_t why_len)
{
    char *end;
    errno = 0;
    long long v = strtoll(rest, &end, 10);
    if (rest[0] < '0' || rest[0] > '9' || errno || v < 1 || (*end && *end != '/'))
        return fail(http, 400, why, why_len, "queue item id '%.40s' is not a positive integer", rest);
    *id = v;
    *verb = *end ? end + 1 : "";
    return 0;
}

int campaign_route(const campaign_ctx *c, const char *method, const char *path, const json_t *body, json_t **out,
                   int *http, char *why, size_t why_len)
{
    *http = 200;
    int post = !strcmp(method, "POST");
    if (!strcmp(path, "/specimens"))
        return post ? specimen_add(c, body, out, http, why, why_len) : specimens_list(c, out, http, why, why_len);
    if (!strncmp(path, "/specimens/", 11)) {
        char name[80];
        const char *seg = path + 11, *slash = strchr(seg, '/');
        size_t n = slash ? (size_t)(slash - seg) : strlen(seg);
        if (n >= sizeof name) return fail(http, 400, why, why_len, "specimen name longer than 63 bytes");
        memcpy(name, seg, n);
        name[n] = '\0';
        if (!slash) return need(method, "GET", http, why, why_len) ? -1 : specimen_show(c, name, out, http, why, why_len);
        if (!strcmp(slash, "/retire"))
            return need(method, "POST", http, why, why_len) ? -1
                                                             : specimen_retire(c, name, body, out, http, why, why_len);
        return fail(http, 404, why, why_len, "no route %s", path);
    }
    if (!strcmp(path, "/campaign/phase"))
        return need(method, "GET", http, why, why_len) ? -1 : phase_data(c, out, http, why, why_len);
    if (!strcmp(path, "/plan")) return need(method, "GET", http, why, why_len) ? -1 : plan_list(c, out, http, why, why_len);
    if (!strncmp(path, "/plan/", 6)) {
        int64_t pid = 0;
        const char *pverb = "";
        if (queue_path(path + 6, &pid, &pverb, http, why, why_len)) return -1;
        if (strcmp(pverb, "approve")) return fail(http, 404, why, why_len, "no route %s (a proposal has: approve)", path);
        return need(method, "POST", http, why, why_len) ? -1 : plan_approve(c, pid, body, out, http, why, why_len);
    }
    if (!strcmp(path, "/queue")) {
        if (!post) return campaign_queue_list(c->q, out, http, why, why_len);
        int rc = campaign_queue_add(c->q, body, out, http, why, why_len);
        if (rc == 0) *http = 201;
        return rc;
    }
    if (!strcmp(path, "/queue/start") || !strcmp(path, "/queue/stop"))
        return need(method, "POST", http, why, why_len)
                   ? -1
                   : campaign_queue_set_running(c->q, !strcmp(path, "/queue/start"), out, http, why, why_len);
    int64_t id = 0;
    const char *verb = "";
    if (queue_path(path + 7, &id, &verb, http, why, why_len)) return -1;
    if (!*verb) return need(method, "GET", http, why, why_len) ? -1 : campaign_queue_show(c->q, id, out, http, why, why_len);
    if (need(method, "POST", http, why, why_len)) return -1;
    if (!strcmp(verb, "remove")) return campaign_queue_remove(c->q, id, out, http, why, why_len);
    if (!strcmp(verb, "move")) return campaign_queue_move(c->q, id, body, out, http, why, why_len);
    if (!strcmp(verb, "confirm")) return campaign_queue_confirm(c->q, id, body, out, http, why, why_len);
    return fail(http, 404, why, why_len, "no route %s (a queue item has: remove, move, confirm)", path);
}
