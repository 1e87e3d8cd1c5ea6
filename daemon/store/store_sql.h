/* store_sql.h: the store's SQL helpers (store_sql.c), which every record file of the room uses to
 * prepare, bind, read and fail the same way, and the handle's layout they work on. Nobody outside
 * daemon/store/ sees it: the room's face is store.h.
 *
 * Conventions the helpers carry:
 *   - a double NaN binds as SQL NULL and a NULL column reads back as NaN;
 *   - an id 0 binds as NULL and a NULL id reads back as 0;
 *   - a NULL or empty optional text binds as NULL and reads back as "";
 *   - every SQLite failure becomes a store_err plus "what: SQLite's message" in why. */
#ifndef RIBBON_STORE_SQL_H
#define RIBBON_STORE_SQL_H

#include <sqlite3.h>

#include "store.h"

#ifndef RIBBON_VERSION
#define RIBBON_VERSION "unknown"
#endif

struct store {
    sqlite3 *db;
    int version;    /* schema version of the file after open */
    bool read_only;
};

/* Write a reason and return err (why may be NULL). */
store_err store_fail(char *why, size_t why_len, store_err err, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
/* Map an SQLite result code (extended or primary) to a store_err. */
store_err store_err_of_rc(int rc);
/* Fail with "what: <SQLite's message for db>" and the mapped code. */
store_err store_sql_fail(sqlite3 *db, int rc, char *why, size_t why_len, const char *what);

store_err store_prepare(store *st, const char *sql, sqlite3_stmt **stmt, char *why, size_t why_len);
/* The first column of the first row of sql (a PRAGMA or a count) as an int. */
store_err store_pragma_int(store *st, const char *sql, int *out, char *why, size_t why_len);
/* One value looked up by one id: runs sql (one statement, ?1 = id). A row puts its first column in
 * *out (skipped when out is NULL: an existence check); no row is STORE_E_NOTFOUND "<noun> <id>
 * does not exist"; an SQLite failure is "<what>: <SQLite's message>". */
store_err store_lookup_id(store *st, const char *sql, int64_t id, const char *noun, const char *what, int64_t *out,
                          char *why, size_t why_len);
/* Run one statement that returns no rows (BEGIN, COMMIT, UPDATE without results...). */
store_err store_exec(store *st, const char *sql, char *why, size_t why_len);
/* Run every statement of a constant script (migrations); stops at the first failure. */
store_err store_exec_script(sqlite3 *db, const char *script, char *why, size_t why_len);

/* BEGIN IMMEDIATE (take the write lock now, so busy_timeout applies here and not at COMMIT). */
store_err store_begin(store *st, char *why, size_t why_len);
store_err store_commit(store *st, char *why, size_t why_len);
void store_rollback(store *st); /* best effort; no-op outside a transaction */
/* Refuse writes on a read-only handle. */
store_err store_check_writable(store *st, char *why, size_t why_len);

int store_bind_real(sqlite3_stmt *s, int i, double v);      /* NaN -> NULL */
int store_bind_text(sqlite3_stmt *s, int i, const char *t); /* NULL or "" -> NULL; transient copy */
int store_bind_id(sqlite3_stmt *s, int i, int64_t id);      /* 0 -> NULL */
double store_col_real(sqlite3_stmt *s, int i);              /* NULL -> NaN */
int64_t store_col_id(sqlite3_stmt *s, int i);               /* NULL -> 0 */
void store_col_text(sqlite3_stmt *s, int i, char *out, size_t out_len); /* NULL -> "" */
char *store_col_strdup(sqlite3_stmt *s, int i);             /* NULL -> NULL; malloc'ed */

/* Room for element len of a growing array v of *cap elements of elem_size bytes (the readers'
 * row buffers): v itself while len < *cap, else v reallocated to twice the capacity (first
 * elements the first time) with *cap updated. NULL when out of memory; v is then unchanged and
 * still the caller's to free. */
void *store_grow(void *v, size_t len, size_t *cap, size_t elem_size, size_t first);

/* Value checks at the entry points; field names the value in the reason. */
store_err store_need_finite(double v, const char *field, char *why, size_t why_len);
store_err store_need_positive(double v, const char *field, char *why, size_t why_len);
/* NaN (missing) allowed, infinity refused. */
store_err store_need_not_inf(double v, const char *field, char *why, size_t why_len);
/* A text that must fit a read-back field of cap bytes (NUL included); NULL allowed. */
store_err store_need_fits(const char *t, size_t cap, const char *field, char *why, size_t why_len);
/* A JSON text that must parse (NULL allowed). */
store_err store_need_json(const char *t, const char *field, char *why, size_t why_len);

#endif
