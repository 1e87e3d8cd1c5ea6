/* test_store.c: the SQLite store. Schema creation with WAL on; migration of a real version 1 file
 * (its DDL frozen below) to the current version with its data; refusal of newer, foreign and
 * non-database files; a failing migration step leaving the file as it was; every record
 * round-tripping; NaN and infinity refused with a reason and nothing written; the trial life
 * cycle; JSON keys with null for missing values; CSV rows; the batched writer's three commit
 * triggers; a disk-full fault (max_page_count) keeping the batch and recovering. Each test has
 * its own temporary directory. Crash safety is in test_store_crash.c. */
#include <dirent.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <cmocka.h>

#include <sqlite3.h>

#include "store.h"

#define NEAR(a, b, tol) assert_true(fabs((a) - (b)) <= (tol))
#define OK(call)                                                                                            \
    do {                                                                                                    \
        store_err e_ = (call);                                                                              \
        if (e_ != STORE_OK)                                                                                 \
            fail_msg("%s -> %s: %s", #call, store_err_message(e_), why);                                    \
    } while (0)

static char why[512];

/* ---- fixture: a temporary directory and a database path in it ---------------------------- */

typedef struct fixture {
    char dir[256];
    char db[320];
} fixture;

static void rm_tree(const char *path)
{
    DIR *d = opendir(path);
    if (d) {
        struct dirent *de;
        while ((de = readdir(d))) {
            if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0)
                continue;
            char sub[1024];
            snprintf(sub, sizeof sub, "%s/%s", path, de->d_name);
            rm_tree(sub);
        }
        closedir(d);
        rmdir(path);
    } else {
        unlink(path);
    }
}

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    const char *tmp = getenv("TMPDIR");
    snprintf(f->dir, sizeof f->dir, "%s/test_store.XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(f->dir))
        return -1;
    snprintf(f->db, sizeof f->db, "%s/ribbon.sqlite", f->dir);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    rm_tree(f->dir);
    free(f);
    return 0;
}

/* One integer from a query on a raw connection. */
static long long q_int(sqlite3 *db, const char *sql)
{
    sqlite3_stmt *s;
    assert_int_equal(sqlite3_prepare_v2(db, sql, -1, &s, NULL), SQLITE_OK);
    assert_int_equal(sqlite3_step(s), SQLITE_ROW);
    long long v = sqlite3_column_int64(s, 0);
    sqlite3_finalize(s);
    return v;
}

static void q_text(sqlite3 *db, const char *sql, char *out, size_t n)
{
    sqlite3_stmt *s;
    assert_int_equal(sqlite3_prepare_v2(db, sql, -1, &s, NULL), SQLITE_OK);
    assert_int_equal(sqlite3_step(s), SQLITE_ROW);
    snprintf(out, n, "%s", sqlite3_column_text(s, 0) ? (const char *)sqlite3_column_text(s, 0) : "(null)");
    sqlite3_finalize(s);
}

static void exec_raw(const char *path, const char *sql)
{
    sqlite3 *db;
    assert_int_equal(sqlite3_open(path, &db), SQLITE_OK);
    char *err = NULL;
    if (sqlite3_exec(db, sql, NULL, NULL, &err) != SQLITE_OK)
        fail_msg("raw SQL failed: %s", err);
    sqlite3_close(db);
}

static long long raw_int(const char *path, const char *sql)
{
    sqlite3 *db;
    assert_int_equal(sqlite3_open_v2(path, &db, SQLITE_OPEN_READONLY, NULL), SQLITE_OK);
    long long v = q_int(db, sql);
    sqlite3_close(db);
    return v;
}

static const double T0 = 1767225600.0; /* 2026-01-01T00:00:00Z */

static int64_t new_trial(store *st, store_mode mode)
{
    store_trial_def d = store_trial_def_default();
    d.mode = mode;
    d.config_text = "[rig]\nmode = mock\n";
    d.created_wall_s = T0;
    int64_t id = 0;
    OK(store_trial_create(st, &d, &id, why, sizeof why));
    assert_true(id > 0);
    return id;
}

/* ---- schema ------------------------------------------------------------------------------ */

static void test_create_schema_wal(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    assert_int_equal(store_schema_version(st), STORE_SCHEMA_VERSION);
    sqlite3 *db = store_handle(st);
    char mode[16];
    q_text(db, "PRAGMA journal_mode", mode, sizeof mode);
    assert_string_equal(mode, "wal");
    assert_int_equal(q_int(db, "PRAGMA foreign_keys"), 1);
    assert_int_equal(q_int(db, "PRAGMA synchronous"), 1); /* NORMAL */
    assert_int_equal(q_int(db, "PRAGMA user_version"), STORE_SCHEMA_VERSION);
    assert_int_equal(q_int(db, "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name IN"
                               " ('specimens','trials','samples','events','predictions','prediction_curve','ladder')"),
                     7);
    store_close(st);
    /* Reopening runs no migration and keeps the version. */
    OK(store_open(f->db, &st, why, sizeof why));
    assert_int_equal(store_schema_version(st), STORE_SCHEMA_VERSION);
    store_close(st);
}

/* The version 1 schema exactly as shipped: a frozen copy, so the v1 -> current path is tested
 * on what files in the field contain, even if store.c's copy were edited by mistake. */
static const char v1_ddl[] =
    "CREATE TABLE specimens (id INTEGER PRIMARY KEY, name TEXT NOT NULL UNIQUE CHECK (length(name) > 0),"
    " length_m REAL NOT NULL, width_m REAL NOT NULL, thickness_m REAL NOT NULL,"
    " youngs_modulus_pa REAL, density_kg_m3 REAL, material TEXT,"
    " crease_angle_left_deg REAL, crease_angle_right_deg REAL, fold_position REAL, crease_orientation TEXT,"
    " trials_count INTEGER NOT NULL DEFAULT 0);"
    "CREATE TABLE trials (id INTEGER PRIMARY KEY,"
    " mode TEXT NOT NULL CHECK (mode IN ('rig','mock','replay')),"
    " status TEXT NOT NULL DEFAULT 'created'"
    "  CHECK (status IN ('created','running','done','failed','aborted','interrupted')),"
    " state TEXT, reason TEXT, config_text TEXT NOT NULL, calibration_json TEXT,"
    " specimen_id INTEGER REFERENCES specimens(id), source_trial_id INTEGER REFERENCES trials(id),"
    " video_path TEXT, created_at TEXT NOT NULL, started_at TEXT, ended_at TEXT,"
    " snapped INTEGER CHECK (snapped IN (0,1)), snap_dw_measured REAL,"
    " regime_measured TEXT CHECK (regime_measured IN ('symmetric','asymmetric','no snap')),"
    " software_version TEXT NOT NULL);"
    "CREATE TABLE samples (trial_id INTEGER NOT NULL REFERENCES trials(id) ON DELETE CASCADE,"
    " seq INTEGER NOT NULL, t_s REAL NOT NULL, kind INTEGER NOT NULL CHECK (kind IN (0,1)), frame INTEGER,"
    " compress_mm REAL, shear_mm REAL, dl REAL, dw REAL, dz REAL, a REAL, quality REAL, reason TEXT,"
    " PRIMARY KEY (trial_id, seq)) WITHOUT ROWID;"
    "CREATE TABLE events (id INTEGER PRIMARY KEY,"
    " trial_id INTEGER NOT NULL REFERENCES trials(id) ON DELETE CASCADE,"
    " t_s REAL, wall_time TEXT NOT NULL, state TEXT,"
    " kind TEXT NOT NULL CHECK (kind IN ('state','info','warning','fault')), message TEXT NOT NULL);"
    "CREATE INDEX events_trial ON events(trial_id);"
    "CREATE TABLE predictions (id INTEGER PRIMARY KEY,"
    " trial_id INTEGER REFERENCES trials(id) ON DELETE SET NULL, scene_hash TEXT NOT NULL,"
    " snapped INTEGER NOT NULL CHECK (snapped IN (0,1)), snap_dw REAL,"
    " regime TEXT CHECK (regime IN ('symmetric','asymmetric','no snap')), peak_abs_a REAL,"
    " nodes INTEGER NOT NULL, dt REAL NOT NULL, adaptive INTEGER NOT NULL CHECK (adaptive IN (0,1)),"
    " imperfection REAL NOT NULL, est_error REAL, wall_s REAL NOT NULL,"
    " software_version TEXT NOT NULL, solver_json TEXT,"
    " created_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')));"
    "CREATE TABLE prediction_curve (prediction_id INTEGER NOT NULL REFERENCES predictions(id) ON DELETE CASCADE,"
    " seq INTEGER NOT NULL, t_s REAL NOT NULL, dw REAL NOT NULL, dz REAL, a REAL,"
    " PRIMARY KEY (prediction_id, seq)) WITHOUT ROWID;"
    "PRAGMA application_id = 1380532802;"
    "PRAGMA user_version = 1;";

/* A version 1 file with one of everything, as a v1 program would have left it. */
static void make_v1_file(const char *path)
{
    exec_raw(path, "PRAGMA journal_mode=WAL;");
    exec_raw(path, v1_ddl);
    exec_raw(path,
             "INSERT INTO specimens (name, length_m, width_m, thickness_m, material, crease_angle_left_deg)"
             " VALUES ('PET-7', 0.2, 0.005, 0.00025, 'PET', 89.5);"
             "INSERT INTO trials (mode, status, state, config_text, specimen_id, created_at, started_at, ended_at,"
             " snapped, snap_dw_measured, regime_measured, software_version)"
             " VALUES ('rig', 'done', 'done', '[rig]', 1, '2025-03-01T10:00:00.000Z', '2025-03-01T10:00:01.000Z',"
             " '2025-03-01T10:01:00.000Z', 1, 0.123, 'asymmetric', '0.0.9');"
             "INSERT INTO samples (trial_id, seq, t_s, kind, frame, dw, dz, a)"
             " VALUES (1, 0, 0.0, 1, 0, 0.0, 0.3, 0.0), (1, 1, 0.04, 1, 1, 0.001, 0.29, 0.01),"
             " (1, 2, 0.05, 0, NULL, NULL, NULL, NULL);"
             "INSERT INTO events (trial_id, t_s, wall_time, state, kind, message)"
             " VALUES (1, 0.0, '2025-03-01T10:00:01.000Z', 'compressing', 'state', 'compressing');"
             "INSERT INTO predictions (trial_id, scene_hash, snapped, snap_dw, regime, nodes, dt, adaptive,"
             " imperfection, est_error, wall_s, software_version)"
             " VALUES (1, 'h1', 1, 0.125, 'asymmetric', 101, 0.001, 0, 0.01, 0.002, 3.5, '0.0.9');"
             "INSERT INTO prediction_curve VALUES (1, 0, 0.0, 0.0, 0.3, 0.0), (1, 1, 1.0, 0.01, 0.2, NULL);");
}

