/* fuzz_set_override.c: fuzz target for `--set section.key=value` overrides (and so the API's
 * "set" array, which takes the same path): the input, split at newlines into at most 16
 * overrides, applied by the real loaders to a shipped scene (config/scenes/paper-gamma013.ini)
 * and to the shipped mock rig file (config/mock.ini, whose scene keys, rail keys and trial keys
 * all take overrides). */
#include <stdlib.h>
#include <string.h>

#include "fuzz_config.h"
#include "fuzz_inputs.h"
#include "scene_file.h"

#define MAX_OVR 16

int fuzz_set_override_one(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1);
    if (!text) return 0;
    memcpy(text, data, size);
    text[size] = '\0';
    const char *ovr[MAX_OVR];
    int n = 0;
    char *p = text;
    while (n < MAX_OVR) {
        ovr[n++] = p;
        char *nl = memchr(p, '\n', (size_t)(text + size - p));
        if (!nl) break;
        *nl = '\0';
        p = nl + 1;
    }
    size_t len;
    const char *scene = fuzz_shipped_text("config/scenes/paper-gamma013.ini", &len);
    rod_scene s;
    cfg_error err;
    cfg_status st = cfg_scene_parse("paper-gamma013.ini", scene, len, ovr, n, &s, &err);
    if (st == CFG_OK) fuzz_check_scene("set_override", &s);
    else if (err.status != st || err.message[0] == '\0') fuzz_fail("set_override", "a refusal without a reason");
    const char *rig = fuzz_shipped_text("config/mock.ini", &len);
    fuzz_rig_text("set_override", rig, len, ovr, n);
    free(text);
    return 0;
}

FUZZ_ENTRY(fuzz_set_override_one)
