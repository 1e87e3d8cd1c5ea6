/* api.h: the API room's face: the control API between ribbond and its clients, HTTP+JSON.
 *   api_server.h   libmicrohttpd server: the route table's operations (api_ops), the token rule
 *   api_client.h   libcurl client (ribbonctl)
 *   api_start_body.h  the checks of POST /trials's body (both modes)
 *   api_overrides.h   what an API client may change in a trial (the table behind "set")
 * api_route.h (the routes' grammar) is the server's own. Everything outside this folder includes
 * this header only. */
#ifndef RIBBON_API_H
#define RIBBON_API_H

#include "api_server.h"
#include "api_client.h"
#include "api_start_body.h"
#include "api_overrides.h"

#endif
