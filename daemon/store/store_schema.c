/* store_schema.c: the store's schema and its migrations (store_schema.h).
 *
 * The schema is an ordered list of migration steps, each a constant script that ends by setting
 * PRAGMA user_version to its own number. Opening runs, in order and each in its own
 * transaction, every step above the file's version; a failing step rolls back and leaves the
 * file at the version before it. A file whose version is above STORE_SCHEMA_VERSION was written
 * by a newer program and is refused before anything is written to it. The file carries
 * application_id 'RIBB' so that an unrelated SQLite database is refused, not "migrated".
 *
 * Step 1 is the base schema as first shipped; it must never change (files in the field are at
 * version 1). Change the schema by appending a step. tests/daemon/store/test_store.c keeps its own
 * copy of the v1 script to check that migrating a real version 1 file preserves its data.
 *
 * Layout (units in the column names; NULL = missing, never NaN; times ISO-8601 UTC text):
 *   specimens        id | name UNIQUE | length_m width_m thickness_m | youngs_modulus_pa
 *                    density_kg_m3 material | crease_angle_left_deg crease_angle_right_deg
 *                    fold_position crease_orientation | trials_count |
 *                    crease_position_left crease_position_right folded_at (v5)
 *   trials           id | mode status state reason | config_text calibration_json |
 *                    specimen_id -> specimens | source_trial_id -> trials | video_path |
 *                    created_at started_at ended_at | snapped snap_dw_measured regime_measured |
 *                    software_version | samples_count (v3, kept by the sample writer) |
 *                    stop_cmd_latency_s stop_stand_latency_s (v4: snap-to-stop latency) |
 *                    video_bytes (v6: the size of video_path) |
 *                    crease_age_s (v5: the creases' age at the trial) |
 *                    camera_offset_s camera_offset_sd_s (v10: measured at the shear's start)
 *   samples          (trial_id -> trials, seq) | t_s kind frame | compress_mm shear_mm |
 *                    dl dw dz a quality reason                              (WITHOUT ROWID)
 *   events           id | trial_id -> trials | t_s wall_time state kind message
 *   predictions      id | trial_id -> trials | scene_hash | snapped snap_dw regime peak_abs_a |
 *                    nodes dt adaptive imperfection | est_error wall_s | software_version
 *                    solver_json created_at | status failure (v5) | crease_angle_left_deg _from
 *                    crease_angle_right_deg _from crease_position_left _from crease_position_right
 *                    _from (v5: what the prediction used, and 'scene' or 'specimen') |
 *                    crease_hinge crease_hinge_stiffness_nm_per_rad (v7: 'rigid' or 'compliant'
 *                    and its stiffness: the crease model the prediction ran)
 *   prediction_curve (prediction_id -> predictions, seq) | t_s dw dz a       (WITHOUT ROWID)
 *   ladder (v2)      (scene_hash, nodes, dt, adaptive) | snap_dw est_error wall_s
 *   specimens (v8)   + phi_deg (design fold angle) | state state_reason state_at
 *   queue_items (v8) id | kind | position (queued only) | specimen_id -> specimens | set_json note |
 *                    prompt fields_json values_json | status trial_id -> trials reason |
 *                    created_at started_at ended_at
 *   queue_state (v8) one row: running reason changed_at
 *   specimens (v12)  + calibration_json (the specimen's strip fitted to its trials, refreshed after
 *                    each) calibration_failure_json (the last refit's failure; NULL after a success)
 *   predictions (v12) + calibration_json (the specimen's calibration the prediction ran with: the
 *                    values that replaced the crease columns' (and E's), which stay the strip as
 *                    measured or designed; NULL = none) */
#include "store_schema.h"

#include <stdio.h>

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

/* v4: the snap-to-stop latency of a live trial (issue 13): from the frame in which the snap was
 * detected to the shear stop command's return, and to the first fresh reading of the shear rail
 * standing (s). NULL when there was no snap stop, or it was not seen standing before the return. */
static const char schema_v4[] =
    "ALTER TABLE trials ADD COLUMN stop_cmd_latency_s REAL CHECK (stop_cmd_latency_s >= 0);"
    "ALTER TABLE trials ADD COLUMN stop_stand_latency_s REAL CHECK (stop_stand_latency_s >= 0);"
    "PRAGMA user_version = 4;";