static void test_migrate_v1_to_current(void **state)
{
    fixture *f = *state;
    make_v1_file(f->db);
    assert_int_equal(raw_int(f->db, "PRAGMA user_version"), 1);
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    assert_int_equal(store_schema_version(st), STORE_SCHEMA_VERSION);
    assert_int_equal(q_int(store_handle(st), "PRAGMA user_version"), STORE_SCHEMA_VERSION);
    assert_int_equal(q_int(store_handle(st), "SELECT count(*) FROM sqlite_master WHERE name = 'predictions_trial'"), 1);

    store_trial t;
    OK(store_trial_get(st, 1, &t, why, sizeof why));
    assert_int_equal(t.mode, STORE_MODE_RIG);
    assert_int_equal(t.status, STORE_STATUS_DONE);
    assert_string_equal(t.specimen_name, "PET-7");
    assert_int_equal(t.snapped, 1);
    NEAR(t.snap_dw_measured, 0.123, 0);
    assert_int_equal(t.regime_measured, STORE_REGIME_ASYMMETRIC);
    assert_string_equal(t.software_version, "0.0.9");
    assert_int_equal(t.samples, 3); /* v3 back-filled the count */
    assert_true(isnan(t.stop_cmd_latency_s) && isnan(t.stop_stand_latency_s)); /* v4: none measured */
    int64_t n;
    OK(store_samples_count(st, 1, &n, why, sizeof why));
    assert_int_equal(n, 3);
    store_prediction p;
    OK(store_prediction_get_by_trial(st, 1, &p, why, sizeof why));
    NEAR(p.snap_dw, 0.125, 0);
    assert_int_equal(p.curve.n, 2);
    assert_true(isnan(p.curve.a[1]));
    store_prediction_free(&p);
    store_specimen sp;
    OK(store_specimen_get_by_name(st, "PET-7", &sp, why, sizeof why));
    NEAR(sp.crease_angle_left_deg, 89.5, 0);
    assert_true(isnan(sp.crease_angle_right_deg));

    /* The v2 table works on the migrated file, and new rows continue the old ids. */
    store_ladder_rung r = {.nodes = 51, .dt = 1e-3, .snap_dw = 0.12, .est_error = 0.01, .wall_s = 0.5};
    OK(store_ladder_put(st, "h1", &r, 1, why, sizeof why));
    assert_int_equal(new_trial(st, STORE_MODE_MOCK), 2);
    store_close(st);
}

static void test_newer_version_refused(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_close(st);
    exec_raw(f->db, "PRAGMA user_version = 99;");
    long long tables = raw_int(f->db, "SELECT count(*) FROM sqlite_master");
    assert_int_equal(store_open(f->db, &st, why, sizeof why), STORE_E_VERSION);
    assert_null(st);
    assert_non_null(strstr(why, "99"));
    assert_non_null(strstr(why, "newer"));
    assert_int_equal(raw_int(f->db, "PRAGMA user_version"), 99);
    assert_int_equal(raw_int(f->db, "SELECT count(*) FROM sqlite_master"), tables);
}

static void test_foreign_files_refused(void **state)
{
    fixture *f = *state;
    store *st;
    /* Another program's SQLite database. */
    exec_raw(f->db, "CREATE TABLE addresses (name TEXT);");
    assert_int_equal(store_open(f->db, &st, why, sizeof why), STORE_E_CORRUPT);
    assert_non_null(strstr(why, "not a ribbon rig store"));
    assert_int_equal(raw_int(f->db, "SELECT count(*) FROM sqlite_master"), 1);
    /* Not a database at all. */
    char txt[400];
    snprintf(txt, sizeof txt, "%s/notes.txt", f->dir);
    FILE *fp = fopen(txt, "w");
    assert_non_null(fp);
    for (int i = 0; i < 200; i++)
        fputs("this is not a database. ", fp);
    fclose(fp);
    assert_int_equal(store_open(txt, &st, why, sizeof why), STORE_E_CORRUPT);
    assert_non_null(strstr(why, "not an SQLite database"));
    /* A directory that does not exist. */
    snprintf(txt, sizeof txt, "%s/missing/dir/x.sqlite", f->dir);
    assert_int_equal(store_open(txt, &st, why, sizeof why), STORE_E_IO);
    assert_non_null(strstr(why, "cannot open"));
    assert_int_equal(store_open("", &st, why, sizeof why), STORE_E_INVALID);
}

static void test_failed_migration_rolls_back(void **state)
{
    fixture *f = *state;
    make_v1_file(f->db);
    /* Something already called "ladder" makes step 2 fail half way. */
    exec_raw(f->db, "CREATE TABLE ladder (x INTEGER);");
    store *st;
    assert_int_equal(store_open(f->db, &st, why, sizeof why), STORE_E_VERSION);
    assert_non_null(strstr(why, "from schema version 1 to 2"));
    assert_non_null(strstr(why, "left at version 1"));
    assert_int_equal(raw_int(f->db, "PRAGMA user_version"), 1);
    assert_int_equal(raw_int(f->db, "SELECT count(*) FROM sqlite_master WHERE name = 'predictions_trial'"), 0);
    assert_int_equal(raw_int(f->db, "SELECT count(*) FROM samples"), 3);
}

static void test_read_only(void **state)
{
    fixture *f = *state;
    store_open_params p = store_open_params_default();
    p.read_only = true;
    store *st;
    make_v1_file(f->db);
    assert_int_equal(store_open_ex(f->db, &p, &st, why, sizeof why), STORE_E_VERSION); /* needs migrating */
    assert_non_null(strstr(why, "read-write"));
    OK(store_open(f->db, &st, why, sizeof why));
    store_close(st);
    OK(store_open_ex(f->db, &p, &st, why, sizeof why));
    store_trial t;
    OK(store_trial_get(st, 1, &t, why, sizeof why));
    assert_int_equal(store_trial_set_state(st, 1, "x", why, sizeof why), STORE_E_STATE);
    assert_non_null(strstr(why, "read-only"));
    store_close(st);
}

/* ---- records ----------------------------------------------------------------------------- */

static void test_names_round_trip(void **state)
{
    (void)state;
    for (int m = 0; m < STORE_MODE_COUNT; m++) {
        store_mode x;
        assert_true(store_mode_parse(store_mode_name((store_mode)m), &x));
        assert_int_equal(x, m);
    }
    for (int s = 0; s < STORE_STATUS_COUNT; s++) {
        store_status x;
        assert_true(store_status_parse(store_status_name((store_status)s), &x));
        assert_int_equal(x, s);
    }
    for (int r = 1; r < STORE_REGIME_COUNT; r++) {
        store_regime x;
        assert_true(store_regime_parse(store_regime_name((store_regime)r), &x));
        assert_int_equal(x, r);
    }
    for (int k = 0; k < STORE_EVENT_COUNT; k++) {
        store_event_kind x;
        assert_true(store_event_kind_parse(store_event_kind_name((store_event_kind)k), &x));
        assert_int_equal(x, k);
    }
    for (int k = 1; k < STORE_SOURCE_COUNT; k++) {
        store_source x;
        assert_true(store_source_parse(store_source_name((store_source)k), &x));
        assert_int_equal(x, k);
    }
    assert_null(store_source_name(STORE_SOURCE_UNKNOWN));
    store_regime r;
    assert_true(store_regime_parse("none", &r));
    assert_int_equal(r, STORE_REGIME_NO_SNAP);
    assert_false(store_regime_parse("sideways", &r));
    assert_null(store_regime_name(STORE_REGIME_UNKNOWN));
    assert_null(store_mode_name(STORE_MODE_COUNT));
    char t[32];
    assert_true(store_wall_format(T0 + 3723.25, t, sizeof t));
    assert_string_equal(t, "2026-01-01T01:02:03.250Z");
    assert_false(store_wall_format(NAN, t, sizeof t));
    assert_false(store_wall_format(-1.0, t, sizeof t));
    assert_true(fabs(store_wall_now() - (double)time(NULL)) < 5.0);
}

