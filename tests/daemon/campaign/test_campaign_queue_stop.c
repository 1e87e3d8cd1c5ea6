/* test_campaign_queue_stop.c: an item that stops the queue ends it and stops the queue in one
 * store transaction. The queue's thread runs against a store where stopping the queue fails (a
 * trigger on the queue's state row raises, as a full disk or a kill between the two writes
 * would leave them): the pause item must not end without the queue stopping, or the queue runs
 * on past it and begins the next item (an operator step here; a trial on the rig). Once the
 * store accepts the write again, the pause ends and the queue stops together, the next item
 * still queued. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>
#include <sqlite3.h>

#include "campaign_queue.h"
#include "store.h"

static char why[600];

static int start_trial(void *user, const store_specimen *sp, const char *const *set, int n_set, const char *note,
                       int64_t *trial_id, char *w, size_t wn)
{
    (void)user, (void)sp, (void)set, (void)n_set, (void)note, (void)trial_id;
    snprintf(w, wn, "no trials in this test");
    return -1;
}

static int trial_running(void *user, int64_t trial_id)
{
    (void)user, (void)trial_id;
    return 0;
}

static void log_line(const char *line) { printf("# %s\n", line); }

static void sql(const char *db, const char *text)
{
    sqlite3 *h = NULL;
    assert_int_equal(sqlite3_open(db, &h), SQLITE_OK);
    sqlite3_busy_timeout(h, 2000);
    char *err = NULL;
    int rc = sqlite3_exec(h, text, NULL, NULL, &err);
    if (rc != SQLITE_OK) fail_msg("%s: %s", text, err ? err : "?");
    sqlite3_close(h);
}

static store_queue_item item(store *st, int64_t id)
{
    store_queue_item it;
    if (store_queue_get(st, id, &it, why, sizeof why) != STORE_OK) fail_msg("item %lld: %s", (long long)id, why);
    return it;
}

static void test_pause_ends_and_stops_together(void **s)
{
    (void)s;
    char dir[] = "/tmp/test_campaign_queue.XXXXXX", db[96], cmd[128];
    assert_non_null(mkdtemp(dir));
    snprintf(db, sizeof db, "%s/s.db", dir);
    store *st = NULL;
    assert_int_equal(store_open(db, &st, why, sizeof why), STORE_OK);
    int64_t pause = 0, op = 0;
    store_queue_item it = store_queue_item_default();
    it.kind = STORE_QUEUE_PAUSE;
    assert_int_equal(store_queue_add(st, &it, 1.8e9, &pause, why, sizeof why), STORE_OK);
    it = store_queue_item_default();
    it.kind = STORE_QUEUE_OPERATOR;
    snprintf(it.prompt, sizeof it.prompt, "mount the next specimen");
    assert_int_equal(store_queue_add(st, &it, 1.8e9, &op, why, sizeof why), STORE_OK);
    /* Stopping the queue fails; starting it still works. */
    sql(db, "CREATE TRIGGER inject_stop_failure BEFORE UPDATE ON queue_state WHEN NEW.running = 0"
            " BEGIN SELECT RAISE(ABORT, 'injected: the queue state cannot be written'); END;");

    campaign_queue_ops ops = {start_trial, trial_running};
    campaign_queue *q = NULL;
    assert_int_equal(campaign_queue_open(db, &ops, NULL, log_line, &q, why, sizeof why), 0);
    json_t *out = NULL;
    int http = 0;
    assert_int_equal(campaign_queue_set_running(q, true, &out, &http, why, sizeof why), 0);
    json_decref(out);
    usleep(3 * CAMPAIGN_TICK_MS * 1000);

    store_queue_item p = item(st, pause), o = item(st, op);
    printf("# with the stop failing: pause %s, operator step %s\n", store_queue_status_name(p.status),
           store_queue_status_name(o.status));
    assert_int_equal(o.status, STORE_QUEUE_QUEUED);   /* the queue did not run past the pause */
    assert_int_equal(p.status, STORE_QUEUE_RUNNING);  /* nor did the pause end alone */

    sql(db, "DROP TRIGGER inject_stop_failure;");
    usleep(3 * CAMPAIGN_TICK_MS * 1000);
    p = item(st, pause);
    o = item(st, op);
    bool running = true;
    char reason[300] = "";
    assert_int_equal(store_queue_state_get(st, &running, reason, sizeof reason, NULL, why, sizeof why), STORE_OK);
    printf("# then: pause %s, operator step %s, queue %s: %s\n", store_queue_status_name(p.status),
           store_queue_status_name(o.status), running ? "running" : "stopped", reason);
    assert_int_equal(p.status, STORE_QUEUE_DONE);
    assert_int_equal(o.status, STORE_QUEUE_QUEUED);
    assert_false(running);
    assert_non_null(strstr(reason, "paused by item"));

    campaign_queue_close(q);
    store_close(st);
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    assert_int_equal(system(cmd), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pause_ends_and_stops_together),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
