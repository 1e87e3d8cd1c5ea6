/* store_json.c: trials as JSON for the control API and `ribbonctl list/show --json`: each trial
 * beside its latest prediction, its sample count and its specimen, from one query. A missing
 * number or text is JSON null, never NaN (jansson would refuse NaN anyway) and never "".
 * Text from the database that is not valid UTF-8 (a device's raw reply in a reason, say) is
 * passed with the offending bytes replaced by '?', so one bad byte cannot drop a key. */
#include "store_sql.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TRIAL_JSON_SELECT                                                                                   \
    "SELECT t.id, t.mode, t.status, t.state, t.reason, t.snapped, t.snap_dw_measured, t.regime_measured,"   \
    " t.video_path, t.source_trial_id, s.name, t.created_at, t.started_at, t.ended_at,"                     \
    " t.software_version, t.samples_count,"                                                                 \
    " p.id, p.snap_dw, p.regime, p.nodes, p.dt, p.adaptive, p.est_error, p.wall_s, p.imperfection,"          \
    " p.scene_hash, t.calibration_json, t.stop_cmd_latency_s, t.stop_stand_latency_s, t.crease_age_s,"     \
    " p.status, p.failure, p.crease_angle_left_deg, p.crease_angle_left_from, p.crease_angle_right_deg,"    \
    " p.crease_angle_right_from, p.crease_position_left, p.crease_position_left_from,"                     \
    " p.crease_position_right, p.crease_position_right_from, t.video_bytes, p.crease_hinge,"               \
    " p.crease_hinge_stiffness_nm_per_rad, t.snap_dw_calibrated, t.snap_sd_calibrated, t.regime_calibrated,"  \
    " t.p_other_calibrated, t.fit_json, t.fit_failure, p.calibration_json"                                 \
    " FROM trials t LEFT JOIN specimens s ON s.id = t.specimen_id"                                          \
    " LEFT JOIN predictions p ON p.id = (SELECT max(id) FROM predictions WHERE trial_id = t.id) "

enum { C_ID, C_MODE, C_STATUS, C_STATE, C_REASON, C_SNAPPED, C_SNAP_DW, C_REGIME, C_VIDEO, C_SOURCE, C_SPECIMEN,
       C_CREATED, C_STARTED, C_ENDED, C_VERSION, C_SAMPLES, C_P_ID, C_P_SNAP_DW, C_P_REGIME, C_P_NODES, C_P_DT,
       C_P_ADAPTIVE, C_P_EST_ERROR, C_P_WALL_S, C_P_IMPERFECTION, C_P_HASH, C_CALIBRATION, C_STOP_CMD,
       C_STOP_STAND, C_CREASE_AGE, C_P_STATUS, C_P_FAILURE, C_P_CREASES /* 8 columns: value, source */,
       C_VIDEO_BYTES = C_P_CREASES + 8, C_P_HINGE, C_P_HINGE_K, C_CAL_SNAP_DW, C_CAL_SNAP_SD,
       C_CAL_REGIME, C_CAL_P_OTHER, C_CAL_FIT, C_CAL_FAILURE, C_P_CALIBRATION };

