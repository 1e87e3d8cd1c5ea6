/* store_export.c: CSV for offline analysis (`ribbonctl export`, and the API's
 * GET /trials/{id}/samples.csv, which sends the same text): one trial's samples, or every trial
 * (trials.csv) plus each trial's samples into a directory.
 *
 * Format (RFC 4180): a header line, comma-separated cells, a missing value is an empty cell, a
 * text cell is quoted when it holds a comma, a quote or a line break. Numbers are printed with the
 * fewest digits that read back to the same double, so an export loses nothing. trials.csv has
 * the keys of store_trials_json with the prediction's flattened as prediction_<key>, so the two
 * views cannot disagree. Files are written to NAME.tmp and renamed when complete: a reader never
 * sees half a file, and a failed export leaves the previous one in place. */
#include "store_sql.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void put_num(FILE *f, double v)
{
    if (!isfinite(v))
        return;
    char buf[40];
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(buf, sizeof buf, "%.*g", prec, v);
        if (strtod(buf, NULL) == v)
            break;
    }
    fputs(buf, f);
}

static void put_text(FILE *f, const char *t)
{
    if (!t || !*t)
        return;
    if (!strpbrk(t, ",\"\r\n")) {
        fputs(t, f);
        return;
    }
    fputc('"', f);
    for (; *t; t++) {
        if (*t == '"')
            fputc('"', f);
        fputc(*t, f);
    }
    fputc('"', f);
}

static store_err write_failed(FILE *f, const char *what, char *why, size_t why_len)
{
    if (fflush(f) != 0 || ferror(f))
        return store_fail(why, why_len, STORE_E_IO, "writing %s: %s", what, strerror(errno ? errno : EIO));
    return STORE_OK;
}

