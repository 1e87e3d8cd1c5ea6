/* api_head.c: reading a request's head and body without a socket (see api_head.h): the guard's
 * scan and sort of the raw bytes, the server's checks of the parsed request line and headers,
 * the body's JSON, and the constant-time token comparison. */
#include "api_head.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* ---------------------------------------------------------------- raw bytes (the guard) */

/* How many bytes of buf[0..len) are whole empty lines ("\r\n" or "\n") before the request line.
 * They are no request (RFC 9112, 2.2: a server ignores them), so a head of blank lines only is
 * never complete: such a connection waits in the guard until its header timeout, never in a pool
 * (issue 33, item 6). */
static size_t blank_lines(const char *buf, size_t len)
{
    size_t i = 0;
    for (;;) {
        if (i < len && buf[i] == '\n')
            i += 1;
        else if (i + 1 < len && buf[i] == '\r' && buf[i + 1] == '\n')
            i += 2;
        else
            return i;
    }
}

/* Where the headers end in buf[0..len): index past the blank line that follows the request line
 * (which starts at `start`, after the leading empty lines), or 0. */
static size_t head_end(const char *buf, size_t len, size_t start)
{
    for (size_t i = start; i + 1 < len; i++) {
        if (buf[i] != '\n')
            continue;
        if (buf[i + 1] == '\n')
            return i + 2;
        if (buf[i + 1] == '\r' && i + 2 < len && buf[i + 2] == '\n')
            return i + 3;
    }
    return 0;
}

int api_head_scan(const char *buf, size_t len, size_t line_max, size_t head_max, size_t *end)
{
    size_t start = blank_lines(buf, len);
    *end = head_end(buf, len, start);
    size_t rest = len - start;
    size_t look = rest < line_max + 2 ? rest : line_max + 2;
    const char *nl = memchr(buf + start, '\n', look);
    if (nl && (size_t)(nl - (buf + start)) > line_max + 1)
        nl = NULL;
    if (!nl && rest > line_max + 1)
        return 414;
    if (*end == 0)
        return len > head_max ? 431 : 0;
    return 1;
}

/* The request line "METHOD SP target SP version" of head: method and path (up to '?') copied,
 * bounded. */
static void request_line(const char *head, size_t len, char *method, size_t mcap, char *path, size_t pcap)
{
    size_t i = 0, k = 0;
    while (i < len && head[i] != ' ' && head[i] != '\r' && head[i] != '\n') {
        if (k + 1 < mcap)
            method[k++] = head[i];
        i++;
    }
    method[k] = '\0';
    while (i < len && head[i] == ' ')
        i++;
    k = 0;
    while (i < len && head[i] != ' ' && head[i] != '?' && head[i] != '\r' && head[i] != '\n') {
        if (k + 1 < pcap)
            path[k++] = head[i];
        i++;
    }
    path[k] = '\0';
}

/* true when head[0..len) has a header of that name (case-insensitive) at the start of a line;
 * "Content-Length: 0" does not count as a Content-Length (it is no body). Every read stays
 * below len. */
static bool has_header(const char *head, size_t len, const char *name)
{
    size_t nl = strlen(name);
    for (size_t i = 0; i + 1 < len; i++) {
        if (head[i] != '\n')
            continue;
        if (i + 1 + nl < len && strncasecmp(head + i + 1, name, nl) == 0 && head[i + 1 + nl] == ':') {
            if (strcasecmp(name, "content-length") == 0) {
                size_t v = i + 2 + nl;
                while (v < len && (head[v] == ' ' || head[v] == '\t'))
                    v++;
                if (v + 1 < len && head[v] == '0' && (head[v + 1] == '\r' || head[v + 1] == '\n'))
                    continue;
            }
            return true;
        }
    }
    return false;
}

