/* live_routes.c: the live routes' replies (see live_routes.h). */
#include "live_routes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "live_jpeg.h"
#include "live_stream.h"

int live_route_events(live_bus *b, api_stream *out, char *why, size_t why_len)
{
    if (!b) {
        snprintf(why, why_len, "this daemon has no live bus");
        return -1;
    }
    return live_stream_open(b, out, why, why_len);
}

int live_route_camera(live_bus *b, unsigned char **jpg, size_t *len, int *http_status, char *why, size_t why_len)
{
    live_frame f;
    if (!b || live_bus_latest_frame(b, &f) != 0) {
        *http_status = 404;
        snprintf(why, why_len, "no camera frame yet (frames come while a trial runs)");
        return -1;
    }
    int rc = live_jpeg_encode(&f, LIVE_JPEG_QUALITY, jpg, len, why, why_len);
    free(f.pixels);
    if (rc) *http_status = 500;
    return rc;
}

static json_t *array_of(const double *v, size_t n)
{
    json_t *a = json_array();
    for (size_t i = 0; a && i < n; i++) json_array_append_new(a, isfinite(v[i]) ? json_real(v[i]) : json_null());
    return a;
}

int live_route_prediction(live_bus *b, json_t **out, int *http_status, char *why, size_t why_len)
{
    int64_t id = 0;
    double *dw = NULL, *dz = NULL, *a = NULL;
    size_t m = b ? live_bus_curve(b, &id, &dw, &dz, &a) : 0;
    if (m == 0) {
        *http_status = 404;
        snprintf(why, why_len, "no predicted curve yet");
        return -1;
    }
    *out = json_pack("{s:I, s:o, s:o, s:o}", "trial", (json_int_t)id, "dw", array_of(dw, m), "dz", array_of(dz, m),
                     "a", array_of(a, m));
    free(dw);
    free(dz);
    free(a);
    if (!*out) {
        *http_status = 500;
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    return 0;
}
