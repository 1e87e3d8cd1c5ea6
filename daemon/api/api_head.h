/* api_head.h: everything the API's own code reads from a request's head (request line and
 * headers) and body, as plain functions of bytes and strings with no socket and no libmicrohttpd,
 * so that the server (api_guard.c, api_server.c) and the fuzz target (fuzz/fuzz_api_headers.c)
 * run the same code.
 *
 * Two places read a head. The guard reads the raw bytes as they arrive (api_head_scan: complete,
 * or 414/431) and sorts a complete head into a pool (api_head_sort). libmicrohttpd then parses
 * it, and the server checks the parsed request line and header pairs before any body is read
 * (api_head_check: token 401, path 400/404, method 405, pool 500, Content-Length 413); once the
 * body is in, api_body_object parses it. */
#ifndef RIBBON_DAEMON_API_HEAD_H
#define RIBBON_DAEMON_API_HEAD_H

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "api_route.h"

/* What the raw bytes buf[0..len) that have arrived so far say, against the limits: 0 (not
 * complete: wait for more), 414 (no end of the request line within line_max + 1 bytes), 431 (no
 * blank line within head_max bytes), or 1 with *end the index just past the blank line ("\n\n" or
 * "\n\r\n") that ends the head. Empty lines before the request line are skipped (RFC 9112, 2.2):
 * they neither start nor end a head, so blank lines alone are never complete. */
int api_head_scan(const char *buf, size_t len, size_t line_max, size_t head_max, size_t *end);

/* Where a complete head (head[0..len), up to and including its blank line, empty lines before
 * its request line skipped) goes. */
typedef struct api_head_sort {
    char method[16];  /* the request line's method, cut to 15 bytes */
    char path[64];    /* its target up to '?', cut to 63 bytes */
    bool stream;      /* GET /live/events: the stream pool */
    bool control;     /* bodiless GET /status or POST /trials/current/abort (no Content-Length other
                         than 0, no Transfer-Encoding): may use the reserved control slots */
} api_head_sort;

void api_head_sort_raw(const char *head, size_t len, api_head_sort *out);

/* One request header as libmicrohttpd parsed it (value NULL is read as ""). */
typedef struct api_header {
    const char *name;
    const char *value;
} api_header;

/* The value of the first header named name (case-insensitive), or NULL. */
const char *api_header_find(const api_header *h, size_t n, const char *name);

/* The server's settings that the checks of a head depend on. */
typedef struct api_head_policy {
    const char *token;  /* token_len bytes; token_len 0: no token required */
    size_t token_len;
    size_t max_body;    /* bytes */
} api_head_policy;

/* The outcome of api_head_check. */
typedef struct api_head_verdict {
    int status;         /* 0: go on (read the body, then dispatch); else the HTTP status to answer
                           with the reason in why: 400, 401, 404, 405, 413 or 500 */
    api_route route;
    int64_t id;         /* for the {id} routes */
    const char *allow;  /* the Allow header of a 405 (static), else NULL */
} api_head_verdict;

/* The checks that need no body, in the server's order: token (when p->token_len > 0, the
 * request needs "Authorization: Bearer TOKEN"; "Bearer" in any case, spaces around the token
 * ignored), path grammar and route, method, pool (stream_pool: the request came through the
 * stream pool, which only GET /live/events may), two Content-Length headers that disagree (400),
 * Content-Length over p->max_body. url is the
 * path without its query; method, url and the headers are NUL-terminated strings. */
void api_head_check(const api_head_policy *p, bool stream_pool, const char *method, const char *url,
                    const api_header *h, size_t n, api_head_verdict *v, char *why, size_t why_len);

/* The body body[0..len) as a JSON object: {} when empty or blank. NULL with a reason in why when
 * it is malformed JSON (line and column) or not an object. */
json_t *api_body_object(const char *body, size_t len, char *why, size_t why_len);

/* The longest token (api_server_config's token) and the token comparison: true when
 * given[0..glen) equals want[0..wlen). Its running time depends on neither length nor content
 * (always API_TOKEN_MAX + 1 bytes compared). */
#define API_TOKEN_MAX 256
bool api_token_equal(const char *given, size_t glen, const char *want, size_t wlen);

#endif
