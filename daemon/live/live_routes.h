/* live_routes.h: the replies of the API's live routes, made from the live bus (the daemon's
 * api_ops call these with its bus): GET /live/events, /live/camera.jpg, /live/prediction. */
#ifndef RIBBON_DAEMON_LIVE_ROUTES_H
#define RIBBON_DAEMON_LIVE_ROUTES_H

#include <jansson.h>
#include <stddef.h>

#include "api.h"
#include "live_bus.h"

#define LIVE_JPEG_QUALITY 80

int live_route_events(live_bus *b, api_stream *out, char *why, size_t why_len);
/* 404 until a frame was published. */
int live_route_camera(live_bus *b, unsigned char **jpg, size_t *len, int *http_status, char *why, size_t why_len);
/* {"trial": ID, "dw": [...], "dz": [...], "a": [...]}; 404 until a curve was published. */
int live_route_prediction(live_bus *b, json_t **out, int *http_status, char *why, size_t why_len);

#endif