static void test_specimen_round_trip(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "PET-200x5x0.25-A");
    sp.length_m = 0.2;
    sp.width_m = 0.005;
    sp.thickness_m = 0.00025;
    sp.youngs_modulus_pa = 4e9;
    sp.density_kg_m3 = 1380;
    snprintf(sp.material, sizeof sp.material, "PET");
    sp.crease_angle_left_deg = 88.0;
    sp.crease_angle_right_deg = 91.5;
    sp.fold_position = 0.13;
    snprintf(sp.crease_orientation, sizeof sp.crease_orientation, "up");
    int64_t id = 0, id2 = 0;
    OK(store_specimen_upsert(st, &sp, &id, why, sizeof why));
    store_specimen back;
    OK(store_specimen_get(st, id, &back, why, sizeof why));
    assert_string_equal(back.name, sp.name);
    assert_true(back.length_m == 0.2 && back.width_m == 0.005 && back.thickness_m == 0.00025);
    assert_true(back.youngs_modulus_pa == 4e9 && back.density_kg_m3 == 1380);
    assert_string_equal(back.material, "PET");
    assert_true(back.crease_angle_left_deg == 88.0 && back.crease_angle_right_deg == 91.5);
    assert_true(back.fold_position == 0.13);
    assert_string_equal(back.crease_orientation, "up");
    assert_int_equal(back.trials_count, 0);

    OK(store_specimen_count_trial(st, id, why, sizeof why));
    OK(store_specimen_count_trial(st, id, why, sizeof why));
    /* Re-measured: same name, same row, the count kept; an unknown value stays unknown. */
    sp.crease_angle_right_deg = NAN;
    sp.crease_angle_left_deg = 87.0;
    OK(store_specimen_upsert(st, &sp, &id2, why, sizeof why));
    assert_int_equal(id2, id);
    OK(store_specimen_get_by_name(st, sp.name, &back, why, sizeof why));
    assert_int_equal(back.trials_count, 2);
    assert_true(back.crease_angle_left_deg == 87.0);
    assert_true(isnan(back.crease_angle_right_deg));

    /* Required NaN, infinity, bad range: refused, nothing written. */
    store_specimen bad = sp;
    snprintf(bad.name, sizeof bad.name, "other");
    bad.thickness_m = NAN;
    assert_int_equal(store_specimen_upsert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "thickness_m"));
    bad.thickness_m = 0.00025;
    bad.crease_angle_left_deg = INFINITY;
    assert_int_equal(store_specimen_upsert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "crease_angle_left_deg"));
    bad.crease_angle_left_deg = 90;
    bad.fold_position = 1.5;
    assert_int_equal(store_specimen_upsert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    bad.fold_position = 0.2;
    bad.name[0] = '\0';
    assert_int_equal(store_specimen_upsert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_int_equal(q_int(store_handle(st), "SELECT count(*) FROM specimens"), 1);
    assert_int_equal(store_specimen_get(st, 999, &back, why, sizeof why), STORE_E_NOTFOUND);
    assert_int_equal(store_specimen_count_trial(st, 999, why, sizeof why), STORE_E_NOTFOUND);
    store_close(st);
}

static void test_trial_round_trip_and_life_cycle(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "S1");
    sp.length_m = 0.2;
    sp.width_m = 0.005;
    sp.thickness_m = 0.00025;
    int64_t spid;
    OK(store_specimen_upsert(st, &sp, &spid, why, sizeof why));

    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_RIG;
    d.config_text = "[rig]\nmode = rig\nscene = paper.ini\n\n; scene\n[ribbon]\nlength_m = 0.2\n";
    d.calibration_json = "{\"compress_zero_mm\": 12.5, \"camera_side\": \"left\"}";
    d.specimen_id = spid;
    d.video_path = "/data/trials/1.mkv";
    d.software_version = "9.9.9";
    d.created_wall_s = T0;
    int64_t id;
    OK(store_trial_create(st, &d, &id, why, sizeof why));
    store_trial t;
    OK(store_trial_get(st, id, &t, why, sizeof why));
    assert_int_equal(t.mode, STORE_MODE_RIG);
    assert_int_equal(t.status, STORE_STATUS_CREATED);
    assert_string_equal(t.specimen_name, "S1");
    assert_int_equal(t.specimen_id, spid);
    assert_int_equal(t.source_trial_id, 0);
    assert_string_equal(t.video_path, "/data/trials/1.mkv");
    assert_string_equal(t.created_at, "2026-01-01T00:00:00.000Z");
    assert_string_equal(t.started_at, "");
    assert_int_equal(t.snapped, -1);
    assert_true(isnan(t.snap_dw_measured));
    assert_int_equal(t.regime_measured, STORE_REGIME_UNKNOWN);
    assert_string_equal(t.software_version, "9.9.9");
    char *cfg, *cal;
    OK(store_trial_texts(st, id, &cfg, &cal, why, sizeof why));
    assert_string_equal(cfg, d.config_text);
    assert_string_equal(cal, d.calibration_json);
    free(cfg);
    free(cal);

    OK(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, T0 + 1, why, sizeof why));
    OK(store_trial_set_state(st, id, "shearing", why, sizeof why));
    /* NaN where the result needs a number: refused, nothing changed. */
    assert_int_equal(store_trial_set_result(st, id, true, NAN, STORE_REGIME_SYMMETRIC, why, sizeof why),
                     STORE_E_INVALID);
    assert_non_null(strstr(why, "snap_dw"));
    assert_int_equal(store_trial_set_result(st, id, true, 0.1, STORE_REGIME_NO_SNAP, why, sizeof why),
                     STORE_E_INVALID);
    assert_int_equal(store_trial_set_result(st, id, false, 0.1, STORE_REGIME_NO_SNAP, why, sizeof why),
                     STORE_E_INVALID);
    OK(store_trial_get(st, id, &t, why, sizeof why));
    assert_int_equal(t.snapped, -1);
    /* A snap only the load witness saw: snapped, a Delta W, the regime unknown (NULL). */
    OK(store_trial_set_result(st, id, true, 0.43, STORE_REGIME_UNKNOWN, why, sizeof why));
    OK(store_trial_get(st, id, &t, why, sizeof why));
    assert_int_equal(t.snapped, 1);
    assert_true(t.snap_dw_measured == 0.43);
    assert_int_equal(t.regime_measured, STORE_REGIME_UNKNOWN);
    OK(store_trial_set_result(st, id, true, 0.4302, STORE_REGIME_SYMMETRIC, why, sizeof why));
    OK(store_trial_set_video(st, id, "/data/trials/1-crop.mkv", why, sizeof why));
    OK(store_trial_set_status(st, id, STORE_STATUS_DONE, "snapped", T0 + 61.5, why, sizeof why));
    OK(store_trial_get(st, id, &t, why, sizeof why));
    assert_int_equal(t.status, STORE_STATUS_DONE);
    assert_string_equal(t.state, "shearing");
    assert_string_equal(t.reason, "snapped");
    assert_string_equal(t.started_at, "2026-01-01T00:00:01.000Z");
    assert_string_equal(t.ended_at, "2026-01-01T00:01:01.500Z");
    assert_int_equal(t.snapped, 1);
    assert_true(t.snap_dw_measured == 0.4302);
    assert_int_equal(t.regime_measured, STORE_REGIME_SYMMETRIC);
    assert_string_equal(t.video_path, "/data/trials/1-crop.mkv");

    /* End states are final; nothing goes back to created. */
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_ABORTED, "late", T0 + 70, why, sizeof why),
                     STORE_E_STATE);
    assert_non_null(strstr(why, "'done'"));
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_CREATED, NULL, T0, why, sizeof why), STORE_E_STATE);
    int64_t id2 = new_trial(st, STORE_MODE_MOCK);
    assert_int_equal(store_trial_set_status(st, id2, STORE_STATUS_DONE, NULL, T0, why, sizeof why), STORE_E_STATE);
    OK(store_trial_set_status(st, id2, STORE_STATUS_FAILED, "upper state not reached: Delta Z = -0.2", T0, why,
                              sizeof why));
    OK(store_trial_set_result(st, id2, false, NAN, STORE_REGIME_NO_SNAP, why, sizeof why));
    OK(store_trial_get(st, id2, &t, why, sizeof why));
    assert_int_equal(t.status, STORE_STATUS_FAILED);
    assert_string_equal(t.started_at, "");
    assert_int_equal(t.snapped, 0);
    assert_true(isnan(t.snap_dw_measured));
    assert_int_equal(t.regime_measured, STORE_REGIME_NO_SNAP);

    /* A replay links to its source. */
    d = store_trial_def_default();
    d.mode = STORE_MODE_REPLAY;
    d.source_trial_id = id;
    d.created_wall_s = T0 + 100;
    int64_t id3;
    OK(store_trial_create(st, &d, &id3, why, sizeof why));
    OK(store_trial_get(st, id3, &t, why, sizeof why));
    assert_int_equal(t.source_trial_id, id);
    OK(store_trial_texts(st, id3, NULL, &cal, why, sizeof why));
    assert_null(cal);

    /* Bad definitions: refused with the field named, nothing written. */
    long long before = q_int(store_handle(st), "SELECT count(*) FROM trials");
    d.source_trial_id = 0;
    d.calibration_json = "{not json";
    assert_int_equal(store_trial_create(st, &d, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "calibration_json"));
    d.calibration_json = NULL;
    d.specimen_id = 77;
    assert_int_equal(store_trial_create(st, &d, NULL, why, sizeof why), STORE_E_NOTFOUND);
    assert_non_null(strstr(why, "specimen 77"));
    d.specimen_id = 0;
    d.created_wall_s = NAN;
    assert_int_equal(store_trial_create(st, &d, NULL, why, sizeof why), STORE_E_INVALID);
    d.created_wall_s = T0;
    d.mode = (store_mode)7;
    assert_int_equal(store_trial_create(st, &d, NULL, why, sizeof why), STORE_E_INVALID);
    assert_int_equal(q_int(store_handle(st), "SELECT count(*) FROM trials"), before);
    assert_int_equal(store_trial_get(st, 999, &t, why, sizeof why), STORE_E_NOTFOUND);
    assert_int_equal(store_trial_set_state(st, 999, "x", why, sizeof why), STORE_E_NOTFOUND);
    assert_int_equal(store_trial_set_status(st, 999, STORE_STATUS_RUNNING, NULL, T0, why, sizeof why),
                     STORE_E_NOTFOUND);

    store_trial *list;
    size_t n;
    OK(store_trial_list(st, &list, &n, why, sizeof why));
    assert_int_equal(n, 3);
    assert_int_equal(list[0].id, id);
    assert_int_equal(list[2].mode, STORE_MODE_REPLAY);
    free(list);
    store_close(st);
}

static void test_mark_interrupted(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    int64_t a = new_trial(st, STORE_MODE_MOCK), b = new_trial(st, STORE_MODE_RIG), c = new_trial(st, STORE_MODE_MOCK);
    OK(store_trial_set_status(st, a, STORE_STATUS_RUNNING, NULL, T0, why, sizeof why));
    OK(store_trial_set_status(st, b, STORE_STATUS_RUNNING, NULL, T0, why, sizeof why));
    OK(store_trial_set_state(st, b, "holding", why, sizeof why));
    OK(store_trial_set_status(st, b, STORE_STATUS_DONE, NULL, T0 + 1, why, sizeof why));
    OK(store_trial_set_status(st, c, STORE_STATUS_RUNNING, NULL, T0, why, sizeof why));
    OK(store_trial_set_state(st, c, "shearing", why, sizeof why));
    int count = -1;
    OK(store_trial_mark_interrupted(st, T0 + 5, &count, why, sizeof why));
    assert_int_equal(count, 2);
    store_trial t;
    OK(store_trial_get(st, a, &t, why, sizeof why));
    assert_int_equal(t.status, STORE_STATUS_INTERRUPTED);
    assert_string_equal(t.ended_at, "2026-01-01T00:00:05.000Z");
    assert_non_null(strstr(t.reason, "daemon stopped"));
    OK(store_trial_get(st, b, &t, why, sizeof why));
    assert_int_equal(t.status, STORE_STATUS_DONE);
    store_event *ev;
    size_t n;
    OK(store_events_get(st, c, &ev, &n, why, sizeof why));
    assert_int_equal(n, 1);
    assert_int_equal(ev[0].kind, STORE_EVENT_FAULT);
    assert_string_equal(ev[0].state, "shearing");
    assert_true(isnan(ev[0].t_s));
    free(ev);
    OK(store_trial_mark_interrupted(st, T0 + 6, &count, why, sizeof why));
    assert_int_equal(count, 0);
    store_close(st);
}

/* A daemon killed before its trial reached running (during the ladder or the prediction) left it
 * 'created': the start-up pass ends it too, with its own reason (issue 17, defect 5). */
static void test_mark_interrupted_created(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    int64_t a = new_trial(st, STORE_MODE_MOCK), b = new_trial(st, STORE_MODE_RIG);
    OK(store_trial_set_status(st, b, STORE_STATUS_ABORTED, "abort", T0, why, sizeof why));
    int count = -1;
    OK(store_trial_mark_interrupted(st, T0 + 5, &count, why, sizeof why));
    assert_int_equal(count, 1);
    store_trial t;
    OK(store_trial_get(st, a, &t, why, sizeof why));
    assert_int_equal(t.status, STORE_STATUS_INTERRUPTED);
    assert_non_null(strstr(t.reason, "before the trial started"));
    OK(store_trial_get(st, b, &t, why, sizeof why));
    assert_int_equal(t.status, STORE_STATUS_ABORTED);
    store_event *ev;
    size_t n;
    OK(store_events_get(st, a, &ev, &n, why, sizeof why));
    assert_int_equal(n, 1);
    assert_int_equal(ev[0].kind, STORE_EVENT_FAULT);
    assert_non_null(strstr(ev[0].message, "before this trial started"));
    free(ev);
    store_close(st);
}