store_err store_export_trial_csv(store *st, int64_t id, FILE *out, char *why, size_t why_len)
{
    int64_t count;
    store_err e = store_samples_count(st, id, &count, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_stmt *s;
    e = store_prepare(st,
                      "SELECT seq, t_s, kind, frame, compress_mm, shear_mm, dl, dw, dz, a, quality, reason"
                      " FROM samples WHERE trial_id = ?1 ORDER BY seq",
                      &s, why, why_len);
    if (e != STORE_OK)
        return e;
    sqlite3_bind_int64(s, 1, id);
    fputs("seq,t_s,kind,frame,compress_mm,shear_mm,dl,dw,dz,a,quality,reason\n", out);
    int rc;
    while ((rc = sqlite3_step(s)) == SQLITE_ROW) {
        fprintf(out, "%lld,", (long long)sqlite3_column_int64(s, 0));
        put_num(out, store_col_real(s, 1));
        fputs(sqlite3_column_int(s, 2) == 1 ? ",frame," : ",rail,", out);
        if (sqlite3_column_type(s, 3) != SQLITE_NULL)
            fprintf(out, "%lld", (long long)sqlite3_column_int64(s, 3));
        for (int c = 4; c <= 10; c++) {
            fputc(',', out);
            put_num(out, store_col_real(s, c));
        }
        fputc(',', out);
        put_text(out, (const char *)sqlite3_column_text(s, 11));
        fputc('\n', out);
    }
    if (rc != SQLITE_DONE)
        e = store_sql_fail(st->db, rc, why, why_len, "reading samples for CSV");
    sqlite3_finalize(s);
    if (e == STORE_OK)
        e = write_failed(out, "the samples CSV", why, why_len);
    return e;
}

store_err store_export_trial_csv_text(store *st, int64_t id, char **text, size_t *len, char *why, size_t why_len)
{
    *text = NULL;
    *len = 0;
    char *buf = NULL;
    size_t n = 0;
    FILE *f = open_memstream(&buf, &n);
    if (!f)
        return store_fail(why, why_len, STORE_E_NOMEM, "no memory for the samples CSV: %s", strerror(errno));
    store_err e = store_export_trial_csv(st, id, f, why, why_len);
    if (fclose(f) != 0 && e == STORE_OK)
        e = store_fail(why, why_len, STORE_E_NOMEM, "no memory for the samples CSV");
    if (e != STORE_OK) {
        free(buf);
        return e;
    }
    *text = buf;
    *len = n;
    return STORE_OK;
}

/* The columns of trials.csv: JSON key, and the prediction's key when nested. */
static const char *const trial_keys[] = {
    "id", "mode", "status", "state", "reason", "snapped", "snap_dw_measured", "snap_dw_predicted",
    "regime_measured", "regime_predicted", "samples", "video_path", "source_trial", "specimen",
    "created", "started", "ended", "software_version", "crease_age_s",
};
static const char *const prediction_keys[] = {"id", "nodes", "dt", "adaptive", "est_error", "wall_s",
                                              "imperfection", "scene_hash", "status", "failure"};

static void put_json(FILE *f, const json_t *v)
{
    switch (json_typeof(v)) {
    case JSON_STRING:
        put_text(f, json_string_value(v));
        break;
    case JSON_INTEGER:
        fprintf(f, "%lld", (long long)json_integer_value(v));
        break;
    case JSON_REAL:
        put_num(f, json_real_value(v));
        break;
    case JSON_TRUE:
        fputc('1', f);
        break;
    case JSON_FALSE:
        fputc('0', f);
        break;
    default: /* null (and nothing else occurs): empty cell */
        break;
    }
}

static void write_trials(FILE *f, const json_t *trials)
{
    const size_t nk = sizeof trial_keys / sizeof trial_keys[0];
    const size_t np = sizeof prediction_keys / sizeof prediction_keys[0];
    for (size_t k = 0; k < nk; k++)
        fprintf(f, "%s%s", k ? "," : "", trial_keys[k]);
    for (size_t k = 0; k < np; k++)
        fprintf(f, ",prediction_%s", prediction_keys[k]);
    fputc('\n', f);
    size_t i;
    const json_t *t;
    json_array_foreach(trials, i, t)
    {
        for (size_t k = 0; k < nk; k++) {
            if (k)
                fputc(',', f);
            const json_t *v = json_object_get(t, trial_keys[k]);
            if (v)
                put_json(f, v);
        }
        const json_t *p = json_object_get(t, "prediction");
        for (size_t k = 0; k < np; k++) {
            fputc(',', f);
            const json_t *v = json_is_object(p) ? json_object_get(p, prediction_keys[k]) : NULL;
            if (v)
                put_json(f, v);
        }
        fputc('\n', f);
    }
}

/* Open path.tmp for writing; finish() closes and renames it over path. */
static FILE *start(const char *path, char *tmp, size_t tmp_len, char *why, size_t why_len, store_err *e)
{
    if ((size_t)snprintf(tmp, tmp_len, "%s.tmp", path) >= tmp_len) {
        *e = store_fail(why, why_len, STORE_E_INVALID, "export path too long: %s", path);
        return NULL;
    }
    FILE *f = fopen(tmp, "w");
    if (!f)
        *e = store_fail(why, why_len, STORE_E_IO, "cannot create %s: %s", tmp, strerror(errno));
    return f;
}

static store_err finish(FILE *f, store_err e, const char *tmp, const char *path, char *why, size_t why_len)
{
    if (e == STORE_OK)
        e = write_failed(f, tmp, why, why_len);
    if (fclose(f) != 0 && e == STORE_OK)
        e = store_fail(why, why_len, STORE_E_IO, "closing %s: %s", tmp, strerror(errno));
    if (e == STORE_OK && rename(tmp, path) != 0)
        e = store_fail(why, why_len, STORE_E_IO, "renaming %s to %s: %s", tmp, path, strerror(errno));
    if (e != STORE_OK)
        unlink(tmp);
    return e;
}

store_err store_export_all(store *st, const char *dir, char *why, size_t why_len)
{
    if (!dir || !*dir)
        return store_fail(why, why_len, STORE_E_INVALID, "no export directory given");
    if (mkdir(dir, 0777) != 0 && errno != EEXIST)
        return store_fail(why, why_len, STORE_E_IO, "cannot create directory %s: %s", dir, strerror(errno));
    json_t *trials = NULL;
    store_err e = store_trials_json(st, &trials, why, why_len);
    if (e != STORE_OK)
        return e;
    char path[4096], tmp[4200];
    size_t i;
    json_t *t;
    json_array_foreach(trials, i, t)
    {
        long long id = (long long)json_integer_value(json_object_get(t, "id"));
        if ((size_t)snprintf(path, sizeof path, "%s/trial-%lld-samples.csv", dir, id) >= sizeof path) {
            e = store_fail(why, why_len, STORE_E_INVALID, "export directory path too long: %s", dir);
            break;
        }
        FILE *f = start(path, tmp, sizeof tmp, why, why_len, &e);
        if (!f)
            break;
        e = finish(f, store_export_trial_csv(st, id, f, why, why_len), tmp, path, why, why_len);
        if (e != STORE_OK)
            break;
    }
    if (e == STORE_OK) {
        if ((size_t)snprintf(path, sizeof path, "%s/trials.csv", dir) >= sizeof path) {
            e = store_fail(why, why_len, STORE_E_INVALID, "export directory path too long: %s", dir);
        } else {
            FILE *f = start(path, tmp, sizeof tmp, why, why_len, &e);
            if (f) {
                write_trials(f, trials);
                e = finish(f, STORE_OK, tmp, path, why, why_len);
            }
        }
    }
    json_decref(trials);
    return e;
}
