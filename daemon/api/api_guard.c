/* api_guard.c: accepting connections and holding them until their headers are complete (see
 * api_guard.h). One epoll set, edge-triggered on the waiting sockets (each arrival of data wakes
 * the guard once; MSG_PEEK leaves the bytes for libmicrohttpd), a list of waiting connections in
 * the order they were accepted (so the oldest is the first to expire and the first evicted), and
 * an eventfd that stops the thread. */
#define _GNU_SOURCE /* accept4 */
#include "api_guard.h"

#include "api_head.h"

#include <errno.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

typedef struct pending {
    int fd;
    int draining;              /* replied: discarding input until EOF or the deadline */
    uint64_t deadline_ms;
    struct sockaddr_storage peer;
    socklen_t peer_len;
    struct pending *prev, *next;
} pending;

struct api_guard {
    api_guard_config cfg;
    int ep, stop_fd;
    pthread_t thread;
    pending *head, *tail;      /* waiting for headers, oldest first */
    pending *dhead, *dtail;    /* draining after a reply, oldest first */
    pending *dead;             /* closed during this batch of events, freed after it (a later
                                  event of the same batch may still name them) */
    unsigned n_waiting;
    char *peek;                /* head_max + 1 bytes */
};

static char listen_tag, stop_tag; /* epoll data for the two special descriptors (addresses only) */

static uint64_t now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

size_t api_guard_reply(char *buf, size_t cap, int status, const char *msg)
{
    const char *phrase = status == 400 ? "Bad Request"
                         : status == 408 ? "Request Timeout"
                         : status == 414 ? "URI Too Long"
                         : status == 431 ? "Request Header Fields Too Large"
                         : status == 503 ? "Service Unavailable"
                                         : "Error";
    char body[600];
    int bl = snprintf(body, sizeof body, "{\"error\":\"%s\",\"status\":%d}\n", msg, status);
    if (bl < 0 || (size_t)bl >= sizeof body) return 0;
    int n = snprintf(buf, cap,
                     "HTTP/1.1 %d %s\r\nContent-Type: application/json\r\nCache-Control: no-store\r\n"
                     "Connection: close\r\nContent-Length: %d\r\n\r\n%s",
                     status, phrase, bl, body);
    return n < 0 || (size_t)n >= cap ? 0 : (size_t)n;
}

static void unlink_node(pending **h, pending **t, pending *p)
{
    if (p->prev) p->prev->next = p->next; else *h = p->next;
    if (p->next) p->next->prev = p->prev; else *t = p->prev;
    p->prev = p->next = NULL;
}

static void append_node(pending **h, pending **t, pending *p)
{
    p->prev = *t;
    p->next = NULL;
    if (*t) (*t)->next = p; else *h = p;
    *t = p;
}

static void drop(api_guard *g, pending *p)
{
    if (p->draining) unlink_node(&g->dhead, &g->dtail, p);
    else {
        unlink_node(&g->head, &g->tail, p);
        g->n_waiting--;
    }
    epoll_ctl(g->ep, EPOLL_CTL_DEL, p->fd, NULL);
    close(p->fd);
    p->fd = -1;
    p->next = g->dead;
    g->dead = p;
}

static void bury(api_guard *g)
{
    while (g->dead) {
        pending *p = g->dead;
        g->dead = p->next;
        free(p);
    }
}

static void on_readable(api_guard *g, pending *p);

/* Answer p with an error and move it to the draining list. */
static void refuse(api_guard *g, pending *p, int status, const char *msg)
{
    char reply[1024];
    size_t len = api_guard_reply(reply, sizeof reply, status, msg);
    if (len) {
        ssize_t w = send(p->fd, reply, len, MSG_NOSIGNAL | MSG_DONTWAIT);
        (void)w; /* a small reply fits the socket buffer; a client that cannot take it loses it */
    }
    shutdown(p->fd, SHUT_WR);
    unlink_node(&g->head, &g->tail, p);
    g->n_waiting--;
    p->draining = 1;
    p->deadline_ms = now_ms() + 1000;
    append_node(&g->dhead, &g->dtail, p);
    on_readable(g, p); /* discard what is already in; may close p */
}

static void on_readable(api_guard *g, pending *p)
{
    if (p->fd < 0) return; /* closed earlier in this batch */
    if (p->draining) {
        char sink[4096];
        for (;;) {
            ssize_t r = recv(p->fd, sink, sizeof sink, MSG_DONTWAIT);
            if (r > 0) continue;
            if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return;
            drop(g, p);
            return;
        }
    }
    ssize_t r = recv(p->fd, g->peek, g->cfg.head_max + 1, MSG_PEEK | MSG_DONTWAIT);
    if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return;
    if (r <= 0) {
        drop(g, p);
        return;
    }
    size_t end = 0;
    int scan = api_head_scan(g->peek, (size_t)r, g->cfg.line_max, g->cfg.head_max, &end);
    if (scan == 414) {
        char msg[160];
        snprintf(msg, sizeof msg, "request line longer than %zu bytes (the API's paths are short)", g->cfg.line_max);
        refuse(g, p, 414, msg);
        return;
    }
    if (scan == 431) {
        char msg[160];
        snprintf(msg, sizeof msg, "request headers larger than %zu bytes", g->cfg.head_max);
        refuse(g, p, 431, msg);
        return;
    }
    if (scan == 0)
        return; /* wait for more */
    char why[400] = "";
    unlink_node(&g->head, &g->tail, p);
    g->n_waiting--;
    epoll_ctl(g->ep, EPOLL_CTL_DEL, p->fd, NULL);
    int status = g->cfg.take(g->cfg.user, p->fd, (struct sockaddr *)&p->peer, p->peer_len, g->peek, end, why,
                             sizeof why);
    if (status == 0) { /* the socket is the pool's now; the node is freed after the batch */
        p->fd = -1;
        p->next = g->dead;
        g->dead = p;
        return;
    }
    /* Refused: back on the list so refuse() can answer and drain it. */
    append_node(&g->head, &g->tail, p);
    g->n_waiting++;
    struct epoll_event ev = {.events = EPOLLIN | EPOLLET | EPOLLRDHUP, .data.ptr = p};
    epoll_ctl(g->ep, EPOLL_CTL_ADD, p->fd, &ev);
    refuse(g, p, status, why[0] ? why : "request refused");
}