static void test_events_round_trip(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    int64_t id = new_trial(st, STORE_MODE_MOCK);
    store_event e = {.trial_id = id, .t_s = NAN, .wall_s = T0, .kind = STORE_EVENT_INFO};
    snprintf(e.message, sizeof e.message, "prediction started: N = 101, dt = 1 ms");
    OK(store_event_append(st, &e, why, sizeof why));
    e.t_s = 12.5;
    e.wall_s = T0 + 12.5;
    e.kind = STORE_EVENT_FAULT;
    snprintf(e.state, sizeof e.state, "shearing");
    snprintf(e.message, sizeof e.message, "rail shear: alarm 9, \"limit\"");
    OK(store_event_append(st, &e, why, sizeof why));
    store_event *v;
    size_t n;
    OK(store_events_get(st, id, &v, &n, why, sizeof why));
    assert_int_equal(n, 2);
    assert_true(isnan(v[0].t_s));
    assert_string_equal(v[0].state, "");
    assert_int_equal(v[0].kind, STORE_EVENT_INFO);
    assert_string_equal(v[1].wall_time, "2026-01-01T00:00:12.500Z");
    assert_true(v[1].t_s == 12.5);
    assert_string_equal(v[1].message, e.message);
    free(v);
    e.t_s = -INFINITY;
    assert_int_equal(store_event_append(st, &e, why, sizeof why), STORE_E_INVALID);
    e.t_s = 1;
    e.message[0] = '\0';
    assert_int_equal(store_event_append(st, &e, why, sizeof why), STORE_E_INVALID);
    snprintf(e.message, sizeof e.message, "x");
    e.trial_id = 4242;
    assert_int_equal(store_event_append(st, &e, why, sizeof why), STORE_E_NOTFOUND);
    assert_int_equal(q_int(store_handle(st), "SELECT count(*) FROM events"), 2);
    store_close(st);
}

static store_prediction sample_prediction(int64_t trial, double *t, double *dw, double *dz, double *a, size_t n)
{
    store_prediction p = store_prediction_default();
    p.trial_id = trial;
    snprintf(p.scene_hash, sizeof p.scene_hash, "sha256:4f2a");
    p.snapped = true;
    p.snap_dw = 0.43031;
    p.regime = STORE_REGIME_ASYMMETRIC;
    p.peak_abs_a = 1.7;
    p.nodes = 201;
    p.dt = 1e-3;
    p.adaptive = true;
    p.imperfection = 0.01;
    p.est_error = 4e-4;
    p.wall_s = 12.25;
    p.solver_json = "{\"damping\":0.1,\"fold_stiffness\":10}";
    p.curve = (store_curve){.n = n, .t_s = t, .dw = dw, .dz = dz, .a = a};
    return p;
}

static void test_prediction_round_trip(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    int64_t trial = new_trial(st, STORE_MODE_MOCK);
    double t[3] = {0, 1, 2}, dw[3] = {0, 0.2, 0.43}, dz[3] = {0.4, 0.3, NAN}, a[3] = {0, 0.1, -1.5};
    store_prediction p = sample_prediction(trial, t, dw, dz, a, 3);
    int64_t pid;
    OK(store_prediction_insert(st, &p, &pid, why, sizeof why));
    store_prediction back;
    OK(store_prediction_get_by_trial(st, trial, &back, why, sizeof why));
    assert_int_equal(back.id, pid);
    assert_int_equal(back.trial_id, trial);
    assert_string_equal(back.scene_hash, "sha256:4f2a");
    assert_true(back.snapped && back.snap_dw == 0.43031 && back.regime == STORE_REGIME_ASYMMETRIC);
    assert_true(back.peak_abs_a == 1.7 && back.nodes == 201 && back.dt == 1e-3 && back.adaptive);
    assert_true(back.imperfection == 0.01 && back.est_error == 4e-4 && back.wall_s == 12.25);
    assert_string_equal(back.software_version, RIBBON_VERSION);
    assert_string_equal(back.solver_json, p.solver_json);
    assert_int_equal(strlen(back.created_at), 24);
    assert_int_equal(back.curve.n, 3);
    for (int i = 0; i < 3; i++) {
        assert_true(back.curve.t_s[i] == t[i] && back.curve.dw[i] == dw[i] && back.curve.a[i] == a[i]);
    }
    assert_true(back.curve.dz[0] == 0.4 && isnan(back.curve.dz[2]));
    store_prediction_free(&back);

    /* A later prediction for the same trial becomes its prediction; one without a snap and
     * without curve or solver settings round-trips its missing values. */
    store_prediction q = sample_prediction(trial, NULL, NULL, NULL, NULL, 0);
    q.snapped = false;
    q.snap_dw = NAN;
    q.regime = STORE_REGIME_NO_SNAP;
    q.peak_abs_a = NAN;
    q.est_error = NAN;
    q.solver_json = NULL;
    int64_t qid;
    OK(store_prediction_insert(st, &q, &qid, why, sizeof why));
    OK(store_prediction_get_by_trial(st, trial, &back, why, sizeof why));
    assert_int_equal(back.id, qid);
    assert_false(back.snapped);
    assert_true(isnan(back.snap_dw) && isnan(back.peak_abs_a) && isnan(back.est_error));
    assert_null(back.solver_json);
    assert_int_equal(back.curve.n, 0);
    store_prediction_free(&back);
    OK(store_prediction_get(st, pid, &back, why, sizeof why));
    assert_int_equal(back.curve.n, 3);
    store_prediction_free(&back);

    /* Refusals write nothing: no row, no curve point. */
    long long rows = q_int(store_handle(st), "SELECT count(*) FROM predictions");
    long long pts = q_int(store_handle(st), "SELECT count(*) FROM prediction_curve");
    store_prediction bad = sample_prediction(trial, t, dw, dz, a, 3);
    bad.snap_dw = NAN;
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "snap_dw"));
    bad = sample_prediction(trial, t, dw, dz, a, 3);
    bad.wall_s = NAN;
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "wall_s"));
    double bad_dw[3] = {0, NAN, 0.4};
    bad = sample_prediction(trial, t, bad_dw, dz, a, 3);
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "point 1"));
    bad = sample_prediction(trial, t, dw, dz, a, 3);
    bad.solver_json = "{";
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    bad = sample_prediction(4242, t, dw, dz, a, 3);
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_NOTFOUND);
    assert_int_equal(q_int(store_handle(st), "SELECT count(*) FROM predictions"), rows);
    assert_int_equal(q_int(store_handle(st), "SELECT count(*) FROM prediction_curve"), pts);

    /* The predicted curve for reports is the latest prediction's. */
    store_curve c;
    OK(store_prediction_curve(st, trial, &c, why, sizeof why));
    assert_int_equal(c.n, 0);
    store_curve_free(&c);
    int64_t other = new_trial(st, STORE_MODE_MOCK);
    assert_int_equal(store_prediction_curve(st, other, &c, why, sizeof why), STORE_E_NOTFOUND);
    assert_int_equal(store_prediction_get_by_trial(st, other, &back, why, sizeof why), STORE_E_NOTFOUND);
    store_close(st);
}

/* v5 (issue 31): the specimen's measured positions and fold date; the creases' age of a trial;
 * a failed prediction (its status and reason, no snap, no curve) and the creases a prediction
 * used with their sources, in the record and in the JSON; refusals of rows that say less.
 * v7: the crease model it ran (a compliant hinge's stiffness, rigid, or not recorded) read back
 * and in the JSON (a number, "rigid", null); a stiffness of 0 or below refused. */
