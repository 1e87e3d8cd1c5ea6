/* store_specimens.c: the specimen records. A specimen is known by the name on its label: upsert
 * by name keeps one row per physical ribbon (re-measuring its creases updates the row), and
 * trials_count only ever grows, through store_specimen_count_trial. Its state (v6) moves
 * new -> in use (its first trial) -> retired | broken (store_specimen_retire), never back; the
 * design angle phi_deg, once known, is kept by later upserts that do not know it. Its calibration
 * (v12) is written only by store_specimen_set_calibration: an upsert (every trial's start) keeps it. */
#include "store_sql.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

store_specimen store_specimen_default(void)
{
    store_specimen s;
    memset(&s, 0, sizeof s);
    s.length_m = s.width_m = s.thickness_m = NAN;
    s.youngs_modulus_pa = s.density_kg_m3 = NAN;
    s.crease_angle_left_deg = s.crease_angle_right_deg = NAN;
    s.fold_position = NAN;
    s.crease_position_left = s.crease_position_right = NAN;
    s.phi_deg = NAN;
    s.state = STORE_SPECIMEN_NEW;
    return s;
}

static store_err optional_positive(double v, const char *field, char *why, size_t why_len)
{
    if (isnan(v))
        return STORE_OK;
    return store_need_positive(v, field, why, why_len);
}

static store_err check(const store_specimen *sp, char *why, size_t why_len)
{
    store_err e;
    if (!sp->name[0])
        return store_fail(why, why_len, STORE_E_INVALID, "specimen name is empty");
    if (!memchr(sp->name, '\0', sizeof sp->name) || !memchr(sp->material, '\0', sizeof sp->material) ||
        !memchr(sp->crease_orientation, '\0', sizeof sp->crease_orientation) ||
        !memchr(sp->folded_at, '\0', sizeof sp->folded_at))
        return store_fail(why, why_len, STORE_E_INVALID, "specimen text field not NUL-terminated");
    if ((e = store_need_positive(sp->length_m, "specimen length_m", why, why_len)) ||
        (e = store_need_positive(sp->width_m, "specimen width_m", why, why_len)) ||
        (e = store_need_positive(sp->thickness_m, "specimen thickness_m", why, why_len)) ||
        (e = optional_positive(sp->youngs_modulus_pa, "specimen youngs_modulus_pa", why, why_len)) ||
        (e = optional_positive(sp->density_kg_m3, "specimen density_kg_m3", why, why_len)) ||
        (e = store_need_not_inf(sp->crease_angle_left_deg, "specimen crease_angle_left_deg", why, why_len)) ||
        (e = store_need_not_inf(sp->crease_angle_right_deg, "specimen crease_angle_right_deg", why, why_len)))
        return e;
    for (int k = 0; k < 2; k++) {
        double v = k ? sp->crease_position_right : sp->crease_position_left;
        if (!isnan(v) && !(v > 0.0 && v < 1.0))
            return store_fail(why, why_len, STORE_E_INVALID, "specimen crease_position_%s must be in (0, 1) (got %g)",
                              k ? "right" : "left", v);
    }
    if (!isnan(sp->phi_deg) && !(sp->phi_deg > 0.0 && sp->phi_deg < 180.0))
        return store_fail(why, why_len, STORE_E_INVALID, "specimen phi_deg must be in (0, 180) (got %g)", sp->phi_deg);
    if (!isnan(sp->fold_position) && !(sp->fold_position > 0.0 && sp->fold_position < 1.0))
        return store_fail(why, why_len, STORE_E_INVALID, "specimen fold_position must be in (0, 1) (got %g)",
                          sp->fold_position);
    return STORE_OK;
}

/* The insert both writers share; the upsert adds its ON CONFLICT clause. */
#define SPECIMEN_INSERT                                                                                     \
    "INSERT INTO specimens (name, length_m, width_m, thickness_m, youngs_modulus_pa,"                      \
    " density_kg_m3, material, crease_angle_left_deg, crease_angle_right_deg,"                             \
    " fold_position, crease_orientation, crease_position_left, crease_position_right,"                     \
    " folded_at, phi_deg) VALUES (?1,?2,?3,?4,?5,?6,?7,?8,?9,?10,?11,?12,?13,?14,?15)"