void api_head_sort_raw(const char *head, size_t len, api_head_sort *out)
{
    size_t start = blank_lines(head, len); /* as api_head_scan: the request line follows them */
    request_line(head + start, len - start, out->method, sizeof out->method, out->path, sizeof out->path);
    bool get = strcmp(out->method, "GET") == 0, post = strcmp(out->method, "POST") == 0;
    out->stream = get && strcmp(out->path, "/live/events") == 0;
    out->control = ((get && strcmp(out->path, "/status") == 0) ||
                    (post && strcmp(out->path, "/trials/current/abort") == 0)) &&
                   !has_header(head, len, "content-length") && !has_header(head, len, "transfer-encoding");
}

/* ---------------------------------------------------------------- parsed head (the server) */

const char *api_header_find(const api_header *h, size_t n, const char *name)
{
    for (size_t i = 0; i < n; i++)
        if (h[i].name != NULL && strcasecmp(h[i].name, name) == 0)
            return h[i].value ? h[i].value : "";
    return NULL;
}

/* Constant-time comparison: the loop always runs over API_TOKEN_MAX + 1 bytes, whatever either
 * length is, so the time taken tells neither how many leading bytes were right nor how long the
 * token is. Bytes past a string's end compare as 0 (read from a zeroed copy, never out of bounds);
 * the lengths are compared too, so a prefix of the token never matches. */
bool api_token_equal(const char *given, size_t glen, const char *want, size_t wlen)
{
    unsigned char a[API_TOKEN_MAX + 1] = {0}, b[API_TOKEN_MAX + 1] = {0};
    volatile unsigned char diff = 0;
    if (glen > API_TOKEN_MAX) { /* longer than any token: still compared over the same bytes */
        glen = API_TOKEN_MAX + 1;
        diff = 1;
    }
    if (wlen > API_TOKEN_MAX) {
        wlen = API_TOKEN_MAX + 1;
        diff = 1;
    }
    memcpy(a, given, glen > API_TOKEN_MAX ? API_TOKEN_MAX : glen);
    memcpy(b, want, wlen > API_TOKEN_MAX ? API_TOKEN_MAX : wlen);
    size_t lx = glen ^ wlen;
    for (size_t i = 0; i < API_TOKEN_MAX + 1; i++)
        diff |= (unsigned char)(a[i] ^ b[i]);
    for (size_t k = 0; k < sizeof lx; k++)
        diff |= (unsigned char)(lx >> (8 * k));
    return diff == 0;
}

/* 0 when the headers carry the right bearer token (or none is required), else -1 and a reason. */
static int check_token(const api_head_policy *p, const api_header *h, size_t n, char *why, size_t why_len)
{
    if (p->token_len == 0)
        return 0;
    const char *a = api_header_find(h, n, "Authorization");
    if (a == NULL) {
        snprintf(why, why_len, "this daemon requires a token: send \"Authorization: Bearer TOKEN\" "
                               "(the token is [api] token in the rig file)");
        return -1;
    }
    if (strncasecmp(a, "Bearer ", 7) != 0) {
        snprintf(why, why_len, "Authorization header must be \"Bearer TOKEN\"");
        return -1;
    }
    const char *t = a + 7;
    while (*t == ' ')
        t++;
    size_t len = strlen(t);
    while (len > 0 && (t[len - 1] == ' ' || t[len - 1] == '\t'))
        len--;
    if (!api_token_equal(t, len, p->token, p->token_len)) {
        snprintf(why, why_len, "wrong token");
        return -1;
    }
    return 0;
}

/* A Content-Length value as a number: decimal digits only (libmicrohttpd has trimmed the blanks
 * around it). 0 and *out, or -1 when it is not such a number or too large. */
static int length_value(const char *text, unsigned long long *out)
{
    unsigned long long v = 0;
    if (*text == '\0')
        return -1;
    for (const char *c = text; *c; c++) {
        if (*c < '0' || *c > '9' || v > (ULLONG_MAX - 9) / 10)
            return -1;
        v = 10 * v + (unsigned long long)(*c - '0');
    }
    *out = v;
    return 0;
}