static void test_specimen_in_prediction(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "PET-B");
    sp.length_m = 0.2;
    sp.width_m = 0.005;
    sp.thickness_m = 0.00025;
    sp.crease_position_left = 0.12;
    sp.crease_position_right = 0.86;
    snprintf(sp.folded_at, sizeof sp.folded_at, "2026-11-30T14:05+01:00");
    int64_t spid = 0;
    OK(store_specimen_upsert(st, &sp, &spid, why, sizeof why));
    store_specimen back;
    OK(store_specimen_get(st, spid, &back, why, sizeof why));
    assert_true(back.crease_position_left == 0.12 && back.crease_position_right == 0.86);
    assert_string_equal(back.folded_at, "2026-11-30T14:05+01:00");
    sp.crease_position_right = 1.5;
    assert_int_equal(store_specimen_upsert(st, &sp, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "crease_position_right"));

    store_trial_def d = store_trial_def_default();
    assert_true(isnan(d.crease_age_s));
    d.config_text = "";
    d.created_wall_s = T0;
    d.specimen_id = spid;
    d.crease_age_s = 3.5 * 86400.0;
    int64_t trial = 0;
    OK(store_trial_create(st, &d, &trial, why, sizeof why));
    d.crease_age_s = -1.0;
    assert_int_equal(store_trial_create(st, &d, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "crease_age_s"));
    store_trial tr;
    OK(store_trial_get(st, trial, &tr, why, sizeof why));
    assert_true(tr.crease_age_s == 3.5 * 86400.0);

    /* A failed prediction with the creases it was to use. */
    store_prediction p = store_prediction_default();
    p.trial_id = trial;
    snprintf(p.scene_hash, sizeof p.scene_hash, "h1");
    p.status = STORE_PREDICTION_FAILED;
    snprintf(p.failure, sizeof p.failure, "ladder rung N = 31: no snap up to Delta W = 0.6");
    p.nodes = 61;
    p.dt = 2e-3;
    p.imperfection = -3.0 / 89.5;
    p.wall_s = 0.0;
    p.creases.angle_deg[0] = -88.0;
    p.creases.angle_from[0] = STORE_SOURCE_SPECIMEN;
    p.creases.angle_deg[1] = -90.0;
    p.creases.angle_from[1] = STORE_SOURCE_SCENE;
    p.creases.position[0] = 0.13;
    p.creases.position_from[0] = STORE_SOURCE_SCENE;
    p.creases.position[1] = 0.87;
    p.creases.position_from[1] = STORE_SOURCE_SCENE;
    p.creases.hinge_stiffness = 3.5e-3;
    int64_t pid = 0;
    OK(store_prediction_insert(st, &p, &pid, why, sizeof why));
    store_prediction pb;
    OK(store_prediction_get_by_trial(st, trial, &pb, why, sizeof why));
    assert_int_equal(pb.status, STORE_PREDICTION_FAILED);
    assert_string_equal(pb.failure, p.failure);
    assert_false(pb.snapped);
    assert_true(isnan(pb.snap_dw) && pb.regime == STORE_REGIME_UNKNOWN && pb.curve.n == 0);
    assert_true(pb.creases.angle_deg[0] == -88.0 && pb.creases.angle_from[0] == STORE_SOURCE_SPECIMEN);
    assert_true(pb.creases.angle_deg[1] == -90.0 && pb.creases.angle_from[1] == STORE_SOURCE_SCENE);
    assert_true(pb.creases.position[1] == 0.87 && pb.creases.position_from[1] == STORE_SOURCE_SCENE);
    assert_true(pb.creases.hinge_stiffness == 3.5e-3);
    store_prediction_free(&pb);

    json_t *j = NULL;
    OK(store_trial_json(st, trial, &j, why, sizeof why));
    json_t *jp = json_object_get(j, "prediction");
    assert_string_equal(json_string_value(json_object_get(jp, "status")), "failed");
    assert_string_equal(json_string_value(json_object_get(jp, "failure")), p.failure);
    assert_true(json_is_null(json_object_get(j, "snap_dw_predicted")));
    assert_true(json_is_null(json_object_get(j, "regime_predicted")));
    assert_true(json_number_value(json_object_get(j, "crease_age_s")) == 3.5 * 86400.0);
    json_t *jc = json_object_get(jp, "creases");
    assert_true(json_number_value(json_object_get(jc, "angle_left_deg")) == -88.0);
    assert_string_equal(json_string_value(json_object_get(jc, "angle_left_from")), "specimen");
    assert_string_equal(json_string_value(json_object_get(jc, "angle_right_from")), "scene");
    assert_true(json_number_value(json_object_get(jc, "position_right")) == 0.87);
    assert_true(json_number_value(json_object_get(jc, "hinge_stiffness")) == 3.5e-3);
    json_decref(j);

    /* Rigid creases: INFINITY in, INFINITY out, "rigid" in the JSON; not recorded: NaN, null. */
    store_prediction rigid = p;
    rigid.creases.hinge_stiffness = INFINITY;
    OK(store_prediction_insert(st, &rigid, &pid, why, sizeof why));
    OK(store_prediction_get(st, pid, &pb, why, sizeof why));
    assert_true(isinf(pb.creases.hinge_stiffness) && pb.creases.hinge_stiffness > 0.0);
    store_prediction_free(&pb);
    OK(store_trial_json(st, trial, &j, why, sizeof why));
    jc = json_object_get(json_object_get(j, "prediction"), "creases");
    assert_string_equal(json_string_value(json_object_get(jc, "hinge_stiffness")), "rigid");
    json_decref(j);
    store_prediction unknown = p;
    unknown.creases.hinge_stiffness = NAN;
    OK(store_prediction_insert(st, &unknown, &pid, why, sizeof why));
    OK(store_prediction_get(st, pid, &pb, why, sizeof why));
    assert_true(isnan(pb.creases.hinge_stiffness));
    store_prediction_free(&pb);
    OK(store_trial_json(st, trial, &j, why, sizeof why));
    jc = json_object_get(json_object_get(j, "prediction"), "creases");
    assert_true(json_is_null(json_object_get(jc, "hinge_stiffness")));
    json_decref(j);

    /* Refused, nothing written: a failed row without its reason, or with a snap; a done row with
     * a failure text; a value without its source. */
    long long rows = q_int(store_handle(st), "SELECT count(*) FROM predictions");
    store_prediction bad = p;
    bad.failure[0] = '\0';
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "reason"));
    bad = p;
    bad.snapped = true;
    bad.snap_dw = 0.4;
    bad.regime = STORE_REGIME_SYMMETRIC;
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    bad = p;
    bad.status = STORE_PREDICTION_DONE;
    bad.regime = STORE_REGIME_NO_SNAP;
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    bad = p;
    bad.creases.angle_from[0] = STORE_SOURCE_UNKNOWN;
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "source"));
    bad = p;
    bad.creases.hinge_stiffness = 0.0;
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "hinge_stiffness"));
    bad.creases.hinge_stiffness = -INFINITY;
    assert_int_equal(store_prediction_insert(st, &bad, NULL, why, sizeof why), STORE_E_INVALID);
    assert_int_equal(q_int(store_handle(st), "SELECT count(*) FROM predictions"), rows);
    store_close(st);
}

static void test_ladder(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_ladder_rung r[3] = {
        {.nodes = 201, .dt = 1e-3, .adaptive = false, .snap_dw = 0.4303, .est_error = 1e-4, .wall_s = 40},
        {.nodes = 51, .dt = 4e-3, .adaptive = true, .snap_dw = 0.428, .est_error = 3e-3, .wall_s = 1.5},
        {.nodes = 101, .dt = 2e-3, .adaptive = false, .snap_dw = NAN, .est_error = NAN, .wall_s = 9},
    };
    OK(store_ladder_put(st, "scene-a", r, 3, why, sizeof why));
    store_ladder_rung *v;
    size_t n;
    OK(store_ladder_get(st, "scene-a", &v, &n, why, sizeof why));
    assert_int_equal(n, 3);
    assert_int_equal(v[0].nodes, 51); /* cheapest first */
    assert_true(v[0].adaptive && v[0].dt == 4e-3 && v[0].snap_dw == 0.428);
    assert_int_equal(v[1].nodes, 101);
    assert_true(isnan(v[1].snap_dw) && isnan(v[1].est_error));
    assert_int_equal(v[2].nodes, 201);
    free(v);
    /* A put replaces; a bad put (repeated resolution) keeps the old ladder. */
    OK(store_ladder_put(st, "scene-a", &r[0], 1, why, sizeof why));
    OK(store_ladder_get(st, "scene-a", &v, &n, why, sizeof why));
    assert_int_equal(n, 1);
    free(v);
    store_ladder_rung dup[2] = {r[1], r[1]};
    assert_int_equal(store_ladder_put(st, "scene-a", dup, 2, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "rung 1"));
    OK(store_ladder_get(st, "scene-a", &v, &n, why, sizeof why));
    assert_int_equal(n, 1);
    assert_int_equal(v[0].nodes, 201);
    free(v);
    store_ladder_rung nan_wall = r[1];
    nan_wall.wall_s = NAN;
    assert_int_equal(store_ladder_put(st, "scene-b", &nan_wall, 1, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "wall_s"));
    assert_int_equal(store_ladder_get(st, "scene-b", &v, &n, why, sizeof why), STORE_E_NOTFOUND);
    assert_null(v);
    store_close(st);
}

/* ---- samples ----------------------------------------------------------------------------- */

static store_sample frame_at(double t, int64_t frame)
{
    store_sample s = store_sample_default();
    s.kind = STORE_SAMPLE_FRAME;
    s.t_s = t;
    s.frame = frame;
    s.compress_mm = 100.0;
    s.shear_mm = 0.5 * t;
    s.dl = 0.5;
    s.dw = 0.01 * t;
    s.dz = 0.3 - 0.001 * t;
    s.a = 0.02 * t;
    s.quality = 0.9;
    return s;
}

static void test_writer_commit_triggers(void **state)
{
    fixture *f = *state;
    store *st, *reader;
    OK(store_open(f->db, &st, why, sizeof why));
    OK(store_open(f->db, &reader, why, sizeof why)); /* another connection sees only commits */
    int64_t id = new_trial(st, STORE_MODE_MOCK);
    store_writer_params p = store_writer_params_default();
    assert_int_equal(p.batch_rows, 256);
    assert_true(p.max_age_s == 0.25);
    p.batch_rows = 4;
    store_samples *w;
    OK(store_samples_begin(st, id, &p, &w, why, sizeof why));
    int64_t seen;
    /* Batch size: nothing visible until the 4th row. t steps 0.01 s, far from the age limit. */
    for (int i = 0; i < 3; i++) {
        store_sample s = frame_at(0.01 * i, i);
        OK(store_samples_add(w, &s, why, sizeof why));
    }
    assert_int_equal(store_samples_pending(w), 3);
    OK(store_samples_count(reader, id, &seen, why, sizeof why));
    assert_int_equal(seen, 0);
    store_sample s = frame_at(0.03, 3);
    OK(store_samples_add(w, &s, why, sizeof why));
    assert_int_equal(store_samples_committed(w), 4);
    OK(store_samples_count(reader, id, &seen, why, sizeof why));
    assert_int_equal(seen, 4);
    /* Age: the caller's clock passing 0.25 s since the last commit (at t = 0.03) commits. */
    s = frame_at(0.20, 4);
    OK(store_samples_add(w, &s, why, sizeof why));
    assert_int_equal(store_samples_pending(w), 1);
    s = frame_at(0.28, 5);
    OK(store_samples_add(w, &s, why, sizeof why));
    assert_int_equal(store_samples_pending(w), 0);
    assert_int_equal(store_samples_committed(w), 6);
    /* Flush. */
    s = frame_at(0.29, 6);
    OK(store_samples_add(w, &s, why, sizeof why));
    OK(store_samples_flush(w, why, sizeof why));
    OK(store_samples_count(reader, id, &seen, why, sizeof why));
    assert_int_equal(seen, 7);
    /* A refused sample is not added and takes no sequence number. */
    s = frame_at(0.3, 7);
    s.dz = INFINITY;
    assert_int_equal(store_samples_add(w, &s, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "dz"));
    s = frame_at(NAN, 7);
    assert_int_equal(store_samples_add(w, &s, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "t_s"));
    s = frame_at(0.3, 7);
    s.quality = 1.5;
    assert_int_equal(store_samples_add(w, &s, why, sizeof why), STORE_E_INVALID);
    assert_int_equal(store_samples_pending(w), 0);
    /* A rail reading with missing values and a reason; end flushes it. */
    store_sample r = store_sample_default();
    r.t_s = 0.31;
    r.compress_mm = 99.5;
    snprintf(r.reason, sizeof r.reason, "vision: ribbon lost, \"edge\"");
    OK(store_samples_add(w, &r, why, sizeof why));
    OK(store_samples_end(w, why, sizeof why));
    OK(store_samples_count(reader, id, &seen, why, sizeof why));
    assert_int_equal(seen, 8);
    store_trial tr;
    OK(store_trial_get(reader, id, &tr, why, sizeof why));
    assert_int_equal(tr.samples, 8);

    /* A second writer continues the numbering. */
    OK(store_samples_begin(st, id, NULL, &w, why, sizeof why));
    s = frame_at(0.4, 8);
    OK(store_samples_add(w, &s, why, sizeof why));
    OK(store_samples_end(w, why, sizeof why));

    store_sample *v;
    size_t n;
    OK(store_samples_get(reader, id, &v, &n, why, sizeof why));
    assert_int_equal(n, 9);
    for (size_t i = 0; i < n; i++)
        assert_int_equal(v[i].seq, (int64_t)i);
    store_sample e = frame_at(0.01, 1);
    assert_int_equal(v[1].kind, STORE_SAMPLE_FRAME);
    assert_int_equal(v[1].frame, 1);
    assert_true(v[1].t_s == e.t_s && v[1].compress_mm == e.compress_mm && v[1].shear_mm == e.shear_mm &&
                v[1].dl == e.dl && v[1].dw == e.dw && v[1].dz == e.dz && v[1].a == e.a && v[1].quality == e.quality);
    assert_string_equal(v[1].reason, "");
    assert_int_equal(v[7].kind, STORE_SAMPLE_RAIL);
    assert_int_equal(v[7].frame, -1);
    assert_true(v[7].compress_mm == 99.5);
    assert_true(isnan(v[7].shear_mm) && isnan(v[7].dw) && isnan(v[7].dz) && isnan(v[7].a) && isnan(v[7].quality));
    assert_string_equal(v[7].reason, r.reason);
    free(v);
    /* Nothing stored is NaN: SQL NULL instead. */
    assert_int_equal(q_int(store_handle(reader), "SELECT count(*) FROM samples WHERE dz IS NULL"), 1);
    assert_int_equal(store_samples_begin(st, 4242, NULL, &w, why, sizeof why), STORE_E_NOTFOUND);
    p.batch_rows = 0;
    assert_int_equal(store_samples_begin(st, id, &p, &w, why, sizeof why), STORE_E_INVALID);
    store_close(reader);
    store_close(st);
}

