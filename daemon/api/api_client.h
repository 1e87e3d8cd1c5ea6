/* api_client.h: ribbonctl's side of the control API (libcurl). One call = one HTTP exchange with
 * ribbond; see api_server.h for the routes.
 *
 * THREADS. libcurl's global set-up is not thread-safe, so the program calls
 * api_client_global_init() exactly once from main() before it starts any thread, and
 * api_client_global_cleanup() once at the end. api_client_request itself keeps no state between
 * calls (one curl handle per call) and may be called from several threads at once. */
#ifndef RIBBON_DAEMON_API_CLIENT_H
#define RIBBON_DAEMON_API_CLIENT_H

#include <jansson.h>
#include <stddef.h>

typedef struct api_client_config {
    const char *base_url; /* "http://127.0.0.1:8377" (http:// or https://, no path); a trailing
                             slash is allowed */
    const char *token;    /* bearer token, NULL or "" = none */
    double timeout_s;     /* whole exchange, seconds (> 0); connecting gets at most 5 s of it */
} api_client_config;

/* http://127.0.0.1:8377, no token, 30 s. */
api_client_config api_client_config_default(void);

/* Call once from main() before any thread exists. 0, or -1 with a reason. */
int api_client_global_init(char *why, size_t why_len);
void api_client_global_cleanup(void);

/* Send method ("GET", "POST", ...) to base_url + path (path starts with '/'), with body as JSON
 * when body is not NULL (a POST without body sends an empty one).
 *
 * Returns 0 when an HTTP exchange completed, whatever its status; *http_status gets the status.
 * For a status >= 400 why gets the server's "error" message (or "HTTP N" when it sent none).
 * The reply body goes to:
 *   json_out  (may be NULL) when the reply is application/json: a new reference for the caller;
 *             error replies too ({"error", "status"}).
 *   bytes_out (may be NULL) when the reply is not JSON (report.png): malloc'ed, free() it;
 *             *len_out its size.
 * Returns -1 with a reason in why when ribbond cannot be reached ("cannot reach ribbond at URL:
 * connection refused; is it running? (ribbond --config FILE)"), does not answer in time, or when
 * the reply is not what the caller can take: invalid JSON, or not JSON while json_out was given
 * and bytes_out was not. On -1 nothing is returned through json_out / bytes_out. */
int api_client_request(const api_client_config *c, const char *method, const char *path, const json_t *body,
                       int *http_status, json_t **json_out, unsigned char **bytes_out, size_t *len_out, char *why,
                       size_t why_len);

#endif
