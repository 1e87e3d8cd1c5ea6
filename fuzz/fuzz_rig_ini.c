/* fuzz_rig_ini.c: fuzz target for rig files through the real loader (config/rig_config.c on text
 * in memory, relative paths from the shipped config/ folder, so "scene = scenes/..." loads a real
 * scene): a refusal carries a status and a message; an accepted rig holds a scene the simulator
 * accepts and finite trial settings. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_inputs.h"
#include "fuzz_config.h"
#include "rig_config.h"

static void check_rig(const char *who, const rig_config *c)
{
    fuzz_check_scene(who, &c->scene);
    const double v[] = {c->trial.hold_s, c->trial.compress_speed_mm_s};
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
        if (!isfinite(v[i])) fuzz_fail(who, "an accepted rig holds a non-finite value");
    if ((int)c->mode < 0 || (int)c->mode > RIG_MODE_REPLAY) fuzz_fail(who, "a mode out of its enum");
}

void fuzz_rig_text(const char *who, const char *text, size_t len, const char *const *ovr, int n)
{
    static rig_config cfg; /* large: off the stack */
    cfg_error err;
    cfg_status st = rig_config_parse("fuzz-rig.ini", RIBBON_SOURCE_DIR "/config", text, len, ovr, n,
                                     &cfg, &err);
    if (st == CFG_OK) {
        check_rig(who, &cfg);
        char *j = rig_calibration_json(&cfg);
        if (!j) fuzz_fail(who, "no calibration JSON for an accepted rig");
        free(j);
        j = rig_specimen_json(&cfg);
        free(j);
    } else if (err.status != st || err.message[0] == '\0') {
        fuzz_fail(who, "a refusal without a reason");
    }
}

int fuzz_rig_ini_one(const uint8_t *data, size_t size)
{
    fuzz_rig_text("rig_ini", (const char *)data, size, NULL, 0);
    return 0;
}

FUZZ_ENTRY(fuzz_rig_ini_one)
