/* store_trials.c: the trial records: creation, the status life cycle, the runner's state, the
 * measured result, the video path, the start-up sweep for trials a dead daemon left running,
 * and reading trials back.
 *
 * The life cycle is enforced here, not left to callers: created -> running -> an end state
 * (done, failed, aborted, interrupted), or created -> failed / aborted / interrupted (a daemon
 * killed while it predicted or computed the ladder). An end state is final,
 * so a late abort cannot overwrite "interrupted" and a restarted daemon cannot revive a trial.
 * Each transition is one UPDATE guarded by the allowed previous states, so it is atomic even
 * with several connections on the file. */
#include "store_sql.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

store_trial_def store_trial_def_default(void)
{
    return (store_trial_def){.mode = STORE_MODE_MOCK, .config_text = "", .created_wall_s = store_wall_now(),
                             .crease_age_s = NAN};
}

store_err store_trial_create(store *st, const store_trial_def *def, int64_t *id, char *why, size_t why_len)
{
    char created[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    if (!store_mode_name(def->mode))
        return store_fail(why, why_len, STORE_E_INVALID, "trial mode %d is not rig, mock or replay", (int)def->mode);
    if (!def->config_text)
        return store_fail(why, why_len, STORE_E_INVALID, "trial config_text is missing (give \"\" for none)");
    if (!store_wall_format(def->created_wall_s, created, sizeof created))
        return store_fail(why, why_len, STORE_E_INVALID, "trial created_wall_s %g is not a valid time",
                          def->created_wall_s);
    if ((e = store_need_json(def->calibration_json, "trial calibration_json", why, why_len)) ||
        (e = store_need_fits(def->video_path, sizeof((store_trial *)0)->video_path, "trial video_path", why,
                             why_len)) ||
        (e = store_need_fits(def->software_version, sizeof((store_trial *)0)->software_version,
                             "trial software_version", why, why_len)))
        return e;
    if (isinf(def->crease_age_s) || def->crease_age_s < 0.0) /* NaN compares false: unknown */
        return store_fail(why, why_len, STORE_E_INVALID,
                          "trial crease_age_s must be finite and >= 0 (got %g): the specimen folded after the trial?",
                          def->crease_age_s);
    if (def->specimen_id < 0 || def->source_trial_id < 0)
        return store_fail(why, why_len, STORE_E_INVALID, "trial specimen_id and source_trial_id must be >= 0");
    if (def->specimen_id && (e = store_lookup_id(st, "SELECT 1 FROM specimens WHERE id = ?1", def->specimen_id,
                                                 "specimen", "looking up a record", NULL, why, why_len)))
        return e;
    if (def->source_trial_id && (e = store_lookup_id(st, "SELECT 1 FROM trials WHERE id = ?1", def->source_trial_id,
                                                     "source trial", "looking up a record", NULL, why, why_len)))
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "INSERT INTO trials (mode, status, config_text, calibration_json, specimen_id,"
                      " source_trial_id, video_path, created_at, software_version, crease_age_s)"
                      " VALUES (?1, 'created', ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_text(s, 1, store_mode_name(def->mode), -1, SQLITE_STATIC);
    sqlite3_bind_text(s, 2, def->config_text, -1, SQLITE_TRANSIENT);
    store_bind_text(s, 3, def->calibration_json);
    store_bind_id(s, 4, def->specimen_id);
    store_bind_id(s, 5, def->source_trial_id);
    store_bind_text(s, 6, def->video_path);
    sqlite3_bind_text(s, 7, created, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(s, 8, def->software_version && *def->software_version ? def->software_version : RIBBON_VERSION,
                      -1, SQLITE_TRANSIENT);
    store_bind_real(s, 9, def->crease_age_s);
    int rc = sqlite3_step(s);
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "creating the trial");
    else if (id)
        *id = sqlite3_last_insert_rowid(st->db);
    sqlite3_finalize(s);
    return e;
}

static store_err status_of(store *st, int64_t id, store_status *out, char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, "SELECT status FROM trials WHERE id = ?1", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        if (!store_status_parse((const char *)sqlite3_column_text(s, 0), out))
            e = store_fail(why, why_len, STORE_E_CORRUPT, "trial %lld has an unknown status", (long long)id);
    } else if (rc == SQLITE_DONE) {
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "trial %lld does not exist", (long long)id);
    } else {
        e = store_sql_fail(st->db, rc, why, why_len, "reading a trial's status");
    }
    sqlite3_finalize(s);
    return e;
}

