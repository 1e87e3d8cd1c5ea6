/* store.c: opening and closing the store, and the schema with its migrations.
 *
 * The schema is an ordered list of migration steps, each a constant script that ends by setting
 * PRAGMA user_version to its own number. Opening runs, in order and each in its own
 * transaction, every step above the file's version; a failing step rolls back and leaves the
 * file at the version before it. A file whose version is above STORE_SCHEMA_VERSION was written
 * by a newer program and is refused before anything is written to it. The file carries
 * application_id 'RIBB' so that an unrelated SQLite database is refused, not "migrated".
 *
 * Step 1 is the base schema as first shipped; it must never change (files in the field are at
 * version 1). Change the schema by appending a step. tests/daemon/test_store.c keeps its own
 * copy of the v1 script to check that migrating a real version 1 file preserves its data.
 *
 * Layout (units in the column names; NULL = missing, never NaN; times ISO-8601 UTC text):
 *   specimens        id | name UNIQUE | length_m width_m thickness_m | youngs_modulus_pa
 *                    density_kg_m3 material | crease_angle_left_deg crease_angle_right_deg
 *                    fold_position crease_orientation | trials_count
 *   trials           id | mode status state reason | config_text calibration_json |
 *                    specimen_id -> specimens | source_trial_id -> trials | video_path |
 *                    created_at started_at ended_at | snapped snap_dw_measured regime_measured |
 *                    software_version | samples_count (v3, kept by the sample writer)
 *   samples          (trial_id -> trials, seq) | t_s kind frame | compress_mm shear_mm |
 *                    dl dw dz a quality reason                              (WITHOUT ROWID)
 *   events           id | trial_id -> trials | t_s wall_time state kind message
 *   predictions      id | trial_id -> trials | scene_hash | snapped snap_dw regime peak_abs_a |
 *                    nodes dt adaptive imperfection | est_error wall_s | software_version
 *                    solver_json created_at
 *   prediction_curve (prediction_id -> predictions, seq) | t_s dw dz a       (WITHOUT ROWID)
 *   ladder (v2)      (scene_hash, nodes, dt, adaptive) | snap_dw est_error wall_s */
#include "store_int.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#define STORE_APPLICATION_ID 0x52494242 /* "RIBB" */