/* v5: the specimen in the prediction (issue 31). specimens: the measured crease positions and
 * when the creases were folded. trials: the creases' age at the trial. predictions: its status
 * ('done', or 'failed' with the reason: a failed prediction no longer stops its trial), and the
 * crease angles (deg, signed as the scene's folds.angle_deg) and positions (fraction of the free
 * length) it used, each with where it came from ('scene' or 'specimen'). Rows from before keep
 * NULL inputs and status 'done'. */
static const char schema_v5[] =
    "ALTER TABLE specimens ADD COLUMN crease_position_left REAL;"
    "ALTER TABLE specimens ADD COLUMN crease_position_right REAL;"
    "ALTER TABLE specimens ADD COLUMN folded_at TEXT;"
    "ALTER TABLE trials ADD COLUMN crease_age_s REAL CHECK (crease_age_s >= 0);"
    "ALTER TABLE predictions ADD COLUMN status TEXT NOT NULL DEFAULT 'done' CHECK (status IN ('done','failed'));"
    "ALTER TABLE predictions ADD COLUMN failure TEXT;"
    "ALTER TABLE predictions ADD COLUMN crease_angle_left_deg REAL;"
    "ALTER TABLE predictions ADD COLUMN crease_angle_left_from TEXT CHECK (crease_angle_left_from IN ('scene','specimen'));"
    "ALTER TABLE predictions ADD COLUMN crease_angle_right_deg REAL;"
    "ALTER TABLE predictions ADD COLUMN crease_angle_right_from TEXT CHECK (crease_angle_right_from IN ('scene','specimen'));"
    "ALTER TABLE predictions ADD COLUMN crease_position_left REAL;"
    "ALTER TABLE predictions ADD COLUMN crease_position_left_from TEXT CHECK (crease_position_left_from IN ('scene','specimen'));"
    "ALTER TABLE predictions ADD COLUMN crease_position_right REAL;"
    "ALTER TABLE predictions ADD COLUMN crease_position_right_from TEXT CHECK (crease_position_right_from IN ('scene','specimen'));"
    "PRAGMA user_version = 5;";

/* v6: the size of a trial's video file (issue 34, part D): the raw recording's at the trial's
 * end, then the lossless transcode's once verified (video_path names which). NULL = unknown. */
static const char schema_v6[] =
    "ALTER TABLE trials ADD COLUMN video_bytes INTEGER CHECK (video_bytes >= 0);"
    "PRAGMA user_version = 6;";

/* v7: the crease model a prediction ran (issue 31 follow-up): crease_hinge 'rigid' or
 * 'compliant', and for a compliant hinge its rotational stiffness (the scene's
 * folds.hinge_stiffness, N m/rad). Rows from before keep NULL (not recorded). */
static const char schema_v7[] =
    "ALTER TABLE predictions ADD COLUMN crease_hinge TEXT CHECK (crease_hinge IN ('rigid','compliant'));"
    "ALTER TABLE predictions ADD COLUMN crease_hinge_stiffness_nm_per_rad REAL"
    " CHECK (crease_hinge_stiffness_nm_per_rad > 0);"
    "PRAGMA user_version = 7;";

/* v8: the campaign (issue 35). A specimen's design fold angle and its state (new, in use,
 * retired, broken); the queue's items (a trial, an operator step, a pause) with their history,
 * and the queue's one state row (running or stopped, and why). Existing specimens read 'new'
 * (or 'in use' once trialled). At most one item runs (a partial unique index). */
