/* live_bus.c: the live page's bounded buffers (see live_bus.h). One mutex, a condition variable
 * readers wait on, a ring of fixed-size slots, one frame slot and one curve slot. */
#include "live_bus.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct live_slot {
    uint64_t seq;
    char text[LIVE_MSG_MAX];
} live_slot;

struct live_bus {
    pthread_mutex_t lock;
    pthread_cond_t more;
    int closed;
    uint64_t next;             /* sequence of the next message; messages 1 .. next-1 were published */
    uint64_t trial_first;      /* first message of the current trial, 0 = none */
    live_slot *ring;           /* LIVE_RING slots, message seq in slot seq % LIVE_RING */

    /* latest frame */
    double frame_t;            /* publisher time of the last copied frame */
    int have_frame_t;
    live_frame frame;
    size_t frame_cap;

    /* prediction curve */
    int64_t curve_trial;
    size_t curve_n;
    double curve[3][LIVE_CURVE_MAX];
};

live_bus *live_bus_create(void)
{
    live_bus *b = calloc(1, sizeof *b);
    if (!b) return NULL;
    b->ring = calloc(LIVE_RING, sizeof *b->ring);
    if (!b->ring) {
        free(b);
        return NULL;
    }
    pthread_mutex_init(&b->lock, NULL);
    pthread_cond_init(&b->more, NULL);
    b->next = 1;
    b->frame.index = -1;
    return b;
}

void live_bus_free(live_bus *b)
{
    if (!b) return;
    pthread_cond_destroy(&b->more);
    pthread_mutex_destroy(&b->lock);
    free(b->frame.pixels);
    free(b->ring);
    free(b);
}

void live_bus_close(live_bus *b)
{
    if (!b) return;
    pthread_mutex_lock(&b->lock);
    b->closed = 1;
    pthread_cond_broadcast(&b->more);
    pthread_mutex_unlock(&b->lock);
}

void live_bus_publish(live_bus *b, const char *json, int trial_start)
{
    if (!b || !json) return;
    size_t len = strlen(json);
    pthread_mutex_lock(&b->lock);
    uint64_t seq = b->next++;
    live_slot *s = &b->ring[seq % LIVE_RING];
    s->seq = seq;
    if (len < LIVE_MSG_MAX)
        memcpy(s->text, json, len + 1);
    else
        snprintf(s->text, sizeof s->text,
                 "{\"type\":\"error\",\"message\":\"a live message of %zu bytes was too long (limit %d)\"}", len,
                 LIVE_MSG_MAX - 1);
    if (trial_start) b->trial_first = seq;
    pthread_cond_broadcast(&b->more);
    pthread_mutex_unlock(&b->lock);
}

const char *live_num(char *buf, size_t n, double v)
{
    if (isfinite(v))
        snprintf(buf, n, "%.9g", v);
    else
        snprintf(buf, n, "null");
    return buf;
}

const char *live_str(char *buf, size_t n, const char *s)
{
    size_t o = 0;
    if (n == 0) return buf;
    for (const unsigned char *p = (const unsigned char *)(s ? s : ""); *p; p++) {
        char esc[8];
        size_t k;
        if (*p == '"' || *p == '\\') {
            esc[0] = '\\';
            esc[1] = (char)*p;
            k = 2;
        } else if (*p < 0x20) {
            k = (size_t)snprintf(esc, sizeof esc, "\\u%04x", *p);
        } else if (*p >= 0x80) {
            esc[0] = '?'; /* not known to be UTF-8: kept ASCII so the JSON is always valid */
            k = 1;
        } else {
            esc[0] = (char)*p;
            k = 1;
        }
        if (o + k + 1 > n) break;
        memcpy(buf + o, esc, k);
        o += k;
    }
    buf[o] = '\0';
    return buf;
}

uint64_t live_bus_first(live_bus *b)
{
    pthread_mutex_lock(&b->lock);
    uint64_t oldest = b->next > LIVE_RING ? b->next - LIVE_RING : 1;
    uint64_t first = b->trial_first >= oldest ? b->trial_first : oldest;
    if (b->trial_first == 0) first = b->next; /* no trial yet: only what comes */
    pthread_mutex_unlock(&b->lock);
    return first;
}

