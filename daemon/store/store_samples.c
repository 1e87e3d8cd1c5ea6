/* store_samples.c: the samples of a trial (rail readings and camera frames) and the batched
 * writer that puts them into the database fast enough for every reading of a run.
 *
 * One transaction per row would cost a WAL append and a lock round trip per sample; the writer
 * instead keeps up to batch_rows samples in memory and commits them in one transaction, with one
 * prepared INSERT reused for every row. What bounds the loss on a crash is the age of the batch:
 * a commit is also due once the caller's clock (the samples' own t_s, no hidden clock) is
 * max_age_s past the last commit. Committed rows survive kill -9 (WAL). A failed commit keeps
 * its rows pending so a later flush can retry; the batch never grows beyond batch_rows.
 * Sequence numbers are the writer's: 0, 1, 2... per trial, continuing after rows already stored.
 * Each commit also adds its rows to trials.samples_count, so the count a trial list shows is
 * exact after any crash without counting the samples. */
#include "store_curve.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct store_samples {
    store *st;
    int64_t trial_id;
    store_writer_params p;
    sqlite3_stmt *insert; /* prepared once, reset per row */
    sqlite3_stmt *count;  /* trials.samples_count += rows, in the same commit */
    store_sample *batch;  /* p.batch_rows slots */
    size_t pending;       /* rows in batch waiting for a commit */
    int64_t next_seq;
    int64_t committed;
    double last_commit_t; /* s, caller's clock at the last commit; NaN before the first sample */
    double last_t;        /* s, t_s of the latest sample added */
};

store_writer_params store_writer_params_default(void)
{
    return (store_writer_params){.batch_rows = 256, .max_age_s = 0.25};
}

store_sample store_sample_default(void)
{
    store_sample s;
    memset(&s, 0, sizeof s);
    s.kind = STORE_SAMPLE_RAIL;
    s.frame = -1;
    s.t_s = s.compress_mm = s.shear_mm = s.dl = s.dw = s.dz = s.a = s.quality = NAN;
    return s;
}

store_err store_samples_begin(store *st, int64_t trial_id, const store_writer_params *p, store_samples **out,
                              char *why, size_t why_len)
{
    *out = NULL;
    store_writer_params def = store_writer_params_default();
    if (!p)
        p = &def;
    store_err e = store_check_writable(st, why, why_len);
    if (e != STORE_OK)
        return e;
    if (p->batch_rows < 1 || p->batch_rows > 1000000)
        return store_fail(why, why_len, STORE_E_INVALID, "sample batch_rows must be in [1, 1000000] (got %zu)",
                          p->batch_rows);
    if (!isfinite(p->max_age_s) || p->max_age_s < 0.0)
        return store_fail(why, why_len, STORE_E_INVALID, "sample max_age_s must be finite and >= 0 (got %g)",
                          p->max_age_s);
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "SELECT (SELECT 1 FROM trials WHERE id = ?1),"
                      " (SELECT max(seq) FROM samples WHERE trial_id = ?1)",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, trial_id);
    int rc = sqlite3_step(s);
    bool exists = false;
    int64_t next = 0;
    if (rc == SQLITE_ROW) {
        exists = sqlite3_column_type(s, 0) != SQLITE_NULL;
        next = sqlite3_column_type(s, 1) == SQLITE_NULL ? 0 : sqlite3_column_int64(s, 1) + 1;
    } else {
        e = store_sql_fail(st->db, rc, why, why_len, "starting the sample writer");
    }
    sqlite3_finalize(s);
    if (e != STORE_OK)
        return e;
    if (!exists)
        return store_fail(why, why_len, STORE_E_NOTFOUND, "samples for trial %lld: no such trial",
                          (long long)trial_id);
    store_samples *w = calloc(1, sizeof *w);
    store_sample *batch = w ? malloc(p->batch_rows * sizeof *batch) : NULL;
    if (!batch) {
        free(w);
        return store_fail(why, why_len, STORE_E_NOMEM, "out of memory for a batch of %zu samples", p->batch_rows);
    }
    w->st = st;
    w->trial_id = trial_id;
    w->p = *p;
    w->batch = batch;
    w->next_seq = next;
    w->last_commit_t = NAN;
    w->last_t = NAN;
    e = store_prepare(st,
                      "INSERT INTO samples (trial_id, seq, t_s, kind, frame, compress_mm, shear_mm,"
                      " dl, dw, dz, a, quality, reason) VALUES (?1,?2,?3,?4,?5,?6,?7,?8,?9,?10,?11,?12,?13)",
                      &w->insert, why, why_len);
    if (e == STORE_OK)
        e = store_prepare(st, "UPDATE trials SET samples_count = samples_count + ?1 WHERE id = ?2", &w->count, why,
                          why_len);
    if (e != STORE_OK) {
        sqlite3_finalize(w->insert);
        free(batch);
        free(w);
        return e;
    }
    *out = w;
    return STORE_OK;
}

