/* store_names.c: the text each enumerated column holds in the database (and in JSON and CSV),
 * one table per enum, so the CHECK constraints in store.c, the C enums in store.h and the words
 * users see cannot drift apart silently: a test round-trips every value. */
#include "store.h"

#include <string.h>

static const char *const mode_names[STORE_MODE_COUNT] = {"rig", "mock", "replay"};
static const char *const status_names[STORE_STATUS_COUNT] = {"created", "running", "done",
                                                             "failed",  "aborted", "interrupted"};
static const char *const regime_names[STORE_REGIME_COUNT] = {NULL, "symmetric", "asymmetric", "no snap"};
static const char *const event_names[STORE_EVENT_COUNT] = {"state", "info", "warning", "fault"};
static const char *const source_names[STORE_SOURCE_COUNT] = {NULL, "scene", "specimen"};

static const char *const err_names[STORE_E_COUNT] = {
    "ok",
    "invalid argument",
    "not found",
    "not allowed in the current state",
    "unsupported schema version",
    "not a ribbon rig database, or corrupt",
    "database busy",
    "database or file system error",
    "refused by a database constraint",
    "out of memory",
    "the name is taken",
};

const char *store_err_message(store_err err)
{
    return (unsigned)err < STORE_E_COUNT ? err_names[err] : "unknown store error";
}

static int find(const char *const *names, int count, const char *s)
{
    if (!s)
        return -1;
    for (int i = 0; i < count; i++)
        if (names[i] && strcmp(names[i], s) == 0)
            return i;
    return -1;
}

const char *store_mode_name(store_mode m)
{
    return (unsigned)m < STORE_MODE_COUNT ? mode_names[m] : NULL;
}

const char *store_status_name(store_status s)
{
    return (unsigned)s < STORE_STATUS_COUNT ? status_names[s] : NULL;
}

const char *store_regime_name(store_regime r)
{
    return (unsigned)r < STORE_REGIME_COUNT ? regime_names[r] : NULL;
}

const char *store_event_kind_name(store_event_kind k)
{
    return (unsigned)k < STORE_EVENT_COUNT ? event_names[k] : NULL;
}

bool store_mode_parse(const char *s, store_mode *out)
{
    int i = find(mode_names, STORE_MODE_COUNT, s);
    if (i >= 0)
        *out = (store_mode)i;
    return i >= 0;
}

bool store_status_parse(const char *s, store_status *out)
{
    int i = find(status_names, STORE_STATUS_COUNT, s);
    if (i >= 0)
        *out = (store_status)i;
    return i >= 0;
}

bool store_regime_parse(const char *s, store_regime *out)
{
    int i = find(regime_names, STORE_REGIME_COUNT, s);
    if (i < 0 && s && strcmp(s, "none") == 0)
        i = STORE_REGIME_NO_SNAP;
    if (i >= 0)
        *out = (store_regime)i;
    return i >= 0;
}

bool store_event_kind_parse(const char *s, store_event_kind *out)
{
    int i = find(event_names, STORE_EVENT_COUNT, s);
    if (i >= 0)
        *out = (store_event_kind)i;
    return i >= 0;
}

const char *store_source_name(store_source s)
{
    return (unsigned)s < STORE_SOURCE_COUNT ? source_names[s] : NULL;
}

bool store_source_parse(const char *s, store_source *out)
{
    int i = find(source_names, STORE_SOURCE_COUNT, s);
    if (i >= 0)
        *out = (store_source)i;
    return i >= 0;
}
