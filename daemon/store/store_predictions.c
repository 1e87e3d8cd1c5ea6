/* store_predictions.c: the simulator's predictions and their curves. A prediction keeps what is
 * needed to reproduce it (scene hash, resolution, imperfection, solver settings, software
 * version) beside what it predicted (snap, regime, peak |A|, curve) and what it cost (wall_s,
 * estimated error). A row and its curve go in one transaction and are never changed afterwards;
 * a trial's prediction is its latest row. A failed prediction is a row too (status 'failed', its
 * reason in failure, no snap and no curve), so a trial says why it has no prediction. Each row
 * records the creases it used (angles and positions) and where each came from (scene, specimen). */
#include "store_curve.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

store_prediction store_prediction_default(void)
{
    store_prediction p;
    memset(&p, 0, sizeof p);
    p.snap_dw = p.peak_abs_a = p.dt = p.imperfection = p.est_error = p.wall_s = NAN;
    p.regime = STORE_REGIME_UNKNOWN;
    p.creases = store_creases_unknown();
    return p;
}

store_creases store_creases_unknown(void)
{
    store_creases c;
    memset(&c, 0, sizeof c);
    for (int k = 0; k < 2; k++) c.angle_deg[k] = c.position[k] = NAN;
    c.hinge_stiffness = NAN;
    return c;
}

/* A recorded crease value has a source, and a source a finite value; a hinge is positive
 * (infinite: rigid) or not recorded. */
static store_err check_creases(const store_creases *c, char *why, size_t why_len)
{
    if (c->hinge_stiffness <= 0.0)
        return store_fail(why, why_len, STORE_E_INVALID,
                          "prediction crease hinge_stiffness %g: must be > 0 N m/rad (infinite: rigid; NaN: not recorded)",
                          c->hinge_stiffness);
    for (int k = 0; k < 2; k++) {
        const char *side = k ? "right" : "left";
        if ((unsigned)c->angle_from[k] >= STORE_SOURCE_COUNT || (unsigned)c->position_from[k] >= STORE_SOURCE_COUNT)
            return store_fail(why, why_len, STORE_E_INVALID, "prediction crease %s: unknown source", side);
        if (isinf(c->angle_deg[k]) || isinf(c->position[k]) ||
            isnan(c->angle_deg[k]) != (c->angle_from[k] == STORE_SOURCE_UNKNOWN) ||
            isnan(c->position[k]) != (c->position_from[k] == STORE_SOURCE_UNKNOWN))
            return store_fail(why, why_len, STORE_E_INVALID,
                              "prediction crease %s: a value needs its source and a source its finite value", side);
    }
    return STORE_OK;
}

