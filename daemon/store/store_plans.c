/* store_plans.c: the planner's proposals (schema v9, issue 35 part D): each batch of next
 * specimens `ribbonctl plan` proposed, and the approval that turns one into a specimen, an
 * operator step and a trial in the queue. A new batch supersedes every proposal still waiting,
 * so "proposal N" always means what the operator saw last; approval is once and final. */
#include "store_sql.h"

#include <stdlib.h>
#include <string.h>

static const char *const names[STORE_PLAN_STATUS_COUNT] = {"proposed", "approved", "superseded"};

const char *store_plan_status_name(store_plan_status s)
{
    return (unsigned)s < STORE_PLAN_STATUS_COUNT ? names[s] : NULL;
}

static store_err step_done(store *st, sqlite3_stmt *s, const char *what, char *why, size_t why_len)
{
    int rc = sqlite3_step(s);
    store_err e = rc == SQLITE_DONE ? STORE_OK : store_sql_fail(st->db, rc, why, why_len, what);
    sqlite3_finalize(s);
    return e;
}

store_err store_plan_add_batch(store *st, store_plan_proposal *p, size_t n, double wall_s, char *why, size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e) return e;
    if (!store_wall_format(wall_s, when, sizeof when))
        return store_fail(why, why_len, STORE_E_INVALID, "wall time %g is not a valid time", wall_s);
    for (size_t k = 0; k < n; k++) {
        if (!(p[k].phi_deg > 0 && p[k].phi_deg < 180) || !(p[k].gamma > 0 && p[k].gamma < 0.5))
            return store_fail(why, why_len, STORE_E_INVALID, "proposal %zu: phi %g deg, Gamma %g out of range", k + 1,
                              p[k].phi_deg, p[k].gamma);
        if ((e = store_need_finite(p[k].sd_before, "sd_before", why, why_len)) ||
            (e = store_need_finite(p[k].predicted_gamma, "predicted_gamma", why, why_len)) ||
            (e = store_need_finite(p[k].offset_mean, "offset_mean", why, why_len)) ||
            (e = store_need_finite(p[k].offset_sd, "offset_sd", why, why_len)))
            return e;
    }
    if ((e = store_begin(st, why, why_len))) return e;
    sqlite3_stmt *s;
    int64_t batch = 1;
    e = store_prepare(st, "SELECT COALESCE(MAX(batch), 0) + 1 FROM plan_proposals", &s, why, why_len);
    if (!e) {
        if (sqlite3_step(s) == SQLITE_ROW) batch = sqlite3_column_int64(s, 0);
        sqlite3_finalize(s);
    }
    if (!e && !(e = store_prepare(st, "UPDATE plan_proposals SET status = 'superseded' WHERE status = 'proposed'", &s,
                                  why, why_len)))
        e = step_done(st, s, "superseding the last plan", why, why_len);
    for (size_t k = 0; k < n && !e; k++) {
        e = store_prepare(st,
                          "INSERT INTO plan_proposals (batch, phi_deg, gamma, sd_before, predicted_gamma, offset_mean,"
                          " offset_sd, calibrated, created_at) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9) RETURNING id",
                          &s, why, why_len);
        if (e) break;
        sqlite3_bind_int64(s, 1, batch);
        sqlite3_bind_double(s, 2, p[k].phi_deg);
        sqlite3_bind_double(s, 3, p[k].gamma);
        sqlite3_bind_double(s, 4, p[k].sd_before);
        sqlite3_bind_double(s, 5, p[k].predicted_gamma);
        sqlite3_bind_double(s, 6, p[k].offset_mean);
        sqlite3_bind_double(s, 7, p[k].offset_sd);
        sqlite3_bind_int(s, 8, p[k].calibrated ? 1 : 0);
        sqlite3_bind_text(s, 9, when, -1, SQLITE_TRANSIENT);
        int rc = sqlite3_step(s);
        if (rc == SQLITE_ROW) {
            p[k].id = sqlite3_column_int64(s, 0);
            p[k].batch = batch;
            p[k].status = STORE_PLAN_PROPOSED;
            rc = sqlite3_step(s);
        }
        if (rc != SQLITE_DONE) e = store_sql_fail(st->db, rc, why, why_len, "adding a proposal");
        sqlite3_finalize(s);
    }
    if (!e) e = store_commit(st, why, why_len);
    if (e) store_rollback(st);
    return e;
}

