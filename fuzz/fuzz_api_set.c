/* fuzz_api_set.c: an accepted API override's key, read independently (see fuzz_api_set.h): the
 * text before the first '=', C-locale blanks trimmed, split at its last '.'. */
#include "fuzz_api_set.h"

#include <ctype.h>
#include <string.h>

#include "fuzz_inputs.h"

static int one_of(const char *s, size_t len, const char *const *names)
{
    for (; *names; names++)
        if (strlen(*names) == len && memcmp(s, *names, len) == 0) return 1;
    return 0;
}

void fuzz_check_api_override(const char *who, const char *ovr)
{
    static const char *const whole[] = {"ribbon", "folds", "imperfection", "protocol", "snap", "mesh", "solver",
                                       "specimen", NULL};
    static const char *const timing[] = {"hold_s", "post_snap_s", "compress_speed_mm_s", "return_speed_mm_s", NULL};
    const char *eq = strchr(ovr, '=');
    if (!eq) fuzz_fail(who, "an override without '=' accepted");
    const char *b = ovr, *e = eq;
    while (b < e && isspace((unsigned char)*b)) b++;
    while (e > b && isspace((unsigned char)e[-1])) e--;
    const char *dot = NULL;
    for (const char *p = b; p < e; p++)
        if (*p == '.') dot = p;
    if (!dot || dot == b || dot + 1 == e) fuzz_fail(who, "an override without section.key accepted");
    size_t ls = (size_t)(dot - b), lk = (size_t)(e - dot - 1);
    const char *key = dot + 1;
    if (ls == 8 && memcmp(b, "specimen", 8) == 0 && lk == 16 && memcmp(key, "min_clamp_gap_mm", 16) == 0)
        fuzz_fail(who, "the specimen's clamp gap (a rail limit) accepted through the API");
    if (one_of(b, ls, whole)) return;
    if (ls == 5 && memcmp(b, "trial", 5) == 0 && one_of(key, lk, timing)) return;
    fuzz_fail(who, "an override of a key a trial may not change accepted through the API");
}
