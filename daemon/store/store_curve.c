/* store_curve.c: curves as the store hands them out: four parallel arrays (t_s, dw, dz, a) in
 * one allocation, so a report takes a measured or predicted curve with one call and releases it
 * with one free. The query is counted first and the block sized once. */
#include "store_curve.h"

#include <stdlib.h>
#include <string.h>

void store_curve_free(store_curve *c)
{
    if (!c)
        return;
    free(c->t_s);
    memset(c, 0, sizeof *c);
}

store_err store_curve_query(store *st, const char *count_sql, const char *rows_sql, int64_t id, store_curve *out,
                            char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    int64_t count = 0; /* count(*): always one row */
    store_err e = store_lookup_id(st, count_sql, id, "record", "counting curve points", &count, why, why_len);
    if (e != STORE_OK || count <= 0)
        return e;
    size_t n = (size_t)count;
    double *block = malloc(4 * n * sizeof *block);
    if (!block)
        return store_fail(why, why_len, STORE_E_NOMEM, "out of memory for a curve of %zu points", n);
    store_curve c = {.n = 0, .t_s = block, .dw = block + n, .dz = block + 2 * n, .a = block + 3 * n};
    sqlite3_stmt *s;
    e = store_prepare(st, rows_sql, &s, why, why_len);
    if (e != STORE_OK) {
        free(block);
        return e;
    }
    sqlite3_bind_int64(s, 1, id);
    int rc = SQLITE_DONE;
    while (c.n < n && (rc = sqlite3_step(s)) == SQLITE_ROW) {
        c.t_s[c.n] = store_col_real(s, 0);
        c.dw[c.n] = store_col_real(s, 1);
        c.dz[c.n] = store_col_real(s, 2);
        c.a[c.n] = store_col_real(s, 3);
        c.n++;
    }
    if (c.n < n && rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "reading a curve");
    sqlite3_finalize(s);
    if (e != STORE_OK) {
        free(block);
        return e;
    }
    *out = c;
    return STORE_OK;
}
