/* test_trial_publish: the messages a trial and a replay publish for the live page
 * (daemon/trial/trial_publish.h), read back from a real bus as JSON: a measured frame's sample,
 * a frame the pipeline dropped and one not tracked (untracked "dropped" / "skipped", no dz or a),
 * a rail reading (frame -1, untracked null), a state by name (the replay's "replaying") and the
 * stored message. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <jansson.h>
#include <math.h>
#include <string.h>

#include "trial_publish.h"

static json_t *next(live_bus *b, uint64_t *cursor)
{
    char buf[1100];
    uint64_t seq = 0, missed = 0;
    int n = live_bus_read(b, cursor, buf, sizeof buf, 1000, &seq, &missed);
    assert_true(n > 0);
    json_error_t e;
    json_t *j = json_loads(buf, 0, &e);
    if (!j) fail_msg("not JSON: %s", buf);
    return j;
}

static void test_messages(void **state)
{
    (void)state;
    live_bus *b = live_bus_create();
    assert_non_null(b);
    trial_publish_begin(b, 7, "replay", "a \"note\"");
    uint64_t cursor = live_bus_first(b);
    trial_sample s;
    memset(&s, 0, sizeof s);
    s.kind = 1;
    s.frame = 12;
    s.t_s = 0.4;
    s.dw = 0.25;
    s.measured = 1;
    s.dz = 0.3;
    s.a = -0.01;
    s.quality = 0.9;
    trial_publish_sample(b, 7, &s);
    s.measured = 0;
    s.not_tracked = 2;
    trial_publish_sample(b, 7, &s);
    s.not_tracked = 1;
    trial_publish_sample(b, 7, &s);
    memset(&s, 0, sizeof s);
    s.dw = NAN;
    trial_publish_sample(b, 7, &s);
    trial_publish_state_name(b, 7, "replaying", NAN, "v.avi");
    trial_publish_stored(b, 7, TRIAL_DONE);

    json_t *j = next(b, &cursor);
    assert_string_equal(json_string_value(json_object_get(j, "type")), "trial");
    assert_string_equal(json_string_value(json_object_get(j, "mode")), "replay");
    assert_string_equal(json_string_value(json_object_get(j, "note")), "a \"note\"");
    json_decref(j);
    j = next(b, &cursor);
    assert_true(json_is_true(json_object_get(j, "measured")));
    assert_true(fabs(json_real_value(json_object_get(j, "dz")) - 0.3) < 1e-12);
    assert_true(json_is_null(json_object_get(j, "untracked")));
    json_decref(j);
    j = next(b, &cursor);
    assert_string_equal(json_string_value(json_object_get(j, "untracked")), "dropped");
    assert_true(json_is_null(json_object_get(j, "dz")));
    json_decref(j);
    j = next(b, &cursor);
    assert_string_equal(json_string_value(json_object_get(j, "untracked")), "skipped");
    json_decref(j);
    j = next(b, &cursor);
    assert_string_equal(json_string_value(json_object_get(j, "kind")), "rail");
    assert_int_equal(json_integer_value(json_object_get(j, "frame")), -1);
    assert_true(json_is_null(json_object_get(j, "dw"))); /* NaN is sent as null */
    assert_true(json_is_null(json_object_get(j, "untracked")));
    json_decref(j);
    j = next(b, &cursor);
    assert_string_equal(json_string_value(json_object_get(j, "state")), "replaying");
    assert_true(json_is_null(json_object_get(j, "t")));
    assert_string_equal(json_string_value(json_object_get(j, "why")), "v.avi");
    json_decref(j);
    j = next(b, &cursor);
    assert_string_equal(json_string_value(json_object_get(j, "type")), "stored");
    assert_int_equal(json_integer_value(json_object_get(j, "trial")), 7);
    assert_string_equal(json_string_value(json_object_get(j, "final")), "done");
    json_decref(j);
    live_bus_free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_messages)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