static store_err check_sample(const store_sample *s, char *why, size_t why_len)
{
    static const char *const names[] = {"compress_mm", "shear_mm", "dl", "dw", "dz", "a", "quality"};
    const double v[] = {s->compress_mm, s->shear_mm, s->dl, s->dw, s->dz, s->a, s->quality};
    if (!isfinite(s->t_s))
        return store_fail(why, why_len, STORE_E_INVALID, "sample t_s must be a finite number (got %g)", s->t_s);
    if (s->kind != STORE_SAMPLE_RAIL && s->kind != STORE_SAMPLE_FRAME)
        return store_fail(why, why_len, STORE_E_INVALID, "sample kind %d is neither rail (0) nor frame (1)",
                          (int)s->kind);
    if (s->frame < -1)
        return store_fail(why, why_len, STORE_E_INVALID, "sample frame %lld must be >= 0, or -1 for none",
                          (long long)s->frame);
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
        if (isinf(v[i]))
            return store_fail(why, why_len, STORE_E_INVALID, "sample at t = %g s: %s is %g; must be finite or NaN",
                              s->t_s, names[i], v[i]);
    if (!isnan(s->quality) && (s->quality < 0.0 || s->quality > 1.0))
        return store_fail(why, why_len, STORE_E_INVALID, "sample at t = %g s: quality %g is outside [0, 1]", s->t_s,
                          s->quality);
    if (!memchr(s->reason, '\0', sizeof s->reason))
        return store_fail(why, why_len, STORE_E_INVALID, "sample reason not NUL-terminated");
    return STORE_OK;
}

static int insert_row(sqlite3_stmt *ins, int64_t trial_id, const store_sample *s)
{
    sqlite3_reset(ins);
    sqlite3_bind_int64(ins, 1, trial_id);
    sqlite3_bind_int64(ins, 2, s->seq);
    sqlite3_bind_double(ins, 3, s->t_s);
    sqlite3_bind_int(ins, 4, (int)s->kind);
    if (s->frame < 0)
        sqlite3_bind_null(ins, 5);
    else
        sqlite3_bind_int64(ins, 5, s->frame);
    store_bind_real(ins, 6, s->compress_mm);
    store_bind_real(ins, 7, s->shear_mm);
    store_bind_real(ins, 8, s->dl);
    store_bind_real(ins, 9, s->dw);
    store_bind_real(ins, 10, s->dz);
    store_bind_real(ins, 11, s->a);
    store_bind_real(ins, 12, s->quality);
    if (s->reason[0])
        sqlite3_bind_text(ins, 13, s->reason, -1, SQLITE_STATIC); /* the batch outlives the step */
    else
        sqlite3_bind_null(ins, 13);
    return sqlite3_step(ins);
}

store_err store_samples_flush(store_samples *w, char *why, size_t why_len)
{
    if (w->pending == 0)
        return STORE_OK;
    char sub[256];
    store_err e = store_begin(w->st, sub, sizeof sub);
    size_t i = 0;
    for (; e == STORE_OK && i < w->pending; i++) {
        int rc = insert_row(w->insert, w->trial_id, &w->batch[i]);
        if (rc != SQLITE_DONE)
            e = store_sql_fail(w->st->db, rc, sub, sizeof sub, "inserting a sample");
    }
    sqlite3_reset(w->insert);
    if (e == STORE_OK) {
        sqlite3_reset(w->count);
        sqlite3_bind_int64(w->count, 1, (int64_t)w->pending);
        sqlite3_bind_int64(w->count, 2, w->trial_id);
        int rc = sqlite3_step(w->count);
        if (rc != SQLITE_DONE)
            e = store_sql_fail(w->st->db, rc, sub, sizeof sub, "counting the trial's samples");
        sqlite3_reset(w->count);
    }
    if (e == STORE_OK)
        e = store_commit(w->st, sub, sizeof sub);
    if (e != STORE_OK) {
        store_rollback(w->st);
        return store_fail(why, why_len, e, "trial %lld: committing %zu samples failed (kept pending): %s",
                          (long long)w->trial_id, w->pending, sub);
    }
    w->committed += (int64_t)w->pending;
    w->pending = 0;
    w->last_commit_t = w->last_t;
    return STORE_OK;
}

store_err store_samples_add(store_samples *w, const store_sample *s, char *why, size_t why_len)
{
    store_err e = check_sample(s, why, why_len);
    if (e != STORE_OK)
        return e;
    if (w->pending == w->p.batch_rows) {
        /* Only after an earlier failed commit: make room or refuse. */
        char sub[384];
        if ((e = store_samples_flush(w, sub, sizeof sub)))
            return store_fail(why, why_len, e, "sample batch full and its commit still fails: %s", sub);
    }
    store_sample *slot = &w->batch[w->pending++];
    *slot = *s;
    slot->seq = w->next_seq++;
    w->last_t = s->t_s;
    if (isnan(w->last_commit_t))
        w->last_commit_t = s->t_s;
    if (w->pending == w->p.batch_rows || s->t_s - w->last_commit_t >= w->p.max_age_s)
        return store_samples_flush(w, why, why_len);
    return STORE_OK;
}

