/* fuzz_fail.c: how a fuzz harness reports a broken invariant (see fuzz_inputs.h). */
#include <stdio.h>
#include <stdlib.h>

#include "fuzz_inputs.h"

void fuzz_fail(const char *target, const char *what)
{
    fprintf(stderr, "fuzz %s: invariant broken: %s\n", target, what);
    abort();
}