store_err store_trial_set_status(store *st, int64_t id, store_status status, const char *reason, double wall_s,
                                 char *why, size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    if (!store_status_name(status))
        return store_fail(why, why_len, STORE_E_INVALID, "trial status %d is unknown", (int)status);
    if (!store_wall_format(wall_s, when, sizeof when))
        return store_fail(why, why_len, STORE_E_INVALID, "wall time %g is not a valid time", wall_s);
    /* Allowed previous states of each target (two slots; NULL = unused). */
    const char *from1 = NULL, *from2 = NULL;
    switch (status) {
    case STORE_STATUS_RUNNING:
        from1 = "created";
        break;
    case STORE_STATUS_FAILED:
    case STORE_STATUS_ABORTED:
        from1 = "created";
        from2 = "running";
        break;
    case STORE_STATUS_DONE:
    case STORE_STATUS_INTERRUPTED:
        from1 = "running";
        break;
    default:
        break;
    }
    if (!from1)
        return store_fail(why, why_len, STORE_E_STATE, "a trial cannot be set back to '%s'",
                          store_status_name(status));
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "UPDATE trials SET status = ?1, reason = COALESCE(?2, reason),"
                      " started_at = COALESCE(?3, started_at), ended_at = COALESCE(?4, ended_at)"
                      " WHERE id = ?5 AND status IN (?6, ?7)",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_text(s, 1, store_status_name(status), -1, SQLITE_STATIC);
    store_bind_text(s, 2, reason);
    store_bind_text(s, 3, status == STORE_STATUS_RUNNING ? when : NULL);
    store_bind_text(s, 4, status == STORE_STATUS_RUNNING ? NULL : when);
    sqlite3_bind_int64(s, 5, id);
    sqlite3_bind_text(s, 6, from1, -1, SQLITE_STATIC);
    store_bind_text(s, 7, from2);
    int rc = sqlite3_step(s);
    int changed = sqlite3_changes(st->db);
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "setting a trial's status");
    sqlite3_finalize(s);
    if (e != STORE_OK || changed > 0)
        return e;
    store_status now;
    e = status_of(st, id, &now, why, why_len);
    if (e != STORE_OK)
        return e;
    return store_fail(why, why_len, STORE_E_STATE, "trial %lld is '%s'; it cannot become '%s'", (long long)id,
                      store_status_name(now), store_status_name(status));
}

/* One UPDATE of one trial's columns from a prepared statement whose last parameter is the id. */
static store_err update_one(store *st, sqlite3_stmt *s, int64_t id, const char *what, char *why, size_t why_len)
{
    store_err e = STORE_OK;
    int rc = sqlite3_step(s);
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, what);
    else if (sqlite3_changes(st->db) == 0)
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "trial %lld does not exist", (long long)id);
    sqlite3_finalize(s);
    return e;
}

store_err store_trial_set_state(store *st, int64_t id, const char *state, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e == STORE_OK)
        e = store_need_fits(state, sizeof((store_trial *)0)->state, "trial state", why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st, "UPDATE trials SET state = ?1 WHERE id = ?2", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    store_bind_text(s, 1, state);
    sqlite3_bind_int64(s, 2, id);
    return update_one(st, s, id, "setting a trial's state", why, why_len);
}

