/* test_store_crash.c: committed samples survive kill -9. A child process opens the store, starts
 * a trial, and writes samples through the batched writer as fast as it can, reporting on a pipe
 * how many it has committed after every commit. The parent kills it with SIGKILL mid-stream (it
 * is always inside a batch, often inside a commit), reopens the file and checks: PRAGMA
 * integrity_check is ok, every sample reported committed is there with its values, the rows
 * have no gaps, the trial's sample count matches its rows, and store_trial_mark_interrupted
 * turns the child's 'running' trial into 'interrupted'. Three rounds on one file, killed at different points. */
#include <errno.h>
#include <math.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include <sqlite3.h>

#include "store.h"

static char why[512];

#define OK(call)                                                                                            \
    do {                                                                                                    \
        store_err e_ = (call);                                                                              \
        if (e_ != STORE_OK)                                                                                 \
            fail_msg("%s -> %s: %s", #call, store_err_message(e_), why);                                    \
    } while (0)

/* The sample with sequence number i, so the parent can check values without a copy. */
static store_sample sample_of(int64_t i)
{
    store_sample s = store_sample_default();
    s.t_s = 1e-3 * (double)i;
    s.kind = (i % 3 == 0) ? STORE_SAMPLE_FRAME : STORE_SAMPLE_RAIL;
    s.frame = s.kind == STORE_SAMPLE_FRAME ? i / 3 : -1;
    s.compress_mm = 50.0 - 1e-4 * (double)i;
    s.shear_mm = 1e-3 * (double)i;
    if (s.kind == STORE_SAMPLE_FRAME) {
        s.dw = 1e-5 * (double)i;
        s.dz = 0.3 + 1e-6 * (double)i;
        s.a = (double)(i % 17);
    }
    return s;
}

static bool write_all(int fd, const void *p, size_t n)
{
    const char *c = p;
    while (n > 0) {
        ssize_t k = write(fd, c, n);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            return false;
        c += k;
        n -= (size_t)k;
    }
    return true;
}

static bool read_all(int fd, void *p, size_t n)
{
    char *c = p;
    while (n > 0) {
        ssize_t k = read(fd, c, n);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0)
            return false;
        c += k;
        n -= (size_t)k;
    }
    return true;
}

/* The writer process: never returns. */
static void child(const char *db, int fd)
{
    char w_why[256];
    store *st;
    if (store_open(db, &st, w_why, sizeof w_why) != STORE_OK)
        _exit(2);
    store_trial_def d = store_trial_def_default();
    d.mode = STORE_MODE_MOCK;
    int64_t id;
    if (store_trial_create(st, &d, &id, w_why, sizeof w_why) != STORE_OK ||
        store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, store_wall_now(), w_why, sizeof w_why) != STORE_OK)
        _exit(3);
    if (!write_all(fd, &id, sizeof id))
        _exit(4);
    store_writer_params p = store_writer_params_default();
    p.batch_rows = 50;
    store_samples *w;
    if (store_samples_begin(st, id, &p, &w, w_why, sizeof w_why) != STORE_OK)
        _exit(5);
    int64_t reported = 0;
    for (int64_t i = 0; i < 100000000; i++) {
        store_sample s = sample_of(i);
        if (store_samples_add(w, &s, w_why, sizeof w_why) != STORE_OK)
            _exit(6);
        int64_t c = store_samples_committed(w);
        if (c != reported) {
            reported = c;
            if (!write_all(fd, &c, sizeof c))
                _exit(7);
        }
    }
    _exit(8);
}

static void check_samples(store *st, int64_t trial, int64_t at_least)
{
    store_sample *v;
    size_t n;
    OK(store_samples_get(st, trial, &v, &n, why, sizeof why));
    if ((int64_t)n < at_least)
        fail_msg("only %zu samples after the kill; %lld were reported committed", n, (long long)at_least);
    for (size_t i = 0; i < n; i++) {
        store_sample e = sample_of((int64_t)i);
        const store_sample *g = &v[i];
        bool same = g->seq == (int64_t)i && g->t_s == e.t_s && g->kind == e.kind && g->frame == e.frame &&
                    g->compress_mm == e.compress_mm && g->shear_mm == e.shear_mm &&
                    (g->dw == e.dw || (isnan(g->dw) && isnan(e.dw))) &&
                    (g->dz == e.dz || (isnan(g->dz) && isnan(e.dz))) && (g->a == e.a || (isnan(g->a) && isnan(e.a)));
        if (!same)
            fail_msg("sample %zu differs after the kill", i);
    }
    free(v);
}

