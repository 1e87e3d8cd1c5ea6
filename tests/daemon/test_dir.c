/* test_dir.c: see test_dir.h. */
#define _XOPEN_SOURCE 700 /* nftw */
#include "test_dir.h"

#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>

static int rm_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb;
    (void)flag;
    (void)ftw;
    return remove(path);
}

void test_dir_done(const char *dir, int passed, const char *what)
{
    if (!dir || !dir[0])
        return;
    const char *keep = getenv("RIBBON_TEST_KEEP");
    if (passed && !(keep && keep[0] == '1')) {
        if (nftw(dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS) != 0)
            printf("# could not remove %s\n", dir);
    } else {
        printf("# kept %s (%s)\n", dir, what);
    }
}
