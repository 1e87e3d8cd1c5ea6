/* test_store_read_only.c: a WAL store opened read-only (ribbonctl --db) from a directory the
 * reader cannot write (issue 33: "PRAGMA user_version: unable to open database file"). A store
 * closed cleanly (no -wal pages) is read, its trial there; a store with pages still in its -wal
 * file and no -shm index is refused in words that say a WAL store needs a writable directory.
 * The reader is a child process: as root it drops to nobody (65534), since root writes any
 * directory; otherwise the directory is made read-only. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include <sqlite3.h>

#include "store.h"

static char dir[256], db[320];

static void rm_dir(const char *d)
{
    char p[400];
    static const char *const names[] = {"ribbon.sqlite", "ribbon.sqlite-wal", "ribbon.sqlite-shm"};
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
        snprintf(p, sizeof p, "%s/%s", d, names[k]);
        unlink(p);
    }
    rmdir(d);
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/test_store_read_only.XXXXXX");
    if (!mkdtemp(dir)) return -1;
    snprintf(db, sizeof db, "%s/ribbon.sqlite", dir);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    chmod(dir, 0700);
    rm_dir(dir);
    return 0;
}

/* A store with one trial, closed (WAL mode, no -wal left). */
static void make_store(void)
{
    char why[512];
    store *st;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    store_trial_def tp = store_trial_def_default();
    int64_t id = 0;
    assert_int_equal(store_trial_create(st, &tp, &id, why, sizeof why), STORE_OK);
    store_close(st);
    chmod(db, 0644);
}

/* In a child that cannot write dir: opens db read-only; exit 0 when opened and trial 1 read, 1
 * when refused (the reason on stdout, prefixed "why: "), 2 on anything else. */
static int read_in_child(char *why_out, size_t why_len)
{
    int fd[2];
    assert_int_equal(pipe(fd), 0);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        close(fd[0]);
        if (getuid() == 0) {
            if (chmod(dir, 0755) != 0 || setgid(65534) != 0 || setuid(65534) != 0) _exit(2);
        }
        if (access(dir, W_OK) == 0) _exit(2); /* not the case under test */
        char why[512] = "";
        store_open_params p = store_open_params_default();
        p.read_only = true;
        store *st = NULL;
        int code = 1;
        if (store_open_ex(db, &p, &st, why, sizeof why) == STORE_OK) {
            store_trial t;
            code = store_trial_get(st, 1, &t, why, sizeof why) == STORE_OK ? 0 : 2;
            store_close(st);
        }
        if (write(fd[1], why, strlen(why)) < 0) code = 2;
        _exit(code);
    }
    close(fd[1]);
    if (getuid() != 0) chmod(dir, 0555);
    size_t n = 0;
    ssize_t k;
    while (n + 1 < why_len && (k = read(fd[0], why_out + n, why_len - 1 - n)) > 0) n += (size_t)k;
    why_out[n] = '\0';
    close(fd[0]);
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    chmod(dir, 0700);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 3;
}

static void test_clean_wal_store_read_from_read_only_dir(void **state)
{
    (void)state;
    make_store();
    char p[400];
    snprintf(p, sizeof p, "%s-wal", db);
    assert_int_equal(access(p, F_OK), -1); /* closed cleanly: every page in the file */
    char why[512];
    int code = read_in_child(why, sizeof why);
    if (code != 0) fail_msg("read-only open: exit %d: %s", code, why);
}

static void test_wal_pages_without_index_refused_in_words(void **state)
{
    (void)state;
    make_store();
    /* Pages left in the -wal file (a writer that has not checkpointed), and no -shm: a copy of
     * the pair taken while a connection held them. */
    sqlite3 *h = NULL;
    assert_int_equal(sqlite3_open(db, &h), SQLITE_OK);
    assert_int_equal(sqlite3_exec(h, "PRAGMA wal_autocheckpoint=0; CREATE TABLE pending(x); INSERT INTO pending VALUES(1);",
                                  NULL, NULL, NULL),
                     SQLITE_OK);
    char other[256], cmd[1200];
    snprintf(other, sizeof other, "/tmp/test_store_read_only_copy.XXXXXX");
    assert_non_null(mkdtemp(other));
    snprintf(cmd, sizeof cmd, "cp %s %s-wal %s/", db, db, other);
    assert_int_equal(system(cmd), 0);
    sqlite3_close(h);
    rm_dir(dir);
    snprintf(dir, sizeof dir, "%s", other);
    snprintf(db, sizeof db, "%s/ribbon.sqlite", dir);
    chmod(db, 0644);
    char wal[400];
    snprintf(wal, sizeof wal, "%s-wal", db);
    chmod(wal, 0644);
    char why[512];
    int code = read_in_child(why, sizeof why);
    print_message("%s\n", why);
    assert_int_equal(code, 1);
    assert_non_null(strstr(why, "needs a writable directory"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_clean_wal_store_read_from_read_only_dir, setup, teardown),
        cmocka_unit_test_setup_teardown(test_wal_pages_without_index_refused_in_words, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
