/* api_route.h: the control API's route table (paths and methods), kept apart from the HTTP
 * server so it can be tested, fuzzed and printed on its own. See api_server.h for what each route
 * does. Paths are matched exactly (no trailing slash, no query string: libmicrohttpd strips it). */
#ifndef RIBBON_DAEMON_API_ROUTE_H
#define RIBBON_DAEMON_API_ROUTE_H

#include <stddef.h>
#include <stdint.h>

typedef enum api_route {
    API_ROUTE_NONE = 0, /* no such path: 404 */
    API_ROUTE_BAD_ID,   /* /trials/{id}[/report.png|/samples.csv] with a bad id: 400 */
    API_ROUTE_STATUS,   /* /status                   GET */
    API_ROUTE_TRIALS,   /* /trials                   GET (list), POST (start) */
    API_ROUTE_ABORT,    /* /trials/current/abort     POST */
    API_ROUTE_TRIAL,    /* /trials/{id}              GET */
    API_ROUTE_REPORT,   /* /trials/{id}/report.png   GET */
    API_ROUTE_SAMPLES_CSV, /* /trials/{id}/samples.csv GET */
    API_ROUTE_EVENTS,   /* /live/events              GET (the stream pool) */
    API_ROUTE_CAMERA,   /* /live/camera.jpg          GET */
    API_ROUTE_PREDICTION, /* /live/prediction        GET */
    API_ROUTE_PHASE,    /* /phase.png                GET */
    API_ROUTE_CAMPAIGN, /* /specimens[/...], /queue[/...], /checks  GET, POST (the campaign op sorts
                           them; a path of at most API_CAMPAIGN_PATH_MAX - 1 bytes) */
    API_ROUTE_RAIL,     /* /rails/{name}/home, /rails/{name}/confirm-zero  POST (the op parses the
                           name and the action; a path of at most API_CAMPAIGN_PATH_MAX - 1 bytes) */
    API_ROUTE_BAD_PATH, /* a byte outside the grammar (or not starting with '/'): 400 (keep last:
                           the fuzz target checks routes against it) */
} api_route;

#define API_CAMPAIGN_PATH_MAX 160 /* bytes of a campaign path, with its NUL */

/* 1 when path is made only of the bytes the routes use, [A-Za-z0-9._/-], and starts with '/';
 * else 0 with the offending byte and its offset in why. libmicrohttpd is told not to decode
 * percent-escapes, so "%00" or "%2F" arrive as they were sent and are refused here. */
int api_path_grammar_ok(const char *path, char *why, size_t why_len);

/* Parse a request path (API_ROUTE_BAD_PATH when api_path_grammar_ok refuses it). For {id} routes *id gets the id (1 .. INT64_MAX, decimal digits only);
 * a path of an {id} route whose id is not that gives API_ROUTE_BAD_ID and a reason in why. */
api_route api_route_parse(const char *path, int64_t *id, char *why, size_t why_len);

/* Methods allowed on a route, as an Allow header value ("GET", "GET, POST", "POST"); NULL for
 * API_ROUTE_NONE and API_ROUTE_BAD_ID. */
const char *api_route_allow(api_route r);

/* 1 when method (exact, case-sensitive as HTTP says) is allowed on r, else 0. */
int api_route_method_ok(api_route r, const char *method);

#endif
