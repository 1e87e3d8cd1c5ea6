/* sim_sweep_row.c: reading and writing sweep rows (see sim_sweep_row.h). */
#include "sim_sweep_row.h"
#include "cfg_ini.h"
#include "cfg_number.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char header[] = "kind,phi_deg,gamma,gamma_lo,gamma_hi,dl,regime,first_type,first_dw,first_dz,upper,wall_s,note";

static const char *kind_name(char k) { return k == 'p' ? "point" : k == 'q' ? "probe" : "boundary"; }

void sweep_row_write_header(FILE *f) { fprintf(f, "%s\n", header); }

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

/* Splits line in place into at most NFIELDS fields (the last takes the rest). */
static int parse_row(char *line, sweep_row *r)
{
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
    if (n != NFIELDS) return 0;
    memset(r, 0, sizeof *r);
    if (!strcmp(f[0], "point")) r->kind = 'p';
    else if (!strcmp(f[0], "probe")) r->kind = 'q';
    else if (!strcmp(f[0], "boundary")) r->kind = 'b';
    else return 0;
    if (!parse_double(f[1], &r->phi) || !parse_double(f[2], &r->gamma) || !parse_double(f[3], &r->gamma_lo) ||
        !parse_double(f[4], &r->gamma_hi) || !parse_double(f[5], &r->dl) || !parse_double(f[8], &r->first_dw) ||
        !parse_double(f[9], &r->first_dz) || !parse_double(f[11], &r->wall_s))
        return 0;
    if (strlen(f[6]) >= sizeof r->regime || strlen(f[7]) >= sizeof r->first_type || strlen(f[10]) >= sizeof r->upper)
        return 0;
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
    int lineno = 0, rc = 0, continued = 0;
    while (fgets(line, sizeof line, f)) {
        size_t len = strlen(line);
        int complete = len > 0 && line[len - 1] == '\n';
        /* The rest of a line longer than the buffer is not a row of its own. */
        int tail = continued;
        continued = !complete;
        if (tail) continue;
        lineno++;
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) line[--len] = '\0';
        if (lineno == 1) {
            if (strcmp(line, header) != 0) {
                snprintf(why, why_len, "%s is not a sweep file (line 1 is not the sweep header); refusing to append", path);
                rc = -1;
                break;
            }
            continue;
        }
        sweep_row r;
        if (!complete || !parse_row(line, &r)) continue;
        if (!sweep_table_add(t, &r)) {
            snprintf(why, why_len, "out of memory reading %s", path);
            rc = -1;
            break;
        }
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

void sweep_table_fix_tail(const char *path, FILE *f)
{
    FILE *r = fopen(path, "rb");
    if (!r) return;
    int last = EOF;
    if (fseek(r, -1, SEEK_END) == 0) last = fgetc(r);
    fclose(r);
    if (last != EOF && last != '\n') {
        fputc('\n', f);
        fflush(f);
    }
}