static const char schema_v8[] =
    "ALTER TABLE specimens ADD COLUMN phi_deg REAL CHECK (phi_deg > 0 AND phi_deg < 180);"
    "ALTER TABLE specimens ADD COLUMN state TEXT NOT NULL DEFAULT 'new'"
    " CHECK (state IN ('new','in use','retired','broken'));"
    "ALTER TABLE specimens ADD COLUMN state_reason TEXT;"
    "ALTER TABLE specimens ADD COLUMN state_at TEXT;"
    "UPDATE specimens SET state = 'in use' WHERE trials_count > 0;"
    "CREATE TABLE queue_items ("
    " id INTEGER PRIMARY KEY,"
    " kind TEXT NOT NULL CHECK (kind IN ('trial','operator','pause')),"
    " position INTEGER CHECK (position >= 1),"
    " specimen_id INTEGER REFERENCES specimens(id),"
    " set_json TEXT NOT NULL DEFAULT '[]' CHECK (json_valid(set_json)),"
    " note TEXT, prompt TEXT,"
    " fields_json TEXT NOT NULL DEFAULT '[]' CHECK (json_valid(fields_json)),"
    " values_json TEXT CHECK (values_json IS NULL OR json_valid(values_json)),"
    " status TEXT NOT NULL DEFAULT 'queued'"
    "  CHECK (status IN ('queued','running','done','failed','aborted','skipped','unknown')),"
    " trial_id INTEGER REFERENCES trials(id),"
    " reason TEXT,"
    " created_at TEXT NOT NULL, started_at TEXT, ended_at TEXT,"
    " CHECK ((status = 'queued') = (position IS NOT NULL)));"
    "CREATE UNIQUE INDEX queue_one_running ON queue_items(status) WHERE status = 'running';"
    "CREATE INDEX queue_by_position ON queue_items(position) WHERE position IS NOT NULL;"
    "CREATE TABLE queue_state ("
    " id INTEGER PRIMARY KEY CHECK (id = 1),"
    " running INTEGER NOT NULL CHECK (running IN (0,1)),"
    " reason TEXT NOT NULL, changed_at TEXT NOT NULL);"
    "INSERT INTO queue_state VALUES (1, 0, 'never started', strftime('%Y-%m-%dT%H:%M:%fZ','now'));"
    "PRAGMA user_version = 8;";

/* v9: the planner's proposals (issue 35 part D): each next specimen the planner proposed, the
 * belief it was proposed from, and once approved the specimen made for it and its queue items. A
 * proposal is 'proposed' until approved once ('approved', final) or replaced by a newer plan's
 * ('superseded', final). */
static const char schema_v9[] =
    "CREATE TABLE plan_proposals ("
    " id INTEGER PRIMARY KEY,"
    " batch INTEGER NOT NULL CHECK (batch >= 1),"
    " phi_deg REAL NOT NULL CHECK (phi_deg > 0 AND phi_deg < 180),"
    " gamma REAL NOT NULL CHECK (gamma > 0 AND gamma < 0.5),"
    " sd_before REAL NOT NULL CHECK (sd_before >= 0),"
    " predicted_gamma REAL NOT NULL,"
    " offset_mean REAL NOT NULL, offset_sd REAL NOT NULL CHECK (offset_sd >= 0),"
    " calibrated INTEGER NOT NULL CHECK (calibrated IN (0,1)),"
    " status TEXT NOT NULL DEFAULT 'proposed' CHECK (status IN ('proposed','approved','superseded')),"
    " specimen_id INTEGER REFERENCES specimens(id),"
    " operator_item_id INTEGER REFERENCES queue_items(id),"
    " trial_item_id INTEGER REFERENCES queue_items(id),"
    " created_at TEXT NOT NULL, approved_at TEXT,"
    " CHECK ((status = 'approved') = (specimen_id IS NOT NULL AND trial_item_id IS NOT NULL)));"
    "PRAGMA user_version = 9;";

/* v10: the camera's time offset measured at the trial's shear start (issue 34 C,
 * daemon/trial/trial_cam_offset.h): t_shown = t_frame + offset, s, and its standard deviation.
 * NULL when not measured (rows from before, other modes, a fit that could not be made). */
static const char schema_v10[] =
    "ALTER TABLE trials ADD COLUMN camera_offset_s REAL;"
    "ALTER TABLE trials ADD COLUMN camera_offset_sd_s REAL CHECK (camera_offset_sd_s >= 0);"
    "PRAGMA user_version = 10;";

/* v11: the calibrated prediction beside the scene's (issue 32 B): the trial's own strip fitted to
 * its compression and hold (and shear frames before the snap, when refreshed), its snap with a
 * 1-sigma band, its regime and the probability of the other one, the fitted parameters with their
 * standard errors (fit_json), or the named reason the fit failed (fit_failure). NULL = no fit. */