/* Fault injection: max_page_count makes the file "full"; commits fail with a reason, the batch
 * is kept, a full batch refuses more, and raising the limit lets the same rows through. */
static void test_writer_disk_full(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    int64_t id = new_trial(st, STORE_MODE_MOCK);
    store_writer_params p = {.batch_rows = 64, .max_age_s = 1e9};
    store_samples *w;
    OK(store_samples_begin(st, id, &p, &w, why, sizeof why));
    sqlite3 *db = store_handle(st);
    long long pages = q_int(db, "PRAGMA page_count");
    char sql[64];
    snprintf(sql, sizeof sql, "PRAGMA max_page_count = %lld", pages);
    q_int(db, sql);
    store_err e = STORE_OK;
    int i = 0;
    for (; i < 10000 && e == STORE_OK; i++) {
        store_sample s = frame_at(1e-3 * i, i);
        snprintf(s.reason, sizeof s.reason, "padding padding padding padding padding padding %d", i);
        e = store_samples_add(w, &s, why, sizeof why);
    }
    assert_int_equal(e, STORE_E_IO);
    assert_non_null(strstr(why, "full"));
    assert_non_null(strstr(why, "kept pending"));
    int64_t committed = store_samples_committed(w);
    assert_int_equal(store_samples_pending(w), 64);
    /* Full batch and still full disk: refused, not added. */
    store_sample s = frame_at(100.0, 99999);
    assert_int_equal(store_samples_add(w, &s, why, sizeof why), STORE_E_IO);
    assert_non_null(strstr(why, "batch full"));
    assert_int_equal(store_samples_pending(w), 64);
    int64_t stored;
    OK(store_samples_count(st, id, &stored, why, sizeof why));
    assert_int_equal(stored, committed);
    q_int(db, "PRAGMA max_page_count = 1073741823");
    OK(store_samples_flush(w, why, sizeof why));
    OK(store_samples_end(w, why, sizeof why));
    OK(store_samples_count(st, id, &stored, why, sizeof why));
    assert_int_equal(stored, committed + 64);
    assert_int_equal(stored, i); /* every accepted sample is there, none twice */
    char ok[16];
    q_text(db, "PRAGMA integrity_check", ok, sizeof ok);
    assert_string_equal(ok, "ok");
    store_close(st);
}

static void test_trial_curve(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    int64_t id = new_trial(st, STORE_MODE_MOCK);
    store_samples *w;
    OK(store_samples_begin(st, id, NULL, &w, why, sizeof why));
    for (int i = 0; i < 10; i++) {
        store_sample s = frame_at(0.1 * i, i);
        if (i == 3)
            s.a = NAN; /* tracker lost the asymmetry: not on the curve */
        if (i == 5)
            s.kind = STORE_SAMPLE_RAIL, s.frame = -1;
        OK(store_samples_add(w, &s, why, sizeof why));
    }
    OK(store_samples_end(w, why, sizeof why));
    store_curve c;
    OK(store_trial_curve(st, id, &c, why, sizeof why));
    assert_int_equal(c.n, 8);
    assert_true(c.t_s[3] == 0.4 && c.dw[3] == frame_at(0.4, 4).dw);
    for (size_t i = 0; i < c.n; i++)
        assert_true(isfinite(c.dz[i]) && isfinite(c.a[i]));
    store_curve_free(&c);
    assert_int_equal(store_trial_curve(st, 4242, &c, why, sizeof why), STORE_E_NOTFOUND);
    store_close(st);
}

/* ---- views ------------------------------------------------------------------------------- */

static void assert_keys(const json_t *o)
{
    static const char *const keys[] = {"id", "mode", "status", "state", "reason", "snapped", "snap_dw_measured",
                                       "snap_dw_predicted", "regime_measured", "regime_predicted", "samples",
                                       "video_path", "video_bytes", "source_trial", "specimen", "created", "started", "ended",
                                       "software_version", "prediction"};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++)
        if (!json_object_get(o, keys[i]))
            fail_msg("key %s missing", keys[i]);
}

/* v4: the snap-to-stop latency of a trial: stored, read back, NULL for NaN, in the JSON, and a
 * negative or infinite latency refused without touching the row. */
static void test_trial_latency(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_RIG;
    d.created_wall_s = T0;
    int64_t id;
    OK(store_trial_create(st, &d, &id, why, sizeof why));
    store_trial t;
    OK(store_trial_get(st, id, &t, why, sizeof why));
    assert_true(isnan(t.stop_cmd_latency_s) && isnan(t.stop_stand_latency_s));
    OK(store_trial_set_latency(st, id, 0.0254, 0.0711, why, sizeof why));
    OK(store_trial_get(st, id, &t, why, sizeof why));
    NEAR(t.stop_cmd_latency_s, 0.0254, 0);
    NEAR(t.stop_stand_latency_s, 0.0711, 0);
    assert_int_equal(store_trial_set_latency(st, id, -0.001, NAN, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "stop_cmd_latency_s"));
    assert_int_equal(store_trial_set_latency(st, id, 0.01, INFINITY, why, sizeof why), STORE_E_INVALID);
    OK(store_trial_get(st, id, &t, why, sizeof why));
    NEAR(t.stop_cmd_latency_s, 0.0254, 0); /* unchanged by the refusals */
    json_t *j = NULL;
    OK(store_trial_json(st, id, &j, why, sizeof why));
    NEAR(json_real_value(json_object_get(j, "stop_cmd_latency_s")), 0.0254, 0);
    json_decref(j);
    OK(store_trial_set_latency(st, id, 0.03, NAN, why, sizeof why)); /* not seen standing: NULL */
    assert_int_equal(q_int(store_handle(st), "SELECT count(*) FROM trials WHERE stop_stand_latency_s IS NULL"), 1);
    OK(store_trial_json(st, id, &j, why, sizeof why));
    assert_true(json_is_null(json_object_get(j, "stop_stand_latency_s")));
    json_decref(j);
    assert_int_equal(store_trial_set_latency(st, id + 99, 0.1, 0.1, why, sizeof why), STORE_E_NOTFOUND);
    store_close(st);
}

/* v11: a trial's calibrated prediction (issue 32 B): null until set; a band, a regime and the fit's
 * JSON stored and read back in the JSON view; NaN is null; a failure clears the numbers and keeps
 * its reason; infinite numbers, an unknown regime, invalid JSON and an empty reason refused
 * without touching the row; a later call replaces an earlier one. */
static void test_trial_calibrated(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_MOCK;
    d.created_wall_s = T0;
    int64_t id;
    OK(store_trial_create(st, &d, &id, why, sizeof why));
    json_t *j = NULL;
    OK(store_trial_json(st, id, &j, why, sizeof why));
    assert_true(json_is_null(json_object_get(j, "snap_dw_calibrated")) && json_is_null(json_object_get(j, "fit")) &&
                json_is_null(json_object_get(j, "fit_failure")) && json_is_null(json_object_get(j, "regime_calibrated")));
    json_decref(j);
    store_calibrated c = {.snap_dw = 0.40522, .snap_sd = 0.0023, .p_other = 0.0, .regime = "asymmetric",
                          .fit_json = "{\"refresh\":3,\"parameters\":[]}", .failure = NULL};
    OK(store_trial_set_calibrated(st, id, &c, why, sizeof why));
    OK(store_trial_json(st, id, &j, why, sizeof why));
    NEAR(json_real_value(json_object_get(j, "snap_dw_calibrated")), 0.40522, 0);
    NEAR(json_real_value(json_object_get(j, "snap_sd_calibrated")), 0.0023, 0);
    assert_string_equal(json_string_value(json_object_get(j, "regime_calibrated")), "asymmetric");
    assert_int_equal(json_integer_value(json_object_get(json_object_get(j, "fit"), "refresh")), 3);
    json_decref(j);
    store_calibrated bad = c;
    bad.snap_sd = INFINITY;
    assert_int_equal(store_trial_set_calibrated(st, id, &bad, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "snap_sd_calibrated"));
    bad = c;
    bad.regime = "sideways";
    assert_int_equal(store_trial_set_calibrated(st, id, &bad, why, sizeof why), STORE_E_INVALID);
    bad = c;
    bad.fit_json = "{not json";
    assert_true(store_trial_set_calibrated(st, id, &bad, why, sizeof why) != STORE_OK);
    bad = c;
    bad.failure = "";
    assert_int_equal(store_trial_set_calibrated(st, id, &bad, why, sizeof why), STORE_E_INVALID);
    OK(store_trial_json(st, id, &j, why, sizeof why));
    NEAR(json_real_value(json_object_get(j, "snap_dw_calibrated")), 0.40522, 0); /* unchanged */
    json_decref(j);
    store_calibrated nb = c; /* no band: NaN is null */
    nb.snap_sd = nb.p_other = NAN;
    OK(store_trial_set_calibrated(st, id, &nb, why, sizeof why));
    OK(store_trial_json(st, id, &j, why, sizeof why));
    assert_true(json_is_null(json_object_get(j, "snap_sd_calibrated")));
    assert_true(json_is_null(json_object_get(j, "p_other_regime_calibrated")));
    json_decref(j);
    store_calibrated fl = {.snap_dw = 0.4, .snap_sd = 0.1, .p_other = 0.5, .regime = "symmetric",
                           .fit_json = NULL, .failure = "misfit: no parameter set fits these frames"};
    OK(store_trial_set_calibrated(st, id, &fl, why, sizeof why));
    OK(store_trial_json(st, id, &j, why, sizeof why));
    assert_true(json_is_null(json_object_get(j, "snap_dw_calibrated")) &&
                json_is_null(json_object_get(j, "regime_calibrated")) && json_is_null(json_object_get(j, "fit")));
    assert_string_equal(json_string_value(json_object_get(j, "fit_failure")), "misfit: no parameter set fits these frames");
    json_decref(j);
    assert_int_equal(store_trial_set_calibrated(st, id + 99, &c, why, sizeof why), STORE_E_NOTFOUND);
    store_close(st);
}

