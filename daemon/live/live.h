/* live.h: the live room's face: the live page (docs/live-page.md). Everything outside this folder
 * includes this header only.
 *   live_bus.h      the bounded buffers the trial's threads publish into (messages, the latest
 *                   frame, the predicted curve)
 *   live_stream.h   one browser's Server-Sent Events stream over the bus
 *   live_jpeg.h     the camera picture: the latest frame with the tracked centreline, as JPEG
 *   live_routes.h   the replies of the API's live routes
 *   live_assets.h   the page's files (embedded) and Debian's Chart.js */
#ifndef RIBBON_LIVE_H
#define RIBBON_LIVE_H

#include "live_bus.h"
#include "live_stream.h"
#include "live_jpeg.h"
#include "live_routes.h"
#include "live_assets.h"

#endif