#define COLS                                                                                                         \
    "p.id, p.batch, p.phi_deg, p.gamma, p.sd_before, p.predicted_gamma, p.offset_mean, p.offset_sd, p.calibrated," \
    " p.status, p.specimen_id, p.operator_item_id, p.trial_item_id, s.name, p.created_at, p.approved_at"           \
    " FROM plan_proposals p LEFT JOIN specimens s ON s.id = p.specimen_id"

static void row(sqlite3_stmt *s, store_plan_proposal *o)
{
    memset(o, 0, sizeof *o);
    o->id = sqlite3_column_int64(s, 0);
    o->batch = sqlite3_column_int64(s, 1);
    o->phi_deg = sqlite3_column_double(s, 2);
    o->gamma = sqlite3_column_double(s, 3);
    o->sd_before = sqlite3_column_double(s, 4);
    o->predicted_gamma = sqlite3_column_double(s, 5);
    o->offset_mean = sqlite3_column_double(s, 6);
    o->offset_sd = sqlite3_column_double(s, 7);
    o->calibrated = sqlite3_column_int(s, 8);
    const char *t = (const char *)sqlite3_column_text(s, 9);
    for (int k = 0; t && k < STORE_PLAN_STATUS_COUNT; k++)
        if (!strcmp(t, names[k])) o->status = (store_plan_status)k;
    o->specimen_id = store_col_id(s, 10);
    o->operator_item_id = store_col_id(s, 11);
    o->trial_item_id = store_col_id(s, 12);
    store_col_text(s, 13, o->specimen_name, sizeof o->specimen_name);
    store_col_text(s, 14, o->created_at, sizeof o->created_at);
    store_col_text(s, 15, o->approved_at, sizeof o->approved_at);
}

store_err store_plan_get(store *st, int64_t id, store_plan_proposal *out, char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, "SELECT " COLS " WHERE p.id = ?1", &s, why, why_len);
    if (e) return e;
    sqlite3_bind_int64(s, 1, id);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) row(s, out);
    else if (rc == SQLITE_DONE) e = store_fail(why, why_len, STORE_E_NOTFOUND, "no proposal %lld", (long long)id);
    else e = store_sql_fail(st->db, rc, why, why_len, "reading a proposal");
    sqlite3_finalize(s);
    return e;
}

store_err store_plan_list(store *st, store_plan_proposal **out, size_t *n, char *why, size_t why_len)
{
    *out = NULL;
    *n = 0;
    sqlite3_stmt *s;
    store_err e = store_prepare(st, "SELECT " COLS " ORDER BY p.id DESC", &s, why, why_len);
    if (e) return e;
    size_t cap = 0;
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
        store_plan_proposal *g = store_grow(*out, *n, &cap, sizeof **out, 16);
        if (!g) {
            e = store_fail(why, why_len, STORE_E_NOMEM, "listing proposals: out of memory");
            break;
        }
        *out = g;
        row(s, &(*out)[(*n)++]);
    }
    if (!e && rc != SQLITE_DONE) e = store_sql_fail(st->db, rc, why, why_len, "listing proposals");
    sqlite3_finalize(s);
    if (e) {
        free(*out);
        *out = NULL;
        *n = 0;
    }
    return e;
}

