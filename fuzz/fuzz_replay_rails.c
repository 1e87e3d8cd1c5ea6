/* fuzz_replay_rails.c: fuzz target for the outside replay's rails CSV (daemon/trial/
 * replay_rails_csv.c, read from memory): an accepted file gives at least two readings, all
 * finite and within REPLAY_RAILS_MAX_MM of zero, t strictly increasing; a refusal says why. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "fuzz_inputs.h"
#include "replay_rails_csv.h"

int fuzz_replay_rails_one(const uint8_t *data, size_t size)
{
    if (size == 0) return 0; /* fmemopen needs a buffer; the empty file is a test's */
    FILE *f = fmemopen((void *)data, size, "r");
    if (!f) return 0;
    rail_reading *r = NULL;
    size_t n = 0;
    char why[512] = "";
    if (replay_rails_csv_read(f, "fuzz.csv", &r, &n, why, sizeof why) == 0) {
        if (n < 2 || !r) fuzz_fail("replay_rails", "fewer than two readings accepted");
        for (size_t k = 0; k < n; k++) {
            if (!isfinite(r[k].t) || !isfinite(r[k].compress_mm) || !isfinite(r[k].shear_mm))
                fuzz_fail("replay_rails", "a non-finite reading accepted");
            if (!(fabs(r[k].compress_mm) <= REPLAY_RAILS_MAX_MM) || !(fabs(r[k].shear_mm) <= REPLAY_RAILS_MAX_MM))
                fuzz_fail("replay_rails", "a position beyond any rail accepted");
            if (k > 0 && !(r[k].t > r[k - 1].t)) fuzz_fail("replay_rails", "t not increasing");
        }
    } else if (why[0] == '\0' || r != NULL || n != 0) {
        fuzz_fail("replay_rails", "a refusal without a reason, or with readings left");
    }
    free(r);
    fclose(f);
    return 0;
}

FUZZ_ENTRY(fuzz_replay_rails_one)