/* 1 with a reason when two Content-Length headers disagree (issue 33, item 8: the first used to
 * win, and a body framed by one length was read by another). Two that give the same number are
 * one length (RFC 9110, 8.6); two that are not both numbers disagree unless they are the same
 * text. */
static int conflicting_lengths(const api_header *h, size_t n, char *why, size_t why_len)
{
    const char *first = NULL;
    for (size_t i = 0; i < n; i++) {
        if (h[i].name == NULL || strcasecmp(h[i].name, "Content-Length") != 0)
            continue;
        const char *val = h[i].value ? h[i].value : "";
        if (first == NULL) {
            first = val;
            continue;
        }
        unsigned long long a, b;
        bool same = (length_value(first, &a) == 0 && length_value(val, &b) == 0) ? a == b : strcmp(first, val) == 0;
        if (!same) {
            snprintf(why, why_len, "two Content-Length headers that disagree (%.24s and %.24s): a request has one length",
                     first, val);
            return 1;
        }
    }
    return 0;
}

void api_head_check(const api_head_policy *p, bool stream_pool, const char *method, const char *url,
                    const api_header *h, size_t n, api_head_verdict *v, char *why, size_t why_len)
{
    v->status = 0;
    v->route = API_ROUTE_NONE;
    v->id = 0;
    v->allow = NULL;
    if (check_token(p, h, n, why, why_len) != 0) {
        v->status = 401;
        return;
    }
    v->route = api_route_parse(url, &v->id, why, why_len);
    if (v->route == API_ROUTE_BAD_PATH || v->route == API_ROUTE_BAD_ID) {
        v->status = 400;
        return;
    }
    if (v->route == API_ROUTE_NONE) {
        v->status = 404;
        snprintf(why, why_len,
                 "no such path: %.200s (paths: /status, /trials, /trials/current/abort, /trials/ID, "
                 "/trials/ID/report.png, /trials/ID/samples.csv, /phase.png, /live/events, "
                 "/live/camera.jpg, /live/prediction)",
                 url);
        return;
    }
    if (!api_route_method_ok(v->route, method)) {
        v->allow = api_route_allow(v->route);
        v->status = 405;
        snprintf(why, why_len, "method %.20s not allowed on %.200s (allowed: %s)", method, url, v->allow);
        return;
    }
    if ((v->route == API_ROUTE_EVENTS) != stream_pool) { /* the guard sorts by the same path */
        v->status = 500;
        snprintf(why, why_len, "internal error: request reached the wrong connection pool");
        return;
    }
    if (conflicting_lengths(h, n, why, why_len)) {
        v->status = 400;
        return;
    }
    const char *cl = api_header_find(h, n, "Content-Length");
    if (cl != NULL) {
        char *end = NULL;
        errno = 0;
        unsigned long long len = strtoull(cl, &end, 10);
        if (end != cl && errno == 0 && len > p->max_body) {
            v->status = 413;
            snprintf(why, why_len, "request body of %llu bytes is larger than the limit of %zu bytes", len,
                     p->max_body);
            return;
        }
    }
}

/* ---------------------------------------------------------------- body */

json_t *api_body_object(const char *body, size_t len, char *why, size_t why_len)
{
    size_t i = 0;
    while (i < len && (body[i] == ' ' || body[i] == '\t' || body[i] == '\r' || body[i] == '\n'))
        i++;
    if (i == len)
        return json_object();
    json_error_t err;
    json_t *j = json_loadb(body, len, JSON_REJECT_DUPLICATES, &err);
    if (j == NULL) {
        snprintf(why, why_len, "malformed JSON body at line %d, column %d: %s", err.line, err.column, err.text);
        return NULL;
    }
    if (!json_is_object(j)) {
        static const char *const names[] = {"an object", "an array", "a string", "a number", "a number",
                                            "true", "false", "null"};
        int t = (int)json_typeof(j);
        snprintf(why, why_len, "request body must be a JSON object, got %s",
                 t >= 0 && t < (int)(sizeof names / sizeof names[0]) ? names[t] : "something else");
        json_decref(j);
        return NULL;
    }
    return j;
}
