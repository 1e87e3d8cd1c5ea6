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
 *   GET  /trials/{id}/samples.csv  samples_csv(id)            200 CSV      404, 500
 *   GET  /phase.png                phase_png                  200 PNG      500
 *   GET  /live/events              events                     200 text/event-stream (never ends)
 *   GET  /live/camera.jpg          camera_jpeg                200 JPEG     404 no frame yet
 *   GET  /live/prediction          prediction                 200 object   404 none yet
 *   GET, POST /specimens[/...], /queue[/...], /checks  campaign(method, path, body)  200/201  400 404 405 409 503
 *   POST /rails/{name}/home, /rails/{name}/confirm-zero  rail(path, body)  200/202  400 404 409
 *   GET  any path of cfg.assets    (served by the server)     200 the asset, no token needed
 *
 * The live routes feed the live page (docs/live-page.md); the assets are the page itself (HTML,
 * CSS, JavaScript: no data, no power), served without the token so the page can ask for it.
 *
 * CONNECTIONS. The server accepts every connection itself (api_guard.h) and hands it to
 * libmicrohttpd only once its request headers are complete (header_timeout_ms after the accept at
 * most, else 408), into one of two pools: GET /live/events to the stream pool (one thread per
 * stream, at most max_streams, else 503), everything else to the control pool (max_connections,
 * else 503). The control pool keeps RESERVED_CONTROL more slots for bodiless GET /status and
 * POST /trials/current/abort, so that stopping a trial never waits for a free slot. Control
 * replies close their connection (no keep-alive), and a request body must be complete within
 * body_timeout_ms of its headers (else 408, whether or not data still arrives), so a control
 * slot is held for one request's time only. A request line
 * over API_LINE_MAX bytes gets 414, a head over API_HEAD_MAX bytes 431, as JSON.
 *
 * Errors found by the server itself: 400 (a path byte outside the routes' grammar [A-Za-z0-9._/-]:
 * percent-escapes are not decoded, so "%00" is refused, never truncates; {id} not a positive integer, malformed JSON body with
 * line and column, body not an object, two Content-Length headers that disagree), 401 (token
 * missing or wrong), 404 (unknown path),
 * 405 (known path, wrong method; the reply carries an Allow header), 408 (head or body late), 413 (body larger than
 * max_body_bytes), 500 (an op broke its contract), 501 (op left NULL). Every error reply is
 * application/json: {"error": "human message", "status": N}.
 *
 * THREADING CONTRACT. The server runs libmicrohttpd's internal polling thread (one thread for
 * every control connection). Every op but events is called from that thread, one at a time: two ops never run
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
 * another 2xx on success. An op's 503 (busy with something that ends soon) is sent with
 * Retry-After: 1.
 */
#ifndef RIBBON_DAEMON_API_SERVER_H
#define RIBBON_DAEMON_API_SERVER_H

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define API_LINE_MAX 8192          /* request line, bytes: longer is 414 */
#define API_HEAD_MAX 16384         /* request line and headers, bytes: longer is 431 */
#define API_BODY_TIMEOUT_MS 10000  /* from the headers to the end of the body: the default of
                                      api_server_config's body_timeout_ms */
#define API_RESERVED_CONTROL 8     /* control slots only bodiless /status and abort may use */

/* A file of the page, served as is to GET path (no token). data is borrowed: it must outlive
 * the server. */
typedef struct api_asset {
    const char *path;            /* "/", "/live.js", ... (in the routes' grammar) */
    const char *content_type;
    const unsigned char *data;
    size_t len;
} api_asset;

/* A reply that does not end by itself (an event stream). The server calls read from the stream's
 * own thread whenever it can send more: read writes up to max bytes into buf and returns how many
 * (> 0; it may wait, but at most about a second, and then return a keep-alive), or -1 to end the
 * stream. close is called once when the stream ends for any reason (client gone, shutdown). */
typedef struct api_stream {
    long (*read)(void *ctx, char *buf, size_t max);
    void (*close)(void *ctx);
    void *ctx;
} api_stream;

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
    unsigned max_connections;    /* simultaneous control connections (1..1000), besides the
                                    reserved ones and the streams; default 64 */
    unsigned max_streams;        /* simultaneous event streams (1..256); default 32 */
    unsigned header_timeout_ms;  /* accept to complete headers (100..60000); default 5000 */
    unsigned pending_max;        /* connections waiting for their headers (16..4096); the oldest
                                    is closed when a new one comes and this many wait; default 256 */
    unsigned body_timeout_ms;    /* from the end of the headers to the end of the body
                                    (1000..60000, whole seconds count: libmicrohttpd's timer is in
                                    seconds); later is 408; default API_BODY_TIMEOUT_MS */
    const api_asset *assets;     /* the page's files (array copied, data borrowed); may be NULL */
    size_t n_assets;
} api_server_config;

