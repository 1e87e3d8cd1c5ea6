/* test_vision_block_ids.c: a live camera's block ids counted into lost frames (vis_block_ids_next):
 * gaps, the GigE Vision 1.x 16-bit wrap, and a buffer delivered after a newer one (late), which
 * was counted lost once and must not be counted again nor move the ids back (the old rule read it
 * as a wrap, or, after an incomplete buffer, counted the frames after it a second time). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "vision.h"

static void test_first_and_consecutive(void **state)
{
    (void)state;
    vis_block_ids ids = {0, 0};
    assert_int_equal(vis_block_ids_next(&ids, 17), 0); /* the first id: nothing known lost */
    assert_int_equal(vis_block_ids_next(&ids, 18), 0);
    assert_int_equal(vis_block_ids_next(&ids, 21), 2); /* 19 and 20 never arrived */
}

static void test_wrap_16bit(void **state)
{
    (void)state;
    vis_block_ids ids = {0, 0};
    vis_block_ids_next(&ids, 65534);
    assert_int_equal(vis_block_ids_next(&ids, 65535), 0);
    assert_int_equal(vis_block_ids_next(&ids, 1), 0); /* 65535 -> 1: 0 is never used */
    /* a buffer from before the wrap, delivered after it: late, not 65,531 frames ahead */
    assert_int_equal(vis_block_ids_next(&ids, 65533), VIS_BLOCK_LATE);
    assert_int_equal(ids.last, 1);
    assert_int_equal(vis_block_ids_next(&ids, 2), 0);
    vis_block_ids wrap_gap = {1, 65530};
    assert_int_equal(vis_block_ids_next(&wrap_gap, 3), 7); /* 65531..65535, 1, 2 */
}

static void test_late_buffer_counted_once(void **state)
{
    (void)state;
    /* 100 arrives, 102 completes before 101 (101's packets were missing: its buffer is closed by
     * the timeout after 102), then 103. Frames accounted: 100, 101 lost once, 102, 103. */
    vis_block_ids ids = {0, 0};
    long lost = 0;
    assert_int_equal(vis_block_ids_next(&ids, 100), 0);
    lost += vis_block_ids_next(&ids, 102);
    assert_int_equal(lost, 1);
    assert_int_equal(vis_block_ids_next(&ids, 101), VIS_BLOCK_LATE);
    assert_int_equal(vis_block_ids_next(&ids, 102), VIS_BLOCK_LATE); /* a repeat */
    lost += vis_block_ids_next(&ids, 103);
    assert_int_equal(lost, 1);
    assert_int_equal(ids.last, 103);
}

static void test_late_below_wrap_threshold_in_16bit_range(void **state)
{
    (void)state;
    /* Small 16-bit ids going back by one (a late buffer) were read as a wrap by the old rule:
     * 65,000 frames counted lost. */
    vis_block_ids ids = {0, 0};
    vis_block_ids_next(&ids, 231);
    vis_block_ids_next(&ids, 233);
    assert_int_equal(vis_block_ids_next(&ids, 232), VIS_BLOCK_LATE);
    assert_int_equal(vis_block_ids_next(&ids, 234), 0);
}

static void test_64bit_ids_restart(void **state)
{
    (void)state;
    vis_block_ids ids = {0, 0};
    vis_block_ids_next(&ids, 70000);
    assert_int_equal(vis_block_ids_next(&ids, 69990), VIS_BLOCK_LATE);
    assert_int_equal(vis_block_ids_next(&ids, 5), 0); /* far back: the ids started again */
    assert_int_equal(ids.last, 5);
    assert_int_equal(vis_block_ids_next(&ids, 8), 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_first_and_consecutive),
        cmocka_unit_test(test_wrap_16bit),
        cmocka_unit_test(test_late_buffer_counted_once),
        cmocka_unit_test(test_late_below_wrap_threshold_in_16bit_range),
        cmocka_unit_test(test_64bit_ids_restart),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
