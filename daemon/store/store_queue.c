/* store_queue.c: the campaign's queue (issue 35): its items and its one state row.
 *
 * Invariants the schema keeps (v8): an item is queued exactly when it has a position; the queued
 * positions are 1 .. n without gaps (every call that takes an item out of the order, or moves
 * one, renumbers inside its transaction); at most one item is running (a partial unique index).
 * End states are final. The state row says whether the queue runs and, when it does not, why:
 * the daemon never starts the queue by itself, and store_queue_recover (start-up) stops it. */
#include "store_sql.h"

#include <stdlib.h>
#include <string.h>

static const char *const kind_names[STORE_QUEUE_KIND_COUNT] = {"trial", "operator", "pause"};
static const char *const qstatus_names[STORE_QUEUE_STATUS_COUNT] = {"queued",  "running", "done",   "failed",
                                                                   "aborted", "skipped", "unknown"};

const char *store_queue_kind_name(store_queue_kind k)
{
    return (unsigned)k < STORE_QUEUE_KIND_COUNT ? kind_names[k] : NULL;
}

bool store_queue_kind_parse(const char *s, store_queue_kind *out)
{
    for (int k = 0; s && k < STORE_QUEUE_KIND_COUNT; k++)
        if (strcmp(s, kind_names[k]) == 0) {
            *out = (store_queue_kind)k;
            return true;
        }
    return false;
}

const char *store_queue_status_name(store_queue_status s)
{
    return (unsigned)s < STORE_QUEUE_STATUS_COUNT ? qstatus_names[s] : NULL;
}

static bool status_parse(const char *s, store_queue_status *out)
{
    for (int k = 0; s && k < STORE_QUEUE_STATUS_COUNT; k++)
        if (strcmp(s, qstatus_names[k]) == 0) {
            *out = (store_queue_status)k;
            return true;
        }
    return false;
}

store_queue_item store_queue_item_default(void)
{
    store_queue_item it;
    memset(&it, 0, sizeof it);
    strcpy(it.set_json, "[]");
    strcpy(it.fields_json, "[]");
    return it;
}

static store_err now_text(double wall_s, char *when, char *why, size_t why_len)
{
    if (!store_wall_format(wall_s, when, 32))
        return store_fail(why, why_len, STORE_E_INVALID, "wall time %g is not a valid time", wall_s);
    return STORE_OK;
}

/* One statement with up to three int64 and two text parameters; *changes gets the rows changed. */
static store_err run(store *st, const char *sql, int64_t a, int64_t b, const char *t3, const char *t4,
                     const char *what, int *changes, char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, sql, &s, why, why_len);
    if (e != STORE_OK)
        return e;
    int np = sqlite3_bind_parameter_count(s);
    if (np >= 1) sqlite3_bind_int64(s, 1, a);
    if (np >= 2) sqlite3_bind_int64(s, 2, b);
    if (np >= 3) store_bind_text(s, 3, t3);
    if (np >= 4) store_bind_text(s, 4, t4);
    int rc = sqlite3_step(s);
    if (rc != SQLITE_DONE && rc != SQLITE_ROW)
        e = store_sql_fail(st->db, rc, why, why_len, what);
    else if (changes)
        *changes = sqlite3_changes(st->db);
    sqlite3_finalize(s);
    return e;
}

/* Positions 1 .. n again, in the current order. */
static store_err renumber(store *st, char *why, size_t why_len)
{
    return run(st,
               "UPDATE queue_items SET position = (SELECT COUNT(*) FROM queue_items q"
               " WHERE q.position IS NOT NULL AND (q.position < queue_items.position OR"
               " (q.position = queue_items.position AND q.id <= queue_items.id)))"
               " WHERE position IS NOT NULL AND ?1 = ?1 AND ?2 = ?2",
               0, 0, NULL, NULL, "renumbering the queue", NULL, why, why_len);
}

