/* sim_sweep_row.c: reading and writing sweep rows (see sim_sweep_row.h). */
#include "sim_sweep_row.h"
#include "cfg_ini.h"
#include "cfg_number.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char header[] = "kind,phi_deg,gamma,gamma_lo,gamma_hi,dl,regime,first_type,first_dw,first_dz,upper,wall_s,note";

static const char *kind_name(char k) { return k == 'p' ? "point" : k == 'q' ? "probe" : "boundary"; }

static const char origin_tag[] = "# made by: ";

void sweep_row_write_header(FILE *f, const char *origin)
{
    fprintf(f, "%s\n", header);
    if (origin && origin[0]) fprintf(f, "%s%s\n", origin_tag, origin);
}

void sweep_row_write(FILE *f, const sweep_row *r)
{
    char note[sizeof r->note];
    snprintf(note, sizeof note, "%s", r->note);
    for (char *p = note; *p; p++)
        if (*p == ',' || *p == '\n' || *p == '\r') *p = ';';
    fprintf(f, "%s,%.17g,%.17g,%.17g,%.17g,%.17g,%s,%s,%.10g,%.10g,%s,%.4g,%s\n", kind_name(r->kind), r->phi,
            r->gamma, r->gamma_lo, r->gamma_hi, r->dl, r->regime, r->first_type, r->first_dw, r->first_dz,
            r->upper[0] ? r->upper : "-", r->wall_s, note);
}

int sweep_table_add(sweep_table *t, const sweep_row *r)
{
    if (t->n == t->cap) {
        size_t cap = t->cap ? 2 * t->cap : 64;
        sweep_row *nr = realloc(t->rows, cap * sizeof *nr);
        if (!nr) return 0;
        t->rows = nr;
        t->cap = cap;
    }
    t->rows[t->n++] = *r;
    return 1;
}

void sweep_table_free(sweep_table *t)
{
    free(t->rows);
    t->rows = NULL;
    t->n = t->cap = 0;
}

static int parse_double(const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = cfg_number_strtod(s, &end);
    if (errno || end == s || *end || !isfinite(v)) return 0;
    *out = v;
    return 1;
}

#define NFIELDS 13

/* Splits line in place into NFIELDS fields (the last, the note, takes the rest) and reads them
 * into r: 1, or 0 with what is wrong in why. */
static int parse_row(char *line, sweep_row *r, char *why, size_t why_len)
{
    static const char *const names[NFIELDS] = {"kind",   "phi_deg",    "gamma",    "gamma_lo", "gamma_hi",
                                               "dl",     "regime",     "first_type", "first_dw", "first_dz",
                                               "upper",  "wall_s",     "note"};
    char *f[NFIELDS];
    int n = 0;
    char *p = line;
    while (n < NFIELDS) {
        f[n++] = p;
        if (n == NFIELDS) break;
        char *c = strchr(p, ',');
        if (!c) break;
        *c = '\0';
        p = c + 1;
    }
    if (n != NFIELDS) {
        snprintf(why, why_len, "%d fields, not %d (%s)", n, NFIELDS, header);
        return 0;
    }
    memset(r, 0, sizeof *r);
    if (!strcmp(f[0], "point")) r->kind = 'p';
    else if (!strcmp(f[0], "probe")) r->kind = 'q';
    else if (!strcmp(f[0], "boundary")) r->kind = 'b';
    else {
        snprintf(why, why_len, "kind '%.20s' is not point, probe or boundary", f[0]);
        return 0;
    }
    const int numeric[] = {1, 2, 3, 4, 5, 8, 9, 11};
    double *dst[] = {&r->phi, &r->gamma, &r->gamma_lo, &r->gamma_hi, &r->dl, &r->first_dw, &r->first_dz, &r->wall_s};
    for (size_t k = 0; k < sizeof numeric / sizeof numeric[0]; k++)
        if (!parse_double(f[numeric[k]], dst[k])) {
            snprintf(why, why_len, "%s '%.40s' is not a finite number", names[numeric[k]], f[numeric[k]]);
            return 0;
        }
    const int text[] = {6, 7, 10};
    const size_t cap[] = {sizeof r->regime, sizeof r->first_type, sizeof r->upper};
    for (size_t k = 0; k < 3; k++)
        if (strlen(f[text[k]]) >= cap[k]) {
            snprintf(why, why_len, "%s '%.40s' is longer than %zu bytes", names[text[k]], f[text[k]], cap[k] - 1);
            return 0;
        }
    strcpy(r->regime, f[6]);
    strcpy(r->first_type, f[7]);
    strcpy(r->upper, f[10]);
    snprintf(r->note, sizeof r->note, "%s", f[12]);
    return 1;
}

int sweep_table_load(const char *path, sweep_table *t, char *why, size_t why_len)
{
    memset(t, 0, sizeof *t);
    char open_why[160];
    errno = 0;
    FILE *f = cfg_open_regular(path, open_why, sizeof open_why);
    if (!f) {
        if (errno == ENOENT) return 0;
        snprintf(why, why_len, "cannot read %s: %s", path, open_why);
        return -1;
    }
    int rc = sweep_table_read(f, path, t, why, why_len);
    fclose(f);
    return rc;
}

