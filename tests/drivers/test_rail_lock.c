/* test_rail_lock: one owner per store and per rail device (issue 33, item 1).
 *   - owner_lock: a second take of one lock file is refused (in this process too: flock, not
 *     fcntl) naming the holder's pid and since when; a holder killed with SIGKILL leaves the
 *     lock free (the kernel releases it), its stale line replaced by the next holder's.
 *   - rail_locks: two gcode rails on one port take one lock; a second owner of that port is
 *     refused naming the rail, the port and the holder, also through another name of the same
 *     device (a symlink); a Modbus TCP drive is locked by its address; mock rails lock nothing.
 * Lock files go to a temporary RIBBON_LOCK_DIR; the serial "port" is /dev/null (a character
 * device: the lock is keyed on its numbers and never opens it).
 *   - the lock directory: a ribbond with RIBBON_LOCK_DIR and a ribbonctl without it (and the other
 *     way round) see each other's lock, the refusal naming the lock file found held. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "owner_lock.h"
#include "rail_lock.h"

static char dir[64];

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/rail-lock-XXXXXX");
    if (!mkdtemp(dir)) return -1;
    setenv("RIBBON_LOCK_DIR", dir, 1);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static void owner_lock_names_holder_and_dies_with_it(void **state)
{
    (void)state;
    char path[128], why[512], pid[32];
    snprintf(path, sizeof path, "%s/store.db.lock", dir);
    int held = -1;
    owner_lock *a = owner_lock_take(path, "first owner", &held, why, sizeof why);
    assert_non_null(a);
    assert_int_equal(held, 0);
    /* A second owner in the same process is refused (fcntl locks would let it through). */
    owner_lock *b = owner_lock_take(path, "second owner", &held, why, sizeof why);
    printf("second owner: %s\n", why);
    assert_null(b);
    assert_int_equal(held, 1);
    snprintf(pid, sizeof pid, "pid %ld since ", (long)getpid());
    assert_non_null(strstr(why, pid));
    assert_non_null(strstr(why, "(first owner)"));
    owner_lock_release(a);
    b = owner_lock_take(path, "second owner", &held, why, sizeof why);
    assert_non_null(b);
    owner_lock_release(b);

    /* A holder killed with SIGKILL: refused while it lives, free once it is dead. */
    int ready[2];
    assert_int_equal(pipe(ready), 0);
    pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) {
        char w[256];
        owner_lock *c = owner_lock_take(path, "child", NULL, w, sizeof w);
        if (write(ready[1], c ? "y" : "n", 1) != 1) _exit(2);
        for (;;) pause();
    }
    char c = 0;
    assert_int_equal(read(ready[0], &c, 1), 1);
    assert_int_equal(c, 'y');
    b = owner_lock_take(path, "parent", &held, why, sizeof why);
    assert_null(b);
    snprintf(pid, sizeof pid, "pid %ld since ", (long)child);
    printf("while the child lives: %s\n", why);
    assert_non_null(strstr(why, pid));
    kill(child, SIGKILL);
    waitpid(child, NULL, 0);
    b = owner_lock_take(path, "parent after the kill", &held, why, sizeof why);
    assert_non_null(b);
    owner_lock *again = owner_lock_take(path, "third", &held, why, sizeof why);
    assert_null(again);
    assert_non_null(strstr(why, "(parent after the kill)")); /* the dead child's line is gone */
    owner_lock_release(b);
    close(ready[0]);
    close(ready[1]);
}

static rail_open_spec gcode_spec(const char *name, const char *port)
{
    rail_open_spec s;
    memset(&s, 0, sizeof s);
    snprintf(s.driver, sizeof s.driver, "gcode");
    s.params = rail_params_default();
    snprintf(s.params.name, sizeof s.params.name, "%s", name);
    s.gcode = rail_gcode_params_default();
    snprintf(s.gcode.port, sizeof s.gcode.port, "%s", port);
    return s;
}

