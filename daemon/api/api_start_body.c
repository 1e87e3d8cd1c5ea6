/* api_start_body.c: the checks of POST /trials's body (see api_start_body.h). */
#include "api_start_body.h"

#include "api_overrides.h"

#include <stdio.h>
#include <string.h>

static int check_note(const json_t *note, api_start_body *out, char *why, size_t why_len)
{
    if (!note) return 0;
    if (!json_is_string(note)) {
        snprintf(why, why_len, "\"note\" must be a string");
        return -1;
    }
    size_t len = json_string_length(note);
    if (len > API_START_NOTE_MAX) {
        snprintf(why, why_len, "\"note\" is %zu bytes; at most %d are kept, so it is refused rather than cut",
                 len, API_START_NOTE_MAX);
        return -1;
    }
    if (strlen(json_string_value(note)) != len) {
        snprintf(why, why_len, "\"note\" contains a NUL character");
        return -1;
    }
    out->note = json_string_value(note);
    return 0;
}

int api_start_body_parse(const json_t *body, int replay, api_start_body *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    if (!json_is_object(body)) {
        snprintf(why, why_len, "request body must be a JSON object");
        return -1;
    }
    const char *key;
    json_t *val;
    json_object_foreach((json_t *)body, key, val)
    {
        int ok = !strcmp(key, "note") ||
                 (replay ? !strcmp(key, "source_trial") : !strcmp(key, "set") || !strcmp(key, "specimen"));
        if (!ok) {
            char shown[64];
            size_t k = 0;
            for (; key[k] && k < sizeof shown - 1; k++)
                shown[k] = (key[k] >= 0x20 && key[k] < 0x7f && key[k] != '"') ? key[k] : '?';
            shown[k] = '\0';
            snprintf(why, why_len, replay ? "unknown field \"%s\" in replay mode (allowed: source_trial, note)"
                                    : "unknown field \"%s\" (allowed: specimen, set, note)",
                     shown);
            return -1;
        }
    }
    if (check_note(json_object_get(body, "note"), out, why, why_len)) return -1;
    if (replay) {
        json_t *src = json_object_get(body, "source_trial");
        if (src && (!json_is_integer(src) || json_integer_value(src) < 1)) {
            snprintf(why, why_len, "\"source_trial\" must be a trial id (an integer >= 1)");
            return -1;
        }
        out->source_trial = src ? (int64_t)json_integer_value(src) : 0;
        return 0;
    }
    json_t *sp = json_object_get(body, "specimen");
    if (sp) {
        if (!json_is_string(sp) || json_string_length(sp) == 0 || json_string_length(sp) > 63 ||
            strlen(json_string_value(sp)) != json_string_length(sp)) {
            snprintf(why, why_len, "\"specimen\" must be a specimen's name (1 to 63 bytes)");
            return -1;
        }
        out->specimen = json_string_value(sp);
    }
    json_t *set = json_object_get(body, "set");
    if (!set) return 0;
    if (!json_is_array(set)) {
        snprintf(why, why_len, "\"set\" must be an array of \"section.key=value\" strings");
        return -1;
    }
    size_t count = json_array_size(set);
    if (count > API_START_MAX_SET) {
        snprintf(why, why_len, "\"set\" has %zu overrides; at most %d", count, API_START_MAX_SET);
        return -1;
    }
    for (size_t k = 0; k < count; k++) {
        const json_t *s = json_array_get(set, k);
        if (!json_is_string(s)) {
            snprintf(why, why_len, "\"set\"[%zu] must be a string \"section.key=value\"", k);
            return -1;
        }
        if (strlen(json_string_value(s)) != json_string_length(s)) {
            snprintf(why, why_len, "\"set\"[%zu] contains a NUL character", k);
            return -1;
        }
        char not_allowed[400];
        if (api_override_check(json_string_value(s), not_allowed, sizeof not_allowed) != 0) {
            snprintf(why, why_len, "\"set\"[%zu]: %s", k, not_allowed);
            return -1;
        }
        out->set[out->n_set++] = json_string_value(s);
    }
    return 0;
}