store_err store_queue_add(store *st, const store_queue_item *it, double wall_s, int64_t *id, char *why,
                          size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e || (e = now_text(wall_s, when, why, why_len)))
        return e;
    if ((unsigned)it->kind >= STORE_QUEUE_KIND_COUNT)
        return store_fail(why, why_len, STORE_E_INVALID, "queue item kind %d unknown", (int)it->kind);
    if (it->kind == STORE_QUEUE_TRIAL && it->specimen_id <= 0)
        return store_fail(why, why_len, STORE_E_INVALID, "a trial in the queue names its specimen");
    if (it->kind == STORE_QUEUE_OPERATOR && !it->prompt[0])
        return store_fail(why, why_len, STORE_E_INVALID, "an operator step needs its prompt");
    if (!memchr(it->set_json, '\0', sizeof it->set_json) || !memchr(it->note, '\0', sizeof it->note) ||
        !memchr(it->prompt, '\0', sizeof it->prompt) || !memchr(it->fields_json, '\0', sizeof it->fields_json))
        return store_fail(why, why_len, STORE_E_INVALID, "queue item text field not NUL-terminated");
    if ((e = store_need_json(it->set_json[0] ? it->set_json : "[]", "queue item set_json", why, why_len)) ||
        (e = store_need_json(it->fields_json[0] ? it->fields_json : "[]", "queue item fields_json", why, why_len)))
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "INSERT INTO queue_items (kind, position, specimen_id, set_json, note, prompt, fields_json,"
                      " created_at) VALUES (?1, (SELECT COALESCE(MAX(position), 0) + 1 FROM queue_items),"
                      " ?2, ?3, ?4, ?5, ?6, ?7) RETURNING id",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_text(s, 1, kind_names[it->kind], -1, SQLITE_STATIC);
    store_bind_id(s, 2, it->specimen_id);
    sqlite3_bind_text(s, 3, it->set_json[0] ? it->set_json : "[]", -1, SQLITE_TRANSIENT);
    store_bind_text(s, 4, it->note);
    store_bind_text(s, 5, it->prompt);
    sqlite3_bind_text(s, 6, it->fields_json[0] ? it->fields_json : "[]", -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s, 7, when, -1, SQLITE_TRANSIENT);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        if (id)
            *id = sqlite3_column_int64(s, 0);
        rc = sqlite3_step(s);
    }
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "adding to the queue");
    sqlite3_finalize(s);
    return e;
}

#define ITEM_COLUMNS                                                                                        \
    "SELECT q.id, q.kind, q.status, q.position, q.specimen_id, s.name, q.set_json, q.note, q.prompt,"       \
    " q.fields_json, q.values_json, q.trial_id, q.reason, q.created_at, q.started_at, q.ended_at"           \
    " FROM queue_items q LEFT JOIN specimens s ON s.id = q.specimen_id "

static void read_row(sqlite3_stmt *s, store_queue_item *it)
{
    *it = store_queue_item_default();
    it->id = sqlite3_column_int64(s, 0);
    store_queue_kind k = STORE_QUEUE_PAUSE;
    store_queue_kind_parse((const char *)sqlite3_column_text(s, 1), &k);
    it->kind = k;
    store_queue_status st = STORE_QUEUE_UNKNOWN;
    status_parse((const char *)sqlite3_column_text(s, 2), &st);
    it->status = st;
    it->position = store_col_id(s, 3);
    it->specimen_id = store_col_id(s, 4);
    store_col_text(s, 5, it->specimen_name, sizeof it->specimen_name);
    store_col_text(s, 6, it->set_json, sizeof it->set_json);
    store_col_text(s, 7, it->note, sizeof it->note);
    store_col_text(s, 8, it->prompt, sizeof it->prompt);
    store_col_text(s, 9, it->fields_json, sizeof it->fields_json);
    store_col_text(s, 10, it->values_json, sizeof it->values_json);
    it->trial_id = store_col_id(s, 11);
    store_col_text(s, 12, it->reason, sizeof it->reason);
    store_col_text(s, 13, it->created_at, sizeof it->created_at);
    store_col_text(s, 14, it->started_at, sizeof it->started_at);
    store_col_text(s, 15, it->ended_at, sizeof it->ended_at);
}

static store_err read_one(store *st, const char *where, int64_t id, store_queue_item *out, const char *none,
                          char *why, size_t why_len)
{
    char sql[600];
    snprintf(sql, sizeof sql, "%s%s", ITEM_COLUMNS, where);
    sqlite3_stmt *s;
    store_err e = store_prepare(st, sql, &s, why, why_len);
    if (e != STORE_OK)
        return e;
    if (sqlite3_bind_parameter_count(s) >= 1)
        sqlite3_bind_int64(s, 1, id);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW)
        read_row(s, out);
    else if (rc == SQLITE_DONE)
        e = store_fail(why, why_len, STORE_E_NOTFOUND, none, (long long)id);
    else
        e = store_sql_fail(st->db, rc, why, why_len, "reading the queue");
    sqlite3_finalize(s);
    return e;
}