static store_err check(const store_prediction *p, char *why, size_t why_len)
{
    store_err e;
    if (!memchr(p->scene_hash, '\0', sizeof p->scene_hash) ||
        !memchr(p->software_version, '\0', sizeof p->software_version))
        return store_fail(why, why_len, STORE_E_INVALID, "prediction text field not NUL-terminated");
    if (!p->scene_hash[0])
        return store_fail(why, why_len, STORE_E_INVALID, "prediction scene_hash is empty");
    if (p->trial_id < 0)
        return store_fail(why, why_len, STORE_E_INVALID, "prediction trial_id must be >= 0 (0 = none)");
    if (!memchr(p->failure, '\0', sizeof p->failure))
        return store_fail(why, why_len, STORE_E_INVALID, "prediction failure text not NUL-terminated");
    if ((e = check_creases(&p->creases, why, why_len)))
        return e;
    if (p->status == STORE_PREDICTION_FAILED) {
        if (!p->failure[0])
            return store_fail(why, why_len, STORE_E_INVALID, "a failed prediction needs its reason (failure)");
        if (p->snapped || !isnan(p->snap_dw) || p->regime != STORE_REGIME_UNKNOWN || p->curve.n > 0)
            return store_fail(why, why_len, STORE_E_INVALID,
                              "a failed prediction has no snap, snap_dw, regime or curve");
    } else if (p->status != STORE_PREDICTION_DONE) {
        return store_fail(why, why_len, STORE_E_INVALID, "prediction status %d is not done or failed", (int)p->status);
    } else if (p->failure[0]) {
        return store_fail(why, why_len, STORE_E_INVALID, "a prediction that is done has no failure text");
    } else if (p->snapped) {
        if ((e = store_need_finite(p->snap_dw, "predicted snap_dw", why, why_len)))
            return e;
        if (p->regime != STORE_REGIME_SYMMETRIC && p->regime != STORE_REGIME_ASYMMETRIC)
            return store_fail(why, why_len, STORE_E_INVALID,
                              "a predicted snap's regime must be symmetric or asymmetric");
    } else {
        if (!isnan(p->snap_dw))
            return store_fail(why, why_len, STORE_E_INVALID,
                              "a prediction without a snap has no snap_dw (got %g; pass NaN)", p->snap_dw);
        if (p->regime != STORE_REGIME_NO_SNAP)
            return store_fail(why, why_len, STORE_E_INVALID, "a prediction without a snap has regime 'no snap'");
    }
    if (p->nodes < 2)
        return store_fail(why, why_len, STORE_E_INVALID, "prediction nodes must be >= 2 (got %d)", p->nodes);
    if ((e = store_need_positive(p->dt, "prediction dt", why, why_len)) ||
        (e = store_need_finite(p->imperfection, "prediction imperfection", why, why_len)) ||
        (e = store_need_finite(p->wall_s, "prediction wall_s", why, why_len)) ||
        (e = store_need_not_inf(p->peak_abs_a, "prediction peak_abs_a", why, why_len)) ||
        (e = store_need_not_inf(p->est_error, "prediction est_error", why, why_len)) ||
        (e = store_need_json(p->solver_json, "prediction solver_json", why, why_len)) ||
        (e = store_need_json(p->calibration_json, "prediction calibration_json", why, why_len)))
        return e;
    if (p->calibration_json && p->calibration_json[0] != '{')
        return store_fail(why, why_len, STORE_E_INVALID, "prediction calibration_json must be a JSON object");
    if (p->wall_s < 0.0 || p->peak_abs_a < 0.0 || p->est_error < 0.0) /* NaN compares false */
        return store_fail(why, why_len, STORE_E_INVALID, "prediction wall_s, peak_abs_a and est_error must be >= 0");
    const store_curve *c = &p->curve;
    if (c->n > 0 && (!c->t_s || !c->dw))
        return store_fail(why, why_len, STORE_E_INVALID, "prediction curve of %zu points without t_s or dw", c->n);
    for (size_t i = 0; i < c->n; i++) {
        if (!isfinite(c->t_s[i]) || !isfinite(c->dw[i]) || (c->dz && isinf(c->dz[i])) || (c->a && isinf(c->a[i])))
            return store_fail(why, why_len, STORE_E_INVALID,
                              "prediction curve point %zu: t_s and dw must be finite, dz and a finite or NaN", i);
    }
    return STORE_OK;
}

static store_err insert_curve(store *st, int64_t pid, const store_curve *c, char *why, size_t why_len)
{
    if (c->n == 0)
        return STORE_OK;
    sqlite3_stmt *s;
    store_err e = store_prepare(st,
                                "INSERT INTO prediction_curve (prediction_id, seq, t_s, dw, dz, a)"
                                " VALUES (?1,?2,?3,?4,?5,?6)",
                                &s, why, why_len);
    if (e != STORE_OK)
        return e;
    for (size_t i = 0; i < c->n && e == STORE_OK; i++) {
        sqlite3_reset(s);
        sqlite3_bind_int64(s, 1, pid);
        sqlite3_bind_int64(s, 2, (int64_t)i);
        sqlite3_bind_double(s, 3, c->t_s[i]);
        sqlite3_bind_double(s, 4, c->dw[i]);
        store_bind_real(s, 5, c->dz ? c->dz[i] : NAN);
        store_bind_real(s, 6, c->a ? c->a[i] : NAN);
        int rc = sqlite3_step(s);
        if (rc != SQLITE_DONE)
            e = store_sql_fail(st->db, rc, why, why_len, "saving a prediction curve point");
    }
    sqlite3_finalize(s);
    return e;
}