api_server_config api_server_config_default(void);

/* The callback table. user is the pointer given to api_server_start. Any op may be NULL: its
 * route then answers 501. See the file comment for threading and ownership. Return 0 on success,
 * -1 on failure. */
typedef struct api_ops {
    /* GET /status: the daemon's state (mode, runner state, current trial, rails, ...). */
    int (*status)(void *user, json_t **out, char *why, size_t why_len);
    /* POST /trials: start a trial. body is always a JSON object ({} when the request had no
     * body), e.g. {"scene": "...", "set": ["protocol.compression=0.4"], "note": "..."}; the op
     * validates the fields (400 naming the field), refuses with 409 while a trial runs, and on
     * success returns the created trial (status preset to 201). */
    int (*start)(void *user, const json_t *body, json_t **out, int *http_status, char *why, size_t why_len);
    /* POST /trials/current/abort: abort the running trial; 409 when nothing runs. */
    int (*abort_current)(void *user, json_t **out, int *http_status, char *why, size_t why_len);
    /* GET /trials: a JSON array of trial summaries. */
    int (*list)(void *user, json_t **out, char *why, size_t why_len);
    /* GET /trials/{id}: one trial (id >= 1, already checked); 404 when it does not exist. */
    int (*show)(void *user, int64_t id, json_t **out, int *http_status, char *why, size_t why_len);
    /* GET /trials/{id}/report.png: the report image as PNG bytes, malloc'ed (the server calls
     * free()); *len > 0. 404 when the trial does not exist. */
    int (*report_png)(void *user, int64_t id, unsigned char **png, size_t *len, int *http_status,
                      char *why, size_t why_len);
    /* GET /trials/{id}/samples.csv: the trial's samples as CSV (the text `ribbonctl export ID --csv`
     * writes), malloc'ed (the server calls free()); *len > 0. 404 when the trial does not exist.
     * Sent as text/csv with Content-Disposition naming trial-ID-samples.csv. */
    int (*samples_csv)(void *user, int64_t id, char **csv, size_t *len, int *http_status, char *why,
                       size_t why_len);
    /* GET /phase.png: the phase report (every trial's measured regime on the predicted map) as PNG
     * bytes, malloc'ed. map (map_len bytes) gets one line on the predicted map's state ("ready",
     * "computing 4/30", "failed: ..."), sent as the X-Phase-Map header. */
    int (*phase_png)(void *user, unsigned char **png, size_t *len, char *map, size_t map_len, int *http_status,
                     char *why, size_t why_len);
    /* GET /live/events: a new event stream for one client (see api_stream). The exception to the
     * threading contract: it is called on the stream pool's thread for that client, so it may run
     * concurrently with the other ops (and with itself); it must only touch thread-safe state. */
    int (*events)(void *user, api_stream *out, char *why, size_t why_len);
    /* GET /live/camera.jpg: the latest camera frame as JPEG bytes, malloc'ed; 404 when none. */
    int (*camera_jpeg)(void *user, unsigned char **jpg, size_t *len, int *http_status, char *why, size_t why_len);
    /* GET /live/prediction: the current trial's predicted curve; 404 when none yet. */
    int (*prediction)(void *user, json_t **out, int *http_status, char *why, size_t why_len);
    /* GET or POST on a campaign path (/specimens, /queue and below; docs/campaign.md): path as
     * requested, body the JSON object of a POST ({} when none), NULL for a GET. The op checks the
     * method per path (405 naming the allowed one). */
    int (*campaign)(void *user, const char *method, const char *path, const json_t *body, json_t **out,
                    int *http_status, char *why, size_t why_len);
    /* POST /rails/{name}/home or /rails/{name}/confirm-zero with {"confirm": true} (path as
     * requested): home a rail or confirm its zero between trials (docs/api.md). */
    int (*rail)(void *user, const char *path, const json_t *body, json_t **out, int *http_status, char *why,
                size_t why_len);
} api_ops;

typedef struct api_server api_server;

/* Bind, listen and start the polling thread. ops is copied; user is passed to every op and must
 * outlive the server. Returns 0 and *out, or -1 with a reason in why (bad config, address in
 * use, non-loopback without a token, ...). */
int api_server_start(const api_server_config *cfg, const api_ops *ops, void *user, api_server **out,
                     char *why, size_t why_len);


/* The TCP port actually bound (useful with port 0). */
unsigned api_server_port(const api_server *s);

/* Stop accepting, close every connection, join the polling thread (waits for an op in
 * progress: see the threading contract), free. NULL is a no-op. */
void api_server_stop(api_server *s);

#endif
