/* test_store_queue.c: the campaign's records (issue 35): a specimen's state (new -> in use on its
 * first trial -> retired | broken, final) and the queue: order by position with moves and
 * removals (skipped), one running item that can be neither moved nor removed, end states, the
 * queue's state row, and start-up recovery (the running item becomes unknown, the queue stops
 * and says why). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include "store.h"

#define OK(call)                                                                                            \
    do {                                                                                                    \
        store_err e_ = (call);                                                                              \
        if (e_ != STORE_OK)                                                                                 \
            fail_msg("%s -> %s: %s", #call, store_err_message(e_), why);                                    \
    } while (0)

static char why[512];
static const double T0 = 1.8e9;

typedef struct fx {
    char dir[64];
    char db[96];
    store *st;
} fx;

static int setup(void **state)
{
    fx *f = calloc(1, sizeof *f);
    snprintf(f->dir, sizeof f->dir, "/tmp/test_store_queue.XXXXXX");
    if (!mkdtemp(f->dir)) return -1;
    snprintf(f->db, sizeof f->db, "%s/s.db", f->dir);
    if (store_open(f->db, &f->st, why, sizeof why) != STORE_OK) return -1;
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fx *f = *state;
    store_close(f->st);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", f->dir);
    if (system(cmd) != 0) return -1;
    free(f);
    return 0;
}

static int64_t add_specimen(store *st, const char *name)
{
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "%s", name);
    sp.length_m = 0.2;
    sp.width_m = 0.005;
    sp.thickness_m = 2.5e-4;
    sp.phi_deg = 90.0;
    sp.fold_position = 0.17;
    int64_t id = 0;
    OK(store_specimen_upsert(st, &sp, &id, why, sizeof why));
    return id;
}

static void test_specimen_states(void **state)
{
    fx *f = *state;
    int64_t id = add_specimen(f->st, "S-12");
    store_specimen sp;
    OK(store_specimen_get(f->st, id, &sp, why, sizeof why));
    assert_int_equal(sp.state, STORE_SPECIMEN_NEW);
    assert_true(sp.phi_deg == 90.0);
    /* An upsert that does not know phi keeps it. */
    sp.phi_deg = NAN;
    OK(store_specimen_upsert(f->st, &sp, NULL, why, sizeof why));
    OK(store_specimen_get(f->st, id, &sp, why, sizeof why));
    assert_true(sp.phi_deg == 90.0);
    OK(store_specimen_count_trial(f->st, id, why, sizeof why));
    OK(store_specimen_get(f->st, id, &sp, why, sizeof why));
    assert_int_equal(sp.state, STORE_SPECIMEN_IN_USE);
    assert_int_equal(store_specimen_retire(f->st, id, STORE_SPECIMEN_RETIRED, "", T0, why, sizeof why),
                     STORE_E_INVALID);
    assert_int_equal(store_specimen_retire(f->st, id, STORE_SPECIMEN_NEW, "x", T0, why, sizeof why),
                     STORE_E_INVALID);
    OK(store_specimen_retire(f->st, id, STORE_SPECIMEN_BROKEN, "torn at the left clamp", T0, why, sizeof why));
    OK(store_specimen_get(f->st, id, &sp, why, sizeof why));
    assert_int_equal(sp.state, STORE_SPECIMEN_BROKEN);
    assert_string_equal(sp.state_reason, "torn at the left clamp");
    assert_true(sp.state_at[0] != '\0');
    assert_int_equal(store_specimen_retire(f->st, id, STORE_SPECIMEN_RETIRED, "again", T0, why, sizeof why),
                     STORE_E_STATE);
    assert_non_null(strstr(why, "already broken"));
    /* A later trial count does not revive it. */
    OK(store_specimen_count_trial(f->st, id, why, sizeof why));
    OK(store_specimen_get(f->st, id, &sp, why, sizeof why));
    assert_int_equal(sp.state, STORE_SPECIMEN_BROKEN);
    sp.phi_deg = 180.0;
    assert_int_equal(store_specimen_upsert(f->st, &sp, NULL, why, sizeof why), STORE_E_INVALID);
    add_specimen(f->st, "A-1");
    store_specimen *all = NULL;
    size_t n = 0;
    OK(store_specimen_list(f->st, &all, &n, why, sizeof why));
    assert_int_equal(n, 2);
    assert_string_equal(all[0].name, "A-1");
    assert_string_equal(all[1].name, "S-12");
    free(all);
}