static void test_kill9_mid_stream(void **state)
{
    (void)state;
    char dir[256];
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/test_store_crash.XXXXXX", tmp && *tmp ? tmp : "/tmp");
    assert_non_null(mkdtemp(dir));
    char db[320];
    snprintf(db, sizeof db, "%s/ribbon.sqlite", dir);
    signal(SIGPIPE, SIG_IGN);

    /* Committed samples seen before the kill, and a delay after that (us) so the kill lands at a
     * different point of the stream each round: between rows, in a commit, between commits. */
    static const int64_t kill_after[3] = {1000, 2600, 5150};
    static const useconds_t delay_us[3] = {0, 700, 2300};
    for (int round = 0; round < 3; round++) {
        int pfd[2];
        assert_int_equal(pipe(pfd), 0);
        pid_t pid = fork();
        assert_true(pid >= 0);
        if (pid == 0) {
            close(pfd[0]);
            child(db, pfd[1]);
        }
        close(pfd[1]);
        int64_t trial = 0, committed = 0, c;
        if (!read_all(pfd[0], &trial, sizeof trial)) {
            int st = 0;
            waitpid(pid, &st, 0);
            fail_msg("the writer child died before starting (exit %d)", WIFEXITED(st) ? WEXITSTATUS(st) : -1);
        }
        while (committed < kill_after[round] && read_all(pfd[0], &c, sizeof c))
            committed = c;
        if (delay_us[round])
            usleep(delay_us[round]);
        assert_int_equal(kill(pid, SIGKILL), 0);
        int status = 0;
        assert_int_equal(waitpid(pid, &status, 0), pid);
        assert_true(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
        /* Whatever the child reported before it died was committed. */
        while (read_all(pfd[0], &c, sizeof c))
            committed = c;
        close(pfd[0]);
        assert_true(committed >= kill_after[round]);

        store *st;
        OK(store_open(db, &st, why, sizeof why));
        sqlite3_stmt *s;
        assert_int_equal(sqlite3_prepare_v2(store_handle(st), "PRAGMA integrity_check", -1, &s, NULL), SQLITE_OK);
        assert_int_equal(sqlite3_step(s), SQLITE_ROW);
        assert_string_equal((const char *)sqlite3_column_text(s, 0), "ok");
        sqlite3_finalize(s);
        check_samples(st, trial, committed);
        store_trial t;
        OK(store_trial_get(st, trial, &t, why, sizeof why));
        assert_int_equal(t.status, STORE_STATUS_RUNNING);
        /* The trial's cached count went in the same commits as the rows. */
        assert_int_equal(sqlite3_prepare_v2(store_handle(st), "SELECT count(*) FROM samples WHERE trial_id = ?1", -1,
                                            &s, NULL),
                         SQLITE_OK);
        sqlite3_bind_int64(s, 1, trial);
        assert_int_equal(sqlite3_step(s), SQLITE_ROW);
        assert_int_equal(sqlite3_column_int64(s, 0), t.samples);
        sqlite3_finalize(s);
        int n = 0;
        OK(store_trial_mark_interrupted(st, store_wall_now(), &n, why, sizeof why));
        assert_int_equal(n, 1);
        OK(store_trial_get(st, trial, &t, why, sizeof why));
        assert_int_equal(t.status, STORE_STATUS_INTERRUPTED);
        assert_true(t.ended_at[0] != '\0');
        store_close(st);
    }
    static const char *const files[] = {"ribbon.sqlite", "ribbon.sqlite-wal", "ribbon.sqlite-shm"};
    for (int i = 0; i < 3; i++) {
        char p[400];
        snprintf(p, sizeof p, "%s/%s", dir, files[i]);
        unlink(p);
    }
    assert_int_equal(rmdir(dir), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kill9_mid_stream),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