int sweep_table_read(FILE *f, const char *path, sweep_table *t, char *why, size_t why_len)
{
    memset(t, 0, sizeof *t);
    char line[1024];
    int lineno = 0, rc = 0;
    while (fgets(line, sizeof line, f)) {
        size_t len = strlen(line);
        int complete = len > 0 && line[len - 1] == '\n';
        lineno++;
        if (!complete && len == sizeof line - 1) {
            snprintf(why, why_len, "%s line %d: longer than %zu bytes; not a sweep row", path, lineno, sizeof line - 2);
            rc = -1;
            break;
        }
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) line[--len] = '\0';
        if (lineno == 1) {
            if (strcmp(line, header) != 0) {
                snprintf(why, why_len, "%s is not a sweep file (line 1 is not the sweep header); refusing to append", path);
                rc = -1;
                break;
            }
            continue;
        }
        if (!complete) {
            /* The last line, cut by a kill while it was written: not a row. */
            t->cut_line = lineno;
            break;
        }
        if (lineno == 2 && !strncmp(line, origin_tag, strlen(origin_tag))) {
            const char *o = line + strlen(origin_tag);
            size_t ol = strlen(o);
            if (ol >= sizeof t->origin) {
                snprintf(why, why_len, "%s line 2: the made-by line is longer than %zu bytes", path,
                         sizeof t->origin - 1);
                rc = -1;
                break;
            }
            memcpy(t->origin, o, ol + 1);
            continue;
        }
        sweep_row r;
        char sub[200];
        if (!parse_row(line, &r, sub, sizeof sub)) {
            snprintf(why, why_len, "%s line %d: %s", path, lineno, sub);
            rc = -1;
            break;
        }
        if (!sweep_table_add(t, &r)) {
            snprintf(why, why_len, "out of memory reading %s", path);
            rc = -1;
            break;
        }
    }
    if (rc == 0 && ferror(f)) {
        snprintf(why, why_len, "%s: read error", path);
        rc = -1;
    }
    if (rc == 0 && lineno == 0) {
        /* An empty file: treated as new (the header is written by the caller only for a new file,
         * so say so rather than append headerless rows). */
        snprintf(why, why_len, "%s is empty; remove it or name another file", path);
        rc = -1;
    }
    if (rc != 0) sweep_table_free(t);
    return rc;
}

static int same(double a, double b) { return fabs(a - b) <= 1e-9 * fmax(1.0, fabs(a)); }

const sweep_row *sweep_table_find(const sweep_table *t, double phi, double gamma, double dl)
{
    for (size_t k = 0; k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if ((r->kind == 'p' || r->kind == 'q') && strcmp(r->regime, "failed") != 0 && same(r->phi, phi) &&
            same(r->gamma, gamma) && same(r->dl, dl))
            return r;
    }
    return NULL;
}

const sweep_row *sweep_table_find_boundary(const sweep_table *t, double phi, double dl, double lo, double hi)
{
    for (size_t k = 0; k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind == 'b' && same(r->phi, phi) && same(r->dl, dl) && r->gamma >= fmin(lo, hi) &&
            r->gamma <= fmax(lo, hi))
            return r;
    }
    return NULL;
}

const sweep_row *sweep_table_find_same(const sweep_table *t, const sweep_row *x)
{
    for (size_t k = 0; k < t->n; k++) {
        const sweep_row *r = &t->rows[k];
        if (r->kind == x->kind && same(r->phi, x->phi) && same(r->gamma, x->gamma) &&
            same(r->gamma_lo, x->gamma_lo) && same(r->gamma_hi, x->gamma_hi) && same(r->dl, x->dl))
            return r;
    }
    return NULL;
}

static int kind_rank(char k) { return k == 'p' ? 0 : k == 'q' ? 1 : 2; }

static int cmp(double a, double b) { return a < b ? -1 : a > b; }

int sweep_row_compare(const void *a, const void *b)
{
    const sweep_row *x = a, *y = b;
    int c = cmp(x->dl, y->dl);
    if (!c) c = cmp(x->phi, y->phi);
    if (!c) c = kind_rank(x->kind) - kind_rank(y->kind);
    if (!c) c = cmp(x->gamma, y->gamma);
    if (!c) c = cmp(x->gamma_lo, y->gamma_lo);
    return c;
}

int sweep_row_same_result(const sweep_row *a, const sweep_row *b, char *what, size_t what_len)
{
    char x[48], y[48];
    const char *name = NULL;
    if (strcmp(a->regime, b->regime)) {
        name = "regime";
        snprintf(x, sizeof x, "%s", a->regime);
        snprintf(y, sizeof y, "%s", b->regime);
    } else if (strcmp(a->first_type, b->first_type)) {
        name = "first_type";
        snprintf(x, sizeof x, "%s", a->first_type);
        snprintf(y, sizeof y, "%s", b->first_type);
    } else if (a->first_dw != b->first_dw) {
        name = "first_dw";
        snprintf(x, sizeof x, "%.10g", a->first_dw);
        snprintf(y, sizeof y, "%.10g", b->first_dw);
    } else if (a->first_dz != b->first_dz) {
        name = "first_dz";
        snprintf(x, sizeof x, "%.10g", a->first_dz);
        snprintf(y, sizeof y, "%.10g", b->first_dz);
    } else if (strcmp(a->upper, b->upper)) {
        name = "upper";
        snprintf(x, sizeof x, "%s", a->upper);
        snprintf(y, sizeof y, "%s", b->upper);
    } else if (strcmp(a->note, b->note)) {
        name = "note";
        snprintf(x, sizeof x, "%.40s", a->note);
        snprintf(y, sizeof y, "%.40s", b->note);
    }
    if (!name) return 1;
    snprintf(what, what_len, "%s %s against %s", name, x, y);
    return 0;
}

int sweep_table_fix_tail(const char *path)
{
    FILE *r = fopen(path, "rb");
    if (!r) return 0;
    /* The offset just past the last newline: everything after it is a cut row. */
    long keep = 0, pos = 0;
    int c, last = EOF;
    while ((c = fgetc(r)) != EOF) {
        pos++;
        if (c == '\n') keep = pos;
        last = c;
    }
    fclose(r);
    if (last == EOF || last == '\n') return 0;
    return truncate(path, (off_t)keep);
}
