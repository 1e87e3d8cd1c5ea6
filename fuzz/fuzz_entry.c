/* fuzz_entry.c: LLVMFuzzerTestOneInput for a target whose body lives in the harness library
 * (fuzz_scene_ini.c, fuzz_rig_ini.c: their checks are shared with the other config targets);
 * RIBBON_FUZZ_ENTRY names the target's function. */
#include "fuzz_inputs.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return RIBBON_FUZZ_ENTRY(data, size);
}