/* upsert 1: update the row of the same name; 0: a name taken is STORE_E_EXISTS. */
static store_err save(store *st, const store_specimen *sp, int upsert, int64_t *id, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e == STORE_OK)
        e = check(sp, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st,
                      !upsert ? SPECIMEN_INSERT " RETURNING id" :
                      SPECIMEN_INSERT
                      " ON CONFLICT(name) DO UPDATE SET length_m=excluded.length_m,"
                      " width_m=excluded.width_m, thickness_m=excluded.thickness_m,"
                      " youngs_modulus_pa=excluded.youngs_modulus_pa, density_kg_m3=excluded.density_kg_m3,"
                      " material=excluded.material, crease_angle_left_deg=excluded.crease_angle_left_deg,"
                      " crease_angle_right_deg=excluded.crease_angle_right_deg,"
                      " fold_position=excluded.fold_position, crease_orientation=excluded.crease_orientation,"
                      " crease_position_left=excluded.crease_position_left,"
                      " crease_position_right=excluded.crease_position_right, folded_at=excluded.folded_at,"
                      " phi_deg=COALESCE(excluded.phi_deg, specimens.phi_deg)"
                      " RETURNING id",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    store_bind_text(s, 1, sp->name);
    store_bind_real(s, 2, sp->length_m);
    store_bind_real(s, 3, sp->width_m);
    store_bind_real(s, 4, sp->thickness_m);
    store_bind_real(s, 5, sp->youngs_modulus_pa);
    store_bind_real(s, 6, sp->density_kg_m3);
    store_bind_text(s, 7, sp->material);
    store_bind_real(s, 8, sp->crease_angle_left_deg);
    store_bind_real(s, 9, sp->crease_angle_right_deg);
    store_bind_real(s, 10, sp->fold_position);
    store_bind_text(s, 11, sp->crease_orientation);
    store_bind_real(s, 12, sp->crease_position_left);
    store_bind_real(s, 13, sp->crease_position_right);
    store_bind_text(s, 14, sp->folded_at);
    store_bind_real(s, 15, sp->phi_deg);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        if (id)
            *id = sqlite3_column_int64(s, 0);
        rc = sqlite3_step(s);
    }
    if (rc != SQLITE_DONE && !upsert && sqlite3_extended_errcode(st->db) == SQLITE_CONSTRAINT_UNIQUE)
        e = store_fail(why, why_len, STORE_E_EXISTS, "specimen %s exists: name the new strip (\"name\")", sp->name);
    else if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "saving the specimen");
    sqlite3_finalize(s);
    return e;
}

store_err store_specimen_upsert(store *st, const store_specimen *sp, int64_t *id, char *why, size_t why_len)
{
    return save(st, sp, 1, id, why, why_len);
}

store_err store_specimen_insert(store *st, const store_specimen *sp, int64_t *id, char *why, size_t why_len)
{
    return save(st, sp, 0, id, why, why_len);
}

#define SPECIMEN_COLUMNS                                                                                    \
    "SELECT id, name, length_m, width_m, thickness_m, youngs_modulus_pa, density_kg_m3, material,"          \
    " crease_angle_left_deg, crease_angle_right_deg, fold_position, crease_orientation, trials_count,"      \
    " crease_position_left, crease_position_right, folded_at, phi_deg, state, state_reason, state_at,"     \
    " calibration_json, calibration_failure_json"                                                          \
    " FROM specimens "

