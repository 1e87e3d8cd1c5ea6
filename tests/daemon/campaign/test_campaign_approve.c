/* test_campaign_approve.c: approving a plan proposal (POST /plan/ID/approve) is all or nothing.
 *
 * - A failure mid-approval (a trigger makes the store refuse the trial item, as a full disk would,
 *   after the specimen and the operator step were written; then the same for the proposal's own
 *   update) leaves nothing: no specimen, no queue row (not even a skipped one), the proposal still
 *   proposed, and the reason reaches the caller. Once the store accepts again, the same name
 *   approves.
 * - Two approvals of one name at once, from two connections (two daemons' API threads on one
 *   store): a third connection holds the write lock while both start, so both have looked at the
 *   store before either writes. Exactly one wins (201); the other gets 409 naming the specimen,
 *   from the store's UNIQUE constraint, and the winner's specimen keeps the winner's design. The
 *   same for two POST /specimens of one name. */
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>
#include <sqlite3.h>

#include "campaign.h"
#include "store.h"

#define OK(x) assert_int_equal((x), STORE_OK)

static char why[600];
static const double T0 = 1.8e9;

typedef struct fx {
    char dir[64], db[96];
    store *st;
} fx;

static int setup(void **state)
{
    fx *f = calloc(1, sizeof *f);
    snprintf(f->dir, sizeof f->dir, "/tmp/test_campaign_approve.XXXXXX");
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

static int no_trial(void *user, const store_specimen *sp, const char *const *set, int n_set, const char *note,
                    int64_t *trial_id, char *w, size_t wl)
{
    (void)user, (void)sp, (void)set, (void)n_set, (void)note, (void)trial_id;
    snprintf(w, wl, "no trials in this test");
    return -1;
}

static int none_running(void *user, int64_t trial_id)
{
    (void)user, (void)trial_id;
    return 0;
}

static void sql(const char *db, const char *text)
{
    sqlite3 *h = NULL;
    assert_int_equal(sqlite3_open(db, &h), SQLITE_OK);
    sqlite3_busy_timeout(h, 5000);
    char *err = NULL;
    if (sqlite3_exec(h, text, NULL, NULL, &err) != SQLITE_OK) fail_msg("%s: %s", text, err ? err : "?");
    sqlite3_close(h);
}

static long long count(store *st, const char *query)
{
    sqlite3_stmt *s = NULL;
    assert_int_equal(sqlite3_prepare_v2(store_handle(st), query, -1, &s, NULL), SQLITE_OK);
    assert_int_equal(sqlite3_step(s), SQLITE_ROW);
    long long n = sqlite3_column_int64(s, 0);
    sqlite3_finalize(s);
    return n;
}

static campaign_ctx ctx_for(store *st)
{
    campaign_ctx c = {.st = st, .defaults = store_specimen_default()};
    c.defaults.length_m = 0.2, c.defaults.width_m = 0.005, c.defaults.thickness_m = 2.5e-4;
    return c;
}

static int approve(const campaign_ctx *c, int64_t id, const char *name, int *http, char *w, size_t wl)
{
    char path[64];
    snprintf(path, sizeof path, "/plan/%lld/approve", (long long)id);
    json_t *body = name ? json_pack("{s:s}", "name", name) : json_object(), *out = NULL;
    int rc = campaign_route(c, "POST", path, body, &out, http, w, wl);
    json_decref(body);
    json_decref(out);
    return rc;
}

/* Nothing of a refused approval is left in the store. */
static void nothing_left(fx *f, int64_t pid)
{
    assert_int_equal(count(f->st, "SELECT COUNT(*) FROM specimens"), 0);
    assert_int_equal(count(f->st, "SELECT COUNT(*) FROM queue_items"), 0);
    store_plan_proposal p;
    OK(store_plan_get(f->st, pid, &p, why, sizeof why));
    assert_int_equal(p.status, STORE_PLAN_PROPOSED);
}

static void failure_mid_approval_leaves_nothing(void **state)
{
    fx *f = *state;
    store_plan_proposal p = {.phi_deg = 120, .gamma = 0.18, .sd_before = 0.01, .predicted_gamma = 0.185};
    OK(store_plan_add_batch(f->st, &p, 1, T0, why, sizeof why));
    campaign_ctx c = ctx_for(f->st);
    campaign_queue_ops ops = {.start_trial = no_trial, .trial_running = none_running};
    assert_int_equal(campaign_queue_open(f->db, &ops, NULL, NULL, &c.q, why, sizeof why), 0);
    int http = 0;

    /* the trial item refused: after the specimen and the operator step were written */
    sql(f->db, "CREATE TRIGGER inject BEFORE INSERT ON queue_items WHEN NEW.kind = 'trial'"
               " BEGIN SELECT RAISE(ABORT, 'injected: the trial item cannot be written'); END;");
    assert_int_equal(approve(&c, p.id, "S1", &http, why, sizeof why), -1);
    printf("# trial item refused: %d %s\n", http, why);
    assert_int_equal(http, 500);
    assert_non_null(strstr(why, "injected: the trial item cannot be written"));
    nothing_left(f, p.id);
    sql(f->db, "DROP TRIGGER inject;");

    /* the proposal's own update refused: the last write of the approval */
    sql(f->db, "CREATE TRIGGER inject BEFORE UPDATE ON plan_proposals WHEN NEW.status = 'approved'"
               " BEGIN SELECT RAISE(ABORT, 'injected: the proposal cannot be written'); END;");
    assert_int_equal(approve(&c, p.id, "S1", &http, why, sizeof why), -1);
    printf("# proposal update refused: %d %s\n", http, why);
    assert_int_equal(http, 500);
    assert_non_null(strstr(why, "injected: the proposal cannot be written"));
    nothing_left(f, p.id);
    sql(f->db, "DROP TRIGGER inject;");

    /* the store accepts again: the same name approves, once */
    assert_int_equal(approve(&c, p.id, "S1", &http, why, sizeof why), 0);
    assert_int_equal(http, 201);
    assert_int_equal(count(f->st, "SELECT COUNT(*) FROM specimens WHERE name = 'S1'"), 1);
    assert_int_equal(count(f->st, "SELECT COUNT(*) FROM queue_items WHERE status = 'queued'"), 2);
    assert_int_equal(count(f->st, "SELECT COUNT(*) FROM queue_items"), 2);
    store_plan_proposal g;
    OK(store_plan_get(f->st, p.id, &g, why, sizeof why));
    assert_int_equal(g.status, STORE_PLAN_APPROVED);
    campaign_queue_close(c.q);
}

typedef struct racer {
    campaign_ctx c; /* its own connection and queue (opened before the race: opening writes) */
    int64_t proposal; /* 0: POST /specimens {"name": "twin", "phi_deg": phi, "gamma": 0.15} instead */
    double phi;
    int rc, http;
    char why[600];
} racer;

static void *race(void *arg)
{
    racer *r = arg;
    if (r->proposal) {
        r->rc = approve(&r->c, r->proposal, "twin", &r->http, r->why, sizeof r->why);
        return NULL;
    }
    json_t *body = json_pack("{s:s,s:f,s:f}", "name", "twin", "phi_deg", r->phi, "gamma", 0.15), *out = NULL;
    r->rc = campaign_route(&r->c, "POST", "/specimens", body, &out, &r->http, r->why, sizeof r->why);
    json_decref(body);
    json_decref(out);
    return NULL;
}

/* Both racers start while a third connection holds the write lock (so both look before either
 * writes), then the lock goes. */
static void run_race(fx *f, racer r[2])
{
    campaign_queue_ops ops = {.start_trial = no_trial, .trial_running = none_running};
    store *own[2];
    for (int k = 0; k < 2; k++) {
        OK(store_open(f->db, &own[k], why, sizeof why));
        r[k].c = ctx_for(own[k]);
        assert_int_equal(campaign_queue_open(f->db, &ops, NULL, NULL, &r[k].c.q, why, sizeof why), 0);
    }
    sqlite3 *hold = NULL;
    assert_int_equal(sqlite3_open(f->db, &hold), SQLITE_OK);
    assert_int_equal(sqlite3_exec(hold, "BEGIN IMMEDIATE", NULL, NULL, NULL), SQLITE_OK);
    pthread_t t[2];
    for (int k = 0; k < 2; k++) assert_int_equal(pthread_create(&t[k], NULL, race, &r[k]), 0);
    struct timespec pause = {0, 800 * 1000 * 1000}; /* both reach their first write meanwhile */
    nanosleep(&pause, NULL);
    assert_int_equal(sqlite3_exec(hold, "COMMIT", NULL, NULL, NULL), SQLITE_OK);
    sqlite3_close(hold);
    for (int k = 0; k < 2; k++) {
        pthread_join(t[k], NULL);
        campaign_queue_close(r[k].c.q);
        store_close(own[k]);
    }
    for (int k = 0; k < 2; k++) printf("# racer %d: rc %d http %d %s\n", k, r[k].rc, r[k].http, r[k].rc ? r[k].why : "");
}

static void two_approvals_of_one_name(void **state)
{
    fx *f = *state;
    store_plan_proposal p[2] = {{.phi_deg = 120, .gamma = 0.18, .sd_before = 0.01, .predicted_gamma = 0.185},
                                {.phi_deg = 60, .gamma = 0.21, .sd_before = 0.01, .predicted_gamma = 0.2}};
    OK(store_plan_add_batch(f->st, p, 2, T0, why, sizeof why));
    racer r[2] = {{.proposal = p[0].id}, {.proposal = p[1].id}};
    run_race(f, r);
    assert_true(r[0].rc == 0 || r[1].rc == 0);
    int w = r[0].rc == 0 ? 0 : 1, l = 1 - w;
    assert_int_equal(r[w].http, 201);
    assert_int_equal(r[l].rc, -1);
    assert_int_equal(r[l].http, 409);
    assert_non_null(strstr(r[l].why, "specimen twin exists"));
    /* the winner's specimen, its design, its queue items; nothing of the loser */
    store_specimen sp;
    OK(store_specimen_get_by_name(f->st, "twin", &sp, why, sizeof why));
    assert_true(sp.phi_deg == p[w].phi_deg && sp.fold_position == p[w].gamma);
    assert_int_equal(count(f->st, "SELECT COUNT(*) FROM specimens"), 1);
    assert_int_equal(count(f->st, "SELECT COUNT(*) FROM queue_items"), 2);
    store_plan_proposal g;
    OK(store_plan_get(f->st, p[w].id, &g, why, sizeof why));
    assert_int_equal(g.status, STORE_PLAN_APPROVED);
    assert_int_equal(g.specimen_id, sp.id);
    OK(store_plan_get(f->st, p[l].id, &g, why, sizeof why));
    assert_int_equal(g.status, STORE_PLAN_PROPOSED);
}

/* POST /specimens has the same race (look, then upsert): two adds of one name at once, one 201, the
 * other 409, and the winner's record is not overwritten. */
static void two_adds_of_one_name(void **state)
{
    fx *f = *state;
    racer r[2] = {{.phi = 60}, {.phi = 120}};
    run_race(f, r);
    assert_true(r[0].rc == 0 || r[1].rc == 0);
    int w = r[0].rc == 0 ? 0 : 1, l = 1 - w;
    assert_int_equal(r[w].http, 201);
    assert_int_equal(r[l].rc, -1);
    assert_int_equal(r[l].http, 409);
    assert_non_null(strstr(r[l].why, "specimen twin exists"));
    store_specimen sp;
    OK(store_specimen_get_by_name(f->st, "twin", &sp, why, sizeof why));
    assert_true(sp.phi_deg == r[w].phi);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(failure_mid_approval_leaves_nothing, setup, teardown),
        cmocka_unit_test_setup_teardown(two_approvals_of_one_name, setup, teardown),
        cmocka_unit_test_setup_teardown(two_adds_of_one_name, setup, teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