store_err store_trial_set_result(store *st, int64_t id, bool snapped, double snap_dw, store_regime regime,
                                 char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    if (snapped) {
        if ((e = store_need_finite(snap_dw, "measured snap_dw", why, why_len)))
            return e;
        if (regime == STORE_REGIME_NO_SNAP || regime < 0 || regime >= STORE_REGIME_COUNT)
            return store_fail(why, why_len, STORE_E_INVALID,
                              "a snapped trial's regime must be symmetric, asymmetric or unknown");
    } else {
        if (!isnan(snap_dw))
            return store_fail(why, why_len, STORE_E_INVALID,
                              "a trial without a snap has no snap_dw (got %g; pass NaN)", snap_dw);
        if (regime != STORE_REGIME_NO_SNAP)
            return store_fail(why, why_len, STORE_E_INVALID, "a trial without a snap has regime 'no snap'");
    }
    sqlite3_stmt *s;
    e = store_prepare(st, "UPDATE trials SET snapped = ?1, snap_dw_measured = ?2, regime_measured = ?3 WHERE id = ?4",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int(s, 1, snapped ? 1 : 0);
    store_bind_real(s, 2, snap_dw);
    sqlite3_bind_text(s, 3, store_regime_name(regime), -1, SQLITE_STATIC);
    sqlite3_bind_int64(s, 4, id);
    return update_one(st, s, id, "saving a trial's result", why, why_len);
}

store_err store_trial_set_latency(store *st, int64_t id, double stop_cmd_s, double stop_stand_s, char *why,
                                  size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    const double v[2] = {stop_cmd_s, stop_stand_s};
    const char *name[2] = {"stop_cmd_latency_s", "stop_stand_latency_s"};
    for (int k = 0; k < 2; k++)
        if (!isnan(v[k]) && !(isfinite(v[k]) && v[k] >= 0.0))
            return store_fail(why, why_len, STORE_E_INVALID, "trial %s %g: a latency is finite and not negative",
                              name[k], v[k]);
    sqlite3_stmt *s;
    e = store_prepare(st, "UPDATE trials SET stop_cmd_latency_s = ?1, stop_stand_latency_s = ?2 WHERE id = ?3", &s,
                      why, why_len);
    if (e != STORE_OK)
        return e;
    store_bind_real(s, 1, stop_cmd_s);
    store_bind_real(s, 2, stop_stand_s);
    sqlite3_bind_int64(s, 3, id);
    return update_one(st, s, id, "saving a trial's snap-to-stop latency", why, why_len);
}

store_err store_trial_set_camera_offset(store *st, int64_t id, double offset_s, double sd_s, char *why,
                                        size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    if (!isfinite(offset_s) || !(isfinite(sd_s) && sd_s >= 0.0))
        return store_fail(why, why_len, STORE_E_INVALID,
                          "trial camera_offset_s %g, camera_offset_sd_s %g: finite, and the deviation not negative",
                          offset_s, sd_s);
    sqlite3_stmt *s;
    e = store_prepare(st, "UPDATE trials SET camera_offset_s = ?1, camera_offset_sd_s = ?2 WHERE id = ?3", &s, why,
                      why_len);
    if (e != STORE_OK)
        return e;
    store_bind_real(s, 1, offset_s);
    store_bind_real(s, 2, sd_s);
    sqlite3_bind_int64(s, 3, id);
    return update_one(st, s, id, "saving a trial's camera offset", why, why_len);
}

store_err store_trial_set_video(store *st, int64_t id, const char *video_path, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e == STORE_OK)
        e = store_need_fits(video_path, sizeof((store_trial *)0)->video_path, "trial video_path", why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st, "UPDATE trials SET video_path = ?1 WHERE id = ?2", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    store_bind_text(s, 1, video_path);
    sqlite3_bind_int64(s, 2, id);
    return update_one(st, s, id, "saving a trial's video path", why, why_len);
}

store_err store_trial_set_video_file(store *st, int64_t id, const char *video_path, int64_t bytes, const int roi[4],
                                     char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e == STORE_OK && (!video_path || !*video_path || bytes < 0))
        e = store_fail(why, why_len, STORE_E_INVALID, "a trial's video file needs a path and a size >= 0 (%lld)",
                       (long long)bytes);
    if (e == STORE_OK)
        e = store_need_fits(video_path, sizeof((store_trial *)0)->video_path, "trial video_path", why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "UPDATE trials SET video_path = ?1, video_bytes = ?2, calibration_json = CASE WHEN ?4 IS NULL"
                      " OR calibration_json IS NULL THEN calibration_json"
                      " ELSE json_set(calibration_json, '$.roi', json(?4)) END WHERE id = ?3",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    store_bind_text(s, 1, video_path);
    sqlite3_bind_int64(s, 2, bytes);
    sqlite3_bind_int64(s, 3, id);
    char r[96];
    if (roi) {
        snprintf(r, sizeof r, "[%d,%d,%d,%d]", roi[0], roi[1], roi[2], roi[3]);
        store_bind_text(s, 4, r);
    }
    return update_one(st, s, id, "saving a trial's video file", why, why_len);
}

store_err store_trial_mark_interrupted(store *st, double wall_s, int *count, char *why, size_t why_len)
{
    char when[32];
    if (count)
        *count = 0;
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    if (!store_wall_format(wall_s, when, sizeof when))
        return store_fail(why, why_len, STORE_E_INVALID, "wall time %g is not a valid time", wall_s);
    static const char *const sql[2] = {
        "INSERT INTO events (trial_id, t_s, wall_time, state, kind, message)"
        " SELECT id, NULL, ?1, state, 'fault', CASE status WHEN 'running' THEN"
        " 'interrupted: the daemon stopped while this trial was running (found at start-up)' ELSE"
        " 'interrupted: the daemon stopped before this trial started (found at start-up)' END"
        " FROM trials WHERE status IN ('running', 'created') ORDER BY id",
        "UPDATE trials SET status = 'interrupted', ended_at = ?1,"
        " reason = COALESCE(reason, CASE status WHEN 'running' THEN"
        " 'the daemon stopped while the trial was running' ELSE"
        " 'the daemon stopped before the trial started' END)"
        " WHERE status IN ('running', 'created')",
    };
    if ((e = store_begin(st, why, why_len)))
        return e;
    int changed = 0;
    for (int i = 0; i < 2 && e == STORE_OK; i++) {
        sqlite3_stmt *s;
        e = store_prepare(st, sql[i], &s, why, why_len);
        if (e != STORE_OK)
            break;
        sqlite3_bind_text(s, 1, when, -1, SQLITE_TRANSIENT);
        int rc = sqlite3_step(s);
        if (rc != SQLITE_DONE)
            e = store_sql_fail(st->db, rc, why, why_len, "marking unfinished trials interrupted");
        changed = sqlite3_changes(st->db);
        sqlite3_finalize(s);
    }
    if (e == STORE_OK)
        e = store_commit(st, why, why_len);
    if (e != STORE_OK) {
        store_rollback(st);
        return e;
    }
    if (count)
        *count = changed;
    return STORE_OK;
}

#define TRIAL_COLUMNS                                                                                       \
    "SELECT t.id, t.mode, t.status, t.state, t.reason, t.specimen_id, s.name, t.source_trial_id,"           \
    " t.video_path, t.created_at, t.started_at, t.ended_at, t.snapped, t.snap_dw_measured,"                 \
    " t.regime_measured, t.software_version, t.samples_count, t.stop_cmd_latency_s, t.stop_stand_latency_s,"                                              \
    " t.crease_age_s, t.video_bytes"                                                                        \
    " FROM trials t LEFT JOIN specimens s ON s.id = t.specimen_id "

/* The shared trial row behind store_trial_get/_list. */
static store_err store_trial_read_row(sqlite3_stmt *s, store_trial *out)
{
    memset(out, 0, sizeof *out);
    out->id = sqlite3_column_int64(s, 0);
    if (!store_mode_parse((const char *)sqlite3_column_text(s, 1), &out->mode) ||
        !store_status_parse((const char *)sqlite3_column_text(s, 2), &out->status))
        return STORE_E_CORRUPT;
    store_col_text(s, 3, out->state, sizeof out->state);
    store_col_text(s, 4, out->reason, sizeof out->reason);
    out->specimen_id = store_col_id(s, 5);
    store_col_text(s, 6, out->specimen_name, sizeof out->specimen_name);
    out->source_trial_id = store_col_id(s, 7);
    store_col_text(s, 8, out->video_path, sizeof out->video_path);
    store_col_text(s, 9, out->created_at, sizeof out->created_at);
    store_col_text(s, 10, out->started_at, sizeof out->started_at);
    store_col_text(s, 11, out->ended_at, sizeof out->ended_at);
    out->snapped = sqlite3_column_type(s, 12) == SQLITE_NULL ? -1 : sqlite3_column_int(s, 12);
    out->snap_dw_measured = store_col_real(s, 13);
    out->regime_measured = STORE_REGIME_UNKNOWN;
    if (sqlite3_column_type(s, 14) != SQLITE_NULL &&
        !store_regime_parse((const char *)sqlite3_column_text(s, 14), &out->regime_measured))
        return STORE_E_CORRUPT;
    store_col_text(s, 15, out->software_version, sizeof out->software_version);
    out->samples = sqlite3_column_int64(s, 16);
    out->stop_cmd_latency_s = store_col_real(s, 17);
    out->stop_stand_latency_s = store_col_real(s, 18);
    out->crease_age_s = store_col_real(s, 19);
    out->video_bytes = sqlite3_column_type(s, 20) == SQLITE_NULL ? -1 : sqlite3_column_int64(s, 20);
    return STORE_OK;
}

store_err store_trial_get(store *st, int64_t id, store_trial *out, char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, TRIAL_COLUMNS "WHERE t.id = ?1", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        if (store_trial_read_row(s, out) != STORE_OK)
            e = store_fail(why, why_len, STORE_E_CORRUPT, "trial %lld has an unknown mode, status or regime",
                           (long long)id);
    } else if (rc == SQLITE_DONE) {
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "trial %lld does not exist", (long long)id);
    } else {
        e = store_sql_fail(st->db, rc, why, why_len, "reading a trial");
    }
    sqlite3_finalize(s);
    return e;
}

