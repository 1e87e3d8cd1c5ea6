/* sim_cmd_sweep_merge.c: `ribbon-sim sweep-merge`: joins the files of a sweep run in shards
 * (`ribbon-sim sweep --shard i/N`, on machines without MPI: Slurm job arrays, GNU parallel) into
 * one sweep file, in the canonical row order (sweep_row_compare), each row once. Merging one file
 * sorts it, so the files of a run in one process, on mpirun and in shards compare line by line
 * (docs/sweeps.md). The merged file is a sweep file like any other: `ribbon-sim sweep` with the
 * same grid on it resumes with nothing left to do and prints the summary and the figure.
 *
 * Refusals (issue 33, item 11): files of different sweeps (their "made by" lines differ:
 * program version, scene, N, grid, tolerance or seed; sim_sweep_origin.h) or a file without that
 * line; a row that is not a row (sweep_table_read names the file and line); two rows at one place
 * that say different things (named, with both files). Rows at one place that agree (wall_s
 * aside) are kept once, from the first file. A last line cut by a kill is left out with a
 * warning: rerunning the sweep on the merged file computes it again. */
#include "sim_cmd.h"
#include "sim_sweep_origin.h"
#include "sim_sweep_row.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char usage[] =
    "usage: ribbon-sim sweep-merge --out MERGED.csv PART.csv [PART.csv ...]\n"
    "  Joins sweep files (the shards of `ribbon-sim sweep --shard i/N`) into MERGED.csv, sorted by\n"
    "  (Delta L, phi, kind, Gamma), each row once (a row in several parts is kept from the first).\n"
    "  The parts must come from one sweep (the same '# made by:' line: program, scene, N, grid,\n"
    "  tolerance, seed); two rows at one place that differ, or a line that is not a row, are\n"
    "  errors. MERGED.csv must not exist yet.\n";

int sim_cmd_sweep_merge(int argc, char **argv)
{
    const char *out = NULL;
    int nin = 0;
    const char **in = calloc((size_t)argc + 1, sizeof *in);
    if (!in) return 1;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(usage, stdout);
            free(in);
            return 0;
        }
        if (!strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
        else if (argv[i][0] == '-') {
            fprintf(stderr, "ribbon-sim sweep-merge: unknown option %s\n%s", argv[i], usage);
            free(in);
            return 2;
        } else in[nin++] = argv[i];
    }
    if (!out || nin == 0) {
        fputs(usage, stderr);
        free(in);
        return 2;
    }
    if (access(out, F_OK) == 0) {
        fprintf(stderr, "ribbon-sim sweep-merge: %s exists; name a new file\n", out);
        free(in);
        return 1;
    }
    sweep_table all = {0};
    int *from = NULL; /* the input each row of `all` came from */
    size_t from_cap = 0;
    int status = 1;
    for (int k = 0; k < nin; k++) {
        sweep_table part;
        char err[512] = "", what[400];
        if (access(in[k], R_OK) != 0) {
            fprintf(stderr, "ribbon-sim sweep-merge: cannot read %s: %s\n", in[k], strerror(errno));
            goto done;
        }
        if (sweep_table_load(in[k], &part, err, sizeof err) != 0) {
            fprintf(stderr, "ribbon-sim sweep-merge: %s\n", err);
            goto done;
        }
        if (!part.origin[0]) {
            fprintf(stderr,
                    "ribbon-sim sweep-merge: %s does not say what made it (no '# made by:' line: an earlier "
                    "ribbon-sim wrote it); rerun that shard\n",
                    in[k]);
            sweep_table_free(&part);
            goto done;
        }
        if (k == 0) {
            snprintf(all.origin, sizeof all.origin, "%s", part.origin);
        } else if (sweep_origin_compare(all.origin, part.origin, what, sizeof what) != 0) {
            fprintf(stderr, "ribbon-sim sweep-merge: %s and %s come from different sweeps (%s); refusing to mix them\n",
                    in[0], in[k], what);
            sweep_table_free(&part);
            goto done;
        }
        if (part.cut_line)
            fprintf(stderr,
                    "ribbon-sim sweep-merge: %s line %ld is cut short (a run killed while writing it): left out; "
                    "rerun the sweep on the merged file to compute it again\n",
                    in[k], part.cut_line);
        for (size_t j = 0; j < part.n; j++) {
            const sweep_row *r = &part.rows[j], *dup = sweep_table_find_same(&all, r);
            if (dup) {
                if (!sweep_row_same_result(dup, r, what, sizeof what)) {
                    fprintf(stderr,
                            "ribbon-sim sweep-merge: the %s row at phi %.10g deg, Gamma %.10g, Delta L %.10g differs "
                            "between %s and %s (%s)\n",
                            r->kind == 'p' ? "point" : r->kind == 'q' ? "probe" : "boundary", r->phi, r->gamma, r->dl,
                            in[from[dup - all.rows]], in[k], what);
                    sweep_table_free(&part);
                    goto done;
                }
                continue;
            }
            if (all.n == from_cap) {
                size_t cap = from_cap ? 2 * from_cap : 64;
                int *nf = realloc(from, cap * sizeof *nf);
                if (!nf) {
                    fprintf(stderr, "ribbon-sim sweep-merge: out of memory\n");
                    sweep_table_free(&part);
                    goto done;
                }
                from = nf;
                from_cap = cap;
            }
            from[all.n] = k;
            if (!sweep_table_add(&all, r)) {
                fprintf(stderr, "ribbon-sim sweep-merge: out of memory\n");
                sweep_table_free(&part);
                goto done;
            }
        }
        sweep_table_free(&part);
    }
    if (all.n == 0) {
        fprintf(stderr, "ribbon-sim sweep-merge: no rows in %d file%s; nothing merged\n", nin, nin == 1 ? "" : "s");
        goto done;
    }
    qsort(all.rows, all.n, sizeof *all.rows, sweep_row_compare);
    FILE *f = fopen(out, "w");
    if (!f) {
        fprintf(stderr, "ribbon-sim sweep-merge: cannot write %s: %s\n", out, strerror(errno));
        goto done;
    }
    sweep_row_write_header(f, all.origin);
    for (size_t j = 0; j < all.n; j++) sweep_row_write(f, &all.rows[j]);
    if (fclose(f) != 0) {
        fprintf(stderr, "ribbon-sim sweep-merge: error writing %s\n", out);
        goto done;
    }
    printf("sweep-merge  %s: %zu rows from %d files\n", out, all.n, nin);
    status = 0;
done:
    free(from);
    sweep_table_free(&all);
    free(in);
    return status;
}