store_err store_queue_get(store *st, int64_t id, store_queue_item *out, char *why, size_t why_len)
{
    return read_one(st, "WHERE q.id = ?1", id, out, "no queue item %lld", why, why_len);
}

store_err store_queue_next(store *st, store_queue_item *out, char *why, size_t why_len)
{
    return read_one(st, "WHERE q.position IS NOT NULL ORDER BY q.position LIMIT 1", 0, out,
                    "the queue is empty%.0lld", why, why_len);
}

store_err store_queue_current(store *st, store_queue_item *out, char *why, size_t why_len)
{
    return read_one(st, "WHERE q.status = 'running'", 0, out, "no queue item is running%.0lld", why, why_len);
}

store_err store_queue_list(store *st, store_queue_item **out, size_t *n, char *why, size_t why_len)
{
    *out = NULL;
    *n = 0;
    sqlite3_stmt *s;
    store_err e = store_prepare(st,
                                ITEM_COLUMNS "ORDER BY CASE q.status WHEN 'running' THEN 0 WHEN 'queued' THEN 1"
                                             " ELSE 2 END, q.position, q.id DESC",
                                &s, why, why_len);
    if (e != STORE_OK)
        return e;
    store_queue_item *v = NULL;
    size_t cap = 0, k = 0;
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
        store_queue_item *g = store_grow(v, k + 1, &cap, sizeof *v, 8);
        if (!g) {
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory listing the queue");
            break;
        }
        v = g;
        read_row(s, &v[k++]);
    }
    if (e == STORE_OK && rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "listing the queue");
    sqlite3_finalize(s);
    if (e != STORE_OK) {
        free(v);
        return e;
    }
    *out = v;
    *n = k;
    return STORE_OK;
}

/* The item must be queued: a running item is named as such, an ended one with its end. */
static store_err need_queued(store *st, int64_t id, const char *verb, char *why, size_t why_len)
{
    store_queue_item it;
    store_err e = store_queue_get(st, id, &it, why, why_len);
    if (e != STORE_OK)
        return e;
    if (it.status == STORE_QUEUE_RUNNING)
        return store_fail(why, why_len, STORE_E_STATE,
                          "queue item %lld is running: it can't be %s (stop the queue; abort its trial or "
                          "confirm its step)",
                          (long long)id, verb);
    if (it.status != STORE_QUEUE_QUEUED)
        return store_fail(why, why_len, STORE_E_STATE, "queue item %lld has already ended (%s): it can't be %s",
                          (long long)id, qstatus_names[it.status], verb);
    return STORE_OK;
}

static store_err finish_tx(store *st, store_err e, char *why, size_t why_len)
{
    if (e == STORE_OK)
        e = store_commit(st, why, why_len);
    if (e != STORE_OK)
        store_rollback(st);
    return e;
}

store_err store_queue_remove(store *st, int64_t id, const char *reason, double wall_s, char *why, size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e || (e = now_text(wall_s, when, why, why_len)) || (e = store_begin(st, why, why_len)))
        return e;
    e = need_queued(st, id, "removed", why, why_len);
    if (e == STORE_OK)
        e = run(st,
                "UPDATE queue_items SET status = 'skipped', position = NULL, ended_at = ?3, reason = ?4"
                " WHERE id = ?1 AND status = 'queued' AND ?2 = ?2",
                id, 0, when, reason && *reason ? reason : "removed from the queue before it ran",
                "removing from the queue", NULL, why, why_len);
    if (e == STORE_OK)
        e = renumber(st, why, why_len);
    return finish_tx(st, e, why, why_len);
}

