/* fuzz_api_headers.c: fuzz target for a whole HTTP request as a client sends it (request line,
 * headers, body), through everything the API's own code reads from it, without a socket
 * (daemon/api/api_head.c, the functions the guard and the server call):
 *   1. the guard's scan of the raw bytes (complete, 414, 431) and its sort into a pool;
 *   2. the head split into request line and header pairs as libmicrohttpd does (method up to the
 *      first space, the version from the back, the query cut at '?'; "Name: value" lines, the
 *      value's surrounding blanks dropped), then the server's checks (token, path, method, pool,
 *      Content-Length) with no token and with the token "s3cret-token";
 *   3. a POST /trials that passes, its body through the server's JSON parsing and the start
 *      body's checks in both modes (the rig loader on its overrides is fuzz_api_request's).
 * Checked beyond memory safety: the token rule against an independent reading of it (a request
 * passes the token check exactly when its first Authorization header is "Bearer" and the token),
 * every refusal has a status and a reason, a 405 an Allow value, and no request the guard sorted
 * ever reaches the wrong pool (500). Issue 33: empty lines before the request line are no
 * request (a head of blank lines only is never complete, and they are skipped before the split,
 * as libmicrohttpd skips them); no request with two Content-Length headers of different numbers
 * passes; an accepted "set" holds only keys a trial may change (fuzz_api_set.h). */
#include <jansson.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "api_head.h"
#include "api_server.h"
#include "api_start_body.h"
#include "fuzz_api_set.h"
#include "fuzz_inputs.h"

#define MAX_HEADERS 128
#define TOKEN "s3cret-token"
#define MAX_BODY (64 * 1024)

static void fail(const char *what)
{
    fuzz_fail("api_headers", what);
}

/* The request line as libmicrohttpd 0.9 parses it: method up to the first space, spaces
 * skipped, the version after the last space, the target in between, cut at '?'. */
static void split_line(char *line, const char **method, const char **url)
{
    char *sp = strchr(line, ' ');
    *method = line;
    if (!sp) {
        *url = "";
        return;
    }
    *sp = '\0';
    char *u = sp + 1;
    while (*u == ' ')
        u++;
    char *v = u + strlen(u);
    while (v > u && v[-1] != ' ')
        v--;
    if (v > u) /* "target version": the target ends at the last space */
        v[-1] = '\0';
    char *q = strchr(u, '?');
    if (q)
        *q = '\0';
    *url = u;
}

/* "Name: value" lines of head (the request line and the blank line excluded), in place. */
static size_t split_headers(char *text, api_header *h)
{
    size_t n = 0;
    char *p = text;
    while (*p && n < MAX_HEADERS) {
        char *eol = strchr(p, '\n');
        if (eol)
            *eol = '\0';
        size_t l = strlen(p);
        if (l > 0 && p[l - 1] == '\r')
            p[--l] = '\0';
        char *colon = strchr(p, ':');
        if (colon && colon > p) {
            *colon = '\0';
            char *v = colon + 1;
            while (*v == ' ' || *v == '\t')
                v++;
            char *e = v + strlen(v);
            while (e > v && (e[-1] == ' ' || e[-1] == '\t'))
                *--e = '\0';
            h[n++] = (api_header){.name = p, .value = v};
        }
        if (!eol)
            break;
        p = eol + 1;
    }
    return n;
}

/* The token rule read independently: the first Authorization header is "Bearer" (any case),
 * a space, then the token with spaces before it and blanks after it ignored. */
static bool token_ok(const api_header *h, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (strcasecmp(h[i].name, "authorization") != 0)
            continue;
        const char *v = h[i].value;
        if (strncasecmp(v, "bearer ", 7) != 0)
            return false;
        v += 7;
        while (*v == ' ')
            v++;
        size_t l = strlen(v);
        while (l > 0 && (v[l - 1] == ' ' || v[l - 1] == '\t'))
            l--;
        return l == strlen(TOKEN) && memcmp(v, TOKEN, l) == 0;
    }
    return false;
}

static void check_body(const char *body, size_t len)
{
    char why[512] = "";
    json_t *j = api_body_object(body, len, why, sizeof why);
    if (!j) {
        if (why[0] == '\0')
            fail("a refused body without a reason");
        return;
    }
    if (!json_is_object(j))
        fail("a body accepted that is not an object");
    for (int replay = 0; replay <= 1; replay++) {
        api_start_body b;
        why[0] = '\0';
        if (api_start_body_parse(j, replay, &b, why, sizeof why) != 0) {
            if (why[0] == '\0')
                fail("a refused start body without a reason");
            continue;
        }
        if (b.note && strlen(b.note) > API_START_NOTE_MAX)
            fail("a note over the limit");
        if (b.n_set < 0 || b.n_set > API_START_MAX_SET)
            fail("too many overrides kept");
        for (int k = 0; k < b.n_set; k++)
            fuzz_check_api_override("api_headers", b.set[k]);
    }
    json_decref(j);
}

/* Two Content-Length headers whose values are not the same number (digits only, else the same
 * text), read independently of api_head.c. */
