/* test_fuzz_replay.c: a short, deterministic run of the drivers' fuzz targets (drivers/fuzz/) in
 * every build: valid seeds, then a fixed stream of byte mutations of them and random inputs.
 * The targets abort on a broken invariant and the sanitizers catch memory errors, so this test
 * fails on anything the fuzzers would report. The open-ended runs are the libFuzzer builds
 * (cmake -DRIBBON_FUZZ=ON with clang). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "fuzz.h"

static uint32_t xs(uint32_t *st)
{
    uint32_t x = *st;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *st = x;
}

static void replay(int (*one)(const uint8_t *, size_t), const uint8_t *const *seeds, const size_t *lens,
                   int nseeds, int mutations)
{
    uint8_t buf[320];
    uint32_t st = 0x9e3779b9u;
    for (int i = 0; i < nseeds; i++)
        assert_int_equal(one(seeds[i], lens[i]), 0);
    for (int m = 0; m < mutations; m++) {
        size_t n;
        if (m % 4 == 3) {
            n = xs(&st) % 64;
            for (size_t i = 0; i < n; i++)
                buf[i] = (uint8_t)xs(&st);
        } else {
            int k = (int)(xs(&st) % (uint32_t)nseeds);
            n = lens[k];
            memcpy(buf, seeds[k], n);
            int flips = 1 + (int)(xs(&st) % 4);
            for (int f = 0; f < flips && n > 0; f++)
                buf[xs(&st) % n] = (uint8_t)xs(&st);
            if (xs(&st) % 3 == 0)
                n = xs(&st) % (n + 1); /* truncate */
        }
        assert_int_equal(one(buf, n), 0);
    }
}

static void test_grbl_status_targets(void **s)
{
    (void)s;
    static const char *const text[] = {
        "<Idle|MPos:10.000,0.000,0.000|FS:0,0>",
        "<Jog|MPos:1.5,2.5,0|Bf:15,127|FS:600,0|WCO:0,0,0>",
        "<Hold:1|WPos:1,2,3|F:100|Pn:XY|Ov:100,100,100>",
        "<Alarm|MPos:0,0,0>",
        "ok",
        "error:15",
        "ALARM:3",
    };
    const uint8_t *seeds[7];
    size_t lens[7];
    for (int i = 0; i < 7; i++) {
        seeds[i] = (const uint8_t *)text[i];
        lens[i] = strlen(text[i]);
    }
    replay(fuzz_grbl_status_one, seeds, lens, 7, 20000);
}

static void test_modbus_reply_targets(void **s)
{
    (void)s;
    /* A valid answer to "read 8 registers" (tid patched by the target), an exception, a short
       frame. */
    static const uint8_t ok[] = {0, 1, 0, 0, 0, 19, 1, 3, 16, 0, 0, 0x30, 0x39, 0, 0, 0, 2,
                                 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    static const uint8_t exc[] = {0, 1, 0, 0, 0, 3, 1, 0x83, 2};
    static const uint8_t shortf[] = {0, 1, 0, 0, 0, 9, 1, 3};
    const uint8_t *seeds[3] = {ok, exc, shortf};
    size_t lens[3] = {sizeof ok, sizeof exc, sizeof shortf};
    replay(fuzz_modbus_reply_one, seeds, lens, 3, 300);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grbl_status_targets),
        cmocka_unit_test(test_modbus_reply_targets),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