store_err store_queue_move(store *st, int64_t id, int64_t position, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e)
        return e;
    if (position < 1)
        return store_fail(why, why_len, STORE_E_INVALID, "queue position must be at least 1 (got %lld)",
                          (long long)position);
    if ((e = store_begin(st, why, why_len)))
        return e;
    e = need_queued(st, id, "moved", why, why_len);
    /* Shift the items between its old and new place by one toward the old, then put it in
     * (positions stay >= 1 throughout; renumber closes any gap a too large position left). */
    store_queue_item it;
    if (e == STORE_OK)
        e = store_queue_get(st, id, &it, why, why_len);
    if (e == STORE_OK && position > it.position)
        e = run(st,
                "UPDATE queue_items SET position = position - 1 WHERE position IS NOT NULL AND position > ?1"
                " AND position <= ?2",
                it.position, position, NULL, NULL, "moving in the queue", NULL, why, why_len);
    if (e == STORE_OK && position < it.position)
        e = run(st,
                "UPDATE queue_items SET position = position + 1 WHERE position IS NOT NULL AND position >= ?2"
                " AND position < ?1",
                it.position, position, NULL, NULL, "moving in the queue", NULL, why, why_len);
    if (e == STORE_OK)
        e = run(st, "UPDATE queue_items SET position = ?2 WHERE id = ?1", id, position, NULL, NULL,
                "moving in the queue", NULL, why, why_len);
    if (e == STORE_OK)
        e = renumber(st, why, why_len);
    return finish_tx(st, e, why, why_len);
}

store_err store_queue_item_begin(store *st, int64_t id, double wall_s, char *why, size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e || (e = now_text(wall_s, when, why, why_len)) || (e = store_begin(st, why, why_len)))
        return e;
    store_queue_item cur;
    if (store_queue_current(st, &cur, NULL, 0) == STORE_OK)
        e = store_fail(why, why_len, STORE_E_STATE, "queue item %lld is already running", (long long)cur.id);
    if (e == STORE_OK)
        e = need_queued(st, id, "started", why, why_len);
    if (e == STORE_OK)
        e = run(st,
                "UPDATE queue_items SET status = 'running', position = NULL, started_at = ?3"
                " WHERE id = ?1 AND ?2 = ?2",
                id, 0, when, NULL, "starting a queue item", NULL, why, why_len);
    if (e == STORE_OK)
        e = renumber(st, why, why_len);
    return finish_tx(st, e, why, why_len);
}

store_err store_queue_item_set_trial(store *st, int64_t id, int64_t trial_id, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e)
        return e;
    int ch = 0;
    e = run(st, "UPDATE queue_items SET trial_id = ?2 WHERE id = ?1 AND status = 'running'", id, trial_id, NULL,
            NULL, "naming a queue item's trial", &ch, why, why_len);
    if (e == STORE_OK && ch == 0)
        e = store_fail(why, why_len, STORE_E_STATE, "queue item %lld is not running", (long long)id);
    return e;
}

/* The item's end (no transaction of its own); when is its time as text. */
static store_err item_end(store *st, int64_t id, store_queue_status status, const char *reason,
                          const char *values_json, const char *when, char *why, size_t why_len)
{
    store_err e = STORE_OK;
    if (status < STORE_QUEUE_DONE || status >= STORE_QUEUE_STATUS_COUNT || status == STORE_QUEUE_SKIPPED)
        return store_fail(why, why_len, STORE_E_INVALID, "a running item ends done, failed, aborted or unknown");
    if (values_json && (e = store_need_json(values_json, "queue item values", why, why_len)))
        return e;
    if (values_json && (e = store_need_fits(values_json, STORE_QUEUE_JSON_MAX, "queue item values", why, why_len)))
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "UPDATE queue_items SET status = ?2, reason = COALESCE(?3, reason), ended_at = ?4,"
                      " values_json = COALESCE(?5, values_json) WHERE id = ?1 AND status = 'running'",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    sqlite3_bind_text(s, 2, qstatus_names[status], -1, SQLITE_STATIC);
    store_bind_text(s, 3, reason);
    sqlite3_bind_text(s, 4, when, -1, SQLITE_TRANSIENT);
    store_bind_text(s, 5, values_json);
    int rc = sqlite3_step(s);
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "ending a queue item");
    else if (sqlite3_changes(st->db) == 0)
        e = store_fail(why, why_len, STORE_E_STATE, "queue item %lld is not running", (long long)id);
    sqlite3_finalize(s);
    return e;
}

store_err store_queue_item_end(store *st, int64_t id, store_queue_status status, const char *reason,
                               const char *values_json, double wall_s, char *why, size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e || (e = now_text(wall_s, when, why, why_len)))
        return e;
    return item_end(st, id, status, reason, values_json, when, why, why_len);
}