static const char schema_v1[] =
    "CREATE TABLE specimens ("
    " id INTEGER PRIMARY KEY,"
    " name TEXT NOT NULL UNIQUE CHECK (length(name) > 0),"
    " length_m REAL NOT NULL, width_m REAL NOT NULL, thickness_m REAL NOT NULL,"
    " youngs_modulus_pa REAL, density_kg_m3 REAL, material TEXT,"
    " crease_angle_left_deg REAL, crease_angle_right_deg REAL,"
    " fold_position REAL, crease_orientation TEXT,"
    " trials_count INTEGER NOT NULL DEFAULT 0);"
    "CREATE TABLE trials ("
    " id INTEGER PRIMARY KEY,"
    " mode TEXT NOT NULL CHECK (mode IN ('rig','mock','replay')),"
    " status TEXT NOT NULL DEFAULT 'created'"
    "  CHECK (status IN ('created','running','done','failed','aborted','interrupted')),"
    " state TEXT, reason TEXT,"
    " config_text TEXT NOT NULL, calibration_json TEXT,"
    " specimen_id INTEGER REFERENCES specimens(id),"
    " source_trial_id INTEGER REFERENCES trials(id),"
    " video_path TEXT,"
    " created_at TEXT NOT NULL, started_at TEXT, ended_at TEXT,"
    " snapped INTEGER CHECK (snapped IN (0,1)),"
    " snap_dw_measured REAL,"
    " regime_measured TEXT CHECK (regime_measured IN ('symmetric','asymmetric','no snap')),"
    " software_version TEXT NOT NULL);"
    "CREATE TABLE samples ("
    " trial_id INTEGER NOT NULL REFERENCES trials(id) ON DELETE CASCADE,"
    " seq INTEGER NOT NULL,"
    " t_s REAL NOT NULL,"
    " kind INTEGER NOT NULL CHECK (kind IN (0,1)),"
    " frame INTEGER,"
    " compress_mm REAL, shear_mm REAL, dl REAL, dw REAL, dz REAL, a REAL, quality REAL,"
    " reason TEXT,"
    " PRIMARY KEY (trial_id, seq)) WITHOUT ROWID;"
    "CREATE TABLE events ("
    " id INTEGER PRIMARY KEY,"
    " trial_id INTEGER NOT NULL REFERENCES trials(id) ON DELETE CASCADE,"
    " t_s REAL, wall_time TEXT NOT NULL, state TEXT,"
    " kind TEXT NOT NULL CHECK (kind IN ('state','info','warning','fault')),"
    " message TEXT NOT NULL);"
    "CREATE INDEX events_trial ON events(trial_id);"
    "CREATE TABLE predictions ("
    " id INTEGER PRIMARY KEY,"
    " trial_id INTEGER REFERENCES trials(id) ON DELETE SET NULL,"
    " scene_hash TEXT NOT NULL,"
    " snapped INTEGER NOT NULL CHECK (snapped IN (0,1)),"
    " snap_dw REAL,"
    " regime TEXT CHECK (regime IN ('symmetric','asymmetric','no snap')),"
    " peak_abs_a REAL,"
    " nodes INTEGER NOT NULL, dt REAL NOT NULL, adaptive INTEGER NOT NULL CHECK (adaptive IN (0,1)),"
    " imperfection REAL NOT NULL, est_error REAL, wall_s REAL NOT NULL,"
    " software_version TEXT NOT NULL, solver_json TEXT,"
    " created_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')));"
    "CREATE TABLE prediction_curve ("
    " prediction_id INTEGER NOT NULL REFERENCES predictions(id) ON DELETE CASCADE,"
    " seq INTEGER NOT NULL,"
    " t_s REAL NOT NULL, dw REAL NOT NULL, dz REAL, a REAL,"
    " PRIMARY KEY (prediction_id, seq)) WITHOUT ROWID;"
    "PRAGMA application_id = 1380532802;" /* STORE_APPLICATION_ID */
    "PRAGMA user_version = 1;";

/* v2: the error-against-run-time ladder cached per scene hash, and the indexes the JSON views
 * and the start-up scan use (latest prediction of a trial, trials by status). */
static const char schema_v2[] =
    "CREATE TABLE ladder ("
    " scene_hash TEXT NOT NULL,"
    " nodes INTEGER NOT NULL, dt REAL NOT NULL, adaptive INTEGER NOT NULL CHECK (adaptive IN (0,1)),"
    " snap_dw REAL, est_error REAL, wall_s REAL NOT NULL,"
    " PRIMARY KEY (scene_hash, nodes, dt, adaptive)) WITHOUT ROWID;"
    "CREATE INDEX predictions_trial ON predictions(trial_id);"
    "CREATE INDEX trials_status ON trials(status);"
    "PRAGMA user_version = 2;";

/* v3: each trial's sample count kept in the trial row, updated in the writer's own commit, so
 * listing trials does not count every sample of every trial (GET /trials on a year of trials).
 * Existing files get it back-filled from their samples. */
static const char schema_v3[] =
    "ALTER TABLE trials ADD COLUMN samples_count INTEGER NOT NULL DEFAULT 0;"
    "UPDATE trials SET samples_count = (SELECT count(*) FROM samples WHERE samples.trial_id = trials.id);"
    "PRAGMA user_version = 3;";

typedef struct store_migration {
    int version;      /* user_version after the step */
    const char *what; /* for reasons */
    const char *sql;
} store_migration;