static void accept_all(api_guard *g)
{
    for (;;) {
        struct sockaddr_storage peer;
        socklen_t plen = sizeof peer;
        int fd = accept4(g->cfg.listen_fd, (struct sockaddr *)&peer, &plen, SOCK_NONBLOCK | SOCK_CLOEXEC);
        if (fd < 0) {
            if (errno == EINTR || errno == ECONNABORTED) continue;
            if ((errno == EMFILE || errno == ENFILE) && g->head) {
                drop(g, g->head); /* out of descriptors: the oldest waiting connection goes */
                continue;
            }
            return; /* EAGAIN, or nothing to free: the kernel keeps the rest in the backlog */
        }
        if (g->n_waiting >= g->cfg.pending_max && g->head) drop(g, g->head);
        pending *p = calloc(1, sizeof *p);
        if (!p) {
            close(fd);
            continue;
        }
        p->fd = fd;
        p->peer = peer;
        p->peer_len = plen;
        p->deadline_ms = now_ms() + g->cfg.header_timeout_ms;
        append_node(&g->head, &g->tail, p);
        g->n_waiting++;
        struct epoll_event ev = {.events = EPOLLIN | EPOLLET | EPOLLRDHUP, .data.ptr = p};
        if (epoll_ctl(g->ep, EPOLL_CTL_ADD, fd, &ev) != 0) {
            unlink_node(&g->head, &g->tail, p);
            g->n_waiting--;
            close(fd);
            free(p);
            continue;
        }
        on_readable(g, p); /* the request may already be there */
    }
}

static void expire(api_guard *g)
{
    uint64_t now = now_ms();
    while (g->dhead && g->dhead->deadline_ms <= now) drop(g, g->dhead);
    while (g->head && g->head->deadline_ms <= now) {
        char msg[160];
        snprintf(msg, sizeof msg, "request headers not complete within %u ms", g->cfg.header_timeout_ms);
        refuse(g, g->head, 408, msg);
    }
}

static void *guard_main(void *arg)
{
    api_guard *g = arg;
    struct epoll_event evs[64];
    for (;;) {
        expire(g);
        bury(g);
        uint64_t next = UINT64_MAX;
        if (g->head) next = g->head->deadline_ms;
        if (g->dhead && g->dhead->deadline_ms < next) next = g->dhead->deadline_ms;
        int timeout = -1;
        if (next != UINT64_MAX) {
            uint64_t now = now_ms();
            timeout = next <= now ? 0 : (int)(next - now > 60000 ? 60000 : next - now);
        }
        int n = epoll_wait(g->ep, evs, 64, timeout);
        if (n < 0 && errno != EINTR) break;
        for (int i = 0; i < n; i++) {
            void *tag = evs[i].data.ptr;
            if (tag == &stop_tag) return NULL;
            if (tag == &listen_tag) accept_all(g);
            else on_readable(g, tag);
        }
        bury(g);
    }
    return NULL;
}

int api_guard_start(const api_guard_config *cfg, api_guard **out, char *why, size_t why_len)
{
    *out = NULL;
    api_guard *g = calloc(1, sizeof *g);
    if (!g || !(g->peek = malloc(cfg->head_max + 1))) {
        free(g);
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    g->cfg = *cfg;
    g->ep = epoll_create1(EPOLL_CLOEXEC);
    g->stop_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    struct epoll_event el = {.events = EPOLLIN, .data.ptr = &listen_tag};
    struct epoll_event es = {.events = EPOLLIN, .data.ptr = &stop_tag};
    if (g->ep < 0 || g->stop_fd < 0 || epoll_ctl(g->ep, EPOLL_CTL_ADD, cfg->listen_fd, &el) != 0 ||
        epoll_ctl(g->ep, EPOLL_CTL_ADD, g->stop_fd, &es) != 0 ||
        pthread_create(&g->thread, NULL, guard_main, g) != 0) {
        snprintf(why, why_len, "cannot start the API's accept thread: %s", strerror(errno));
        if (g->ep >= 0) close(g->ep);
        if (g->stop_fd >= 0) close(g->stop_fd);
        free(g->peek);
        free(g);
        return -1;
    }
    *out = g;
    return 0;
}

void api_guard_stop(api_guard *g)
{
    if (!g) return;
    uint64_t one = 1;
    ssize_t w = write(g->stop_fd, &one, sizeof one);
    (void)w;
    pthread_join(g->thread, NULL);
    while (g->head) drop(g, g->head);
    while (g->dhead) drop(g, g->dhead);
    bury(g);
    close(g->cfg.listen_fd);
    close(g->stop_fd);
    close(g->ep);
    free(g->peek);
    free(g);
}