static store_err read_one(store *st, sqlite3_stmt *s, store_specimen *out, const char *what, char *why,
                          size_t why_len)
{
    store_err e = STORE_OK;
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        *out = store_specimen_default();
        out->id = sqlite3_column_int64(s, 0);
        store_col_text(s, 1, out->name, sizeof out->name);
        out->length_m = store_col_real(s, 2);
        out->width_m = store_col_real(s, 3);
        out->thickness_m = store_col_real(s, 4);
        out->youngs_modulus_pa = store_col_real(s, 5);
        out->density_kg_m3 = store_col_real(s, 6);
        store_col_text(s, 7, out->material, sizeof out->material);
        out->crease_angle_left_deg = store_col_real(s, 8);
        out->crease_angle_right_deg = store_col_real(s, 9);
        out->fold_position = store_col_real(s, 10);
        store_col_text(s, 11, out->crease_orientation, sizeof out->crease_orientation);
        out->trials_count = sqlite3_column_int64(s, 12);
        out->crease_position_left = store_col_real(s, 13);
        out->crease_position_right = store_col_real(s, 14);
        store_col_text(s, 15, out->folded_at, sizeof out->folded_at);
        out->phi_deg = store_col_real(s, 16);
        store_specimen_state state = STORE_SPECIMEN_NEW;
        store_specimen_state_parse((const char *)sqlite3_column_text(s, 17), &state);
        out->state = state;
        store_col_text(s, 18, out->state_reason, sizeof out->state_reason);
        store_col_text(s, 19, out->state_at, sizeof out->state_at);
        store_col_text(s, 20, out->calibration_json, sizeof out->calibration_json);
        store_col_text(s, 21, out->calibration_failure_json, sizeof out->calibration_failure_json);
    } else if (rc == SQLITE_DONE) {
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "no specimen %s", what);
    } else {
        e = store_sql_fail(st->db, rc, why, why_len, "reading a specimen");
    }
    sqlite3_finalize(s);
    return e;
}

store_err store_specimen_get(store *st, int64_t id, store_specimen *out, char *why, size_t why_len)
{
    sqlite3_stmt *s;
    store_err e = store_prepare(st, SPECIMEN_COLUMNS "WHERE id = ?1", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    char what[32];
    snprintf(what, sizeof what, "%lld", (long long)id);
    return read_one(st, s, out, what, why, why_len);
}

store_err store_specimen_get_by_name(store *st, const char *name, store_specimen *out, char *why, size_t why_len)
{
    if (!name || !*name)
        return store_fail(why, why_len, STORE_E_INVALID, "specimen name is empty");
    sqlite3_stmt *s;
    store_err e = store_prepare(st, SPECIMEN_COLUMNS "WHERE name = ?1", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_text(s, 1, name, -1, SQLITE_TRANSIENT);
    char what[80];
    snprintf(what, sizeof what, "named '%.64s'", name);
    return read_one(st, s, out, what, why, why_len);
}

store_err store_specimen_count_trial(store *st, int64_t id, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st, "UPDATE specimens SET trials_count = trials_count + 1,"
                      " state = CASE state WHEN 'new' THEN 'in use' ELSE state END WHERE id = ?1", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    int rc = sqlite3_step(s);
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "counting a specimen's trial");
    else if (sqlite3_changes(st->db) == 0)
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "no specimen %lld", (long long)id);
    sqlite3_finalize(s);
    return e;
}

static const char *const state_names[STORE_SPECIMEN_STATE_COUNT] = {"new", "in use", "retired", "broken"};

const char *store_specimen_state_name(store_specimen_state s)
{
    return (unsigned)s < STORE_SPECIMEN_STATE_COUNT ? state_names[s] : NULL;
}

bool store_specimen_state_parse(const char *s, store_specimen_state *out)
{
    for (int k = 0; s && k < STORE_SPECIMEN_STATE_COUNT; k++)
        if (strcmp(s, state_names[k]) == 0) {
            *out = (store_specimen_state)k;
            return true;
        }
    return false;
}