/* v12: a specimen's calibration: none until set; an upsert (every trial's start) keeps it; a
 * refit's failure keeps it beside the failure; a new calibration clears the failure; kept for a
 * retired specimen (whose last trial may end after the retirement); bad JSON, a JSON that is not
 * an object and one too long for the record refused without touching the row. A prediction's
 * calibration_json reads back and shows in the trial's JSON. */
static void test_specimen_calibration(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "S-1");
    sp.length_m = 0.2;
    sp.width_m = 0.005;
    sp.thickness_m = 0.00025;
    int64_t id = 0;
    OK(store_specimen_upsert(st, &sp, &id, why, sizeof why));
    store_specimen back;
    OK(store_specimen_get(st, id, &back, why, sizeof why));
    assert_string_equal(back.calibration_json, "");
    assert_string_equal(back.calibration_failure_json, "");
    const char *cal = "{\"trials\":[1],\"parameters\":[{\"key\":\"folds.angle_left_deg\",\"value\":-86.5}]}";
    OK(store_specimen_set_calibration(st, id, cal, NULL, why, sizeof why));
    OK(store_specimen_upsert(st, &sp, NULL, why, sizeof why)); /* a trial's start */
    OK(store_specimen_get_by_name(st, "S-1", &back, why, sizeof why));
    assert_string_equal(back.calibration_json, cal);
    const char *fail1 = "{\"reason_key\":\"misfit\",\"after_trial\":2}";
    OK(store_specimen_set_calibration(st, id, NULL, fail1, why, sizeof why));
    OK(store_specimen_get(st, id, &back, why, sizeof why));
    assert_string_equal(back.calibration_json, cal);
    assert_string_equal(back.calibration_failure_json, fail1);
    OK(store_specimen_retire(st, id, STORE_SPECIMEN_RETIRED, "done with it", T0, why, sizeof why));
    const char *cal2 = "{\"trials\":[1,2,3]}";
    OK(store_specimen_set_calibration(st, id, cal2, NULL, why, sizeof why));
    OK(store_specimen_get(st, id, &back, why, sizeof why));
    assert_string_equal(back.calibration_json, cal2);
    assert_string_equal(back.calibration_failure_json, "");
    assert_int_equal(back.state, STORE_SPECIMEN_RETIRED);
    /* Refused, nothing written. */
    assert_int_equal(store_specimen_set_calibration(st, id, "{not json", NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "calibration_json"));
    assert_int_equal(store_specimen_set_calibration(st, id, "[1,2]", NULL, why, sizeof why), STORE_E_INVALID);
    assert_int_equal(store_specimen_set_calibration(st, id, NULL, NULL, why, sizeof why), STORE_E_INVALID);
    char *big = malloc(STORE_SPECIMEN_CALIBRATION_MAX + 16);
    memset(big, ' ', STORE_SPECIMEN_CALIBRATION_MAX + 15);
    big[0] = '{';
    big[STORE_SPECIMEN_CALIBRATION_MAX + 14] = '}';
    big[STORE_SPECIMEN_CALIBRATION_MAX + 15] = '\0';
    assert_int_equal(store_specimen_set_calibration(st, id, big, NULL, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "at most"));
    free(big);
    assert_int_equal(store_specimen_set_calibration(st, id + 99, cal, NULL, why, sizeof why), STORE_E_NOTFOUND);
    OK(store_specimen_get(st, id, &back, why, sizeof why));
    assert_string_equal(back.calibration_json, cal2);

    /* The calibration a prediction ran with. */
    int64_t tid = new_trial(st, STORE_MODE_MOCK);
    store_prediction p = store_prediction_default();
    p.trial_id = tid;
    snprintf(p.scene_hash, sizeof p.scene_hash, "h");
    p.snapped = false;
    p.regime = STORE_REGIME_NO_SNAP;
    p.snap_dw = NAN;
    p.nodes = 31;
    p.dt = 1e-3;
    p.imperfection = 0;
    p.wall_s = 0.5;
    p.calibration_json = "[1]";
    assert_int_equal(store_prediction_insert(st, &p, NULL, why, sizeof why), STORE_E_INVALID);
    p.calibration_json = "{\"trials\":[1],\"applied\":[{\"key\":\"folds.angle_left_deg\",\"value\":-86.5}]}";
    int64_t pid = 0;
    OK(store_prediction_insert(st, &p, &pid, why, sizeof why));
    store_prediction q;
    OK(store_prediction_get(st, pid, &q, why, sizeof why));
    assert_string_equal(q.calibration_json, p.calibration_json);
    store_prediction_free(&q);
    json_t *j = NULL;
    OK(store_trial_json(st, tid, &j, why, sizeof why));
    json_t *pc = json_object_get(json_object_get(j, "prediction"), "calibration");
    assert_true(json_is_object(pc));
    assert_int_equal(json_integer_value(json_array_get(json_object_get(pc, "trials"), 0)), 1);
    json_decref(j);
    p.calibration_json = NULL; /* none: null */
    OK(store_prediction_insert(st, &p, &pid, why, sizeof why));
    OK(store_trial_json(st, tid, &j, why, sizeof why));
    assert_true(json_is_null(json_object_get(json_object_get(j, "prediction"), "calibration")));
    json_decref(j);
    store_close(st);
}

/* v10: the camera's time offset measured at the shear's start: NULL until set, stored with its
 * standard deviation; a NaN offset or a negative deviation refused without touching the row. */
static void test_trial_camera_offset(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_RIG;
    d.created_wall_s = T0;
    int64_t id;
    OK(store_trial_create(st, &d, &id, why, sizeof why));
    sqlite3 *db = store_handle(st);
    assert_int_equal(q_int(db, "SELECT count(*) FROM trials WHERE camera_offset_s IS NULL AND camera_offset_sd_s IS NULL"), 1);
    OK(store_trial_set_camera_offset(st, id, -0.0192, 0.0009, why, sizeof why));
    assert_int_equal(q_int(db, "SELECT count(*) FROM trials WHERE camera_offset_s = -0.0192 AND camera_offset_sd_s = 0.0009"), 1);
    assert_int_equal(store_trial_set_camera_offset(st, id, NAN, 0.001, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "camera_offset_s"));
    assert_int_equal(store_trial_set_camera_offset(st, id, -0.01, -0.001, why, sizeof why), STORE_E_INVALID);
    assert_int_equal(q_int(db, "SELECT count(*) FROM trials WHERE camera_offset_s = -0.0192"), 1);
    assert_int_equal(store_trial_set_camera_offset(st, id + 99, 0.0, 0.001, why, sizeof why), STORE_E_NOTFOUND);
    store_close(st);
}

/* v6: a trial's video file and its size: unknown (NULL) until set, set with the path in one
 * statement, in the JSON; a negative size or no path refused without touching the row. */
static void test_trial_video_file(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_RIG;
    d.created_wall_s = T0;
    int64_t id;
    OK(store_trial_create(st, &d, &id, why, sizeof why));
    store_trial t;
    OK(store_trial_get(st, id, &t, why, sizeof why));
    assert_int_equal(t.video_bytes, -1);
    json_t *j = NULL;
    OK(store_trial_json(st, id, &j, why, sizeof why));
    assert_true(json_is_null(json_object_get(j, "video_bytes")));
    json_decref(j);
    OK(store_trial_set_video_file(st, id, "videos/trial-1.avi", 1566948531LL, NULL, why, sizeof why));
    OK(store_trial_set_video_file(st, id, "videos/trial-1.mkv", 670695772LL, NULL, why, sizeof why));
    assert_int_equal(store_trial_set_video_file(st, id, "videos/x.mkv", -1, NULL, why, sizeof why), STORE_E_INVALID);
    assert_int_equal(store_trial_set_video_file(st, id, "", 5, NULL, why, sizeof why), STORE_E_INVALID);
    OK(store_trial_get(st, id, &t, why, sizeof why));
    assert_string_equal(t.video_path, "videos/trial-1.mkv");
    assert_int_equal(t.video_bytes, 670695772LL);
    OK(store_trial_json(st, id, &j, why, sizeof why));
    assert_int_equal(json_integer_value(json_object_get(j, "video_bytes")), 670695772LL);
    json_decref(j);
    assert_int_equal(store_trial_set_video_file(st, id + 99, "v.mkv", 1, NULL, why, sizeof why), STORE_E_NOTFOUND);
    store_close(st);
}

