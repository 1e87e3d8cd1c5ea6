/* live_stream.c: SSE framing of the live bus for one client (see live_stream.h). */
#include "live_stream.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct live_reader {
    live_bus *bus;
    uint64_t cursor;
    int said_hello;
    char msg[LIVE_MSG_MAX];
} live_reader;

static long reader_read(void *ctx, char *buf, size_t max)
{
    live_reader *r = ctx;
    if (max < LIVE_MSG_MAX + 128) return -1; /* the server's block is 16 KiB: never happens */
    if (!r->said_hello) {
        r->said_hello = 1;
        return snprintf(buf, max, "retry: 1000\ndata: {\"type\":\"hello\",\"first\":%llu}\n\n",
                        (unsigned long long)r->cursor);
    }
    uint64_t seq = 0, missed = 0;
    int len = live_bus_read(r->bus, &r->cursor, r->msg, sizeof r->msg, 1000, &seq, &missed);
    if (len < 0) return -1; /* closing */
    if (len == 0) return snprintf(buf, max, ": keep-alive\n\n");
    int o = 0;
    if (missed) o = snprintf(buf, max, "data: {\"type\":\"gap\",\"missed\":%llu}\n\n", (unsigned long long)missed);
    o += snprintf(buf + o, max - (size_t)o, "id: %llu\ndata: %s\n\n", (unsigned long long)seq, r->msg);
    return o;
}

static void reader_close(void *ctx)
{
    free(ctx);
}

int live_stream_open(live_bus *b, api_stream *out, char *why, size_t why_len)
{
    live_reader *r = calloc(1, sizeof *r);
    if (!r) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    r->bus = b;
    r->cursor = live_bus_first(b);
    out->read = reader_read;
    out->close = reader_close;
    out->ctx = r;
    return 0;
}
