/* fuzz_shipped.c: the shipped files the fuzz targets start from (see fuzz_scene.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_inputs.h"
#include "fuzz_config.h"

#ifndef RIBBON_SOURCE_DIR
#error "RIBBON_SOURCE_DIR must be defined"
#endif

typedef struct shipped {
    const char *rel;
    char *text;
    size_t len;
} shipped;

const char *fuzz_shipped_text(const char *rel, size_t *len)
{
    static shipped cache[8];
    for (int i = 0; i < 8; i++) {
        if (cache[i].rel && strcmp(cache[i].rel, rel) == 0) {
            *len = cache[i].len;
            return cache[i].text;
        }
        if (cache[i].rel) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", RIBBON_SOURCE_DIR, rel);
        FILE *f = fopen(path, "rb");
        if (!f) fuzz_fail("shipped", path);
        char *buf = malloc(1 << 20);
        if (!buf) fuzz_fail("shipped", "out of memory");
        size_t n = fread(buf, 1, (1 << 20) - 1, f);
        fclose(f);
        buf[n] = '\0';
        cache[i] = (shipped){rel, buf, n};
        *len = n;
        return buf;
    }
    fuzz_fail("shipped", "more than 8 shipped files");
    return NULL;
}