static int64_t add_item(store *st, store_queue_kind k, int64_t spec)
{
    store_queue_item it = store_queue_item_default();
    it.kind = k;
    it.specimen_id = spec;
    if (k == STORE_QUEUE_OPERATOR) {
        snprintf(it.prompt, sizeof it.prompt, "mount S-12, measured angles?");
        snprintf(it.fields_json, sizeof it.fields_json, "[\"crease_angle_left_deg\"]");
    }
    int64_t id = 0;
    OK(store_queue_add(st, &it, T0, &id, why, sizeof why));
    return id;
}

/* The queued ids in order. */
static size_t order(store *st, int64_t *ids)
{
    store_queue_item *v = NULL;
    size_t n = 0, k = 0;
    OK(store_queue_list(st, &v, &n, why, sizeof why));
    for (size_t i = 0; i < n; i++)
        if (v[i].status == STORE_QUEUE_QUEUED) {
            assert_int_equal(v[i].position, (int64_t)k + 1); /* 1 .. n, no gaps */
            ids[k++] = v[i].id;
        }
    free(v);
    return k;
}

static void test_queue_order_and_edits(void **state)
{
    fx *f = *state;
    int64_t sp = add_specimen(f->st, "S-12");
    store_queue_item bad = store_queue_item_default();
    bad.kind = STORE_QUEUE_TRIAL;
    assert_int_equal(store_queue_add(f->st, &bad, T0, NULL, why, sizeof why), STORE_E_INVALID);
    bad.kind = STORE_QUEUE_OPERATOR;
    assert_int_equal(store_queue_add(f->st, &bad, T0, NULL, why, sizeof why), STORE_E_INVALID);
    int64_t a = add_item(f->st, STORE_QUEUE_TRIAL, sp), b = add_item(f->st, STORE_QUEUE_OPERATOR, sp),
            c = add_item(f->st, STORE_QUEUE_PAUSE, 0), d = add_item(f->st, STORE_QUEUE_TRIAL, sp);
    int64_t ids[8];
    assert_int_equal(order(f->st, ids), 4);
    assert_true(ids[0] == a && ids[1] == b && ids[2] == c && ids[3] == d);
    OK(store_queue_move(f->st, d, 1, why, sizeof why));
    assert_int_equal(order(f->st, ids), 4);
    assert_true(ids[0] == d && ids[1] == a && ids[2] == b && ids[3] == c);
    OK(store_queue_move(f->st, d, 99, why, sizeof why)); /* past the end: last */
    assert_int_equal(order(f->st, ids), 4);
    assert_true(ids[0] == a && ids[1] == b && ids[2] == c && ids[3] == d);
    OK(store_queue_move(f->st, a, 3, why, sizeof why));
    assert_int_equal(order(f->st, ids), 4);
    assert_true(ids[0] == b && ids[1] == c && ids[2] == a && ids[3] == d);
    assert_int_equal(store_queue_move(f->st, a, 0, why, sizeof why), STORE_E_INVALID);
    OK(store_queue_remove(f->st, c, NULL, T0, why, sizeof why));
    assert_int_equal(order(f->st, ids), 3);
    assert_true(ids[0] == b && ids[1] == a && ids[2] == d);
    store_queue_item it;
    OK(store_queue_get(f->st, c, &it, why, sizeof why));
    assert_int_equal(it.status, STORE_QUEUE_SKIPPED);
    assert_true(it.ended_at[0] != '\0');
    assert_int_equal(store_queue_remove(f->st, c, NULL, T0, why, sizeof why), STORE_E_STATE);
    assert_non_null(strstr(why, "already ended (skipped)"));
    assert_int_equal(store_queue_get(f->st, 999, &it, why, sizeof why), STORE_E_NOTFOUND);

    /* The next item runs: it can't be moved or removed, and a second can't start. */
    OK(store_queue_next(f->st, &it, why, sizeof why));
    assert_int_equal(it.id, b);
    OK(store_queue_item_begin(f->st, b, T0 + 1, why, sizeof why));
    assert_int_equal(store_queue_item_begin(f->st, a, T0 + 1, why, sizeof why), STORE_E_STATE);
    assert_int_equal(store_queue_remove(f->st, b, NULL, T0, why, sizeof why), STORE_E_STATE);
    assert_non_null(strstr(why, "is running: it can't be removed"));
    assert_int_equal(store_queue_move(f->st, b, 2, why, sizeof why), STORE_E_STATE);
    assert_non_null(strstr(why, "is running: it can't be moved"));
    assert_int_equal(order(f->st, ids), 2);
    assert_true(ids[0] == a && ids[1] == d);
    OK(store_queue_current(f->st, &it, why, sizeof why));
    assert_int_equal(it.id, b);
    assert_int_equal(store_queue_item_end(f->st, b, STORE_QUEUE_DONE, "x", "{bad", T0, why, sizeof why),
                     STORE_E_INVALID);
    OK(store_queue_item_end(f->st, b, STORE_QUEUE_DONE, "confirmed", "{\"crease_angle_left_deg\": 88}", T0 + 2, why,
                            sizeof why));
    OK(store_queue_get(f->st, b, &it, why, sizeof why));
    assert_int_equal(it.status, STORE_QUEUE_DONE);
    assert_non_null(strstr(it.values_json, "88"));
    assert_int_equal(store_queue_item_end(f->st, b, STORE_QUEUE_FAILED, "x", NULL, T0, why, sizeof why),
                     STORE_E_STATE);
    assert_int_equal(store_queue_current(f->st, &it, why, sizeof why), STORE_E_NOTFOUND);
}

