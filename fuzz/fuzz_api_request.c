/* fuzz_api_request.c: fuzz target for what an API client sends, without a socket: the request
 * line "METHOD PATH" (the first line of the input) through the real router (api_route.c: route,
 * id, allowed methods), and the rest of the input as the body the server would parse (JSON, with
 * the server's flags) and POST /trials's checks of it in both modes (api_start_body.c); a body
 * that passes, with overrides, then goes through the real rig loader as ribbond would load it
 * (the shipped config/mock.ini), each of its overrides first checked to be of a key a trial may
 * change (fuzz_api_set.h: no path, API, rail limit or twin key gets through, issue 33). The
 * server's HTTP framing and headers are libmicrohttpd's. */
#include <jansson.h>
#include <stdlib.h>
#include <string.h>

#include "api_route.h"
#include "api_start_body.h"
#include "fuzz_api_set.h"
#include "fuzz_config.h"
#include "fuzz_inputs.h"

static void route(const char *line)
{
    const char *sp = strchr(line, ' ');
    char method[16] = "GET";
    const char *path = line;
    if (sp && (size_t)(sp - line) < sizeof method) {
        memcpy(method, line, (size_t)(sp - line));
        method[sp - line] = '\0';
        path = sp + 1;
    }
    int64_t id = -1;
    char why[256] = "";
    api_route r = api_route_parse(path, &id, why, sizeof why);
    if ((int)r < API_ROUTE_NONE || r > API_ROUTE_BAD_PATH) fuzz_fail("api_request", "a route out of its enum");
    if ((r == API_ROUTE_TRIAL || r == API_ROUTE_REPORT || r == API_ROUTE_SAMPLES_CSV) && id < 1)
        fuzz_fail("api_request", "an id route with id < 1");
    if (r == API_ROUTE_BAD_ID && why[0] == '\0') fuzz_fail("api_request", "a bad id without a reason");
    const char *allow = api_route_allow(r);
    int ok = api_route_method_ok(r, method);
    if ((r == API_ROUTE_NONE || r == API_ROUTE_BAD_ID) && (allow || ok))
        fuzz_fail("api_request", "a method allowed on no route");
    if (ok && (!allow || !strstr(allow, method))) fuzz_fail("api_request", "a method allowed but not in Allow");
}

int fuzz_api_request_one(const uint8_t *data, size_t size)
{
    const uint8_t *nl = memchr(data, '\n', size);
    size_t line_len = nl ? (size_t)(nl - data) : size;
    char *line = malloc(line_len + 1);
    if (!line) return 0;
    memcpy(line, data, line_len);
    line[line_len] = '\0'; /* a NUL inside the path ends it, as it would in libmicrohttpd's URL */
    route(line);
    free(line);
    if (!nl) return 0;
    const char *body = (const char *)nl + 1;
    size_t body_len = size - line_len - 1;
    json_error_t je;
    json_t *j = json_loadb(body, body_len, JSON_REJECT_DUPLICATES, &je);
    if (!j) return 0;
    char why[512];
    api_start_body b;
    for (int replay = 0; replay <= 1; replay++) {
        why[0] = '\0';
        if (api_start_body_parse(j, replay, &b, why, sizeof why) != 0) {
            if (why[0] == '\0') fuzz_fail("api_request", "a refused body without a reason");
            continue;
        }
        if (b.note && strlen(b.note) > API_START_NOTE_MAX) fuzz_fail("api_request", "a note over the limit");
        if (b.n_set < 0 || b.n_set > API_START_MAX_SET) fuzz_fail("api_request", "too many overrides kept");
        if (!replay && b.n_set > 0) {
            for (int k = 0; k < b.n_set; k++) fuzz_check_api_override("api_request", b.set[k]);
            size_t len;
            const char *rig = fuzz_shipped_text("config/mock.ini", &len);
            fuzz_rig_text("api_request", rig, len, b.set, b.n_set);
        }
    }
    json_decref(j);
    return 0;
}

FUZZ_ENTRY(fuzz_api_request_one)
