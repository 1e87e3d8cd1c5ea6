/* test_api_start_body.c: the checks of POST /trials's body (daemon/api/api_start_body.h), issue
 * 17 item 12: the too-many-overrides error said "at most 64" while 124 were accepted (the limit
 * counted the command line's overrides too), and a 65,000-character note was silently cut to 255.
 * Now the limit is the one the message names, and a note too long to keep is refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "api_start_body.h"

static int parse(const char *text, int replay, api_start_body *out, char *why, size_t why_len)
{
    json_error_t je;
    json_t *j = json_loads(text, JSON_ALLOW_NUL, &je); /* the server refuses NUL; the checks need not rely on it */
    assert_non_null(j);
    int rc = api_start_body_parse(j, replay, out, why, why_len);
    json_decref(j); /* the strings are not used after this */
    return rc;
}

static void test_override_limit_is_the_one_named(void **s)
{
    (void)s;
    char why[256];
    api_start_body b;
    for (int count = API_START_MAX_SET - 1; count <= 2 * API_START_MAX_SET; count++) {
        json_t *body = json_object(), *set = json_array();
        for (int k = 0; k < count; k++) json_array_append_new(set, json_string("trial.hold_s=1"));
        json_object_set_new(body, "set", set);
        int rc = api_start_body_parse(body, 0, &b, why, sizeof why);
        if (count <= API_START_MAX_SET) {
            assert_int_equal(rc, 0);
            assert_int_equal(b.n_set, count);
        } else {
            assert_int_equal(rc, -1);
            char expect[64];
            snprintf(expect, sizeof expect, "at most %d", API_START_MAX_SET);
            assert_non_null(strstr(why, expect));
        }
        json_decref(body);
    }
}

static void test_long_note_refused_not_cut(void **s)
{
    (void)s;
    char why[256];
    api_start_body b;
    char *note = malloc(65001);
    assert_non_null(note);
    memset(note, 'n', 65000);
    note[65000] = '\0';
    json_t *body = json_pack("{s:s}", "note", note);
    assert_int_equal(api_start_body_parse(body, 0, &b, why, sizeof why), -1);
    assert_non_null(strstr(why, "65000 bytes"));
    assert_int_equal(api_start_body_parse(body, 1, &b, why, sizeof why), -1);
    json_decref(body);
    note[API_START_NOTE_MAX] = '\0';
    body = json_pack("{s:s}", "note", note);
    assert_int_equal(api_start_body_parse(body, 0, &b, why, sizeof why), 0);
    assert_int_equal(strlen(b.note), API_START_NOTE_MAX);
    json_decref(body);
    free(note);
}

static void test_fields_by_mode(void **s)
{
    (void)s;
    char why[256];
    api_start_body b;
    assert_int_equal(parse("{}", 0, &b, why, sizeof why), 0);
    assert_null(b.note);
    assert_int_equal(parse("{\"source_trial\": 3}", 1, &b, why, sizeof why), 0);
    assert_int_equal(b.source_trial, 3);
    assert_int_equal(parse("{\"source_trial\": 3}", 0, &b, why, sizeof why), -1);
    assert_non_null(strstr(why, "unknown field \"source_trial\""));
    assert_int_equal(parse("{\"set\": []}", 1, &b, why, sizeof why), -1);
    assert_int_equal(parse("{\"source_trial\": 0}", 1, &b, why, sizeof why), -1);
    assert_int_equal(parse("{\"source_trial\": 1.5}", 1, &b, why, sizeof why), -1);
    assert_int_equal(parse("{\"set\": \"a.b=1\"}", 0, &b, why, sizeof why), -1);
    assert_int_equal(parse("{\"set\": [1]}", 0, &b, why, sizeof why), -1);
    assert_int_equal(parse("{\"set\": [\"a\\u0000b\"]}", 0, &b, why, sizeof why), -1);
    assert_non_null(strstr(why, "NUL"));
    assert_int_equal(parse("{\"note\": 5}", 0, &b, why, sizeof why), -1);
    assert_int_equal(parse("{\"x\\u0001\": 5}", 0, &b, why, sizeof why), -1);
    assert_non_null(strstr(why, "\"x?\""));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_override_limit_is_the_one_named),
        cmocka_unit_test(test_long_note_refused_not_cut),
        cmocka_unit_test(test_fields_by_mode),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
