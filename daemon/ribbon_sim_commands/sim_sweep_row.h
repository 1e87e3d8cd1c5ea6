/* sim_sweep_row.h: the rows of a sweep CSV and the in-memory table a sweep resumes from.
 *
 * One row per line, the header first:
 *     kind,phi_deg,gamma,gamma_lo,gamma_hi,dl,regime,first_type,first_dw,first_dz,upper,wall_s,note
 * kind is `point` (a grid point), `probe` (a bisection point) or `boundary` (Gamma* for one phi
 * and Delta L, bracketed by gamma_lo .. gamma_hi); regime is asymmetric, symmetric, none,
 * no-upper (no stable upper state found: the note gives the evidence), failed or boundary; upper
 * says how the upper state was reached (route, continued: from the neighbouring Gamma's, -: none);
 * note is free text without commas (the reason of a failure, the regimes either side of a
 * boundary). Numbers are printed with 17 significant digits so a resumed sweep finds its grid
 * points again exactly. Files of the earlier 11-column layout (no dl, no upper) are refused. */
#ifndef RIBBON_DAEMON_SIM_SWEEP_ROW_H
#define RIBBON_DAEMON_SIM_SWEEP_ROW_H

#include <stddef.h>
#include <stdio.h>

typedef struct sweep_row {
    char kind;             /* 'p' point, 'q' probe, 'b' boundary */
    double phi;            /* deg, crease angle magnitude */
    double gamma, gamma_lo, gamma_hi;
    double dl;             /* Delta L of the row */
    char regime[16];
    char first_type[16];   /* rod_event_name of the first instability, or none */
    double first_dw, first_dz;
    char upper[12];        /* route, continued or - */
    double wall_s;
    char note[160];
} sweep_row;

typedef struct sweep_table {
    sweep_row *rows;
    size_t n, cap;
} sweep_table;

/* Reads the rows of an existing sweep file into t (an absent file is an empty table). Lines that
 * do not parse (a row cut by a kill) are skipped. Fails (returns -1 with err) when the file is
 * not a sweep file (wrong header) or memory runs out. */
int sweep_table_load(const char *path, sweep_table *t, char *why, size_t why_len);

/* The same on an open file (path names it in messages): the parser itself, fuzzed on its own
 * (fuzz/fuzz_sweep_csv.c). A line longer than 1023 bytes is skipped whole, never read as a row
 * from its middle. */
int sweep_table_read(FILE *f, const char *path, sweep_table *t, char *why, size_t why_len);
int sweep_table_add(sweep_table *t, const sweep_row *r);
void sweep_table_free(sweep_table *t);

/* A classified row (point or probe, not failed) at (phi, gamma, dl), or NULL. */
const sweep_row *sweep_table_find(const sweep_table *t, double phi, double gamma, double dl);
/* A boundary row of (phi, dl) inside [lo, hi], or NULL. */
const sweep_row *sweep_table_find_boundary(const sweep_table *t, double phi, double dl, double lo, double hi);
/* A row of the same kind at the same place (phi, gamma, gamma_lo, gamma_hi, dl), failed ones
 * included, or NULL: what a writer checks so a retried task does not write a row twice. */
const sweep_row *sweep_table_find_same(const sweep_table *t, const sweep_row *r);

/* The canonical order of rows (dl, phi, kind point < probe < boundary, gamma, gamma_lo): what
 * sweep-merge writes, so files of differently split runs compare line by line. */
int sweep_row_compare(const void *a, const void *b);

void sweep_row_write_header(FILE *f);
void sweep_row_write(FILE *f, const sweep_row *r);

/* When the file at path does not end with a newline (a row cut by a kill), writes one to f (the
 * same file opened for appending) so the next row starts on its own line. */
void sweep_table_fix_tail(const char *path, FILE *f);

#endif
