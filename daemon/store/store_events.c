/* store_events.c: a trial's event log: state changes, information, warnings and faults, each
 * with the trial's monotonic time (when the clock runs) and the wall time. Append-only. */
#include "store_sql.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

store_err store_event_append(store *st, const store_event *ev, char *why, size_t why_len)
{
    char when[32];
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    if (!store_event_kind_name(ev->kind))
        return store_fail(why, why_len, STORE_E_INVALID, "event kind %d is unknown", (int)ev->kind);
    if (!memchr(ev->message, '\0', sizeof ev->message) || !memchr(ev->state, '\0', sizeof ev->state))
        return store_fail(why, why_len, STORE_E_INVALID, "event text not NUL-terminated");
    if (!ev->message[0])
        return store_fail(why, why_len, STORE_E_INVALID, "event message is empty");
    if ((e = store_need_not_inf(ev->t_s, "event t_s", why, why_len)))
        return e;
    if (!store_wall_format(ev->wall_s, when, sizeof when))
        return store_fail(why, why_len, STORE_E_INVALID, "event wall_s %g is not a valid time", ev->wall_s);
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "INSERT INTO events (trial_id, t_s, wall_time, state, kind, message)"
                      " VALUES (?1, ?2, ?3, ?4, ?5, ?6)",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, ev->trial_id);
    store_bind_real(s, 2, ev->t_s);
    sqlite3_bind_text(s, 3, when, -1, SQLITE_TRANSIENT);
    store_bind_text(s, 4, ev->state);
    sqlite3_bind_text(s, 5, store_event_kind_name(ev->kind), -1, SQLITE_STATIC);
    sqlite3_bind_text(s, 6, ev->message, -1, SQLITE_TRANSIENT);
    int rc = sqlite3_step(s);
    if (rc == SQLITE_CONSTRAINT_FOREIGNKEY)
        e = store_fail(why, why_len, STORE_E_NOTFOUND, "event for trial %lld: no such trial",
                       (long long)ev->trial_id);
    else if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "appending an event");
    sqlite3_finalize(s);
    return e;
}

store_err store_events_get(store *st, int64_t trial_id, store_event **out, size_t *n, char *why, size_t why_len)
{
    *out = NULL;
    *n = 0;
    sqlite3_stmt *s;
    store_err e = store_prepare(st,
                                "SELECT id, trial_id, t_s, wall_time, state, kind, message FROM events"
                                " WHERE trial_id = ?1 ORDER BY id",
                                &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, trial_id);
    store_event *v = NULL;
    size_t len = 0, cap = 0;
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
        store_event *nv = store_grow(v, len, &cap, sizeof *v, 16);
        if (!nv) {
            e = store_fail(why, why_len, STORE_E_NOMEM, "out of memory reading events");
            break;
        }
        v = nv;
        store_event *ev = &v[len++];
        memset(ev, 0, sizeof *ev);
        ev->id = sqlite3_column_int64(s, 0);
        ev->trial_id = sqlite3_column_int64(s, 1);
        ev->t_s = store_col_real(s, 2);
        ev->wall_s = NAN;
        store_col_text(s, 3, ev->wall_time, sizeof ev->wall_time);
        store_col_text(s, 4, ev->state, sizeof ev->state);
        if (!store_event_kind_parse((const char *)sqlite3_column_text(s, 5), &ev->kind)) {
            e = store_fail(why, why_len, STORE_E_CORRUPT, "event %lld has an unknown kind", (long long)ev->id);
            break;
        }
        store_col_text(s, 6, ev->message, sizeof ev->message);
    }
    if (e == STORE_OK && rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "reading events");
    sqlite3_finalize(s);
    if (e != STORE_OK) {
        free(v);
        return e;
    }
    *out = v;
    *n = len;
    return STORE_OK;
}

void store_events_state_times(store *st, int64_t id, double *t_check, double *t_shear, double *t_return)
{
    *t_check = *t_shear = *t_return = NAN;
    store_event *ev = NULL;
    size_t n = 0;
    char why[256];
    if (store_events_get(st, id, &ev, &n, why, sizeof why) != STORE_OK) return;
    for (size_t k = 0; k < n; k++) {
        if (ev[k].kind != STORE_EVENT_STATE) continue;
        if (!strncmp(ev[k].message, "state checking", 14) && isnan(*t_check)) *t_check = ev[k].t_s;
        if (!strncmp(ev[k].message, "state shearing", 14) && isnan(*t_shear)) *t_shear = ev[k].t_s;
        if (!strncmp(ev[k].message, "state returning", 15) && isnan(*t_return)) *t_return = ev[k].t_s;
    }
    free(ev);
}
