/* test_thread_class: the best-effort threads' scheduling class (drivers/thread_class.h).
 *   - a thread that calls thread_class_idle_enter runs in SCHED_IDLE, read back from another thread by
 *     its thread id (what the kernel says, not what the call returned);
 *   - the thread that created it keeps its own class (the trial's loop is such a thread);
 *   - a thread it creates afterwards (an encoder's slice thread) is in SCHED_IDLE too;
 *   - a thread id that does not exist reads as -1, not as a class. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>

#include "thread_class.h"

typedef struct probe {
    atomic_long tid, child_tid;
    atomic_int entered, release;
    int enter_rc, self_idle;
} probe;

static void *child_main(void *arg)
{
    probe *p = arg;
    atomic_store(&p->child_tid, thread_class_tid());
    while (!atomic_load(&p->release)) sched_yield();
    return NULL;
}

static void *worker_main(void *arg)
{
    probe *p = arg;
    p->enter_rc = thread_class_idle_enter(NULL, 0);
    p->self_idle = thread_class_is_idle(0);
    pthread_t child;
    int made = pthread_create(&child, NULL, child_main, p) == 0;
    atomic_store(&p->tid, thread_class_tid());
    atomic_store(&p->entered, 1);
    while (!atomic_load(&p->release)) sched_yield();
    if (made) pthread_join(child, NULL);
    return NULL;
}

static void idle_thread_and_its_children(void **state)
{
    (void)state;
    probe p;
    atomic_init(&p.tid, 0);
    atomic_init(&p.child_tid, 0);
    atomic_init(&p.entered, 0);
    atomic_init(&p.release, 0);
    p.enter_rc = -2;
    p.self_idle = -2;
    assert_int_equal(thread_class_is_idle(0), 0); /* the test's thread: the normal class */
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, worker_main, &p), 0);
    while (!atomic_load(&p.entered) || !atomic_load(&p.child_tid)) sched_yield();
    long w = atomic_load(&p.tid), c = atomic_load(&p.child_tid);
    int w_idle = thread_class_is_idle(w), c_idle = thread_class_is_idle(c), me = thread_class_is_idle(thread_class_tid());
    atomic_store(&p.release, 1);
    pthread_join(th, NULL);
    assert_int_equal(p.enter_rc, 0);
    assert_int_equal(p.self_idle, 1);
    assert_int_equal(w_idle, 1);  /* read from outside, by its thread id */
    assert_int_equal(c_idle, 1);  /* inherited */
    assert_int_equal(me, 0);      /* the creator keeps its class */
    assert_int_equal(thread_class_is_idle(0), 0);
}

static void no_such_thread(void **state)
{
    (void)state;
    assert_int_equal(thread_class_is_idle(-1), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(idle_thread_and_its_children),
        cmocka_unit_test(no_such_thread),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