int live_bus_read(live_bus *b, uint64_t *cursor, char *buf, size_t cap, int timeout_ms, uint64_t *seq,
                  uint64_t *missed)
{
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until);
    until.tv_sec += timeout_ms / 1000;
    until.tv_nsec += (long)(timeout_ms % 1000) * 1000000L;
    if (until.tv_nsec >= 1000000000L) {
        until.tv_sec++;
        until.tv_nsec -= 1000000000L;
    }
    *missed = 0;
    pthread_mutex_lock(&b->lock);
    int rc = 0;
    for (;;) {
        if (b->closed) {
            rc = -1;
            break;
        }
        if (*cursor < b->next) {
            uint64_t oldest = b->next > LIVE_RING ? b->next - LIVE_RING : 1;
            if (*cursor < oldest) {
                *missed = oldest - *cursor;
                *cursor = oldest;
            }
            const live_slot *s = &b->ring[*cursor % LIVE_RING];
            size_t len = strlen(s->text);
            if (len >= cap) len = cap - 1;
            memcpy(buf, s->text, len);
            buf[len] = '\0';
            *seq = s->seq;
            (*cursor)++;
            rc = (int)len;
            break;
        }
        if (pthread_cond_timedwait(&b->more, &b->lock, &until) == ETIMEDOUT) break;
    }
    pthread_mutex_unlock(&b->lock);
    return rc;
}

int live_bus_frame_due(live_bus *b, double t_s)
{
    if (!b) return 0;
    pthread_mutex_lock(&b->lock);
    int due = !b->have_frame_t || t_s < b->frame_t || t_s - b->frame_t >= LIVE_FRAME_PERIOD_S;
    pthread_mutex_unlock(&b->lock);
    return due;
}

void live_bus_publish_frame(live_bus *b, double t_s, long index, int width, int height, int channels,
                            size_t stride, const uint8_t *data, const double *uv, size_t n_uv)
{
    if (!b || !data || width <= 0 || height <= 0 || (channels != 1 && channels != 3)) return;
    size_t row = (size_t)width * (size_t)channels;
    size_t need = row * (size_t)height;
    pthread_mutex_lock(&b->lock);
    if (b->have_frame_t && t_s >= b->frame_t && t_s - b->frame_t < LIVE_FRAME_PERIOD_S) goto out;
    if (need > b->frame_cap) {
        uint8_t *p = realloc(b->frame.pixels, need);
        if (!p) goto out; /* the page keeps the older frame; the trial goes on */
        b->frame.pixels = p;
        b->frame_cap = need;
    }
    for (int y = 0; y < height; y++) memcpy(b->frame.pixels + (size_t)y * row, data + (size_t)y * stride, row);
    b->frame.width = width;
    b->frame.height = height;
    b->frame.channels = channels;
    b->frame.index = index;
    b->frame.t_s = t_s;
    b->frame.version++;
    if (n_uv > LIVE_UV_MAX) n_uv = LIVE_UV_MAX;
    b->frame.n_uv = uv ? n_uv : 0;
    if (uv && n_uv) memcpy(b->frame.uv, uv, 2 * n_uv * sizeof *uv);
    b->frame_t = t_s;
    b->have_frame_t = 1;
out:
    pthread_mutex_unlock(&b->lock);
}

int live_bus_latest_frame(live_bus *b, live_frame *out)
{
    pthread_mutex_lock(&b->lock);
    int rc = -1;
    if (b->frame.index >= 0) {
        size_t need = (size_t)b->frame.width * (size_t)b->frame.channels * (size_t)b->frame.height;
        uint8_t *p = malloc(need);
        if (p) {
            *out = b->frame;
            out->pixels = p;
            memcpy(p, b->frame.pixels, need);
            rc = 0;
        }
    }
    pthread_mutex_unlock(&b->lock);
    return rc;
}

void live_bus_publish_curve(live_bus *b, int64_t trial_id, size_t n, const double *dw, const double *dz,
                            const double *a)
{
    if (!b) return;
    pthread_mutex_lock(&b->lock);
    size_t m = n < LIVE_CURVE_MAX ? n : LIVE_CURVE_MAX;
    for (size_t k = 0; k < m; k++) {
        size_t i = m == n ? k : (m > 1 ? k * (n - 1) / (m - 1) : 0); /* evenly thinned, ends kept */
        b->curve[0][k] = dw[i];
        b->curve[1][k] = dz[i];
        b->curve[2][k] = a[i];
    }
    b->curve_n = m;
    b->curve_trial = trial_id;
    pthread_mutex_unlock(&b->lock);
}

size_t live_bus_curve(live_bus *b, int64_t *trial_id, double **dw, double **dz, double **a)
{
    pthread_mutex_lock(&b->lock);
    size_t n = b->curve_n;
    *trial_id = b->curve_trial;
    *dw = *dz = *a = NULL;
    if (n > 0) {
        double **dst[3] = {dw, dz, a};
        for (int c = 0; c < 3; c++) {
            *dst[c] = malloc(n * sizeof(double));
            if (!*dst[c]) {
                for (int k = 0; k < c; k++) {
                    free(*dst[k]);
                    *dst[k] = NULL;
                }
                n = 0;
                break;
            }
            memcpy(*dst[c], b->curve[c], n * sizeof(double));
        }
    }
    pthread_mutex_unlock(&b->lock);
    return n;
}
