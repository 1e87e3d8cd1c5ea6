/* api_overrides.h: what an API client may change in a trial (issue 33, item 5).
 *
 * POST /trials may carry "set" overrides ("section.key=value") applied to the rig file for that
 * trial only. ribbond's own --set is the operator's and may change anything; an API client
 * (without a token, on loopback, any local user) may change only what a trial may: its scene
 * (physics, protocol and the simulator's settings), the specimen's record, the trial's timing.
 * Paths (the scene file, the
 * camera's calibration file and video directory, the store, replay sources), the API itself, the
 * rails (drivers, ports, speeds, limits), the calibration, the camera, snap detection, the
 * prediction's resolution and the twin are the rig file's: an override of one is refused (400)
 * naming its key and why, before anything is loaded, so no API request can make the daemon read
 * or create a file the rig file does not name.
 *
 * One table (after Redis's config.c): each row names a section and a key, or every key of the
 * section ("*"), and whether an API client may set it; the first row that matches decides, and a
 * key no row matches is refused. The scene's sections are allowed whole, so a key added to one of
 * them later needs no change here; a section added to the rig file is refused until a row allows
 * it. docs/api.md shows the table. */
#ifndef RIBBON_DAEMON_API_OVERRIDES_H
#define RIBBON_DAEMON_API_OVERRIDES_H

#include <stdbool.h>
#include <stddef.h>

typedef struct api_override_rule {
    const char *section; /* exactly as the loaders name it: "protocol", "rail.shear" */
    const char *key;     /* exactly, or "*" for every key of the section */
    bool allowed;        /* may an API client set it */
    const char *what;    /* what the row covers, for a refusal and the docs */
} api_override_rule;

/* The table, first match wins; *n gets its length. Static, read-only data. */
const api_override_rule *api_override_rules(size_t *n);

/* 0 when the override ovr ("section.key=value") may come from an API client; else -1 with the
 * reason in why, naming the key. The key is read as the loaders read it (cfg_override_split: the
 * text before the first '=', blanks around it trimmed; the section is what comes before its last
 * '.'), and matched exactly, so no spelling can reach a key the table refuses. The value is not
 * looked at (the loaders check it). */
int api_override_check(const char *ovr, char *why, size_t why_len);

#endif
