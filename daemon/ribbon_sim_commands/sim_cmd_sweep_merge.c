/* sim_cmd_sweep_merge.c: `ribbon-sim sweep-merge`: joins the files of a sweep run in shards
 * (`ribbon-sim sweep --shard i/N`, on machines without MPI: Slurm job arrays, GNU parallel) into
 * one sweep file, in the canonical row order (sweep_row_compare), each row once. Merging one file
 * sorts it, so the files of a run in one process, on mpirun and in shards compare line by line
 * (docs/sweeps.md). The merged file is a sweep file like any other: `ribbon-sim sweep` with the
 * same grid on it resumes with nothing left to do and prints the summary and the figure. */
#include "sim_cmd.h"
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
    "  MERGED.csv must not exist yet.\n";

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
    int status = 1;
    for (int k = 0; k < nin; k++) {
        sweep_table part;
        char err[256] = "";
        if (access(in[k], R_OK) != 0) {
            fprintf(stderr, "ribbon-sim sweep-merge: cannot read %s: %s\n", in[k], strerror(errno));
            goto done;
        }
        if (sweep_table_load(in[k], &part, err, sizeof err) != 0) {
            fprintf(stderr, "ribbon-sim sweep-merge: %s\n", err);
            goto done;
        }
        for (size_t j = 0; j < part.n; j++)
            if (!sweep_table_find_same(&all, &part.rows[j]) && !sweep_table_add(&all, &part.rows[j])) {
                fprintf(stderr, "ribbon-sim sweep-merge: out of memory\n");
                sweep_table_free(&part);
                goto done;
            }
        sweep_table_free(&part);
    }
    qsort(all.rows, all.n, sizeof *all.rows, sweep_row_compare);
    FILE *f = fopen(out, "w");
    if (!f) {
        fprintf(stderr, "ribbon-sim sweep-merge: cannot write %s: %s\n", out, strerror(errno));
        goto done;
    }
    sweep_row_write_header(f);
    for (size_t j = 0; j < all.n; j++) sweep_row_write(f, &all.rows[j]);
    if (fclose(f) != 0) {
        fprintf(stderr, "ribbon-sim sweep-merge: error writing %s\n", out);
        goto done;
    }
    printf("sweep-merge  %s: %zu rows from %d files\n", out, all.n, nin);
    status = 0;
done:
    sweep_table_free(&all);
    free(in);
    return status;
}
