/* api_overrides.c: the table of what an API client may change in a trial, and the check of one
 * override against it (see api_overrides.h). The key is split with the loaders' own splitter
 * (config/cfg_keys.h) so the check and the loader read the same key. */
#include "api_overrides.h"

#include <stdio.h>
#include <string.h>

#include "cfg_keys.h"

/* First match wins: a refusal inside an allowed section comes before the section's row. */
static const api_override_rule rules[] = {
    /* a limit of the rails, though the specimen's record holds it */
    {"specimen", "min_clamp_gap_mm", false, "a limit of the rails: the clamps never come closer"},
    /* the scene, whole sections: physics, protocol, the simulator's settings (a start's
     * prediction is bounded: trial_session_start refuses one estimated too long) */
    {"ribbon", "*", true, "the ribbon's size, material and gravity"},
    {"folds", "*", true, "the creases: angles, positions, stiffness"},
    {"imperfection", "*", true, "the difference between the two creases"},
    {"protocol", "*", true, "compression, shear rate and range, route"},
    {"snap", "*", true, "what the simulator counts as the snap"},
    {"mesh", "*", true, "the simulator's mesh (a start whose prediction would take too long is refused)"},
    {"solver", "*", true, "the simulator's time step, damping and tolerances (the same cost bound)"},
    /* the rig file: the specimen's record and the trial's timing */
    {"specimen", "*", true, "the specimen's name, material and measured creases"},
    {"trial", "hold_s", true, "the hold before the shear"},
    {"trial", "post_snap_s", true, "the recording after the snap"},
    {"trial", "compress_speed_mm_s", true, "the compression's speed (at most the rail's maximum)"},
    {"trial", "return_speed_mm_s", true, "the speed back (at most the rails' maximum)"},
    /* refused, with the reason */
    {"trial", "*", false, "the disk margin and the upper-state check are the rig file's"},
    {"rig", "*", false, "the mode, the scene file, the clock and the output directory are the rig file's"},
    {"rail.compress", "*", false, "the rails' drivers, ports, speeds and limits are the rig file's"},
    {"rail.shear", "*", false, "the rails' drivers, ports, speeds and limits are the rig file's"},
    {"calibration", "*", false, "the rig's calibration is the rig file's"},
    {"camera", "*", false, "the camera, its calibration file and its video directory are the rig file's"},
    {"detect", "*", false, "the snap detector's thresholds are the rig file's"},
    {"sim", "*", false, "the prediction's resolution (its cost) is the rig file's"},
    {"store", "*", false, "the store is the rig file's"},
    {"api", "*", false, "the API's address, port and token are the rig file's"},
    {"replay", "*", false, "replay sources are the rig file's"},
    {"twin", "*", false, "the twin is the bench's, not a trial's"},
};

#define N_RULES (sizeof rules / sizeof rules[0])

const api_override_rule *api_override_rules(size_t *n)
{
    if (n) *n = N_RULES;
    return rules;
}

/* The key as a refusal shows it: printable ASCII, no quotes or backslashes, cut at 64 bytes. */
static void shown_key(char *dst, size_t cap, const char *key)
{
    size_t k = 0;
    for (; key[k] != '\0' && k + 1 < cap && k < 64; k++) {
        unsigned char b = (unsigned char)key[k];
        dst[k] = (b >= 0x20 && b < 0x7f && b != '"' && b != '\\') ? (char)b : '?';
    }
    dst[k] = '\0';
}

/* The allowed rows as one list, "ribbon.*, folds.*, ..., trial.hold_s, ...". */
static void allowed_list(char *buf, size_t cap)
{
    size_t used = 0;
    buf[0] = '\0';
    for (size_t i = 0; i < N_RULES; i++) {
        if (!rules[i].allowed) continue;
        int w = snprintf(buf + used, cap - used, "%s%s.%s", used ? ", " : "", rules[i].section, rules[i].key);
        if (w < 0 || (size_t)w >= cap - used) {
            buf[used] = '\0';
            return;
        }
        used += (size_t)w;
    }
}

int api_override_check(const char *ovr, char *why, size_t why_len)
{
    char key[128], value[8], shown[72], allowed[320];
    allowed_list(allowed, sizeof allowed);
    cfg_split sp = cfg_override_split(ovr, key, sizeof key, value, sizeof value);
    if (sp == CFG_SPLIT_NO_EQUALS || sp == CFG_SPLIT_KEY_TOO_LONG) {
        snprintf(why, why_len, "expected section.key=value");
        return -1;
    }
    /* The value may be long (CFG_SPLIT_VALUE_TOO_LONG): the key has been split, the loader
     * judges the value. */
    shown_key(shown, sizeof shown, key);
    char *dot = strrchr(key, '.');
    if (dot == NULL || dot == key || dot[1] == '\0') {
        snprintf(why, why_len, "%s: expected section.key=value", shown);
        return -1;
    }
    *dot = '\0';
    const char *section = key, *name = dot + 1;
    for (size_t i = 0; i < N_RULES; i++) {
        const api_override_rule *r = &rules[i];
        if (strcmp(r->section, section) != 0 || (strcmp(r->key, "*") != 0 && strcmp(r->key, name) != 0))
            continue;
        if (r->allowed) return 0;
        snprintf(why, why_len, "%s may not be changed through the API (%s); a trial may change %s", shown, r->what,
                 allowed);
        return -1;
    }
    snprintf(why, why_len, "%s may not be changed through the API (not among the keys a trial may change: %s)",
             shown, allowed);
    return -1;
}
