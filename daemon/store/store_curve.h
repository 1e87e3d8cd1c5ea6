/* store_curve.h: private header of store_curve.c, the one query behind every curve the store
 * hands out (measured samples, predicted curves). */
#ifndef RIBBON_STORE_CURVE_H
#define RIBBON_STORE_CURVE_H

#include "store_sql.h"

/* Read a curve: count_sql gives the number of rows and rows_sql the rows as (t_s, dw, dz, a),
 * both with ?1 = id. out gets one block; rows beyond the count are dropped. */
store_err store_curve_query(store *st, const char *count_sql, const char *rows_sql, int64_t id, store_curve *out,
                            char *why, size_t why_len);

#endif