store_err store_prediction_insert(store *st, const store_prediction *p, int64_t *id, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e == STORE_OK)
        e = check(p, why, why_len);
    if (e != STORE_OK)
        return e;
    if ((e = store_begin(st, why, why_len)))
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "INSERT INTO predictions (trial_id, scene_hash, snapped, snap_dw, regime, peak_abs_a,"
                      " nodes, dt, adaptive, imperfection, est_error, wall_s, software_version, solver_json,"
                      " status, failure, crease_angle_left_deg, crease_angle_left_from, crease_angle_right_deg,"
                      " crease_angle_right_from, crease_position_left, crease_position_left_from,"
                      " crease_position_right, crease_position_right_from, crease_hinge, crease_hinge_stiffness_nm_per_rad,"
                      " calibration_json)"
                      " VALUES (?1,?2,?3,?4,?5,?6,?7,?8,?9,?10,?11,?12,?13,?14,?15,?16,?17,?18,?19,?20,?21,?22,?23,?24,"
                      "?25,?26,?27)",
                      &s, why, why_len);
    int64_t pid = 0;
    if (e == STORE_OK) {
        store_bind_id(s, 1, p->trial_id);
        sqlite3_bind_text(s, 2, p->scene_hash, -1, SQLITE_TRANSIENT);
        sqlite3_bind_int(s, 3, p->snapped ? 1 : 0);
        store_bind_real(s, 4, p->snap_dw);
        sqlite3_bind_text(s, 5, store_regime_name(p->regime), -1, SQLITE_STATIC);
        store_bind_real(s, 6, p->peak_abs_a);
        sqlite3_bind_int(s, 7, p->nodes);
        sqlite3_bind_double(s, 8, p->dt);
        sqlite3_bind_int(s, 9, p->adaptive ? 1 : 0);
        sqlite3_bind_double(s, 10, p->imperfection);
        store_bind_real(s, 11, p->est_error);
        sqlite3_bind_double(s, 12, p->wall_s);
        sqlite3_bind_text(s, 13, p->software_version[0] ? p->software_version : RIBBON_VERSION, -1, SQLITE_TRANSIENT);
        store_bind_text(s, 14, p->solver_json);
        sqlite3_bind_text(s, 15, p->status == STORE_PREDICTION_FAILED ? "failed" : "done", -1, SQLITE_STATIC);
        store_bind_text(s, 16, p->failure);
        for (int k = 0; k < 2; k++) {
            const store_creases *c = &p->creases;
            store_bind_real(s, 17 + 2 * k, c->angle_deg[k]);
            store_bind_text(s, 18 + 2 * k, store_source_name(c->angle_from[k]));
            store_bind_real(s, 21 + 2 * k, c->position[k]);
            store_bind_text(s, 22 + 2 * k, store_source_name(c->position_from[k]));
        }
        double k_h = p->creases.hinge_stiffness;
        store_bind_text(s, 25, isnan(k_h) ? NULL : isinf(k_h) ? "rigid" : "compliant");
        store_bind_real(s, 26, isinf(k_h) ? NAN : k_h);
        store_bind_text(s, 27, p->calibration_json);
        int rc = sqlite3_step(s);
        if (rc == SQLITE_CONSTRAINT_FOREIGNKEY)
            e = store_fail(why, why_len, STORE_E_NOTFOUND, "prediction for trial %lld: no such trial",
                           (long long)p->trial_id);
        else if (rc != SQLITE_DONE)
            e = store_sql_fail(st->db, rc, why, why_len, "saving a prediction");
        pid = sqlite3_last_insert_rowid(st->db);
        sqlite3_finalize(s);
    }
    if (e == STORE_OK)
        e = insert_curve(st, pid, &p->curve, why, why_len);
    if (e == STORE_OK)
        e = store_commit(st, why, why_len);
    if (e != STORE_OK) {
        store_rollback(st);
        return e;
    }
    if (id)
        *id = pid;
    return STORE_OK;
}

void store_prediction_free(store_prediction *p)
{
    if (!p)
        return;
    store_curve_free(&p->curve);
    free(p->solver_json);
    p->solver_json = NULL;
    free(p->calibration_json);
    p->calibration_json = NULL;
}

#define CURVE_COUNT "SELECT count(*) FROM prediction_curve WHERE prediction_id = ?1"
#define CURVE_ROWS "SELECT t_s, dw, dz, a FROM prediction_curve WHERE prediction_id = ?1 ORDER BY seq"