static json_t *jreal(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

static json_t *jtext_of(const char *t, size_t n)
{
    if (!t)
        return json_null();
    json_t *j = json_stringn(t, n);
    if (j)
        return j;
    char *c = malloc(n + 1); /* invalid UTF-8: keep ASCII, replace the rest */
    if (!c)
        return NULL;
    for (size_t i = 0; i < n; i++)
        c[i] = ((unsigned char)t[i] < 0x80 && t[i] != '\0') ? t[i] : '?';
    c[n] = '\0';
    j = json_stringn(c, n);
    free(c);
    return j;
}

/* A text column, null when NULL. */
static json_t *jcol_text(sqlite3_stmt *s, int i)
{
    const char *t = (const char *)sqlite3_column_text(s, i);
    return t ? jtext_of(t, (size_t)sqlite3_column_bytes(s, i)) : json_null();
}

static json_t *jcol_int(sqlite3_stmt *s, int i)
{
    return sqlite3_column_type(s, i) == SQLITE_NULL ? json_null() : json_integer(sqlite3_column_int64(s, i));
}

static json_t *jcol_real(sqlite3_stmt *s, int i)
{
    return jreal(store_col_real(s, i));
}

static json_t *jcol_bool(sqlite3_stmt *s, int i)
{
    return sqlite3_column_type(s, i) == SQLITE_NULL ? json_null() : json_boolean(sqlite3_column_int(s, i) != 0);
}

/* Set every key; false if any value could not be made (out of memory). */
static bool set(json_t *o, const char *key, json_t *v)
{
    return v && json_object_set_new(o, key, v) == 0;
}

/* The creases a prediction used: {angle_left_deg, angle_left_from, ..., hinge_stiffness}; null
 * values and sources for rows from before schema 5; hinge_stiffness is the number (N m/rad) of a
 * compliant hinge, "rigid", or null for rows from before schema 7. */
static json_t *creases_object(sqlite3_stmt *s)
{
    static const char *const keys[8] = {"angle_left_deg", "angle_left_from",  "angle_right_deg",
                                        "angle_right_from", "position_left", "position_left_from",
                                        "position_right", "position_right_from"};
    json_t *c = json_object();
    bool ok = c != NULL;
    for (int k = 0; ok && k < 8; k += 2)
        ok = set(c, keys[k], jcol_real(s, C_P_CREASES + k)) && set(c, keys[k + 1], jcol_text(s, C_P_CREASES + k + 1));
    const char *hinge = (const char *)sqlite3_column_text(s, C_P_HINGE);
    if (ok)
        ok = set(c, "hinge_stiffness",
                 !hinge ? json_null() : !strcmp(hinge, "rigid") ? json_string("rigid") : jcol_real(s, C_P_HINGE_K));
    if (!ok) {
        json_decref(c);
        return NULL;
    }
    return c;
}

/* A JSON column (valid JSON on the way in: fit_json, the prediction's calibration_json), or null. */
static json_t *json_col(sqlite3_stmt *s, int col)
{
    const char *f = (const char *)sqlite3_column_text(s, col);
    json_t *j = f ? json_loads(f, JSON_DECODE_ANY, NULL) : NULL;
    return j ? j : json_null();
}

static json_t *trial_object(sqlite3_stmt *s)
{
    json_t *o = json_object();
    if (!o)
        return NULL;
    bool ok = set(o, "id", jcol_int(s, C_ID)) && set(o, "mode", jcol_text(s, C_MODE)) &&
              set(o, "status", jcol_text(s, C_STATUS)) && set(o, "state", jcol_text(s, C_STATE)) &&
              set(o, "reason", jcol_text(s, C_REASON)) && set(o, "snapped", jcol_bool(s, C_SNAPPED)) &&
              set(o, "snap_dw_measured", jcol_real(s, C_SNAP_DW)) &&
              set(o, "snap_dw_predicted", jcol_real(s, C_P_SNAP_DW)) &&
              set(o, "regime_measured", jcol_text(s, C_REGIME)) &&
              set(o, "regime_predicted", jcol_text(s, C_P_REGIME)) && set(o, "samples", jcol_int(s, C_SAMPLES)) &&
              set(o, "video_path", jcol_text(s, C_VIDEO)) && set(o, "video_bytes", jcol_int(s, C_VIDEO_BYTES)) && set(o, "source_trial", jcol_int(s, C_SOURCE)) &&
              set(o, "specimen", jcol_text(s, C_SPECIMEN)) && set(o, "created", jcol_text(s, C_CREATED)) &&
              set(o, "started", jcol_text(s, C_STARTED)) && set(o, "ended", jcol_text(s, C_ENDED)) &&
              set(o, "software_version", jcol_text(s, C_VERSION)) &&
              set(o, "stop_cmd_latency_s", jcol_real(s, C_STOP_CMD)) &&
              set(o, "stop_stand_latency_s", jcol_real(s, C_STOP_STAND)) &&
              set(o, "crease_age_s", jcol_real(s, C_CREASE_AGE)) &&
              set(o, "snap_dw_calibrated", jcol_real(s, C_CAL_SNAP_DW)) &&
              set(o, "snap_sd_calibrated", jcol_real(s, C_CAL_SNAP_SD)) &&
              set(o, "regime_calibrated", jcol_text(s, C_CAL_REGIME)) &&
              set(o, "p_other_regime_calibrated", jcol_real(s, C_CAL_P_OTHER)) &&
              set(o, "fit_failure", jcol_text(s, C_CAL_FAILURE)) && set(o, "fit", json_col(s, C_CAL_FIT));
    if (ok && sqlite3_column_type(s, C_P_ID) == SQLITE_NULL) {
        ok = set(o, "prediction", json_null());
    } else if (ok) {
        json_t *p = json_object();
        ok = p && set(p, "id", jcol_int(s, C_P_ID)) && set(p, "status", jcol_text(s, C_P_STATUS)) &&
             set(p, "failure", jcol_text(s, C_P_FAILURE)) && set(p, "creases", creases_object(s)) &&
             set(p, "nodes", jcol_int(s, C_P_NODES)) &&
             set(p, "dt", jcol_real(s, C_P_DT)) && set(p, "adaptive", jcol_bool(s, C_P_ADAPTIVE)) &&
             set(p, "est_error", jcol_real(s, C_P_EST_ERROR)) && set(p, "wall_s", jcol_real(s, C_P_WALL_S)) &&
             set(p, "imperfection", jcol_real(s, C_P_IMPERFECTION)) && set(p, "scene_hash", jcol_text(s, C_P_HASH)) &&
             set(p, "calibration", json_col(s, C_P_CALIBRATION));
        if (!ok)
            json_decref(p);
        else
            ok = set(o, "prediction", p);
    }
    if (!ok) {
        json_decref(o);
        return NULL;
    }
    return o;
}

static json_t *events_array(store *st, int64_t id, char *why, size_t why_len, store_err *e)
{
    store_event *ev = NULL;
    size_t n = 0;
    *e = store_events_get(st, id, &ev, &n, why, why_len);
    if (*e != STORE_OK)
        return NULL;
    json_t *a = json_array();
    for (size_t i = 0; a && i < n; i++) {
        json_t *o = json_object();
        bool ok = o && set(o, "t_s", jreal(ev[i].t_s)) &&
                  set(o, "wall_time", jtext_of(ev[i].wall_time, strlen(ev[i].wall_time))) &&
                  set(o, "state", ev[i].state[0] ? jtext_of(ev[i].state, strlen(ev[i].state)) : json_null()) &&
                  set(o, "kind", json_string(store_event_kind_name(ev[i].kind))) &&
                  set(o, "message", jtext_of(ev[i].message, strlen(ev[i].message)));
        if (!ok)
            json_decref(o);
        if (!ok || json_array_append_new(a, o) != 0) { /* append_new releases o on failure */
            json_decref(a);
            a = NULL;
        }
    }
    free(ev);
    if (!a)
        *e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory building trial %lld's events", (long long)id);
    return a;
}

store_err store_trial_json(store *st, int64_t id, json_t **out, char *why, size_t why_len)
{
    *out = NULL;
    sqlite3_stmt *s;
    store_err e = store_prepare(st, TRIAL_JSON_SELECT "WHERE t.id = ?1", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    json_t *o = NULL;
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        o = trial_object(s);
        if (!o) {
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory building trial %lld's JSON", (long long)id);
        } else {
            const char *cal = (const char *)sqlite3_column_text(s, C_CALIBRATION);
            json_t *c = cal ? json_loads(cal, JSON_DECODE_ANY, NULL) : NULL;
            /* Stored calibration always parsed on the way in; a null here means none. */
            if (!set(o, "calibration", c ? c : json_null()))
                e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory building trial %lld's JSON", (long long)id);
        }
    } else if (rc == SQLITE_DONE) {
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "trial %lld does not exist", (long long)id);
    } else {
        e = store_sql_fail(st->db, rc, why, why_len, "reading a trial");
    }
    sqlite3_finalize(s);
    if (e == STORE_OK) {
        json_t *ev = events_array(st, id, why, why_len, &e);
        if (e == STORE_OK && !set(o, "events", ev))
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory building trial %lld's JSON", (long long)id);
    }
    if (e != STORE_OK) {
        json_decref(o);
        return e;
    }
    *out = o;
    return STORE_OK;
}

store_err store_trials_json(store *st, json_t **out_array, char *why, size_t why_len)
{
    *out_array = NULL;
    sqlite3_stmt *s;
    store_err e = store_prepare(st, TRIAL_JSON_SELECT "ORDER BY t.id", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    json_t *a = json_array();
    if (!a)
        e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory listing trials");
    int rc = SQLITE_DONE;
    while (e == STORE_OK && (rc = sqlite3_step(s)) == SQLITE_ROW) {
        json_t *o = trial_object(s);
        if (!o || json_array_append_new(a, o) != 0)
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory listing trials");
    }
    if (e == STORE_OK && rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "listing trials");
    sqlite3_finalize(s);
    if (e != STORE_OK) {
        json_decref(a);
        return e;
    }
    *out_array = a;
    return STORE_OK;
}