static void test_queue_recover(void **state)
{
    fx *f = *state;
    int64_t sp = add_specimen(f->st, "S-12");
    bool running = true;
    char reason[300];
    OK(store_queue_state_get(f->st, &running, reason, sizeof reason, NULL, why, sizeof why));
    assert_false(running);
    assert_string_equal(reason, "never started");
    int n = -1;
    OK(store_queue_recover(f->st, T0, &n, why, sizeof why)); /* nothing ran: nothing changes */
    assert_int_equal(n, 0);
    OK(store_queue_state_get(f->st, &running, reason, sizeof reason, NULL, why, sizeof why));
    assert_string_equal(reason, "never started");

    int64_t a = add_item(f->st, STORE_QUEUE_TRIAL, sp), b = add_item(f->st, STORE_QUEUE_TRIAL, sp);
    OK(store_queue_state_set(f->st, true, "started by test", T0, why, sizeof why));
    OK(store_queue_item_begin(f->st, a, T0, why, sizeof why));
    /* A crash: the store is reopened as the next daemon would. */
    store_close(f->st);
    OK(store_open(f->db, &f->st, why, sizeof why));
    OK(store_queue_recover(f->st, T0 + 5, &n, why, sizeof why));
    assert_int_equal(n, 1);
    store_queue_item it;
    OK(store_queue_get(f->st, a, &it, why, sizeof why));
    assert_int_equal(it.status, STORE_QUEUE_UNKNOWN);
    assert_non_null(strstr(it.reason, "found running when ribbond started"));
    OK(store_queue_get(f->st, b, &it, why, sizeof why));
    assert_int_equal(it.status, STORE_QUEUE_QUEUED);
    assert_int_equal(it.position, 1);
    OK(store_queue_state_get(f->st, &running, reason, sizeof reason, NULL, why, sizeof why));
    assert_false(running);
    assert_non_null(strstr(reason, "item"));
    assert_non_null(strstr(reason, "never resumes"));
    /* A queue that ran with nothing running is stopped too. */
    OK(store_queue_state_set(f->st, true, "started by test", T0, why, sizeof why));
    OK(store_queue_recover(f->st, T0 + 6, &n, why, sizeof why));
    assert_int_equal(n, 0);
    OK(store_queue_state_get(f->st, &running, reason, sizeof reason, NULL, why, sizeof why));
    assert_false(running);
    assert_non_null(strstr(reason, "restarted"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(test_specimen_states, setup, teardown),
        cmocka_unit_test_setup_teardown(test_queue_order_and_edits, setup, teardown),
        cmocka_unit_test_setup_teardown(test_queue_recover, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
