/* test_live_campaign.c: the lab's phase diagram and the planner's proposals on the live page
 * (issue 35 parts C and D), in a real browser (chromium through chromedriver, as test_live_queue)
 * against ribbond in mock mode. An empty store first: the section says why there is nothing to
 * draw. Then specimens trialled at known regimes and a proposal written to the daemon's store: the
 * page's edges table shows phi 90's bracket [0.16, 0.17] and the predicted boundary (traced by
 * ribbond from its scene); the proposal's Approve button queues its operator step and trial (the
 * queue's items checked through the API) and the proposal reads approved; no console error (but
 * the 503 of GET /campaign/phase while ribbond traces the boundary, asked again after it). No
 * trial runs (seconds). Heavy and labelled "browser": the sanitizer build skips it. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "live_testkit.h"
#include "store.h"
#include "webdriver.h"

static ribbond_child c;
static webdriver wd;

static int teardown(void **state)
{
    (void)state;
    wd_close(&wd);
    if (c.pid > 0) kit_ribbond_stop(&c);
    return 0;
}

static json_t *get(const char *path)
{
    char url[160], *body = NULL;
    snprintf(url, sizeof url, "%s%s", c.url, path);
    assert_int_equal(kit_http("GET", url, NULL, NULL, &body, 30), 200);
    json_t *j = json_loads(body, 0, NULL);
    free(body);
    assert_non_null(j);
    return j;
}

static void wait_page(const char *script, const char *want, double max_s)
{
    char why[512], got[600] = "";
    double t0 = kit_now();
    do {
        json_t *j = wd_exec(&wd, script, why, sizeof why);
        snprintf(got, sizeof got, "%s", json_is_string(j) ? json_string_value(j) : "?");
        json_decref(j);
        if (!strcmp(got, want)) return;
        kit_sleep_ms(200);
    } while (kit_now() - t0 < max_s);
    fail_msg("page: %s gave '%s', wanted '%s'", script, got, want);
}

static void trial(store *st, int64_t sid, store_regime regime)
{
    char why[256];
    store_trial_def d = store_trial_def_default();
    d.specimen_id = sid;
    int64_t id;
    double t = store_wall_now();
    assert_int_equal(store_trial_create(st, &d, &id, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_RUNNING, NULL, t, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_result(st, id, true, 0.4, regime, why, sizeof why), STORE_OK);
    assert_int_equal(store_trial_set_status(st, id, STORE_STATUS_DONE, NULL, t, why, sizeof why), STORE_OK);
}

static int64_t specimen(store *st, const char *name, double phi, double gamma)
{
    char why[256];
    store_specimen sp = store_specimen_default();
    snprintf(sp.name, sizeof sp.name, "%s", name);
    sp.length_m = 0.2, sp.width_m = 0.005, sp.thickness_m = 2.5e-4;
    sp.phi_deg = phi, sp.fold_position = gamma;
    int64_t id;
    assert_int_equal(store_specimen_upsert(st, &sp, &id, why, sizeof why), STORE_OK);
    return id;
}

static void test_live_campaign(void **state)
{
    (void)state;
    if (!wd_available()) {
        printf("# chromium or chromedriver missing (Debian packages chromium, chromium-driver): skipped\n");
        skip();
    }
    char dir[300], profile[400], why[512], page[128];
    kit_fresh_dir("live_campaign", dir, sizeof dir);
    snprintf(profile, sizeof profile, "/tmp/ribbon-live-campaign-XXXXXX");
    if (!mkdtemp(profile)) fail_msg("mkdtemp failed");
    assert_int_equal(kit_ribbond_start(&c, dir, 0, NULL), 0);
    if (wd_open(&wd, profile, 1400, 2400, why, sizeof why) != 0) fail_msg("webdriver: %s", why);
    snprintf(page, sizeof page, "%s/", c.url);
    if (wd_navigate(&wd, page, why, sizeof why) != 0) fail_msg("navigate: %s", why);
    wait_page("return document.getElementById('campaign-info').textContent.slice(0, 25);", "no specimens in the store", 20);

    /* the store ribbond uses, written beside it */
    json_t *s = get("/status");
    store *st;
    assert_int_equal(store_open(json_string_value(json_object_get(s, "store")), &st, why, sizeof why), STORE_OK);
    json_decref(s);
    trial(st, specimen(st, "A", 90, 0.16), STORE_REGIME_ASYMMETRIC);
    trial(st, specimen(st, "B", 90, 0.17), STORE_REGIME_SYMMETRIC);
    trial(st, specimen(st, "C", 120, 0.17), STORE_REGIME_ASYMMETRIC);
    store_plan_proposal p = {.phi_deg = 120, .gamma = 0.18, .sd_before = 0.01, .predicted_gamma = 0.185,
                             .offset_mean = -0.005, .offset_sd = 0.004, .calibrated = 1};
    assert_int_equal(store_plan_add_batch(st, &p, 1, store_wall_now(), why, sizeof why), STORE_OK);
    store_close(st);
    /* reload instead of waiting 15 s for the next poll */
    if (wd_navigate(&wd, page, why, sizeof why) != 0) fail_msg("navigate: %s", why);
    wait_page("return document.getElementById('edges').dataset.rows || '';", "2", 60);
    wait_page("const r = document.querySelector('#edges tbody tr'); return r ? r.textContent : '';",
              "90bracket0.1650[0.1600, 0.1700]110.1763", 5);
    json_t *info = wd_exec(&wd, "return document.getElementById('campaign-info').textContent;", why, sizeof why);
    printf("# page: %s\n", json_string_value(info));
    assert_non_null(strstr(json_string_value(info), "3 specimens, 3 measured trials; predicted boundary: "));
    json_decref(info);
    /* approve from the page */
    wait_page("const b = document.querySelector('#proposals tbody button'); return b ? b.textContent : '';", "Approve", 10);
    json_decref(wd_exec(&wd, "document.querySelector('#proposals tbody button').click(); return 1;", why, sizeof why));
    wait_page("return document.getElementById('proposal-msg').dataset.status || '';", "201", 10);
    json_t *q = get("/queue");
    json_t *queued = json_object_get(q, "queued");
    assert_int_equal(json_array_size(queued), 2);
    assert_string_equal(json_string_value(json_object_get(json_array_get(queued, 0), "kind")), "operator");
    assert_string_equal(json_string_value(json_object_get(json_array_get(queued, 1), "kind")), "trial");
    json_decref(q);
    wait_page("const r = document.querySelector('#proposals tbody tr'); return r ? r.cells[1].textContent : '';",
              "approved", 10);
    json_t *log = wd_console(&wd, why, sizeof why);
    for (size_t k = 0; k < json_array_size(log); k++) {
        json_t *e = json_array_get(log, k);
        const char *level = json_string_value(json_object_get(e, "level"));
        const char *msg = json_string_value(json_object_get(e, "message"));
        printf("# console %s: %s\n", level ? level : "?", msg ? msg : "");
        /* the 503 of GET /campaign/phase while the boundary is traced is expected (the browser logs
           every non-2xx answer); the page asks again after Retry-After */
        if (level && !strcmp(level, "SEVERE") && !(msg && strstr(msg, "/campaign/phase") && strstr(msg, "503")))
            fail_msg("console error: %s", msg ? msg : "");
    }
    json_decref(log);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test_teardown(test_live_campaign, teardown)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
