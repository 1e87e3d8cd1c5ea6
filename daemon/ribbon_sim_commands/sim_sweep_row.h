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
 * points again exactly. Files of the earlier 11-column layout (no dl, no upper) are refused.
 *
 * Line 2 says what made the file (issue 33, item 11; sim_sweep_origin.h builds and compares it):
 *     # made by: ribbon-sim 1.2.0; scene 0123456789abcdef; nodes 41; phi 60:120:2; ...
 * Every other line is a whole row: a line that does not parse (a nan, a missing field, an unknown
 * kind, a line past 1023 bytes) is an error naming the file and the line, never skipped. The one
 * exception is a last line without its newline, a row cut by a kill: left out and counted
 * (sweep_table.cut_line), and cut off the file when a sweep resumes it. */
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

#define SWEEP_ORIGIN_MAX 512

typedef struct sweep_table {
    sweep_row *rows;
    size_t n, cap;
    char origin[SWEEP_ORIGIN_MAX]; /* line 2 after "# made by: ", "" when the file has none */
    long cut_line;                 /* the number of a last line cut short (left out), else 0 */
} sweep_table;

/* Reads the rows of an existing sweep file into t (an absent file is an empty table). A last line
 * without its newline (a row cut by a kill) is left out (t->cut_line). Fails (returns -1 with
 * err) when the file is not a sweep file (wrong header), a line is not a row ("FILE line N: why")
 * or memory runs out. */
int sweep_table_load(const char *path, sweep_table *t, char *why, size_t why_len);

/* The same on an open file (path names it in messages): the parser itself, fuzzed on its own
 * (fuzz/fuzz_sweep_csv.c). A line longer than 1023 bytes is refused, never read as a row from its
 * middle. */
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

/* The header line, then "# made by: origin" when origin is not empty. */
void sweep_row_write_header(FILE *f, const char *origin);
void sweep_row_write(FILE *f, const sweep_row *r);

/* Whether two rows at the same place say the same (every field but wall_s, a measurement):
 * 1 same, 0 not, with the first field that differs and both values in what. */
int sweep_row_same_result(const sweep_row *a, const sweep_row *b, char *what, size_t what_len);

/* When the file at path does not end with a newline (a row cut by a kill), cuts that last part
 * line off, so the next row appended starts on its own line and the file holds whole rows only.
 * 0, or -1 when the file could not be cut (errno). */
int sweep_table_fix_tail(const char *path);

#endif