static const store_migration migrations[] = {
    {1, "base schema", schema_v1},
    {2, "ladder cache and indexes", schema_v2},
    {3, "sample count per trial", schema_v3},
};
#define N_MIGRATIONS (sizeof migrations / sizeof migrations[0])
_Static_assert(sizeof migrations / sizeof migrations[0] == STORE_SCHEMA_VERSION,
               "one migration step per schema version");

store_open_params store_open_params_default(void)
{
    return (store_open_params){.busy_timeout_ms = 5000, .read_only = false};
}

static store_err pragma_int(store *st, const char *sql, int *out, char *why, size_t why_len)
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

static store_err migrate(store *st, const char *path, char *why, size_t why_len)
{
    char sub[384];
    for (size_t i = 0; i < N_MIGRATIONS; i++) {
        const store_migration *m = &migrations[i];
        if (m->version <= st->version)
            continue;
        store_err e = store_begin(st, sub, sizeof sub);
        if (e != STORE_OK)
            return store_fail(why, why_len, e, "%s: migrating to schema version %d: %s", path, m->version, sub);
        /* Another process may have migrated while we waited for the lock. */
        int now = 0;
        e = pragma_int(st, "PRAGMA user_version", &now, sub, sizeof sub);
        if (e == STORE_OK && now >= m->version) {
            st->version = now;
            e = store_commit(st, sub, sizeof sub);
            if (e != STORE_OK)
                return store_fail(why, why_len, e, "%s: %s", path, sub);
            continue;
        }
        if (e == STORE_OK)
            e = store_exec_script(st->db, m->sql, sub, sizeof sub);
        if (e == STORE_OK) {
            e = pragma_int(st, "PRAGMA user_version", &now, sub, sizeof sub);
            if (e == STORE_OK && now != m->version)
                e = store_fail(sub, sizeof sub, STORE_E_VERSION, "the step left user_version at %d", now);
        }
        if (e == STORE_OK)
            e = store_commit(st, sub, sizeof sub);
        if (e != STORE_OK) {
            store_rollback(st);
            return store_fail(why, why_len, STORE_E_VERSION,
                              "%s: migrating from schema version %d to %d (%s) failed, the file is left at "
                              "version %d: %s",
                              path, st->version, m->version, m->what, st->version, sub);
        }
        st->version = m->version;
    }
    return STORE_OK;
}

/* Is this a file we may migrate? A fresh file has version 0 and no tables. */
static store_err check_identity(store *st, const char *path, char *why, size_t why_len)
{
    char sub[256];
    int version = 0, app = 0, tables = 0;
    store_err e = pragma_int(st, "PRAGMA user_version", &version, sub, sizeof sub);
    if (e == STORE_OK)
        e = pragma_int(st, "PRAGMA application_id", &app, sub, sizeof sub);
    if (e == STORE_OK)
        e = pragma_int(st, "SELECT count(*) FROM sqlite_master", &tables, sub, sizeof sub);
    if (e == STORE_E_CORRUPT)
        return store_fail(why, why_len, e, "%s is not an SQLite database (or it is corrupt): %s", path, sub);
    if (e != STORE_OK)
        return store_fail(why, why_len, e, "%s: reading the schema version: %s", path, sub);
    if (version > STORE_SCHEMA_VERSION)
        return store_fail(why, why_len, STORE_E_VERSION,
                          "%s has schema version %d, newer than this program (ribbon rig %s) knows (%d): "
                          "use a newer program; the file was not changed",
                          path, version, RIBBON_VERSION, STORE_SCHEMA_VERSION);
    if ((version > 0 || tables > 0 || app != 0) && app != STORE_APPLICATION_ID)
        return store_fail(why, why_len, STORE_E_CORRUPT,
                          "%s is an SQLite database but not a ribbon rig store (application_id %d, %d "
                          "tables); refusing to touch it",
                          path, app, tables);
    st->version = version;
    return STORE_OK;
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
    int rc = sqlite3_open_v2(path, &st->db, flags, NULL);
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
    e = check_identity(st, path, why, why_len);
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
            e = migrate(st, path, why, why_len);
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
