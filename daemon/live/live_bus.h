/* live_bus.h: what the live page sees of a trial, published by the trial's threads and read by
 * any number of browsers, without a browser ever slowing a trial.
 *
 * Three things are kept, each bounded:
 *   - messages: JSON objects (text, at most LIVE_MSG_MAX bytes) in a ring of LIVE_RING slots,
 *     numbered by a sequence that only grows. The publisher copies its text into the next slot and
 *     overwrites the oldest; each reader keeps its own cursor and is told how many it missed when
 *     the ring went past it ("each client gets what it can keep up with").
 *   - the latest camera frame (8-bit, 1 or 3 channels) with the tracked centreline, copied at most
 *     every LIVE_FRAME_PERIOD_S of publisher time: the JPEG is made by the reader, never here.
 *   - the current trial's predicted curve (Delta W, Delta Z, A), published once per trial.
 *
 * Publishing never blocks on a reader: the bus's mutex is held only for a bounded copy (one
 * message, one frame, one curve) by publishers and readers alike, never across I/O, and a reader
 * copies out before it formats or sends anything. Publishing allocates nothing except for a frame
 * or curve larger than any before (the buffers grow once, then are reused).
 * Threads: any thread may publish or read. */
#ifndef RIBBON_DAEMON_LIVE_BUS_H
#define RIBBON_DAEMON_LIVE_BUS_H

#include <stddef.h>
#include <stdint.h>

#define LIVE_MSG_MAX 1024          /* bytes of one message's JSON text, NUL included */
#define LIVE_RING 4096             /* messages kept */
#define LIVE_FRAME_PERIOD_S 0.1    /* frames copied at most 10 per second */
#define LIVE_CURVE_MAX 4096        /* curve points kept (a longer curve is thinned evenly) */
#define LIVE_UV_MAX 512            /* centreline points kept with a frame */

typedef struct live_bus live_bus;

live_bus *live_bus_create(void);
void live_bus_free(live_bus *b);
/* Wakes every waiting reader; from now on reads return -1 (the daemon is stopping). */
void live_bus_close(live_bus *b);

/* Publish one JSON object's text (e.g. {"type":"state",...}); the reader's stream adds the
 * sequence number as the SSE id. Text of LIVE_MSG_MAX bytes or more is replaced by an
 * {"type":"error"} message saying so. trial_start marks the message where a browser that
 * connects later begins (the first message of a trial), so it sees the whole trial if the ring
 * still holds it. */
void live_bus_publish(live_bus *b, const char *json, int trial_start);

/* Formatting helpers for publishers (no allocation): */
/* JSON number, or null for NaN/inf, into buf. */
const char *live_num(char *buf, size_t n, double v);
/* s as a JSON string body (quotes not included), escaped and cut to fit n. */
const char *live_str(char *buf, size_t n, const char *s);

/* Reader: the sequence a new reader starts from. */
uint64_t live_bus_first(live_bus *b);
/* Copies the message at *cursor (or the oldest still kept, if the ring went past it: *missed then
 * says how many were skipped) into buf and advances *cursor. Waits up to timeout_ms for one.
 * Returns the length, 0 on timeout, -1 when the bus is closed. *seq gets the message's number. */
int live_bus_read(live_bus *b, uint64_t *cursor, char *buf, size_t cap, int timeout_ms, uint64_t *seq,
                  uint64_t *missed);

/* Frames. live_bus_frame_due tells a publisher whether a frame at time t_s would be kept (so it
 * can skip gathering the centreline); live_bus_publish_frame copies it when due. uv: n_uv (u, v)
 * pixel pairs of the tracked centreline from the left clamp (may be 0). */
int live_bus_frame_due(live_bus *b, double t_s);
void live_bus_publish_frame(live_bus *b, double t_s, long index, int width, int height, int channels,
                            size_t stride, const uint8_t *data, const double *uv, size_t n_uv);

typedef struct live_frame {
    long index;                /* -1: no frame yet */
    uint64_t version;          /* grows with every copied frame */
    double t_s;
    int width, height, channels;
    uint8_t *pixels;           /* width * channels bytes per row, malloc'ed */
    size_t n_uv;
    double uv[2 * LIVE_UV_MAX];
} live_frame;
/* Copies the latest frame into *out (out->pixels malloc'ed, caller frees). Returns 0, or -1 when
 * there is none yet (or out of memory). */
int live_bus_latest_frame(live_bus *b, live_frame *out);

/* The prediction's curve for trial_id (n points; thinned to LIVE_CURVE_MAX). */
void live_bus_publish_curve(live_bus *b, int64_t trial_id, size_t n, const double *dw, const double *dz,
                            const double *a);
/* Copies the curve: arrays malloc'ed (caller frees). Returns the number of points (0: none). */
size_t live_bus_curve(live_bus *b, int64_t *trial_id, double **dw, double **dz, double **a);

#endif
