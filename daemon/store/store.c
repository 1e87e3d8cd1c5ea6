/* store.c: opening and closing the store: the file's identity and schema (store_schema.c), its
 * pragmas (WAL, synchronous NORMAL, foreign keys), read-only opens; the wall clock the records
 * use. The public face of the room is store.h. */
#include "store_open_ro.h"
#include "store_schema.h"
#include "store_sql.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

store_open_params store_open_params_default(void)
{
    return (store_open_params){.busy_timeout_ms = 5000, .read_only = false};
}

static store_err set_pragmas(store *st, const char *path, char *why, size_t why_len)
{
    char sub[256];
    sqlite3_stmt *s;
    store_err e = store_prepare(st, "PRAGMA journal_mode=WAL", &s, sub, sizeof sub);
    if (e != STORE_OK)
        return store_fail(why, why_len, e, "%s: %s", path, sub);
    int rc = sqlite3_step(s);
    char mode[16] = "";
    if (rc == SQLITE_ROW)
        store_col_text(s, 0, mode, sizeof mode);
    else
        e = store_sql_fail(st->db, rc, sub, sizeof sub, "PRAGMA journal_mode=WAL");
    sqlite3_finalize(s);
    if (e != STORE_OK)
        return store_fail(why, why_len, e, "%s: %s", path, sub);
    if (strcmp(mode, "wal") != 0)
        return store_fail(why, why_len, STORE_E_IO,
                          "%s: could not switch to WAL journal mode (still '%s'); is it on a network file "
                          "system?",
                          path, mode);
    e = store_exec(st, "PRAGMA synchronous=NORMAL", sub, sizeof sub);
    if (e == STORE_OK)
        e = store_exec(st, "PRAGMA foreign_keys=ON", sub, sizeof sub);
    if (e != STORE_OK)
        return store_fail(why, why_len, e, "%s: %s", path, sub);
    return STORE_OK;
}

store_err store_open_ex(const char *path, const store_open_params *p, store **out, char *why, size_t why_len)
{
    *out = NULL;
    store_open_params def = store_open_params_default();
    if (!p)
        p = &def;
    if (!path || !*path)
        return store_fail(why, why_len, STORE_E_INVALID, "no database path given");
    if (p->busy_timeout_ms < 0)
        return store_fail(why, why_len, STORE_E_INVALID, "busy_timeout_ms must be >= 0 (got %d)",
                          p->busy_timeout_ms);
    /* Only a regular file is a store: /dev/full or a FIFO would be "opened", and SQLite would
       leave its -journal and -wal files beside it (issue 17, item 12). */
    struct stat sb;
    if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode))
        return store_fail(why, why_len, STORE_E_INVALID, "store %s is not a regular file (%s)", path,
                          S_ISDIR(sb.st_mode)    ? "a directory"
                          : S_ISCHR(sb.st_mode)  ? "a character device"
                          : S_ISBLK(sb.st_mode)  ? "a block device"
                          : S_ISFIFO(sb.st_mode) ? "a FIFO"
                                                 : "a socket or other special file");
    store *st = calloc(1, sizeof *st);
    if (!st)
        return store_fail(why, why_len, STORE_E_NOMEM, "out of memory opening %s", path);
    st->read_only = p->read_only;
    int flags = p->read_only ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE;
    /* Read-only: a WAL store in a directory this user cannot write (store_open_ro.h). */
    char target[2048];
    int uri = 0;
    if (p->read_only && store_open_ro_target(path, target, sizeof target, &uri, why, why_len) != 0) {
        store_close(st);
        return STORE_E_IO;
    }
    int rc = sqlite3_open_v2(p->read_only ? target : path, &st->db, flags | (uri ? SQLITE_OPEN_URI : 0), NULL);
    store_err e = STORE_OK;
    if (rc != SQLITE_OK) {
        e = store_fail(why, why_len, store_err_of_rc(rc) == STORE_OK ? STORE_E_IO : store_err_of_rc(rc),
                       "cannot open database %s: %s", path, st->db ? sqlite3_errmsg(st->db) : sqlite3_errstr(rc));
        store_close(st);
        return e;
    }
    sqlite3_extended_result_codes(st->db, 1);
    sqlite3_busy_timeout(st->db, p->busy_timeout_ms);
    /* SQLite opens a file it may not write read-only without a word; every write would then fail
       (ribbond started and answered each trial with 500). Refused here, at start-up. */
    if (!p->read_only && sqlite3_db_readonly(st->db, "main") == 1) {
        e = store_fail(why, why_len, STORE_E_IO,
                       "store %s can only be opened read-only (file or directory permissions, or a "
                       "read-only file system); a store must be writable",
                       path);
        store_close(st);
        return e;
    }
    e = store_schema_check_identity(st, path, why, why_len);
    if (e == STORE_OK && p->read_only) {
        if (st->version != STORE_SCHEMA_VERSION)
            e = store_fail(why, why_len, STORE_E_VERSION,
                           "%s has schema version %d; this program needs %d: open it read-write once to "
                           "migrate it",
                           path, st->version, STORE_SCHEMA_VERSION);
        else
            e = store_exec(st, "PRAGMA foreign_keys=ON", why, why_len);
    } else if (e == STORE_OK) {
        e = set_pragmas(st, path, why, why_len);
        if (e == STORE_OK)
            e = store_schema_migrate(st, path, why, why_len);
    }
    if (e != STORE_OK) {
        store_close(st);
        return e;
    }
    *out = st;
    return STORE_OK;
}

store_err store_open(const char *path, store **out, char *why, size_t why_len)
{
    return store_open_ex(path, NULL, out, why, why_len);
}

void store_close(store *st)
{
    if (!st)
        return;
    if (st->db)
        sqlite3_close_v2(st->db); /* every statement is finalized by its user; v2 copes if not */
    free(st);
}

int store_schema_version(store *st)
{
    return st->version;
}

struct sqlite3 *store_handle(store *st)
{
    return st->db;
}

double store_wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

bool store_wall_format(double wall_s, char *out, size_t out_len)
{
    if (out_len > 0)
        out[0] = '\0';
    /* Years 1970 to 9999 keep the text at its fixed width. */
    if (!isfinite(wall_s) || wall_s < 0.0 || wall_s >= 253402300800.0 || out_len < 25)
        return false;
    double whole = floor(wall_s);
    time_t t = (time_t)whole;
    int ms = (int)((wall_s - whole) * 1000.0);
    if (ms > 999)
        ms = 999;
    struct tm tm;
    if (!gmtime_r(&t, &tm))
        return false;
    char base[24];
    if (strftime(base, sizeof base, "%Y-%m-%dT%H:%M:%S", &tm) == 0)
        return false;
    snprintf(out, out_len, "%.19s.%03dZ", base, ms);
    return true;
}
