/* live_jpeg.h: the live page's camera picture: the latest frame of the live bus as a JPEG (for
 * the page only: recordings stay lossless), with the tracked centreline drawn in green, its two
 * ends (the clamp points) in red and its arc-length midpoint in blue. Encoded with Debian's
 * libjpeg, on the thread that serves the request, never on the trial's. */
#ifndef RIBBON_DAEMON_LIVE_JPEG_H
#define RIBBON_DAEMON_LIVE_JPEG_H

#include <stddef.h>

#include "live_bus.h"

/* Encodes f (1 or 3 channels; 3 is B, G, R as the camera delivers it) at quality 1..100 into a
 * malloc'ed buffer. Returns 0, or -1 with why. */
int live_jpeg_encode(const live_frame *f, int quality, unsigned char **jpg, size_t *len, char *why, size_t why_len);

#endif