store_err store_trial_list(store *st, store_trial **out, size_t *n, char *why, size_t why_len)
{
    *out = NULL;
    *n = 0;
    sqlite3_stmt *s;
    store_err e = store_prepare(st, TRIAL_COLUMNS "ORDER BY t.id", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    store_trial *v = NULL;
    size_t len = 0, cap = 0;
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
        store_trial *nv = store_grow(v, len, &cap, sizeof *v, 16);
        if (!nv) {
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory listing trials");
            break;
        }
        v = nv;
        if (store_trial_read_row(s, &v[len]) != STORE_OK) {
            e = store_fail(why, why_len, STORE_E_CORRUPT, "trial %lld has an unknown mode, status or regime",
                           (long long)sqlite3_column_int64(s, 0));
            break;
        }
        len++;
    }
    if (e == STORE_OK && rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "listing trials");
    sqlite3_finalize(s);
    if (e != STORE_OK) {
        free(v);
        return e;
    }
    *out = v;
    *n = len;
    return STORE_OK;
}

store_err store_trial_texts(store *st, int64_t id, char **config_text, char **calibration_json, char *why,
                            size_t why_len)
{
    if (config_text)
        *config_text = NULL;
    if (calibration_json)
        *calibration_json = NULL;
    sqlite3_stmt *s;
    store_err e = store_prepare(st, "SELECT config_text, calibration_json FROM trials WHERE id = ?1", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        char *c = config_text ? store_col_strdup(s, 0) : NULL;
        char *k = calibration_json ? store_col_strdup(s, 1) : NULL;
        if ((config_text && !c) || (calibration_json && !k && sqlite3_column_type(s, 1) != SQLITE_NULL)) {
            free(c);
            free(k);
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory reading trial %lld", (long long)id);
        } else {
            if (config_text)
                *config_text = c;
            if (calibration_json)
                *calibration_json = k;
        }
    } else if (rc == SQLITE_DONE) {
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "trial %lld does not exist", (long long)id);
    } else {
        e = store_sql_fail(st->db, rc, why, why_len, "reading a trial's texts");
    }
    sqlite3_finalize(s);
    return e;
}
