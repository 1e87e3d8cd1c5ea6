/* store_sql.c: the store's SQL plumbing (see store_sql.h): failing with a reason, preparing,
 * binding and reading columns under one NULL convention, one-value lookups by id, the readers'
 * growing row arrays, transactions, and the entry-point value checks. Nothing here knows a
 * table. */
#include "store_sql.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

store_err store_fail(char *why, size_t why_len, store_err err, const char *fmt, ...)
{
    if (why && why_len > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(why, why_len, fmt, ap);
        va_end(ap);
    }
    return err;
}

store_err store_err_of_rc(int rc)
{
    switch (rc & 0xff) {
    case SQLITE_OK:
    case SQLITE_ROW:
    case SQLITE_DONE:
        return STORE_OK;
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
        return STORE_E_BUSY;
    case SQLITE_NOMEM:
        return STORE_E_NOMEM;
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
        return STORE_E_CORRUPT;
    case SQLITE_CONSTRAINT:
    case SQLITE_MISMATCH:
        return STORE_E_CONSTRAINT;
    case SQLITE_RANGE:
    case SQLITE_TOOBIG:
        return STORE_E_INVALID;
    default: /* IOERR, FULL, CANTOPEN, READONLY, PERM, ERROR, ... */
        return STORE_E_IO;
    }
}

store_err store_sql_fail(sqlite3 *db, int rc, char *why, size_t why_len, const char *what)
{
    const char *msg = db ? sqlite3_errmsg(db) : sqlite3_errstr(rc);
    return store_fail(why, why_len, store_err_of_rc(rc) == STORE_OK ? STORE_E_IO : store_err_of_rc(rc),
                      "%s: %s", what, msg);
}

store_err store_prepare(store *st, const char *sql, sqlite3_stmt **stmt, char *why, size_t why_len)
{
    int rc = sqlite3_prepare_v2(st->db, sql, -1, stmt, NULL);
    if (rc != SQLITE_OK) {
        *stmt = NULL;
        return store_sql_fail(st->db, rc, why, why_len, "preparing a statement");
    }
    return STORE_OK;
}

store_err store_lookup_id(store *st, const char *sql, int64_t id, const char *noun, const char *what, int64_t *out,
                          char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, sql, &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        if (out)
            *out = sqlite3_column_int64(s, 0);
    } else if (rc == SQLITE_DONE) {
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "%s %lld does not exist", noun, (long long)id);
    } else {
        e = store_sql_fail(st->db, rc, why, why_len, what);
    }
    sqlite3_finalize(s);
    return e;
}

void *store_grow(void *v, size_t len, size_t *cap, size_t elem_size, size_t first)
{
    if (len < *cap)
        return v;
    size_t ncap = *cap ? 2 * *cap : first;
    if (ncap < *cap || ncap > SIZE_MAX / elem_size)
        return NULL;
    void *nv = realloc(v, ncap * elem_size);
    if (nv)
        *cap = ncap;
    return nv;
}

store_err store_exec(store *st, const char *sql, char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, sql, &s, why, why_len);
    if (e != STORE_OK)
        return e;
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW)
        ;
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, sql);
    sqlite3_finalize(s);
    return e;
}

store_err store_exec_script(sqlite3 *db, const char *script, char *why, size_t why_len)
{
    const char *p = script;
    while (p && *p) {
        sqlite3_stmt *s = NULL;
        const char *tail = NULL;
        int rc = sqlite3_prepare_v2(db, p, -1, &s, &tail);
        if (rc != SQLITE_OK)
            return store_sql_fail(db, rc, why, why_len, "schema statement");
        if (!s) /* only whitespace or comments left */
            break;
        while ((rc = sqlite3_step(s)) == SQLITE_ROW)
            ;
        if (rc != SQLITE_DONE) {
            store_err e = store_sql_fail(db, rc, why, why_len, "schema statement");
            sqlite3_finalize(s);
            return e;
        }
        sqlite3_finalize(s);
        p = tail;
    }
    return STORE_OK;
}

store_err store_begin(store *st, char *why, size_t why_len)
{
    return store_exec(st, "BEGIN IMMEDIATE", why, why_len);
}

store_err store_commit(store *st, char *why, size_t why_len)
{
    return store_exec(st, "COMMIT", why, why_len);
}

