/* test_live_queue.c: the campaign's queue on the live page (issue 35), in a real browser (Debian's
 * chromium through chromedriver, as test_live_page) against ribbond in mock mode. A specimen and
 * an operator step asking its two crease angles are queued through the API and the queue started;
 * the page shows the queue and the step's form; an angle that cannot be clamped typed into the
 * form is refused, naming the field, and the step still waits; the right values confirm it: the
 * item is done, the specimen's record has them, the queue runs out and the page says so. No
 * trial runs (seconds). Heavy and labelled "browser": the sanitizer build skips it. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "live_testkit.h"
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
    assert_int_equal(kit_http("GET", url, NULL, NULL, &body, 10), 200);
    json_t *j = json_loads(body, 0, NULL);
    free(body);
    assert_non_null(j);
    return j;
}

static void post(const char *path, const char *json, int want)
{
    char url[160], *body = NULL;
    snprintf(url, sizeof url, "%s%s", c.url, path);
    int st = kit_http("POST", url, NULL, json, &body, 10);
    if (st != want) fail_msg("POST %s: %d, wanted %d: %s", path, st, want, body ? body : "");
    free(body);
}

/* Runs script (returning a string) until it returns want, at most max_s. */
static void wait_page(const char *script, const char *want, double max_s)
{
    char why[512], got[600] = "";
    double t0 = kit_now();
    do {
        json_t *j = wd_exec(&wd, script, why, sizeof why);
        snprintf(got, sizeof got, "%s", json_is_string(j) ? json_string_value(j) : "?");
        json_decref(j);
        if (!strcmp(got, want)) return;
        kit_sleep_ms(100);
    } while (kit_now() - t0 < max_s);
    fail_msg("page: %s gave '%s', wanted '%s'", script, got, want);
}

static void run(const char *script)
{
    char why[512];
    json_t *j = wd_exec(&wd, script, why, sizeof why);
    if (!j) fail_msg("%s: %s", script, why);
    json_decref(j);
}

static void test_live_queue(void **state)
{
    (void)state;
    if (!wd_available()) {
        printf("# chromium or chromedriver missing (Debian packages chromium, chromium-driver): skipped\n");
        skip();
    }
    char dir[300], profile[400], why[512], page[128];
    kit_fresh_dir("live_queue", dir, sizeof dir);
    snprintf(profile, sizeof profile, "/tmp/ribbon-live-queue-XXXXXX");
    if (!mkdtemp(profile)) fail_msg("mkdtemp failed");
    assert_int_equal(kit_ribbond_start(&c, dir, 0, NULL), 0);
    post("/specimens", "{\"name\": \"S-12\", \"phi_deg\": 90, \"gamma\": 0.13}", 201);
    post("/queue", "{\"kind\": \"operator\", \"specimen\": \"S-12\", \"prompt\": \"mount S-12, measured angles?\", "
                   "\"fields\": [\"crease_angle_left_deg\", \"crease_angle_right_deg\"]}", 201);
    post("/queue/start", "{}", 200);
    if (wd_open(&wd, profile, 1400, 1100, why, sizeof why) != 0) fail_msg("webdriver: %s", why);
    snprintf(page, sizeof page, "%s/", c.url);
    if (wd_navigate(&wd, page, why, sizeof why) != 0) fail_msg("navigate: %s", why);

    wait_page("const f = document.getElementById('operator-form'); return f.hidden ? 'hidden' :"
              " document.getElementById('operator-prompt').textContent;",
              "Step 1: mount S-12, measured angles? (S-12)", 20);
    wait_page("return document.getElementById('queue-state').textContent;", "running", 5);
    wait_page("const r = document.querySelector('#queue tbody tr'); return r ? r.dataset.status : '';", "running", 5);
    /* An angle that cannot be clamped: refused, named; the step still waits. */
    run("document.getElementById('field-crease_angle_left_deg').value = '200';"
        "document.getElementById('field-crease_angle_right_deg').value = '91';"
        "document.getElementById('operator-form').requestSubmit(); return 1;");
    wait_page("return document.getElementById('operator-msg').dataset.status || '';", "400", 10);
    json_t *m = wd_exec(&wd, "return document.getElementById('operator-msg').textContent;", why, sizeof why);
    assert_non_null(strstr(json_string_value(m), "crease_angle_left_deg"));
    printf("page refused: %s\n", json_string_value(m));
    json_decref(m);
    json_t *it = get("/queue/1");
    assert_string_equal(json_string_value(json_object_get(it, "status")), "running");
    json_decref(it);
    /* The form keeps what was typed while the queue refreshes; the right value confirms it. */
    kit_sleep_ms(1500);
    wait_page("return document.getElementById('field-crease_angle_right_deg').value;", "91", 1);
    run("document.getElementById('field-crease_angle_left_deg').value = '89';"
        "document.getElementById('operator-confirm').click(); return 1;");
    wait_page("return document.getElementById('operator-msg').dataset.status || '';", "200", 10);
    it = get("/queue/1");
    assert_string_equal(json_string_value(json_object_get(it, "status")), "done");
    json_t *sp = json_object_get(it, "specimen_record");
    assert_true(json_number_value(json_object_get(sp, "crease_angle_left_deg")) == 89.0);
    assert_true(json_number_value(json_object_get(sp, "crease_angle_right_deg")) == 91.0);
    json_decref(it);
    wait_page("return document.getElementById('queue-state').textContent + ': ' +"
              " document.getElementById('queue-reason').textContent;",
              "stopped: ran to its end: no item is left", 10);
    wait_page("return document.getElementById('operator-form').hidden ? 'hidden' : 'shown';", "hidden", 5);
    json_t *log = wd_console(&wd, why, sizeof why);
    for (size_t k = 0; k < json_array_size(log); k++) {
        json_t *e = json_array_get(log, k);
        const char *level = json_string_value(json_object_get(e, "level"));
        const char *msg = json_string_value(json_object_get(e, "message"));
        printf("# console %s: %s\n", level ? level : "?", msg ? msg : "");
        /* the refused confirmation's 400 is the browser's note of an expected answer */
        if (level && !strcmp(level, "SEVERE") && !(msg && strstr(msg, "400")))
            fail_msg("console error: %s", msg ? msg : "");
    }
    json_decref(log);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test_teardown(test_live_queue, teardown)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