static void test_json(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "S2");
    sp.length_m = sp.width_m = sp.thickness_m = 1;
    int64_t spid;
    OK(store_specimen_upsert(st, &sp, &spid, why, sizeof why));
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_RIG;
    d.specimen_id = spid;
    d.created_wall_s = T0;
    d.calibration_json = "{\"camera_side\":\"left\"}";
    int64_t full;
    OK(store_trial_create(st, &d, &full, why, sizeof why));
    OK(store_trial_set_status(st, full, STORE_STATUS_RUNNING, NULL, T0 + 1, why, sizeof why));
    OK(store_trial_set_result(st, full, true, 0.41, STORE_REGIME_SYMMETRIC, why, sizeof why));
    OK(store_trial_set_status(st, full, STORE_STATUS_DONE, NULL, T0 + 2, why, sizeof why));
    double t[2] = {0, 1}, dw[2] = {0, 0.43};
    store_prediction p = sample_prediction(full, t, dw, NULL, NULL, 2);
    p.est_error = NAN;
    OK(store_prediction_insert(st, &p, NULL, why, sizeof why));
    store_samples *w;
    OK(store_samples_begin(st, full, NULL, &w, why, sizeof why));
    for (int i = 0; i < 5; i++) {
        store_sample s = frame_at(i, i);
        OK(store_samples_add(w, &s, why, sizeof why));
    }
    OK(store_samples_end(w, why, sizeof why));
    store_event ev = {.trial_id = full, .t_s = 0.5, .wall_s = T0 + 1.5, .kind = STORE_EVENT_STATE};
    snprintf(ev.state, sizeof ev.state, "compressing");
    snprintf(ev.message, sizeof ev.message, "compressing to Delta L = 0.5");
    OK(store_event_append(st, &ev, why, sizeof why));
    int64_t empty = new_trial(st, STORE_MODE_MOCK);
    /* A reason with bytes that are not UTF-8 (a raw device reply) still makes valid JSON. */
    OK(store_trial_set_status(st, empty, STORE_STATUS_FAILED, "device said \xff\xfe", T0, why, sizeof why));

    json_t *j;
    OK(store_trial_json(st, full, &j, why, sizeof why));
    assert_keys(j);
    assert_int_equal(json_integer_value(json_object_get(j, "id")), full);
    assert_string_equal(json_string_value(json_object_get(j, "mode")), "rig");
    assert_string_equal(json_string_value(json_object_get(j, "status")), "done");
    assert_true(json_is_true(json_object_get(j, "snapped")));
    NEAR(json_real_value(json_object_get(j, "snap_dw_measured")), 0.41, 0);
    NEAR(json_real_value(json_object_get(j, "snap_dw_predicted")), 0.43031, 0);
    assert_string_equal(json_string_value(json_object_get(j, "regime_measured")), "symmetric");
    assert_string_equal(json_string_value(json_object_get(j, "regime_predicted")), "asymmetric");
    assert_int_equal(json_integer_value(json_object_get(j, "samples")), 5);
    assert_string_equal(json_string_value(json_object_get(j, "specimen")), "S2");
    assert_string_equal(json_string_value(json_object_get(j, "started")), "2026-01-01T00:00:01.000Z");
    json_t *pj = json_object_get(j, "prediction");
    assert_int_equal(json_integer_value(json_object_get(pj, "nodes")), 201);
    NEAR(json_real_value(json_object_get(pj, "dt")), 1e-3, 0);
    NEAR(json_real_value(json_object_get(pj, "wall_s")), 12.25, 0);
    assert_true(json_is_null(json_object_get(pj, "est_error")));
    assert_true(json_is_null(json_object_get(j, "video_path")));
    assert_true(json_is_null(json_object_get(j, "source_trial")));
    assert_string_equal(json_string_value(json_object_get(json_object_get(j, "calibration"), "camera_side")), "left");
    json_t *evs = json_object_get(j, "events");
    assert_int_equal(json_array_size(evs), 1);
    assert_string_equal(json_string_value(json_object_get(json_array_get(evs, 0), "kind")), "state");
    json_decref(j);

    OK(store_trial_json(st, empty, &j, why, sizeof why));
    assert_keys(j);
    static const char *const nulls[] = {"state", "snapped", "snap_dw_measured", "snap_dw_predicted",
                                        "regime_measured", "regime_predicted", "video_path", "source_trial",
                                        "specimen", "started", "prediction", "calibration"};
    for (size_t i = 0; i < sizeof nulls / sizeof nulls[0]; i++)
        if (!json_is_null(json_object_get(j, nulls[i])))
            fail_msg("%s should be null", nulls[i]);
    assert_int_equal(json_integer_value(json_object_get(j, "samples")), 0);
    assert_string_equal(json_string_value(json_object_get(j, "reason")), "device said ??");
    assert_non_null(json_object_get(j, "ended"));
    char *text = json_dumps(j, 0);
    assert_non_null(text);
    assert_null(strstr(text, "NaN"));
    assert_null(strstr(text, "nan"));
    free(text);
    json_decref(j);

    OK(store_trials_json(st, &j, why, sizeof why));
    assert_int_equal(json_array_size(j), 2);
    assert_keys(json_array_get(j, 1));
    assert_null(json_object_get(json_array_get(j, 0), "events"));
    json_decref(j);
    assert_int_equal(store_trial_json(st, 4242, &j, why, sizeof why), STORE_E_NOTFOUND);
    assert_null(j);
    store_close(st);
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return NULL;
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

static void test_csv(void **state)
{
    fixture *f = *state;
    store *st;
    OK(store_open(f->db, &st, why, sizeof why));
    int64_t id = new_trial(st, STORE_MODE_MOCK);
    store_samples *w;
    OK(store_samples_begin(st, id, NULL, &w, why, sizeof why));
    store_sample s = store_sample_default();
    s.t_s = 0.1;
    s.compress_mm = 12.5;
    s.shear_mm = 0.0;
    OK(store_samples_add(w, &s, why, sizeof why));
    s = store_sample_default();
    s.kind = STORE_SAMPLE_FRAME;
    s.t_s = 0.2;
    s.frame = 7;
    s.dw = 0.1;
    s.dz = -0.3333333333333333;
    s.a = 1e-12;
    s.quality = 1;
    snprintf(s.reason, sizeof s.reason, "low contrast, \"glare\"");
    OK(store_samples_add(w, &s, why, sizeof why));
    OK(store_samples_end(w, why, sizeof why));

    char path[640];
    snprintf(path, sizeof path, "%s/one.csv", f->dir);
    FILE *out = fopen(path, "w");
    assert_non_null(out);
    OK(store_export_trial_csv(st, id, out, why, sizeof why));
    fclose(out);
    assert_string_equal(slurp(path), "seq,t_s,kind,frame,compress_mm,shear_mm,dl,dw,dz,a,quality,reason\n"
                                     "0,0.1,rail,,12.5,0,,,,,,\n"
                                     "1,0.2,frame,7,,,,0.1,-0.3333333333333333,1e-12,1,"
                                     "\"low contrast, \"\"glare\"\"\"\n");
    assert_int_equal(store_export_trial_csv(st, 4242, stdout, why, sizeof why), STORE_E_NOTFOUND);

    int64_t id2 = new_trial(st, STORE_MODE_REPLAY);
    OK(store_trial_set_status(st, id2, STORE_STATUS_ABORTED, "user abort, from ribbonctl", T0, why, sizeof why));
    char dir[400];
    snprintf(dir, sizeof dir, "%s/export", f->dir);
    OK(store_export_all(st, dir, why, sizeof why));
    snprintf(path, sizeof path, "%s/trials.csv", dir);
    const char *trials = slurp(path);
    assert_non_null(trials);
    static const char head[] = "id,mode,status,state,reason,snapped,snap_dw_measured,snap_dw_predicted,";
    assert_true(strncmp(trials, head, strlen(head)) == 0);
    assert_non_null(strstr(trials, "\n1,mock,created,,,,,,,,2,,,,2026-01-01T00:00:00.000Z,"));
    assert_non_null(strstr(trials, "\n2,replay,aborted,,\"user abort, from ribbonctl\",,"));
    int lines = 0;
    for (const char *c = trials; *c; c++)
        lines += *c == '\n';
    assert_int_equal(lines, 3);
    snprintf(path, sizeof path, "%s/trial-1-samples.csv", dir);
    assert_non_null(strstr(slurp(path), "1,0.2,frame,7,"));
    snprintf(path, sizeof path, "%s/trial-2-samples.csv", dir);
    assert_string_equal(slurp(path), "seq,t_s,kind,frame,compress_mm,shear_mm,dl,dw,dz,a,quality,reason\n");
    snprintf(path, sizeof path, "%s/trials.csv.tmp", dir);
    assert_int_equal(access(path, F_OK), -1);
    /* Exporting again overwrites in place. */
    OK(store_export_all(st, dir, why, sizeof why));
    snprintf(path, sizeof path, "%s/notadir", f->dir);
    fclose(fopen(path, "w"));
    snprintf(dir, sizeof dir, "%s/notadir/sub", f->dir);
    assert_int_equal(store_export_all(st, dir, why, sizeof why), STORE_E_IO);
    store_close(st);
}

static void test_bench_small(void **state)
{
    fixture *f = *state;
    double rate = 0;
    OK(store_bench_samples(f->db, 3000, &rate, why, sizeof why));
    assert_true(rate > 0);
    assert_int_equal(raw_int(f->db, "SELECT count(*) FROM samples"), 3000);
    assert_int_equal(store_bench_samples(f->db, 10, &rate, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "exists"));
}

/* Issue 17, item 12: a store path that is not a regular file (/dev/full left -journal files in
 * /dev) and a store file that may not be written (ribbond started, then answered 500) are refused
 * at open. Root may write any file, so the read-only case runs in a child as nobody when the test
 * runs as root. */
static void test_store_path_must_be_a_writable_regular_file(void **state)
{
    (void)state;
    char why[512];
    store *st = NULL;
    assert_int_equal(store_open("/dev/null", &st, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "not a regular file (a character device)"));
    assert_null(st);
    assert_int_equal(store_open("/tmp", &st, why, sizeof why), STORE_E_INVALID);
    assert_non_null(strstr(why, "a directory"));
    assert_int_equal(access("/dev/null-journal", F_OK), -1);

    char dir[] = "/tmp/ribbon-store-ro-XXXXXX", path[128];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/trials.db", dir);
    assert_int_equal(store_open(path, &st, why, sizeof why), STORE_OK); /* a valid store */
    store_close(st);
    assert_int_equal(chmod(path, 0444), 0);
    assert_int_equal(chmod(dir, 0555), 0);
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        if (getuid() == 0 && (setgid(65534) != 0 || setuid(65534) != 0)) _exit(20);
        store *s2 = NULL;
        char w[512];
        store_err e = store_open(path, &s2, w, sizeof w);
        printf("read-only store: %s\n", w);
        fflush(stdout);
        _exit(e == STORE_E_IO && strstr(w, "read-only") ? 0 : 21);
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    chmod(dir, 0755);
    chmod(path, 0644);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_create_schema_wal, setup, teardown),
        cmocka_unit_test(test_store_path_must_be_a_writable_regular_file),
        cmocka_unit_test_setup_teardown(test_migrate_v1_to_current, setup, teardown),
        cmocka_unit_test_setup_teardown(test_newer_version_refused, setup, teardown),
        cmocka_unit_test_setup_teardown(test_foreign_files_refused, setup, teardown),
        cmocka_unit_test_setup_teardown(test_failed_migration_rolls_back, setup, teardown),
        cmocka_unit_test_setup_teardown(test_read_only, setup, teardown),
        cmocka_unit_test(test_names_round_trip),
        cmocka_unit_test_setup_teardown(test_specimen_round_trip, setup, teardown),
        cmocka_unit_test_setup_teardown(test_trial_round_trip_and_life_cycle, setup, teardown),
        cmocka_unit_test_setup_teardown(test_mark_interrupted_created, setup, teardown),
        cmocka_unit_test_setup_teardown(test_mark_interrupted, setup, teardown),
        cmocka_unit_test_setup_teardown(test_events_round_trip, setup, teardown),
        cmocka_unit_test_setup_teardown(test_prediction_round_trip, setup, teardown),
        cmocka_unit_test_setup_teardown(test_specimen_in_prediction, setup, teardown),
        cmocka_unit_test_setup_teardown(test_ladder, setup, teardown),
        cmocka_unit_test_setup_teardown(test_writer_commit_triggers, setup, teardown),
        cmocka_unit_test_setup_teardown(test_writer_disk_full, setup, teardown),
        cmocka_unit_test_setup_teardown(test_trial_curve, setup, teardown),
        cmocka_unit_test_setup_teardown(test_trial_latency, setup, teardown),
        cmocka_unit_test_setup_teardown(test_trial_camera_offset, setup, teardown),
        cmocka_unit_test_setup_teardown(test_trial_calibrated, setup, teardown),
        cmocka_unit_test_setup_teardown(test_specimen_calibration, setup, teardown),
        cmocka_unit_test_setup_teardown(test_trial_video_file, setup, teardown),
        cmocka_unit_test_setup_teardown(test_json, setup, teardown),
        cmocka_unit_test_setup_teardown(test_csv, setup, teardown),
        cmocka_unit_test_setup_teardown(test_bench_small, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
