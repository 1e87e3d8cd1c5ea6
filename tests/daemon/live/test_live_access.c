/* test_live_access.c: who may see the live page's data. ribbond with a token (the API's rule: a
 * daemon that listens beyond loopback must have one, and then every request needs it): the page's
 * files load without it (they hold no data and can do nothing: the page asks for the token), while
 * the event stream, the camera, the prediction and every API route answer 401 without the token or
 * with a wrong one, and 200 with it. No trial runs (fast: runs in the sanitizer build too). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "live_testkit.h"

#define TOKEN "live-test-token-42"

static void test_token_guards_live_data(void **state)
{
    (void)state;
    char dir[300];
    kit_fresh_dir("live_access", dir, sizeof dir);
    ribbond_child c;
    const char *sets[] = {"api.token=" TOKEN, NULL};
    assert_int_equal(kit_ribbond_start(&c, dir, 0, sets), 0);
    char url[200], *body = NULL;

    /* The page's own files: no token. */
    const char *open_paths[] = {"/", "/live.js", "/live.css"};
    for (size_t i = 0; i < sizeof open_paths / sizeof *open_paths; i++) {
        snprintf(url, sizeof url, "%s%s", c.url, open_paths[i]);
        assert_int_equal(kit_http("GET", url, NULL, NULL, &body, 10), 200);
        assert_true(strlen(body) > 100);
        free(body);
    }
    snprintf(url, sizeof url, "%s/", c.url);
    kit_http("GET", url, NULL, NULL, &body, 10);
    assert_non_null(strstr(body, "/javascript/chart.js/chart.min.js")); /* Debian's, served by ribbond */
    free(body);

    /* The data: 401 without the token and with a wrong one, as the API's JSON error. */
    const char *data_paths[] = {"/live/events", "/live/camera.jpg", "/live/prediction", "/status", "/trials",
                                "/trials/1", "/trials/1/report.png", "/trials/1/samples.csv", "/phase.png"};
    for (size_t i = 0; i < sizeof data_paths / sizeof *data_paths; i++) {
        snprintf(url, sizeof url, "%s%s", c.url, data_paths[i]);
        int st = kit_http("GET", url, NULL, NULL, &body, 10);
        if (st != 401) fail_msg("GET %s without the token answered %d", data_paths[i], st);
        assert_non_null(strstr(body, "\"status\":401"));
        free(body);
        assert_int_equal(kit_http("GET", url, "wrong-token", NULL, NULL, 10), 401);
    }
    snprintf(url, sizeof url, "%s/trials/current/abort", c.url);
    assert_int_equal(kit_http("POST", url, NULL, "{}", NULL, 10), 401);
    snprintf(url, sizeof url, "%s/trials", c.url);
    assert_int_equal(kit_http("POST", url, NULL, "{}", NULL, 10), 401);

    /* With the token. */
    snprintf(url, sizeof url, "%s/status", c.url);
    assert_int_equal(kit_http("GET", url, TOKEN, NULL, NULL, 10), 200);
    snprintf(url, sizeof url, "%s/live/prediction", c.url);
    assert_int_equal(kit_http("GET", url, TOKEN, NULL, NULL, 10), 404); /* none yet, but allowed */
    snprintf(url, sizeof url, "%s/live/camera.jpg", c.url);
    assert_int_equal(kit_http("GET", url, TOKEN, NULL, NULL, 10), 404);
    snprintf(url, sizeof url, "%s/trials/1/samples.csv", c.url);
    assert_int_equal(kit_http("GET", url, TOKEN, NULL, NULL, 10), 404); /* no such trial, but allowed */
    snprintf(url, sizeof url, "%s/phase.png", c.url);
    assert_int_equal(kit_http("GET", url, TOKEN, NULL, NULL, 30), 200); /* no trials yet: the map alone */
    snprintf(url, sizeof url, "%s/live/events", c.url);
    assert_int_equal(kit_http("GET", url, TOKEN, NULL, &body, 1.5), 200);
    assert_non_null(strstr(body, "data: {\"type\":\"hello\""));
    free(body);
    assert_int_equal(kit_ribbond_stop(&c), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_token_guards_live_data)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