static bool lengths_conflict(const api_header *h, size_t n)
{
    const char *first = NULL;
    for (size_t i = 0; i < n; i++) {
        if (strcasecmp(h[i].name, "content-length") != 0)
            continue;
        if (!first) {
            first = h[i].value;
            continue;
        }
        const char *a = first, *b = h[i].value;
        size_t da = strspn(a, "0123456789"), db = strspn(b, "0123456789");
        if (da == 0 || a[da] != '\0' || db == 0 || b[db] != '\0') { /* not both numbers */
            if (strcmp(a, b) != 0)
                return true;
            continue;
        }
        while (*a == '0' && a[1]) a++; /* the same number: the same digits past leading zeros */
        while (*b == '0' && b[1]) b++;
        if (strcmp(a, b) != 0)
            return true;
    }
    return false;
}

static void check_head(const api_head_sort *sort, const char *method, const char *url, const api_header *h,
                       size_t n, const char *body, size_t body_len)
{
    for (int with_token = 0; with_token <= 1; with_token++) {
        api_head_policy p = {.token = with_token ? TOKEN : "", .token_len = with_token ? strlen(TOKEN) : 0,
                             .max_body = MAX_BODY};
        api_head_verdict v;
        char why[512] = "";
        api_head_check(&p, sort->stream, method, url, h, n, &v, why, sizeof why);
        int s = v.status;
        if (s != 0 && s != 400 && s != 401 && s != 404 && s != 405 && s != 413)
            fail(s == 500 ? "a request the guard sorted reached the wrong pool" : "a status outside the API's");
        if (s != 0 && why[0] == '\0')
            fail("a refusal without a reason");
        if ((s == 405) != (v.allow != NULL))
            fail("a 405 without an Allow value, or an Allow value without a 405");
        if (!with_token && s == 401)
            fail("a 401 with no token configured");
        if (with_token && (s != 401) != token_ok(h, n))
            fail("the token check disagrees with the token rule");
        if (s == 413 && !api_header_find(h, n, "content-length"))
            fail("a 413 without a Content-Length");
        if (s == 0 && lengths_conflict(h, n))
            fail("a request with two Content-Length headers that disagree passed");
        if (s != 0)
            continue;
        if (v.route == API_ROUTE_NONE || v.route == API_ROUTE_BAD_ID || v.route == API_ROUTE_BAD_PATH)
            fail("a request passed without a route");
        if ((v.route == API_ROUTE_TRIAL || v.route == API_ROUTE_REPORT || v.route == API_ROUTE_SAMPLES_CSV) && v.id < 1)
            fail("an id route passed with id < 1");
        if (!api_route_method_ok(v.route, method))
            fail("a request passed with a method its route does not allow");
        if ((v.route == API_ROUTE_EVENTS) != sort->stream)
            fail("a request passed in the wrong pool");
        if (with_token && v.route == API_ROUTE_TRIALS && strcmp(method, "POST") == 0 && body_len <= MAX_BODY)
            check_body(body, body_len);
    }
}

int fuzz_api_headers_one(const uint8_t *data, size_t size)
{
    const char *raw = (const char *)data;
    size_t peek = size < API_HEAD_MAX + 1 ? size : API_HEAD_MAX + 1; /* what the guard peeks at */
    size_t end = 0;
    int scan = api_head_scan(raw, peek, API_LINE_MAX, API_HEAD_MAX, &end);
    if (scan != 0 && scan != 1 && scan != 414 && scan != 431)
        fail("a scan outcome outside its contract");
    if (scan != 1)
        return 0;
    if (end < 2 || end > peek || raw[end - 1] != '\n')
        fail("a head that does not end with its blank line");
    size_t start = 0; /* empty lines before the request line, read independently */
    while (start < end && (raw[start] == '\n' || (raw[start] == '\r' && start + 1 < end && raw[start + 1] == '\n')))
        start += raw[start] == '\n' ? 1 : 2;
    if (start >= end || raw[start] == '\n')
        fail("a head of empty lines only taken as complete");
    api_head_sort sort;
    api_head_sort_raw(raw, end, &sort);
    if (sort.stream && (strcmp(sort.method, "GET") != 0 || strcmp(sort.path, "/live/events") != 0))
        fail("the stream pool for a request that is not GET /live/events");
    if (sort.stream && sort.control)
        fail("a request sorted into both pools");

    char *text = malloc(end + 1);
    if (!text)
        return 0;
    memcpy(text, raw + start, end - start); /* the empty lines skipped, as libmicrohttpd does */
    text[end - start] = '\0'; /* a NUL inside the head ends it here, as a C string */
    char *eol = strchr(text, '\n');
    char *rest = "";
    if (eol) {
        *eol = '\0';
        rest = eol + 1;
    }
    size_t l = strlen(text);
    if (l > 0 && text[l - 1] == '\r')
        text[l - 1] = '\0';
    const char *method, *url;
    split_line(text, &method, &url);
    api_header h[MAX_HEADERS];
    size_t n = split_headers(rest, h);
    check_head(&sort, method, url, h, n, raw + end, size - end);
    free(text);
    return 0;
}

FUZZ_ENTRY(fuzz_api_headers_one)
