/* api_start_body.h: what the body of POST /trials may carry, checked before anything runs.
 *
 *   rig and mock mode:  {"specimen": "S-12", "set": ["section.key=value", ...], "note": "..."}
 *   replay mode:        {"source_trial": ID, "note": "..."}
 *
 * Any other field, a "set" that is not an array of at most API_START_MAX_SET strings, a
 * "source_trial" that is not an integer >= 1, a "note" that is not a string of at most
 * API_START_NOTE_MAX bytes (refused, never cut), a "specimen" that is not a string of 1 to 63
 * bytes is a 400 with the reason, and so is an override
 * of a key an API client may not change (api_overrides.h: paths, the API, the rails, the store
 * ...); the rig loader checks the values (rig_config_load). Kept apart from the daemon's ops
 * so the parsing can be tested and fuzzed without a rig (fuzz/fuzz_api_request.c). The strings
 * point into body, which must outlive the result. */
#ifndef RIBBON_DAEMON_API_START_BODY_H
#define RIBBON_DAEMON_API_START_BODY_H

#include <jansson.h>
#include <stddef.h>
#include <stdint.h>

#define API_START_MAX_SET 64    /* overrides in one request's "set" */
#define API_START_NOTE_MAX 255  /* bytes of a trial's note (the trial record keeps as many) */

typedef struct api_start_body {
    const char *set[API_START_MAX_SET];
    int n_set;
    const char *note;     /* NULL when absent */
    const char *specimen; /* a specimen's name in the store (its record sets the trial's specimen
                             and scene keys before "set"); NULL when absent */
    int64_t source_trial; /* replay mode: 0 when absent */
} api_start_body;

/* Check body (a JSON object) for the mode (replay != 0: replay mode). 0 and *out on success;
 * -1 with the reason in why (the reply is a 400) otherwise. */
int api_start_body_parse(const json_t *body, int replay, api_start_body *out, char *why, size_t why_len);

#endif
