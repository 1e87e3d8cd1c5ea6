/* api_route.c: matching a request path against the control API's routes.
 *
 * The table is small and fixed, so matching is a handful of string compares rather than a
 * pattern engine. A trial id is a path segment of decimal digits with value 1 .. INT64_MAX
 * (the store's INTEGER PRIMARY KEY); signs, spaces, hex and overflow are refused with a reason so
 * that "/trials/abc" says what is wrong instead of "not found". "/trials/current" is not a route:
 * "current" exists only as the target of the abort action. */
#include "api_route.h"

#include <stdio.h>
#include <string.h>

/* Parse seg[0..len) as a positive decimal int64. */
static int parse_id(const char *seg, size_t len, int64_t *id, char *why, size_t why_len)
{
    if (len == 0) {
        snprintf(why, why_len, "trial id is empty: expected a positive integer");
        return -1;
    }
    int64_t v = 0;
    for (size_t i = 0; i < len; i++) {
        char c = seg[i];
        if (c < '0' || c > '9') {
            snprintf(why, why_len, "trial id '%.*s' is not a positive integer", (int)(len > 40 ? 40 : len), seg);
            return -1;
        }
        int d = c - '0';
        if (v > (INT64_MAX - d) / 10) {
            snprintf(why, why_len, "trial id '%.*s' is too large", (int)(len > 40 ? 40 : len), seg);
            return -1;
        }
        v = v * 10 + d;
    }
    if (v == 0) {
        snprintf(why, why_len, "trial id must be at least 1, got '%.*s'", (int)(len > 40 ? 40 : len), seg);
        return -1;
    }
    *id = v;
    return 0;
}

int api_path_grammar_ok(const char *path, char *why, size_t why_len)
{
    if (path == NULL || path[0] != '/') {
        snprintf(why, why_len, "request path must start with '/'");
        return 0;
    }
    for (size_t i = 0; path[i] != '\0'; i++) {
        unsigned char c = (unsigned char)path[i];
        int ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                 c == '_' || c == '/' || c == '-';
        if (!ok) {
            if (c > 0x20 && c < 0x7f)
                snprintf(why, why_len, "byte '%c' at offset %zu of the path is outside the API's path grammar "
                                 "[A-Za-z0-9._/-] (percent-escapes are not decoded)", (char)c, i);
            else
                snprintf(why, why_len, "byte 0x%02x at offset %zu of the path is outside the API's path grammar "
                                 "[A-Za-z0-9._/-]", c, i);
            return 0;
        }
    }
    return 1;
}

api_route api_route_parse(const char *path, int64_t *id, char *why, size_t why_len)
{
    static const char prefix[] = "/trials/";
    static const char report[] = "/report.png";
    static const char samples[] = "/samples.csv";
    if (path == NULL)
        return API_ROUTE_NONE;
    if (!api_path_grammar_ok(path, why, why_len))
        return API_ROUTE_BAD_PATH;
    if (strcmp(path, "/live/events") == 0)
        return API_ROUTE_EVENTS;
    if (strcmp(path, "/live/camera.jpg") == 0)
        return API_ROUTE_CAMERA;
    if (strcmp(path, "/live/prediction") == 0)
        return API_ROUTE_PREDICTION;
    if (strcmp(path, "/phase.png") == 0)
        return API_ROUTE_PHASE;
    if (strcmp(path, "/status") == 0)
        return API_ROUTE_STATUS;
    if (strcmp(path, "/trials") == 0)
        return API_ROUTE_TRIALS;
    if ((strcmp(path, "/specimens") == 0 || strncmp(path, "/specimens/", 11) == 0 || strcmp(path, "/queue") == 0 ||
         strncmp(path, "/queue/", 7) == 0 || strcmp(path, "/checks") == 0 || strcmp(path, "/campaign/phase") == 0 || strcmp(path, "/plan") == 0 ||
         strncmp(path, "/plan/", 6) == 0) && strlen(path) < API_CAMPAIGN_PATH_MAX)
        return API_ROUTE_CAMPAIGN;
    if (strncmp(path, "/rails/", 7) == 0 && strlen(path) < API_CAMPAIGN_PATH_MAX)
        return API_ROUTE_RAIL;
    if (strcmp(path, "/trials/current/abort") == 0)
        return API_ROUTE_ABORT;
    if (strncmp(path, prefix, sizeof prefix - 1) != 0)
        return API_ROUTE_NONE;

    const char *seg = path + sizeof prefix - 1;
    const char *slash = strchr(seg, '/');
    api_route r;
    size_t len;
    if (slash == NULL) {
        r = API_ROUTE_TRIAL;
        len = strlen(seg);
    } else if (strcmp(slash, report) == 0) {
        r = API_ROUTE_REPORT;
        len = (size_t)(slash - seg);
    } else if (strcmp(slash, samples) == 0) {
        r = API_ROUTE_SAMPLES_CSV;
        len = (size_t)(slash - seg);
    } else {
        return API_ROUTE_NONE;
    }
    int64_t v = 0;
    if (parse_id(seg, len, &v, why, why_len) != 0)
        return API_ROUTE_BAD_ID;
    if (id)
        *id = v;
    return r;
}

const char *api_route_allow(api_route r)
{
    switch (r) {
    case API_ROUTE_STATUS:
    case API_ROUTE_TRIAL:
    case API_ROUTE_REPORT:
    case API_ROUTE_SAMPLES_CSV:
    case API_ROUTE_EVENTS:
    case API_ROUTE_CAMERA:
    case API_ROUTE_PREDICTION:
    case API_ROUTE_PHASE:
        return "GET";
    case API_ROUTE_TRIALS:
    case API_ROUTE_CAMPAIGN:
        return "GET, POST";
    case API_ROUTE_ABORT:
    case API_ROUTE_RAIL:
        return "POST";
    case API_ROUTE_NONE:
    case API_ROUTE_BAD_ID:
    case API_ROUTE_BAD_PATH:
        break;
    }
    return NULL;
}

int api_route_method_ok(api_route r, const char *method)
{
    if (method == NULL)
        return 0;
    int get = strcmp(method, "GET") == 0;
    int post = strcmp(method, "POST") == 0;
    switch (r) {
    case API_ROUTE_STATUS:
    case API_ROUTE_TRIAL:
    case API_ROUTE_REPORT:
    case API_ROUTE_SAMPLES_CSV:
    case API_ROUTE_EVENTS:
    case API_ROUTE_CAMERA:
    case API_ROUTE_PREDICTION:
    case API_ROUTE_PHASE:
        return get;
    case API_ROUTE_TRIALS:
    case API_ROUTE_CAMPAIGN:
        return get || post;
    case API_ROUTE_ABORT:
    case API_ROUTE_RAIL:
        return post;
    case API_ROUTE_NONE:
    case API_ROUTE_BAD_ID:
    case API_ROUTE_BAD_PATH:
        break;
    }
    return 0;
}
