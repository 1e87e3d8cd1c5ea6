/* store_schema.h: the store's schema as ordered migration steps, and the check that a file is a
 * ribbon store this program may migrate (store_schema.c). Used by store.c when opening. */
#ifndef RIBBON_STORE_SCHEMA_H
#define RIBBON_STORE_SCHEMA_H

#include <stddef.h>

#include "store_sql.h"

/* Is this a file we may migrate (application_id 'RIBB', or a fresh file with no tables; a
 * version no newer than STORE_SCHEMA_VERSION)? Sets st->version. */
store_err store_schema_check_identity(store *st, const char *path, char *why, size_t why_len);
/* Runs every step above st->version, each in its own transaction; a failing step rolls back and
 * leaves the file at the version before it. */
store_err store_schema_migrate(store *st, const char *path, char *why, size_t why_len);

#endif
