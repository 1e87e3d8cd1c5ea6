/* store_bench_main.c: `ribbon-store-bench`, the store's benchmark as a program. Prints one JSON
 * line, {"bench":"store","samples":N,"samples_per_s":R,...}, so scripts and the coming
 * `ribbond bench` can read it. The database goes to a fresh temporary directory (removed after)
 * unless --db names a file, which must not exist yet and is kept. */
#include <errno.h>
#include <jansson.h>
#include <limits.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "store.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: ribbon-store-bench [--samples N] [--db FILE]\n"
               "  writes N samples (default 200000) through the store's batched writer and prints\n"
               "  {\"bench\":\"store\",\"samples\":N,\"samples_per_s\":R,...} on one line.\n"
               "  --db FILE  write to FILE (must not exist; kept); default: a temporary directory\n");
}

int main(int argc, char **argv)
{
    long long n = 200000;
    const char *db = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(argv[i], "--samples") == 0 && i + 1 < argc) {
            char *end;
            errno = 0;
            n = strtoll(argv[++i], &end, 10);
            if (errno || *end || n < 1) {
                fprintf(stderr, "ribbon-store-bench: --samples wants a positive integer, not '%s'\n", argv[i]);
                return 2;
            }
        } else if (strcmp(argv[i], "--db") == 0 && i + 1 < argc) {
            db = argv[++i];
        } else {
            fprintf(stderr, "ribbon-store-bench: unknown argument '%s'\n", argv[i]);
            usage(stderr);
            return 2;
        }
    }
    char dir[PATH_MAX] = "", path[PATH_MAX + 32];
    if (!db) {
        const char *tmp = getenv("TMPDIR");
        snprintf(dir, sizeof dir, "%s/ribbon-store-bench.XXXXXX", tmp && *tmp ? tmp : "/tmp");
        if (!mkdtemp(dir)) {
            fprintf(stderr, "ribbon-store-bench: cannot create a temporary directory %s: %s\n", dir, strerror(errno));
            return 1;
        }
        snprintf(path, sizeof path, "%s/bench.sqlite", dir);
        db = path;
    }
    char why[512] = "";
    double rate = 0.0;
    store_err e = store_bench_samples(db, n, &rate, why, sizeof why);
    if (dir[0]) {
        static const char *const suffix[] = {"", "-wal", "-shm"};
        char f[PATH_MAX + 48];
        for (int i = 0; i < 3; i++) {
            snprintf(f, sizeof f, "%s%s", path, suffix[i]);
            unlink(f);
        }
        rmdir(dir);
    }
    if (e != STORE_OK) {
        fprintf(stderr, "ribbon-store-bench: %s\n", why);
        return 1;
    }
    store_writer_params wp = store_writer_params_default();
    json_t *j = json_pack("{s:s, s:I, s:f, s:i, s:f, s:s, s:s}", "bench", "store", "samples", (json_int_t)n,
                          "samples_per_s", rate, "batch_rows", (int)wp.batch_rows, "max_age_s", wp.max_age_s,
                          "sqlite", sqlite3_libversion(), "version", RIBBON_VERSION);
    char *line = j ? json_dumps(j, JSON_COMPACT | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(6)) : NULL;
    if (!line) {
        fprintf(stderr, "ribbon-store-bench: out of memory\n");
        json_decref(j);
        return 1;
    }
    puts(line);
    free(line);
    json_decref(j);
    return 0;
}
