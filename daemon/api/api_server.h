/* api_server.h: ribbond's control API, HTTP+JSON served with libmicrohttpd.
 *
 * This layer owns HTTP only: listening, the bearer token, body size, routing, JSON parsing and
 * error replies. It knows nothing of trials: each route calls one callback of an api_ops table
 * that the trial runner fills in, and turns what the callback returns into a reply.
 *
 *   route                          op                         success      op-chosen errors
 *   GET  /status                   status                     200 object   500
 *   POST /trials                   start(body)                201 object   400 bad field, 409 running
 *   POST /trials/current/abort     abort_current              200 object   409 nothing runs
 *   GET  /trials                   list                       200 array    500
 *   GET  /trials/{id}              show(id)                   200 object   404 no such trial
 *   GET  /trials/{id}/report.png   report_png(id)             200 PNG      404, 500
 *
 * Errors found by the server itself: 400 ({id} not a positive integer, malformed JSON body with
 * line and column, body not an object), 401 (token missing or wrong), 404 (unknown path),
 * 405 (known path, wrong method; the reply carries an Allow header), 413 (body larger than
 * max_body_bytes), 500 (an op broke its contract), 501 (op left NULL). Every error reply is
 * application/json: {"error": "human message", "status": N}.
 *
 * THREADING CONTRACT. The server runs libmicrohttpd's internal polling thread (one thread for
 * every connection). Every op is called from that thread, one at a time: two ops never run
 * concurrently, and no op ever runs on the thread that called api_server_start. An op shares
 * the runner's state with the runner's own thread, so it takes the runner's mutex, copies what it
 * needs into JSON, releases the mutex and returns; it must not block for long (a slow op stalls
 * every other API client, not the rails). api_server_stop() joins the polling thread and so waits
 * for an op in progress: never call it while holding a lock that an op takes, and never from
 * inside an op.
 *
 * OWNERSHIP. On success an op stores a new JSON reference in *out (or malloc'ed PNG bytes in
 * *png); the server takes it and frees it (json_decref / free). On failure an op returns -1,
 * writes a human reason into why (n bytes, NUL-terminated) and an HTTP status in 400..599 into
 * *http_status (anything else becomes 500); *out is then ignored (and released if set).
 * *http_status arrives preset to the success status (200, 201 for start); an op may change it to
 * another 2xx on success.
 */
#ifndef RIBBON_DAEMON_API_SERVER_H
#define RIBBON_DAEMON_API_SERVER_H

#include <jansson.h>
#include <stddef.h>
#include <stdint.h>

/* Creation parameters. Start from api_server_config_default() and change what you mean to. */
typedef struct api_server_config {
    const char *listen;          /* numeric address to bind: IPv4 dotted ("127.0.0.1", "0.0.0.0")
                                    or IPv6 ("::1", "::"); NULL means 127.0.0.1. Copied. */
    unsigned port;               /* TCP port 1..65535, or 0 = let the kernel pick a free one
                                    (api_server_port() tells which) */
    const char *token;           /* bearer token; NULL or "" = none. Required (start refuses
                                    without it) when listen is not a loopback address. When set,
                                    every request needs "Authorization: Bearer TOKEN". Visible
                                    ASCII only, at most 256 characters. Copied. */
    size_t max_body_bytes;       /* largest accepted request body, bytes (1 KiB .. 16 MiB);
                                    larger gets 413. Default 64 KiB. */
    unsigned connection_timeout_s; /* idle connection closed after this many seconds (1..3600);
                                    default 30 */
    unsigned max_connections;    /* simultaneous connections (1..1000); default 64 */
} api_server_config;

api_server_config api_server_config_default(void);

/* The callback table. user is the pointer given to api_server_start. Any op may be NULL: its
 * route then answers 501. See the file comment for threading and ownership. Return 0 on success,
 * -1 on failure. */
typedef struct api_ops {
    /* GET /status: the daemon's state (mode, runner state, current trial, rails, ...). */
    int (*status)(void *user, json_t **out, char *why, size_t n);
    /* POST /trials: start a trial. body is always a JSON object ({} when the request had no
     * body), e.g. {"scene": "...", "set": ["protocol.compression=0.4"], "note": "..."}; the op
     * validates the fields (400 naming the field), refuses with 409 while a trial runs, and on
     * success returns the created trial (status preset to 201). */
    int (*start)(void *user, const json_t *body, json_t **out, int *http_status, char *why, size_t n);
    /* POST /trials/current/abort: abort the running trial; 409 when nothing runs. */
    int (*abort_current)(void *user, json_t **out, int *http_status, char *why, size_t n);
    /* GET /trials: a JSON array of trial summaries. */
    int (*list)(void *user, json_t **out, char *why, size_t n);
    /* GET /trials/{id}: one trial (id >= 1, already checked); 404 when it does not exist. */
    int (*show)(void *user, int64_t id, json_t **out, int *http_status, char *why, size_t n);
    /* GET /trials/{id}/report.png: the report image as PNG bytes, malloc'ed (the server calls
     * free()); *len > 0. 404 when the trial does not exist. */
    int (*report_png)(void *user, int64_t id, unsigned char **png, size_t *len, int *http_status,
                      char *why, size_t n);
} api_ops;

typedef struct api_server api_server;

/* Bind, listen and start the polling thread. ops is copied; user is passed to every op and must
 * outlive the server. Returns 0 and *out, or -1 with a reason in why (bad config, address in
 * use, non-loopback without a token, ...). */
int api_server_start(const api_server_config *cfg, const api_ops *ops, void *user, api_server **out,
                     char *why, size_t n);

/* The TCP port actually bound (useful with port 0). */
unsigned api_server_port(const api_server *s);

/* Stop accepting, close every connection, join the polling thread (waits for an op in
 * progress: see the threading contract), free. NULL is a no-op. */
void api_server_stop(api_server *s);

#endif