/* The queue's state row (no transaction of its own). */
static store_err state_set(store *st, bool running, const char *reason, const char *when, char *why, size_t why_len)
{
    if (!reason || !*reason)
        return store_fail(why, why_len, STORE_E_INVALID, "the queue's state needs a reason");
    int ch = 0;
    store_err e = run(st, "UPDATE queue_state SET running = ?2, reason = ?3, changed_at = ?4 WHERE id = ?1", 1,
                      running ? 1 : 0, reason, when, "setting the queue's state", &ch, why, why_len);
    if (e == STORE_OK && ch == 0)
        e = store_fail(why, why_len, STORE_E_CORRUPT, "the queue's state row is missing");
    return e;
}

store_err store_queue_item_end_stop(store *st, int64_t id, store_queue_status status, const char *reason,
                                    const char *values_json, const char *stop_reason, double wall_s, char *why,
                                    size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e || (e = now_text(wall_s, when, why, why_len)) || (e = store_begin(st, why, why_len)))
        return e;
    e = item_end(st, id, status, reason, values_json, when, why, why_len);
    if (e == STORE_OK && stop_reason)
        e = state_set(st, false, stop_reason, when, why, why_len);
    return finish_tx(st, e, why, why_len);
}

store_err store_queue_state_get(store *st, bool *running, char *reason, size_t reason_len, char *changed_at,
                                char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, "SELECT running, reason, changed_at FROM queue_state WHERE id = 1", &s, why,
                                why_len);
    if (e != STORE_OK)
        return e;
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        *running = sqlite3_column_int(s, 0) != 0;
        if (reason)
            store_col_text(s, 1, reason, reason_len);
        if (changed_at)
            store_col_text(s, 2, changed_at, 32);
    } else {
        e = rc == SQLITE_DONE ? store_fail(why, why_len, STORE_E_CORRUPT, "the queue's state row is missing")
                              : store_sql_fail(st->db, rc, why, why_len, "reading the queue's state");
    }
    sqlite3_finalize(s);
    return e;
}

store_err store_queue_state_set(store *st, bool running, const char *reason, double wall_s, char *why,
                                size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e || (e = now_text(wall_s, when, why, why_len)))
        return e;
    return state_set(st, running, reason, when, why, why_len);
}

store_err store_queue_recover(store *st, double wall_s, int *count, char *why, size_t why_len)
{
    char when[32];
    if (count)
        *count = 0;
    store_err e = store_check_writable(st, why, why_len);
    if (e || (e = now_text(wall_s, when, why, why_len)) || (e = store_begin(st, why, why_len)))
        return e;
    store_queue_item cur;
    int found = store_queue_current(st, &cur, NULL, 0) == STORE_OK;
    bool running = false;
    e = store_queue_state_get(st, &running, NULL, 0, NULL, why, why_len);
    if (e == STORE_OK && found)
        e = run(st,
                "UPDATE queue_items SET status = 'unknown', ended_at = ?3, reason = ?4"
                " WHERE id = ?1 AND status = 'running' AND ?2 = ?2",
                cur.id, 0, when,
                "found running when ribbond started (it stopped without ending this item: a crash or a kill); "
                "its end is unknown",
                "marking the running queue item unknown", NULL, why, why_len);
    if (e == STORE_OK && (found || running)) {
        char reason[300];
        if (found)
            snprintf(reason, sizeof reason,
                     "stopped at start-up: item %lld (%s) was found running (the daemon stopped without ending it) "
                     "and is now 'unknown'; a restart never resumes the queue: check the rig, then start it",
                     (long long)cur.id, kind_names[cur.kind]);
        else
            snprintf(reason, sizeof reason, "stopped at start-up: ribbond restarted while the queue ran; a restart "
                                            "never resumes the queue: start it again");
        e = run(st, "UPDATE queue_state SET running = 0, reason = ?3, changed_at = ?4 WHERE id = ?1 AND ?2 = ?2", 1, 0,
                reason, when, "stopping the queue at start-up", NULL, why, why_len);
    }
    e = finish_tx(st, e, why, why_len);
    if (e == STORE_OK && count)
        *count = found;
    return e;
}