store_err store_specimen_list(store *st, store_specimen **out, size_t *n, char *why, size_t why_len)
{
    *out = NULL;
    *n = 0;
    sqlite3_stmt *s;
    store_err e = store_prepare(st, "SELECT id FROM specimens ORDER BY name", &s, why, why_len);
    if (e != STORE_OK)
        return e;
    int64_t *ids = NULL;
    size_t nid = 0, cap = 0;
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
        int64_t *g = store_grow(ids, nid + 1, &cap, sizeof *ids, 16);
        if (!g) {
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory listing specimens");
            break;
        }
        ids = g;
        ids[nid++] = sqlite3_column_int64(s, 0);
    }
    if (e == STORE_OK && rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "listing specimens");
    sqlite3_finalize(s);
    store_specimen *v = NULL;
    if (e == STORE_OK && nid && !(v = calloc(nid, sizeof *v)))
        e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory listing specimens");
    for (size_t k = 0; e == STORE_OK && k < nid; k++)
        e = store_specimen_get(st, ids[k], &v[k], why, why_len);
    free(ids);
    if (e != STORE_OK) {
        free(v);
        return e;
    }
    *out = v;
    *n = nid;
    return STORE_OK;
}

store_err store_specimen_retire(store *st, int64_t id, store_specimen_state state, const char *reason,
                                double wall_s, char *why, size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    if (state != STORE_SPECIMEN_RETIRED && state != STORE_SPECIMEN_BROKEN)
        return store_fail(why, why_len, STORE_E_INVALID, "a specimen is retired as 'retired' or 'broken'");
    if (!reason || !*reason)
        return store_fail(why, why_len, STORE_E_INVALID, "retiring a specimen needs a reason");
    if ((e = store_need_fits(reason, 128, "retirement reason", why, why_len)))
        return e;
    if (!store_wall_format(wall_s, when, sizeof when))
        return store_fail(why, why_len, STORE_E_INVALID, "wall time %g is not a valid time", wall_s);
    store_specimen cur;
    if ((e = store_specimen_get(st, id, &cur, why, why_len)))
        return e;
    if (cur.state == STORE_SPECIMEN_RETIRED || cur.state == STORE_SPECIMEN_BROKEN)
        return store_fail(why, why_len, STORE_E_STATE, "specimen %s is already %s (%s, %s)", cur.name,
                          store_specimen_state_name(cur.state), cur.state_reason, cur.state_at);
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "UPDATE specimens SET state = ?2, state_reason = ?3, state_at = ?4 WHERE id = ?1"
                      " AND state IN ('new', 'in use')",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    sqlite3_bind_text(s, 2, store_specimen_state_name(state), -1, SQLITE_STATIC);
    store_bind_text(s, 3, reason);
    store_bind_text(s, 4, when);
    int rc = sqlite3_step(s);
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "retiring a specimen");
    else if (sqlite3_changes(st->db) == 0)
        e = store_fail(why, why_len, STORE_E_STATE, "specimen %s changed state meanwhile", cur.name);
    sqlite3_finalize(s);
    return e;
}

store_err store_specimen_set_calibration(store *st, int64_t id, const char *calibration_json,
                                         const char *failure_json, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    const char *text = calibration_json ? calibration_json : failure_json;
    const char *field = calibration_json ? "specimen calibration_json" : "specimen calibration_failure_json";
    size_t cap = calibration_json ? STORE_SPECIMEN_CALIBRATION_MAX : STORE_SPECIMEN_CALIBRATION_FAILURE_MAX;
    if (!text)
        return store_fail(why, why_len, STORE_E_INVALID, "a specimen's calibration needs a calibration or a failure");
    if ((e = store_need_fits(text, cap, field, why, why_len)) || (e = store_need_json(text, field, why, why_len)))
        return e;
    if (text[0] != '{')
        return store_fail(why, why_len, STORE_E_INVALID, "%s must be a JSON object", field);
    sqlite3_stmt *s;
    e = store_prepare(st,
                      calibration_json
                          ? "UPDATE specimens SET calibration_json = ?2, calibration_failure_json = NULL WHERE id = ?1"
                          : "UPDATE specimens SET calibration_failure_json = ?2 WHERE id = ?1",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    store_bind_text(s, 2, text);
    int rc = sqlite3_step(s);
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "saving a specimen's calibration");
    else if (sqlite3_changes(st->db) == 0)
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "no specimen %lld", (long long)id);
    sqlite3_finalize(s);
    return e;
}
