/* fuzz_sweep_csv.c: fuzz target for the sweep CSV that `ribbon-sim sweep --resume` reads back
 * (daemon/ribbon_sim_commands/sim_sweep_row.c, read from memory): rows kept are of a known kind
 * with finite numbers and terminated text, the made-by line terminated; a refusal says why and
 * keeps nothing. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fuzz_inputs.h"
#include "sim_sweep_row.h"

int fuzz_sweep_csv_one(const uint8_t *data, size_t size)
{
    if (size == 0) return 0; /* fmemopen needs a buffer; the empty file is a test's */
    FILE *f = fmemopen((void *)data, size, "r");
    if (!f) return 0;
    sweep_table t;
    char err[512] = "";
    if (sweep_table_read(f, "fuzz.csv", &t, err, sizeof err) == 0) {
        for (size_t k = 0; k < t.n; k++) {
            const sweep_row *r = &t.rows[k];
            if (r->kind != 'p' && r->kind != 'q' && r->kind != 'b') fuzz_fail("sweep_csv", "a row of no kind");
            const double v[] = {r->phi, r->gamma, r->gamma_lo, r->gamma_hi, r->dl, r->first_dw, r->first_dz, r->wall_s};
            for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
                if (!isfinite(v[i])) fuzz_fail("sweep_csv", "a non-finite number kept");
            if (!memchr(r->regime, '\0', sizeof r->regime) || !memchr(r->note, '\0', sizeof r->note))
                fuzz_fail("sweep_csv", "unterminated text kept");
            (void)sweep_table_find(&t, r->phi, r->gamma, r->dl);
        }
        if (!memchr(t.origin, '\0', sizeof t.origin)) fuzz_fail("sweep_csv", "unterminated made-by line kept");
        sweep_table_free(&t);
    } else if (err[0] == '\0' || t.n != 0) {
        fuzz_fail("sweep_csv", "a refusal without a reason, or with rows left");
    }
    fclose(f);
    return 0;
}

FUZZ_ENTRY(fuzz_sweep_csv_one)
