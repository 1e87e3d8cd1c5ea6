/* api_guard.h: the API's front door. It owns the listening socket and every connection until its
 * request headers are complete, so that no slow or silent client ever holds one of the HTTP
 * server's connection slots.
 *
 * A connection is accepted at once and waits in a bounded pending set (pending_max); it is
 * watched with MSG_PEEK, so nothing is consumed, until its headers end (a blank line). Then the
 * take callback decides where it goes (libmicrohttpd's control or stream pool, see api_server.c)
 * and takes the socket, or names a refusal (an HTTP status) that the guard answers itself. A
 * connection whose headers are not complete header_timeout_ms after it was accepted is answered
 * 408 and closed; when the pending set is full the oldest waiting connection is closed to make
 * room for the new one. A request line longer than line_max gets 414, a head longer than
 * head_max 431. Every reply the guard writes is the API's JSON error object
 * {"error": "...", "status": N}; after a reply the guard stops writing and drains what the client
 * still sends (up to one second) before it closes, so the reply is not lost to a reset.
 *
 * Threads: the guard runs one thread of its own (epoll); take is called on it. */
#ifndef RIBBON_DAEMON_API_GUARD_H
#define RIBBON_DAEMON_API_GUARD_H

#include <stddef.h>
#include <sys/socket.h>

typedef struct api_guard_config {
    int listen_fd;               /* bound, listening, non-blocking; the guard closes it */
    unsigned header_timeout_ms;  /* from accept to the end of the headers */
    unsigned pending_max;        /* connections waiting for their headers */
    size_t line_max;             /* request line, bytes */
    size_t head_max;             /* request line and headers, bytes */
    /* Headers of fd are complete: head[0..len) is what has arrived so far (not consumed).
     * Return 0 when the socket was taken (it is the callee's from now on, even if it then fails),
     * or an HTTP status (>= 400) with a message in why for the guard to answer. */
    int (*take)(void *user, int fd, const struct sockaddr *peer, socklen_t peer_len, const char *head, size_t len,
                char *why, size_t why_len);
    void *user;
} api_guard_config;

typedef struct api_guard api_guard;

int api_guard_start(const api_guard_config *cfg, api_guard **out, char *why, size_t why_len);
/* Stops the thread, closes the listening socket and every connection still waiting. */
void api_guard_stop(api_guard *g);

/* The JSON error reply the API sends ({"error": msg, "status": status}) as a complete HTTP/1.1
 * response with "Connection: close", into buf. Returns its length (0 if it does not fit). msg is
 * the guard's own text (ASCII, no quotes or backslashes needed). */
size_t api_guard_reply(char *buf, size_t cap, int status, const char *msg);

#endif
