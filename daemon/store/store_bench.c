/* store_bench.c: how many samples per second the batched writer puts into SQLite, measured the
 * way a trial writes them: one trial, rail readings and camera frames interleaved, the default
 * batch and age limits, the same PRAGMAs (WAL, synchronous=NORMAL) as the daemon. The target
 * (issue 6) is at least 50,000 samples/s; a trial needs a few hundred. The clock is
 * CLOCK_MONOTONIC around the writer only, so opening and creating the schema are not counted. */
#include "store_sql.h"

#include <errno.h>
#include <math.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

store_err store_bench_samples(const char *path, int64_t n_samples, double *samples_per_s, char *why,
                              size_t why_len)
{
    *samples_per_s = 0.0;
    if (n_samples < 1)
        return store_fail(why, why_len, STORE_E_INVALID, "benchmark needs at least one sample (got %lld)",
                          (long long)n_samples);
    if (!path || !*path)
        return store_fail(why, why_len, STORE_E_INVALID, "no benchmark database path given");
    if (access(path, F_OK) == 0)
        return store_fail(why, why_len, STORE_E_INVALID, "%s exists; the benchmark writes a fresh database", path);
    store *st;
    store_err e = store_open(path, &st, why, why_len);
    if (e != STORE_OK)
        return e;
    store_trial_def def = store_trial_def_default();
    def.mode = STORE_MODE_MOCK;
    def.config_text = "; store benchmark";
    int64_t trial = 0;
    e = store_trial_create(st, &def, &trial, why, why_len);
    store_samples *w = NULL;
    if (e == STORE_OK)
        e = store_samples_begin(st, trial, NULL, &w, why, why_len);
    double t0 = mono_s();
    /* A 1 kHz synthetic stream: every fourth sample a camera frame. */
    for (int64_t i = 0; i < n_samples && e == STORE_OK; i++) {
        store_sample s = store_sample_default();
        s.t_s = 1e-3 * (double)i;
        s.compress_mm = 40.0;
        s.shear_mm = 0.01 * s.t_s;
        if (i % 4 == 3) {
            s.kind = STORE_SAMPLE_FRAME;
            s.frame = i / 4;
            s.dl = 0.5;
            s.dw = 0.002 * s.t_s;
            s.dz = 0.3 - 0.01 * s.t_s;
            s.a = 0.01 * sin(s.t_s);
            s.quality = 0.98;
        }
        e = store_samples_add(w, &s, why, why_len);
    }
    if (w) {
        store_err ee = store_samples_end(w, e == STORE_OK ? why : NULL, e == STORE_OK ? why_len : 0);
        if (e == STORE_OK)
            e = ee;
    }
    double dt = mono_s() - t0;
    if (e == STORE_OK)
        *samples_per_s = dt > 0.0 ? (double)n_samples / dt : INFINITY;
    store_close(st);
    return e;
}