static void rails_lock_their_devices(void **state)
{
    (void)state;
    char why[1024];
    rail_open_spec c = gcode_spec("compress", "/dev/null"), s = gcode_spec("shear", "/dev/null");
    rail_locks *first = NULL, *second = NULL;
    /* Two axes of one controller: one lock, taken once. */
    assert_int_equal(rail_locks_take(&c, &s, "ribbond one", &first, why, sizeof why), RAIL_OK);
    assert_non_null(first);
    /* Another daemon on the same port, through another name of it. */
    char link[128];
    snprintf(link, sizeof link, "%s/grbl", dir);
    assert_int_equal(symlink("/dev/null", link), 0);
    rail_open_spec c2 = gcode_spec("compress", link), s2 = gcode_spec("shear", link);
    rail_err e = rail_locks_take(&c2, &s2, "ribbond two", &second, why, sizeof why);
    printf("second daemon: %s\n", why);
    assert_int_equal(e, RAIL_E_STATE);
    assert_null(second);
    assert_non_null(strstr(why, "rail compress: serial port"));
    assert_non_null(strstr(why, "is in use"));
    assert_non_null(strstr(why, "(ribbond one)"));
    char pid[32];
    snprintf(pid, sizeof pid, "pid %ld", (long)getpid());
    assert_non_null(strstr(why, pid));
    rail_locks_release(first);
    assert_int_equal(rail_locks_take(&c2, &s2, "ribbond two", &second, why, sizeof why), RAIL_OK);
    rail_locks_release(second);

    /* Modbus TCP drives by address; mock rails hold nothing. */
    rail_open_spec m1 = gcode_spec("compress", ""), m2 = gcode_spec("shear", "");
    snprintf(m1.driver, sizeof m1.driver, "modbus");
    snprintf(m2.driver, sizeof m2.driver, "modbus");
    m1.modbus = rail_modbus_params_default();
    m2.modbus = rail_modbus_params_default();
    snprintf(m1.modbus.address, sizeof m1.modbus.address, "127.0.0.1:15020");
    snprintf(m2.modbus.address, sizeof m2.modbus.address, "127.0.0.1:15021");
    assert_int_equal(rail_locks_take(&m1, &m2, "modbus one", &first, why, sizeof why), RAIL_OK);
    rail_open_spec k1 = gcode_spec("compress", ""), k2 = m2;
    snprintf(k1.driver, sizeof k1.driver, "mock");
    e = rail_locks_take(&k1, &k2, "modbus two", &second, why, sizeof why);
    printf("second owner of a drive: %s\n", why);
    assert_int_equal(e, RAIL_E_STATE);
    assert_non_null(strstr(why, "rail shear: Modbus drive 127.0.0.1:15021 is in use"));
    rail_locks_release(first);
    rail_open_spec k2m = k1;
    assert_int_equal(rail_locks_take(&k1, &k2m, "mock", &second, why, sizeof why), RAIL_OK);
    assert_null(second);
}

/* A ribbond started with RIBBON_LOCK_DIR (a systemd unit's Environment=) and a ribbonctl run
 * from a shell without it, and the other way round, resolve different lock directories: each
 * must still find the other's lock, and say which lock file it found held. The device is a
 * Modbus TCP address of this process's own (only its lock's name matters; nothing connects). */
static void env_and_default_lock_dirs_see_each_other(void **state)
{
    (void)state;
    char why[1024], addr[64], def[512];
    rail_open_spec m = gcode_spec("shear", "");
    snprintf(m.driver, sizeof m.driver, "modbus");
    m.modbus = rail_modbus_params_default();
    snprintf(addr, sizeof addr, "127.0.0.1:%d", 20000 + (int)(getpid() % 40000));
    snprintf(m.modbus.address, sizeof m.modbus.address, "%s", addr);
    rail_locks *a = NULL, *b = NULL;

    assert_int_equal(rail_locks_take(&m, NULL, "ribbond with RIBBON_LOCK_DIR", &a, why, sizeof why), RAIL_OK);
    unsetenv("RIBBON_LOCK_DIR");
    snprintf(def, sizeof def, "%s/ribbon-rig-modbus-127.0.0.1_%s.lock", rail_lock_dir(), strchr(addr, ':') + 1);
    rail_err e = rail_locks_take(&m, NULL, "ribbonctl without it", &b, why, sizeof why);
    printf("without the variable: %s\n", why);
    assert_int_equal(e, RAIL_E_STATE);
    assert_null(b);
    assert_non_null(strstr(why, def)); /* the lock file found held, by its path */
    assert_non_null(strstr(why, "(ribbond with RIBBON_LOCK_DIR)"));
    rail_locks_release(a);

    assert_int_equal(rail_locks_take(&m, NULL, "ribbond without it", &a, why, sizeof why), RAIL_OK);
    setenv("RIBBON_LOCK_DIR", dir, 1);
    e = rail_locks_take(&m, NULL, "ribbonctl with RIBBON_LOCK_DIR", &b, why, sizeof why);
    printf("with the variable: %s\n", why);
    assert_int_equal(e, RAIL_E_STATE);
    assert_null(b);
    assert_non_null(strstr(why, def));
    assert_non_null(strstr(why, "(ribbond without it)"));
    rail_locks_release(a);
    /* Free again for either, once released. */
    assert_int_equal(rail_locks_take(&m, NULL, "again", &b, why, sizeof why), RAIL_OK);
    rail_locks_release(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(owner_lock_names_holder_and_dies_with_it),
        cmocka_unit_test(rails_lock_their_devices),
        cmocka_unit_test(env_and_default_lock_dirs_see_each_other),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