void store_rollback(store *st)
{
    if (!sqlite3_get_autocommit(st->db))
        sqlite3_exec(st->db, "ROLLBACK", NULL, NULL, NULL);
}

store_err store_check_writable(store *st, char *why, size_t why_len)
{
    if (st->read_only)
        return store_fail(why, why_len, STORE_E_STATE, "the store was opened read-only");
    return STORE_OK;
}

int store_bind_real(sqlite3_stmt *s, int i, double v)
{
    return isnan(v) ? sqlite3_bind_null(s, i) : sqlite3_bind_double(s, i, v);
}

int store_bind_text(sqlite3_stmt *s, int i, const char *t)
{
    return (!t || !*t) ? sqlite3_bind_null(s, i) : sqlite3_bind_text(s, i, t, -1, SQLITE_TRANSIENT);
}

int store_bind_id(sqlite3_stmt *s, int i, int64_t id)
{
    return id == 0 ? sqlite3_bind_null(s, i) : sqlite3_bind_int64(s, i, id);
}

double store_col_real(sqlite3_stmt *s, int i)
{
    return sqlite3_column_type(s, i) == SQLITE_NULL ? NAN : sqlite3_column_double(s, i);
}

int64_t store_col_id(sqlite3_stmt *s, int i)
{
    return sqlite3_column_type(s, i) == SQLITE_NULL ? 0 : sqlite3_column_int64(s, i);
}

void store_col_text(sqlite3_stmt *s, int i, char *out, size_t out_len)
{
    const unsigned char *t = sqlite3_column_text(s, i);
    if (out_len == 0)
        return;
    out[0] = '\0';
    if (!t)
        return;
    size_t n = (size_t)sqlite3_column_bytes(s, i);
    if (n >= out_len)
        n = out_len - 1;
    memcpy(out, t, n);
    out[n] = '\0';
}

char *store_col_strdup(sqlite3_stmt *s, int i)
{
    const unsigned char *t = sqlite3_column_text(s, i);
    if (!t)
        return NULL;
    size_t n = (size_t)sqlite3_column_bytes(s, i);
    char *c = malloc(n + 1);
    if (c) {
        memcpy(c, t, n);
        c[n] = '\0';
    }
    return c;
}

store_err store_need_finite(double v, const char *field, char *why, size_t why_len)
{
    if (!isfinite(v))
        return store_fail(why, why_len, STORE_E_INVALID, "%s must be a finite number (got %g)", field, v);
    return STORE_OK;
}

store_err store_need_positive(double v, const char *field, char *why, size_t why_len)
{
    if (!isfinite(v) || v <= 0.0)
        return store_fail(why, why_len, STORE_E_INVALID, "%s must be a finite number > 0 (got %g)", field, v);
    return STORE_OK;
}

store_err store_need_not_inf(double v, const char *field, char *why, size_t why_len)
{
    if (isinf(v))
        return store_fail(why, why_len, STORE_E_INVALID, "%s must be finite or missing (NaN), not %g", field, v);
    return STORE_OK;
}

store_err store_need_fits(const char *t, size_t cap, const char *field, char *why, size_t why_len)
{
    if (t && strlen(t) >= cap)
        return store_fail(why, why_len, STORE_E_INVALID, "%s is %zu bytes long; at most %zu fit", field, strlen(t),
                          cap - 1);
    return STORE_OK;
}

store_err store_need_json(const char *t, const char *field, char *why, size_t why_len)
{
    if (!t)
        return STORE_OK;
    json_error_t err;
    json_t *j = json_loads(t, JSON_DECODE_ANY, &err);
    if (!j)
        return store_fail(why, why_len, STORE_E_INVALID, "%s is not valid JSON: line %d column %d: %s", field,
                          err.line, err.column, err.text);
    json_decref(j);
    return STORE_OK;
}

store_err store_pragma_int(store *st, const char *sql, int *out, char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, sql, &s, why, why_len);
    if (e != STORE_OK)
        return e;
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        *out = sqlite3_column_int(s, 0);
        e = STORE_OK;
    } else {
        e = store_sql_fail(st->db, rc == SQLITE_DONE ? SQLITE_ERROR : rc, why, why_len, sql);
    }
    sqlite3_finalize(s);
    return e;
}