store_err store_samples_end(store_samples *w, char *why, size_t why_len)
{
    if (!w)
        return STORE_OK;
    char sub[384];
    size_t pending = w->pending;
    store_err e = store_samples_flush(w, sub, sizeof sub);
    if (e != STORE_OK)
        store_fail(why, why_len, e, "%s; %zu samples lost", sub, pending);
    sqlite3_finalize(w->insert);
    sqlite3_finalize(w->count);
    free(w->batch);
    free(w);
    return e;
}

int64_t store_samples_committed(const store_samples *w)
{
    return w->committed;
}

size_t store_samples_pending(const store_samples *w)
{
    return w->pending;
}

store_err store_samples_count(store *st, int64_t trial_id, int64_t *count, char *why, size_t why_len)
{
    *count = 0;
    return store_lookup_id(st, "SELECT samples_count FROM trials WHERE id = ?1", trial_id, "trial", "counting samples",
                           count, why, why_len);
}

/* The rows themselves counted (store_samples_get sizes its array by what is really there). */
static store_err count_rows(store *st, int64_t trial_id, int64_t *count, char *why, size_t why_len)
{
    int64_t cached;
    store_err e = store_samples_count(st, trial_id, &cached, why, why_len); /* NOTFOUND for a bad id */
    if (e != STORE_OK)
        return e;
    return store_lookup_id(st, "SELECT count(*) FROM samples WHERE trial_id = ?1", trial_id, "trial",
                           "counting samples", count, why, why_len);
}

store_err store_samples_get(store *st, int64_t trial_id, store_sample **out, size_t *n, char *why, size_t why_len)
{
    *out = NULL;
    *n = 0;
    int64_t count = 0;
    store_err e = count_rows(st, trial_id, &count, why, why_len);
    if (e != STORE_OK || count == 0)
        return e;
    store_sample *v = malloc((size_t)count * sizeof *v);
    if (!v)
        return store_fail(why, why_len, STORE_E_NOMEM, "out of memory for %lld samples", (long long)count);
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "SELECT seq, t_s, kind, frame, compress_mm, shear_mm, dl, dw, dz, a, quality, reason"
                      " FROM samples WHERE trial_id = ?1 ORDER BY seq",
                      &s, why, why_len);
    if (e != STORE_OK) {
        free(v);
        return e;
    }
    sqlite3_bind_int64(s, 1, trial_id);
    size_t len = 0;
    int rc = SQLITE_DONE;
    while (len < (size_t)count && (rc = sqlite3_step(s)) == SQLITE_ROW) {
        store_sample *x = &v[len++];
        *x = store_sample_default();
        x->seq = sqlite3_column_int64(s, 0);
        x->t_s = store_col_real(s, 1);
        x->kind = sqlite3_column_int(s, 2) == 1 ? STORE_SAMPLE_FRAME : STORE_SAMPLE_RAIL;
        x->frame = sqlite3_column_type(s, 3) == SQLITE_NULL ? -1 : sqlite3_column_int64(s, 3);
        x->compress_mm = store_col_real(s, 4);
        x->shear_mm = store_col_real(s, 5);
        x->dl = store_col_real(s, 6);
        x->dw = store_col_real(s, 7);
        x->dz = store_col_real(s, 8);
        x->a = store_col_real(s, 9);
        x->quality = store_col_real(s, 10);
        store_col_text(s, 11, x->reason, sizeof x->reason);
    }
    if (rc != SQLITE_DONE && rc != SQLITE_ROW)
        e = store_sql_fail(st->db, rc, why, why_len, "reading samples");
    sqlite3_finalize(s);
    if (e != STORE_OK) {
        free(v);
        return e;
    }
    *out = v;
    *n = len;
    return STORE_OK;
}

store_err store_trial_curve(store *st, int64_t trial_id, store_curve *out, char *why, size_t why_len)
{
    int64_t count;
    store_err e = store_samples_count(st, trial_id, &count, why, why_len); /* NOTFOUND for a bad id */
    if (e != STORE_OK) {
        memset(out, 0, sizeof *out);
        return e;
    }
#define VALID_FRAMES                                                                                        \
    " FROM samples WHERE trial_id = ?1 AND kind = 1 AND dw IS NOT NULL AND dz IS NOT NULL AND a IS NOT NULL"
    return store_curve_query(st, "SELECT count(*)" VALID_FRAMES, "SELECT t_s, dw, dz, a" VALID_FRAMES
                             " ORDER BY t_s, seq", trial_id, out, why, why_len);
#undef VALID_FRAMES
}
