/* store_calibrated.c: a trial's calibrated prediction (issue 32 B), kept in the trial's row beside
 * the scene's prediction (the predictions table): the snap of the strip fitted to the trial's own
 * frames, its band, its regime, the fit's parameters as JSON, or the named reason the fit failed.
 * One row per trial because the trial stores one calibrated prediction (the last made from frames
 * before the snap); the fits before it are in the trial's events. */
#include "store_sql.h"

#include <math.h>
#include <string.h>

store_err store_trial_set_calibrated(store *st, int64_t id, const store_calibrated *c, char *why, size_t why_len)
{
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    int fail = c->failure != NULL;
    if (fail && !*c->failure)
        return store_fail(why, why_len, STORE_E_INVALID, "trial fit_failure: the reason must not be empty");
    const double v[3] = {c->snap_dw, c->snap_sd, c->p_other};
    const char *name[3] = {"snap_dw_calibrated", "snap_sd_calibrated", "p_other_calibrated"};
    for (int k = 0; k < 3 && !fail; k++)
        if (!isnan(v[k]) && !isfinite(v[k]))
            return store_fail(why, why_len, STORE_E_INVALID, "trial %s %g: finite or not given", name[k], v[k]);
    if (!fail && (!c->regime || (strcmp(c->regime, "symmetric") && strcmp(c->regime, "asymmetric") &&
                                 strcmp(c->regime, "no snap"))))
        return store_fail(why, why_len, STORE_E_INVALID,
                          "trial regime_calibrated %s: symmetric, asymmetric or no snap", c->regime ? c->regime : "(none)");
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "UPDATE trials SET snap_dw_calibrated = ?1, snap_sd_calibrated = ?2, regime_calibrated = ?3,"
                      " p_other_calibrated = ?4, fit_json = ?5, fit_failure = ?6 WHERE id = ?7",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    store_bind_real(s, 1, fail ? NAN : c->snap_dw);
    store_bind_real(s, 2, fail ? NAN : c->snap_sd);
    store_bind_text(s, 3, fail ? NULL : c->regime);
    store_bind_real(s, 4, fail ? NAN : c->p_other);
    store_bind_text(s, 5, c->fit_json);
    store_bind_text(s, 6, fail ? c->failure : NULL);
    sqlite3_bind_int64(s, 7, id);
    int rc = sqlite3_step(s);
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "saving a trial's calibrated prediction");
    else if (sqlite3_changes(st->db) == 0)
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "trial %lld does not exist", (long long)id);
    sqlite3_finalize(s);
    return e;
}
