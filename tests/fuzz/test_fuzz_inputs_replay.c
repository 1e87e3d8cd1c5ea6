/* test_fuzz_inputs_replay.c: a short, deterministic run of the input parsers' fuzz targets
 * (fuzz/fuzz_inputs.h) in every build: each target's seeds (fuzz/corpus/<target>/, plus the
 * shipped scene, rig and Modbus map files for the loaders), then a fixed stream of byte mutations of them
 * (flips, truncations, splices, inserted hex floats and NULs). The targets abort on a broken
 * invariant and the sanitizers catch memory errors, so this fails on anything the fuzzers would
 * report; the inputs the fuzzers found are seeds here once fixed. */
#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "fuzz_inputs.h"

#define MAX_SEEDS 64
#define MAX_SEED_BYTES (64 * 1024)

typedef struct seeds {
    uint8_t *data[MAX_SEEDS];
    size_t len[MAX_SEEDS];
    int n;
} seeds;

static void add_file(seeds *s, const char *path)
{
    if (s->n == MAX_SEEDS) return;
    FILE *f = fopen(path, "rb");
    if (!f) return;
    uint8_t *buf = malloc(MAX_SEED_BYTES);
    assert_non_null(buf);
    size_t n = fread(buf, 1, MAX_SEED_BYTES, f);
    fclose(f);
    s->data[s->n] = buf;
    s->len[s->n++] = n;
}

/* Every file of dir whose name ends in suffix ("" for all). */
static void add_dir(seeds *s, const char *dir, const char *suffix)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    char path[1024];
    while ((e = readdir(d)) != NULL) {
        size_t ln = strlen(e->d_name), ls = strlen(suffix);
        if (e->d_name[0] == '.' || ln < ls || strcmp(e->d_name + ln - ls, suffix) != 0) continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        add_file(s, path);
    }
    closedir(d);
}

static void free_seeds(seeds *s)
{
    for (int i = 0; i < s->n; i++) free(s->data[i]);
    s->n = 0;
}

static uint32_t xs(uint32_t *st)
{
    uint32_t x = *st;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    return *st = x;
}

static void replay(int (*one)(const uint8_t *, size_t), const char *target, const char *extra_dir,
                   const char *extra_suffix, int mutations)
{
    seeds s = {0};
    char dir[512];
    snprintf(dir, sizeof dir, "%s/fuzz/corpus/%s", RIBBON_SOURCE_DIR, target);
    add_dir(&s, dir, "");
    if (extra_dir) add_dir(&s, extra_dir, extra_suffix);
    assert_true(s.n > 0);
    for (int i = 0; i < s.n; i++) assert_int_equal(one(s.data[i], s.len[i]), 0);
    static const char *const inserts[] = {"0x1p1", "\n", "\r\n", "=", ",", "[", "]", "1e999", "nan",
                                          "-", ".", ";", "#", "\"", "{", "}", "999999999999"};
    uint8_t *buf = malloc(2 * MAX_SEED_BYTES + 64);
    assert_non_null(buf);
    uint32_t st = 0x9e3779b9u;
    for (int m = 0; m < mutations; m++) {
        int k = (int)(xs(&st) % (uint32_t)s.n);
        size_t n = s.len[k];
        memcpy(buf, s.data[k], n);
        switch (xs(&st) % 4) {
        case 0: /* flips */
            for (int f = 1 + (int)(xs(&st) % 4); f > 0 && n > 0; f--) buf[xs(&st) % n] = (uint8_t)xs(&st);
            break;
        case 1: /* truncate */
            n = xs(&st) % (n + 1);
            break;
        case 2: { /* insert a token */
            const char *t = inserts[xs(&st) % (sizeof inserts / sizeof inserts[0])];
            size_t at = xs(&st) % (n + 1), lt = strlen(t);
            memmove(buf + at + lt, buf + at, n - at);
            memcpy(buf + at, t, lt);
            n += lt;
            break;
        }
        default: { /* splice: a piece of another seed */
            int j = (int)(xs(&st) % (uint32_t)s.n);
            size_t from = s.len[j] ? xs(&st) % s.len[j] : 0, len = s.len[j] - from;
            if (len > 200) len = 200;
            size_t at = xs(&st) % (n + 1);
            memmove(buf + at + len, buf + at, n - at);
            memcpy(buf + at, s.data[j] + from, len);
            n += len;
            if (xs(&st) % 8 == 0 && n > 0) buf[xs(&st) % n] = 0; /* a NUL */
            break;
        }
        }
        assert_int_equal(one(buf, n), 0);
    }
    free(buf);
    free_seeds(&s);
}

static void test_scene_ini(void **st)
{
    (void)st;
    replay(fuzz_scene_ini_one, "scene_ini", RIBBON_SOURCE_DIR "/config/scenes", ".ini", 3000);
}

static void test_rig_ini(void **st)
{
    (void)st;
    replay(fuzz_rig_ini_one, "rig_ini", RIBBON_SOURCE_DIR "/config", ".ini", 2000);
}

static void test_map_ini(void **st)
{
    (void)st;
    replay(fuzz_map_ini_one, "map_ini", RIBBON_SOURCE_DIR "/config/maps", ".ini", 3000);
}

static void test_set_override(void **st)
{
    (void)st;
    replay(fuzz_set_override_one, "set_override", NULL, NULL, 400);
}

static void test_api_request(void **st)
{
    (void)st;
    replay(fuzz_api_request_one, "api_request", NULL, NULL, 3000);
}

static void test_api_headers(void **st)
{
    (void)st;
    replay(fuzz_api_headers_one, "api_headers", NULL, NULL, 3000);
}

static void test_calib_file(void **st)
{
    (void)st;
    replay(fuzz_calib_file_one, "calib_file", NULL, NULL, 3000);
}

static void test_replay_rails(void **st)
{
    (void)st;
    replay(fuzz_replay_rails_one, "replay_rails", NULL, NULL, 3000);
}

static void test_sweep_csv(void **st)
{
    (void)st;
    replay(fuzz_sweep_csv_one, "sweep_csv", NULL, NULL, 3000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scene_ini),   cmocka_unit_test(test_rig_ini),
        cmocka_unit_test(test_map_ini),
        cmocka_unit_test(test_set_override), cmocka_unit_test(test_api_request),
        cmocka_unit_test(test_api_headers),
        cmocka_unit_test(test_calib_file),  cmocka_unit_test(test_replay_rails),
        cmocka_unit_test(test_sweep_csv),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
