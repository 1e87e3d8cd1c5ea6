/* fuzz_grbl_status.c: fuzz target for the GRBL reply parser (grbl_proto.c): line
 * classification and status report parsing on arbitrary bytes; a parsed report must hold only
 * finite positions and a valid state. */
#include <math.h>
#include <stdlib.h>

#include "fuzz.h"
#include "grbl_proto.h"

int fuzz_grbl_status_one(const uint8_t *data, size_t size)
{
    const char *s = (const char *)data;
    int code = 0;
    grbl_line_classify(s, size, &code);
    grbl_report r;
    char why[160];
    if (grbl_status_parse(s, size, &r, why, sizeof why)) {
        for (int i = 0; i < GRBL_MAX_AXES; i++)
            if (!isfinite(r.pos[i]))
                abort(); /* a harness invariant: reported as a crash by the fuzzer */
        if ((int)r.state < 0 || r.state >= GRBL_STATE_COUNT)
            abort();
    } else if (why[0] == 0) {
        abort(); /* every refusal carries a reason */
    }
    return 0;
}

#ifdef RIBBON_LIBFUZZER
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_grbl_status_one(data, size);
}
#endif