static const char schema_v11[] =
    "ALTER TABLE trials ADD COLUMN snap_dw_calibrated REAL;"
    "ALTER TABLE trials ADD COLUMN snap_sd_calibrated REAL CHECK (snap_sd_calibrated >= 0);"
    "ALTER TABLE trials ADD COLUMN regime_calibrated TEXT"
    " CHECK (regime_calibrated IN ('symmetric','asymmetric','no snap'));"
    "ALTER TABLE trials ADD COLUMN p_other_calibrated REAL"
    " CHECK (p_other_calibrated >= 0 AND p_other_calibrated <= 1);"
    "ALTER TABLE trials ADD COLUMN fit_json TEXT CHECK (fit_json IS NULL OR json_valid(fit_json));"
    "ALTER TABLE trials ADD COLUMN fit_failure TEXT;"
    "PRAGMA user_version = 11;";

/* v12: a specimen's own calibration (issue 35 A): its strip fitted to all its finished trials,
 * refreshed by ribbond after each (daemon/trial/trial_specimen_calib.h): the fitted values with
 * their standard errors, the names the data do not determine, the residual, the trials used and
 * when (calibration_json); the last refit's named failure, the calibration before it kept
 * (calibration_failure_json, NULL after a success). A prediction records the specimen calibration
 * it ran with (calibration_json: each value it took and the measured or scene value it replaced);
 * its crease columns keep the strip as measured or designed, so the trial's strip reads back the
 * same whether or not it was calibrated. NULL = none. */
static const char schema_v12[] =
    "ALTER TABLE specimens ADD COLUMN calibration_json TEXT"
    " CHECK (calibration_json IS NULL OR json_valid(calibration_json));"
    "ALTER TABLE specimens ADD COLUMN calibration_failure_json TEXT"
    " CHECK (calibration_failure_json IS NULL OR json_valid(calibration_failure_json));"
    "ALTER TABLE predictions ADD COLUMN calibration_json TEXT"
    " CHECK (calibration_json IS NULL OR json_valid(calibration_json));"
    "PRAGMA user_version = 12;";

typedef struct store_migration {
    int version;      /* user_version after the step */
    const char *what; /* for reasons */
    const char *sql;
} store_migration;

static const store_migration migrations[] = {
    {1, "base schema", schema_v1},
    {2, "ladder cache and indexes", schema_v2},
    {3, "sample count per trial", schema_v3},
    {4, "snap-to-stop latency per trial", schema_v4},
    {5, "the specimen in the prediction, failed predictions", schema_v5},
    {6, "video file size per trial", schema_v6},
    {7, "the crease model of a prediction", schema_v7},
    {8, "specimen states and the queue", schema_v8},
    {9, "the planner's proposals", schema_v9},
    {10, "the camera's measured time offset per trial", schema_v10},
    {11, "the calibrated prediction per trial", schema_v11},
    {12, "a specimen's own calibration, and the one a prediction ran with", schema_v12},
};
#define N_MIGRATIONS (sizeof migrations / sizeof migrations[0])
_Static_assert(sizeof migrations / sizeof migrations[0] == STORE_SCHEMA_VERSION,
               "one migration step per schema version");

store_err store_schema_migrate(store *st, const char *path, char *why, size_t why_len)
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
        e = store_pragma_int(st, "PRAGMA user_version", &now, sub, sizeof sub);
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
            e = store_pragma_int(st, "PRAGMA user_version", &now, sub, sizeof sub);
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
store_err store_schema_check_identity(store *st, const char *path, char *why, size_t why_len)
{
    char sub[256];
    int version = 0, app = 0, tables = 0;
    store_err e = store_pragma_int(st, "PRAGMA user_version", &version, sub, sizeof sub);
    if (e == STORE_OK)
        e = store_pragma_int(st, "PRAGMA application_id", &app, sub, sizeof sub);
    if (e == STORE_OK)
        e = store_pragma_int(st, "SELECT count(*) FROM sqlite_master", &tables, sub, sizeof sub);
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