store_err store_prediction_get(store *st, int64_t id, store_prediction *out, char *why, size_t why_len)
{
    *out = store_prediction_default();
    sqlite3_stmt *s;
    store_err e = store_prepare(st,
                                "SELECT id, trial_id, scene_hash, snapped, snap_dw, regime, peak_abs_a, nodes, dt,"
                                " adaptive, imperfection, est_error, wall_s, software_version, solver_json,"
                                " created_at, status, failure, crease_angle_left_deg, crease_angle_left_from,"
                                " crease_angle_right_deg, crease_angle_right_from, crease_position_left,"
                                " crease_position_left_from, crease_position_right, crease_position_right_from,"
                                " crease_hinge, crease_hinge_stiffness_nm_per_rad, calibration_json"
                                " FROM predictions WHERE id = ?1",
                                &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        out->id = sqlite3_column_int64(s, 0);
        out->trial_id = store_col_id(s, 1);
        store_col_text(s, 2, out->scene_hash, sizeof out->scene_hash);
        out->snapped = sqlite3_column_int(s, 3) != 0;
        out->snap_dw = store_col_real(s, 4);
        if (sqlite3_column_type(s, 5) != SQLITE_NULL &&
            !store_regime_parse((const char *)sqlite3_column_text(s, 5), &out->regime))
            e = store_fail(why, why_len, STORE_E_CORRUPT, "prediction %lld has an unknown regime", (long long)id);
        out->peak_abs_a = store_col_real(s, 6);
        out->nodes = sqlite3_column_int(s, 7);
        out->dt = store_col_real(s, 8);
        out->adaptive = sqlite3_column_int(s, 9) != 0;
        out->imperfection = store_col_real(s, 10);
        out->est_error = store_col_real(s, 11);
        out->wall_s = store_col_real(s, 12);
        store_col_text(s, 13, out->software_version, sizeof out->software_version);
        out->solver_json = store_col_strdup(s, 14);
        if (!out->solver_json && sqlite3_column_type(s, 14) != SQLITE_NULL)
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory reading prediction %lld", (long long)id);
        store_col_text(s, 15, out->created_at, sizeof out->created_at);
        const char *status = (const char *)sqlite3_column_text(s, 16);
        out->status = status && !strcmp(status, "failed") ? STORE_PREDICTION_FAILED : STORE_PREDICTION_DONE;
        store_col_text(s, 17, out->failure, sizeof out->failure);
        for (int k = 0; k < 2; k++) {
            store_creases *c = &out->creases;
            c->angle_deg[k] = store_col_real(s, 18 + 2 * k);
            c->position[k] = store_col_real(s, 22 + 2 * k);
            const char *af = (const char *)sqlite3_column_text(s, 19 + 2 * k);
            const char *pf = (const char *)sqlite3_column_text(s, 23 + 2 * k);
            if ((af && !store_source_parse(af, &c->angle_from[k])) || (pf && !store_source_parse(pf, &c->position_from[k])))
                e = store_fail(why, why_len, STORE_E_CORRUPT, "prediction %lld has an unknown crease source",
                               (long long)id);
        }
        const char *hinge = (const char *)sqlite3_column_text(s, 26);
        out->creases.hinge_stiffness = !hinge                   ? NAN
                                       : !strcmp(hinge, "rigid") ? INFINITY
                                                                 : store_col_real(s, 27);
        out->calibration_json = store_col_strdup(s, 28);
        if (!out->calibration_json && sqlite3_column_type(s, 28) != SQLITE_NULL)
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory reading prediction %lld", (long long)id);
    } else if (rc == SQLITE_DONE) {
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "prediction %lld does not exist", (long long)id);
    } else {
        e = store_sql_fail(st->db, rc, why, why_len, "reading a prediction");
    }
    sqlite3_finalize(s);
    if (e == STORE_OK)
        e = store_curve_query(st, CURVE_COUNT, CURVE_ROWS, id, &out->curve, why, why_len);
    if (e != STORE_OK)
        store_prediction_free(out);
    return e;
}

/* The id of the trial's latest prediction. */
static store_err latest_of(store *st, int64_t trial_id, int64_t *pid, char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, "SELECT max(id) FROM predictions WHERE trial_id = ?1", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, trial_id);
    int rc = sqlite3_step(s);
    if (rc != SQLITE_ROW)
        e = store_sql_fail(st->db, rc, why, why_len, "finding a trial's prediction");
    else if (sqlite3_column_type(s, 0) == SQLITE_NULL)
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "trial %lld has no prediction", (long long)trial_id);
    else
        *pid = sqlite3_column_int64(s, 0);
    sqlite3_finalize(s);
    return e;
}

store_err store_prediction_get_by_trial(store *st, int64_t trial_id, store_prediction *out, char *why,
                                        size_t why_len)
{
    *out = store_prediction_default();
    int64_t pid = 0;
    store_err e = latest_of(st, trial_id, &pid, why, why_len);
    return e != STORE_OK ? e : store_prediction_get(st, pid, out, why, why_len);
}

store_err store_prediction_curve(store *st, int64_t trial_id, store_curve *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    int64_t pid = 0;
    store_err e = latest_of(st, trial_id, &pid, why, why_len);
    return e != STORE_OK ? e : store_curve_query(st, CURVE_COUNT, CURVE_ROWS, pid, out, why, why_len);
}
