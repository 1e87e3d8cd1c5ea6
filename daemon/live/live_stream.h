/* live_stream.h: one browser's event stream over the live bus, in the Server-Sent Events format
 * (text/event-stream): each bus message becomes "id: SEQ\ndata: JSON\n\n"; a reader that fell
 * behind the ring first gets {"type":"gap","missed":N}; a second without news sends a comment
 * line (": keep-alive") so proxies and the browser know the stream is alive. */
#ifndef RIBBON_DAEMON_LIVE_STREAM_H
#define RIBBON_DAEMON_LIVE_STREAM_H

#include "api.h"
#include "live_bus.h"

/* A stream starting at the current trial's first message (live_bus_first), with a
 * {"type":"hello"} message first. Returns 0 and *out, or -1 (out of memory) with why. */
int live_stream_open(live_bus *b, api_stream *out, char *why, size_t why_len);

#endif
