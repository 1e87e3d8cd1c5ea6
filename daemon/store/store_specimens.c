/* store_specimens.c: the specimen records. A specimen is known by the name on its label: upsert
 * by name keeps one row per physical ribbon (re-measuring its creases updates the row), and
 * trials_count only ever grows, through store_specimen_count_trial. */
#include "store_sql.h"

#include <math.h>
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
    if (!isnan(sp->fold_position) && !(sp->fold_position > 0.0 && sp->fold_position < 1.0))
        return store_fail(why, why_len, STORE_E_INVALID, "specimen fold_position must be in (0, 1) (got %g)",
                          sp->fold_position);
    return STORE_OK;
}

store_err store_specimen_upsert(store *st, const store_specimen *sp, int64_t *id, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e == STORE_OK)
        e = check(sp, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "INSERT INTO specimens (name, length_m, width_m, thickness_m, youngs_modulus_pa,"
                      " density_kg_m3, material, crease_angle_left_deg, crease_angle_right_deg,"
                      " fold_position, crease_orientation, crease_position_left, crease_position_right,"
                      " folded_at) VALUES (?1,?2,?3,?4,?5,?6,?7,?8,?9,?10,?11,?12,?13,?14)"
                      " ON CONFLICT(name) DO UPDATE SET length_m=excluded.length_m,"
                      " width_m=excluded.width_m, thickness_m=excluded.thickness_m,"
                      " youngs_modulus_pa=excluded.youngs_modulus_pa, density_kg_m3=excluded.density_kg_m3,"
                      " material=excluded.material, crease_angle_left_deg=excluded.crease_angle_left_deg,"
                      " crease_angle_right_deg=excluded.crease_angle_right_deg,"
                      " fold_position=excluded.fold_position, crease_orientation=excluded.crease_orientation,"
                      " crease_position_left=excluded.crease_position_left,"
                      " crease_position_right=excluded.crease_position_right, folded_at=excluded.folded_at"
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
    int rc = sqlite3_step(s);
    if (rc == SQLITE_ROW) {
        if (id)
            *id = sqlite3_column_int64(s, 0);
        rc = sqlite3_step(s);
    }
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "saving the specimen");
    sqlite3_finalize(s);
    return e;
}

#define SPECIMEN_COLUMNS                                                                                    \
    "SELECT id, name, length_m, width_m, thickness_m, youngs_modulus_pa, density_kg_m3, material,"          \
    " crease_angle_left_deg, crease_angle_right_deg, fold_position, crease_orientation, trials_count,"      \
    " crease_position_left, crease_position_right, folded_at"                                              \
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
    e = store_prepare(st, "UPDATE specimens SET trials_count = trials_count + 1 WHERE id = ?1", &s, why, why_len);
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