store_err store_plan_approve(store *st, int64_t id, int64_t specimen_id, int64_t operator_item_id,
                             int64_t trial_item_id, double wall_s, char *why, size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e) return e;
    if (!store_wall_format(wall_s, when, sizeof when))
        return store_fail(why, why_len, STORE_E_INVALID, "wall time %g is not a valid time", wall_s);
    store_plan_proposal p;
    if ((e = store_plan_get(st, id, &p, why, why_len))) return e;
    if (p.status != STORE_PLAN_PROPOSED)
        return store_fail(why, why_len, STORE_E_STATE, "proposal %lld is %s: only a proposed one can be approved%s",
                          (long long)id, names[p.status],
                          p.status == STORE_PLAN_SUPERSEDED ? " (a newer plan replaced it: ribbonctl plan --list)" : "");
    sqlite3_stmt *s;
    if ((e = store_prepare(st,
                           "UPDATE plan_proposals SET status = 'approved', specimen_id = ?2, operator_item_id = ?3,"
                           " trial_item_id = ?4, approved_at = ?5 WHERE id = ?1 AND status = 'proposed'",
                           &s, why, why_len)))
        return e;
    sqlite3_bind_int64(s, 1, id);
    store_bind_id(s, 2, specimen_id);
    store_bind_id(s, 3, operator_item_id);
    store_bind_id(s, 4, trial_item_id);
    sqlite3_bind_text(s, 5, when, -1, SQLITE_TRANSIENT);
    if ((e = step_done(st, s, "approving a proposal", why, why_len))) return e;
    if (sqlite3_changes(st->db) == 1) return STORE_OK;
    /* Another writer (ribbonctl plan: a new batch) changed it since it was read above. */
    if (store_plan_get(st, id, &p, why, why_len) == STORE_OK && p.status != STORE_PLAN_PROPOSED)
        return store_fail(why, why_len, STORE_E_STATE, "proposal %lld became %s while it was being approved%s",
                          (long long)id, names[p.status],
                          p.status == STORE_PLAN_SUPERSEDED ? " (a newer plan replaced it: ribbonctl plan --list)" : "");
    return store_fail(why, why_len, STORE_E_STATE, "proposal %lld was not approved: it changed while it was being "
                      "approved (ribbonctl plan --list)", (long long)id);
}

/* One transaction, taken before anything is read (BEGIN IMMEDIATE): the proposal's state, the
 * specimen's name and the queue's end are then what the writes below see, and a failure at any
 * write rolls back the rows written before it. */
store_err store_plan_approve_new(store *st, int64_t id, const store_specimen *sp, const store_queue_item *op,
                                 const store_queue_item *trial, double wall_s, store_plan_approval *out,
                                 char *why, size_t why_len)
{
    store_plan_approval a = {0, 0, 0};
    store_err e = store_check_writable(st, why, why_len);
    if (e) return e;
    if (op->kind != STORE_QUEUE_OPERATOR || trial->kind != STORE_QUEUE_TRIAL)
        return store_fail(why, why_len, STORE_E_INVALID, "an approval queues an operator step, then a trial");
    store_queue_item *items = malloc(2 * sizeof *items);
    if (!items) return store_fail(why, why_len, STORE_E_NOMEM, "approving a proposal: out of memory");
    if ((e = store_begin(st, why, why_len))) {
        free(items);
        return e;
    }
    store_plan_proposal p;
    if (!(e = store_plan_get(st, id, &p, why, why_len)) && p.status != STORE_PLAN_PROPOSED)
        e = store_fail(why, why_len, STORE_E_STATE, "proposal %lld is %s: only a proposed one can be approved%s",
                       (long long)id, names[p.status],
                       p.status == STORE_PLAN_SUPERSEDED ? " (a newer plan replaced it: ribbonctl plan --list)" : "");
    if (!e) e = store_specimen_insert(st, sp, &a.specimen_id, why, why_len);
    if (!e) {
        items[0] = *op;
        items[1] = *trial;
        items[0].specimen_id = items[1].specimen_id = a.specimen_id;
        e = store_queue_add(st, &items[0], wall_s, &a.operator_item_id, why, why_len);
    }
    if (!e) e = store_queue_add(st, &items[1], wall_s, &a.trial_item_id, why, why_len);
    if (!e)
        e = store_plan_approve(st, id, a.specimen_id, a.operator_item_id, a.trial_item_id, wall_s, why, why_len);
    if (!e) e = store_commit(st, why, why_len);
    if (e) store_rollback(st);
    free(items);
    if (!e && out) *out = a;
    return e;
}
