/* store_ladder.c: the error-against-run-time ladder, cached per scene hash. Computing a ladder
 * means running the simulator at several resolutions, far longer than one prediction, so it is
 * done once per scene and kept: before each trial the runner reads it and picks the cheapest
 * rung whose estimated error meets the target. A put replaces the whole ladder of its hash in
 * one transaction, so readers see the old ladder or the new one, never a mix. */
#include "store_sql.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static store_err check_hash(const char *h, char *why, size_t why_len)
{
    if (!h || !*h)
        return store_fail(why, why_len, STORE_E_INVALID, "ladder scene_hash is empty");
    return store_need_fits(h, sizeof((store_prediction *)0)->scene_hash, "ladder scene_hash", why, why_len);
}

static store_err check_rung(const store_ladder_rung *r, size_t i, char *why, size_t why_len)
{
    char sub[160];
    store_err e = STORE_OK;
    if (r->nodes < 2)
        e = store_fail(sub, sizeof sub, STORE_E_INVALID, "nodes must be >= 2 (got %d)", r->nodes);
    else if ((e = store_need_positive(r->dt, "dt", sub, sizeof sub)) ||
             (e = store_need_finite(r->wall_s, "wall_s", sub, sizeof sub)) ||
             (e = store_need_not_inf(r->snap_dw, "snap_dw", sub, sizeof sub)) ||
             (e = store_need_not_inf(r->est_error, "est_error", sub, sizeof sub)))
        ;
    else if (r->wall_s < 0.0 || r->est_error < 0.0)
        e = store_fail(sub, sizeof sub, STORE_E_INVALID, "wall_s and est_error must be >= 0");
    return e == STORE_OK ? e : store_fail(why, why_len, e, "ladder rung %zu: %s", i, sub);
}

store_err store_ladder_put(store *st, const char *scene_hash, const store_ladder_rung *rungs, size_t n, char *why,
                           size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e == STORE_OK)
        e = check_hash(scene_hash, why, why_len);
    if (e != STORE_OK)
        return e;
    if (n == 0 || !rungs)
        return store_fail(why, why_len, STORE_E_INVALID, "a ladder needs at least one rung");
    for (size_t i = 0; i < n; i++)
        if ((e = check_rung(&rungs[i], i, why, why_len)))
            return e;
    if ((e = store_begin(st, why, why_len)))
        return e;
    sqlite3_stmt *del = NULL, *ins = NULL;
    e = store_prepare(st, "DELETE FROM ladder WHERE scene_hash = ?1", &del, why, why_len);
    if (e == STORE_OK)
        e = store_prepare(st,
                          "INSERT INTO ladder (scene_hash, nodes, dt, adaptive, snap_dw, est_error, wall_s)"
                          " VALUES (?1,?2,?3,?4,?5,?6,?7)",
                          &ins, why, why_len);
    if (e == STORE_OK) {
        sqlite3_bind_text(del, 1, scene_hash, -1, SQLITE_TRANSIENT);
        int rc = sqlite3_step(del);
        if (rc != SQLITE_DONE)
            e = store_sql_fail(st->db, rc, why, why_len, "clearing the old ladder");
    }
    for (size_t i = 0; i < n && e == STORE_OK; i++) {
        const store_ladder_rung *r = &rungs[i];
        sqlite3_reset(ins);
        sqlite3_bind_text(ins, 1, scene_hash, -1, SQLITE_TRANSIENT);
        sqlite3_bind_int(ins, 2, r->nodes);
        sqlite3_bind_double(ins, 3, r->dt);
        sqlite3_bind_int(ins, 4, r->adaptive ? 1 : 0);
        store_bind_real(ins, 5, r->snap_dw);
        store_bind_real(ins, 6, r->est_error);
        sqlite3_bind_double(ins, 7, r->wall_s);
        int rc = sqlite3_step(ins);
        if (rc == SQLITE_CONSTRAINT_PRIMARYKEY)
            e = store_fail(why, why_len, STORE_E_INVALID, "ladder rung %zu repeats the resolution of an earlier rung",
                           i);
        else if (rc != SQLITE_DONE)
            e = store_sql_fail(st->db, rc, why, why_len, "saving a ladder rung");
    }
    sqlite3_finalize(del);
    sqlite3_finalize(ins);
    if (e == STORE_OK)
        e = store_commit(st, why, why_len);
    if (e != STORE_OK)
        store_rollback(st);
    return e;
}

store_err store_ladder_get(store *st, const char *scene_hash, store_ladder_rung **out, size_t *n, char *why,
                           size_t why_len)
{
    *out = NULL;
    *n = 0;
    store_err e = check_hash(scene_hash, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "SELECT nodes, dt, adaptive, snap_dw, est_error, wall_s FROM ladder WHERE scene_hash = ?1"
                      " ORDER BY wall_s, nodes, dt",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_text(s, 1, scene_hash, -1, SQLITE_TRANSIENT);
    store_ladder_rung *v = NULL;
    size_t len = 0, cap = 0;
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
        store_ladder_rung *nv = store_grow(v, len, &cap, sizeof *v, 8);
        if (!nv) {
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory reading a ladder");
            break;
        }
        v = nv;
        store_ladder_rung *r = &v[len++];
        r->nodes = sqlite3_column_int(s, 0);
        r->dt = store_col_real(s, 1);
        r->adaptive = sqlite3_column_int(s, 2) != 0;
        r->snap_dw = store_col_real(s, 3);
        r->est_error = store_col_real(s, 4);
        r->wall_s = store_col_real(s, 5);
    }
    if (e == STORE_OK && rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "reading a ladder");
    sqlite3_finalize(s);
    if (e == STORE_OK && len == 0)
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "no ladder cached for scene %s", scene_hash);
    if (e != STORE_OK) {
        free(v);
        return e;
    }
    *out = v;
    *n = len;
    return STORE_OK;
}
