// error.cpp: the vision module's status names and the helper that fills a vis_error.
//
// One enum for the whole layer (vision.h); messages are formatted once, at the place that knows
// which field or byte was wrong, and truncated safely to the fixed buffer.
#include "vis_internal.hpp"

#include <cstdarg>
#include <cstdio>

namespace vis {

vis_status fail(vis_error *err, vis_status code, const char *fmt, ...)
{
    if (err) {
        err->code = code;
        va_list ap;
        va_start(ap, fmt);
        std::vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

void ok(vis_error *err)
{
    if (err) {
        err->code = VIS_OK;
        err->message[0] = '\0';
    }
}

}  // namespace vis

extern "C" const char *vis_status_str(vis_status s)
{
    switch (s) {
    case VIS_OK: return "ok";
    case VIS_ERR_ARG: return "invalid argument";
    case VIS_ERR_NOMEM: return "out of memory";
    case VIS_ERR_IO: return "input/output error";
    case VIS_ERR_FORMAT: return "damaged or unexpected content";
    case VIS_ERR_END: return "end of stream";
    case VIS_ERR_NOT_FOUND: return "pattern not found";
    case VIS_ERR_INTERNAL: return "internal error";
    case VIS_ERR_TOO_LARGE: return "image too large";
    }
    return "unknown status";
}

extern "C" const char *vis_reason_str(vis_reason r)
{
    switch (r) {
    case VIS_REASON_NONE: return "ok";
    case VIS_REASON_UNREADABLE: return "frame unreadable";
    case VIS_REASON_DARK: return "frame too dark";
    case VIS_REASON_SATURATED: return "frame saturated";
    case VIS_REASON_CLAMP_NOT_FOUND: return "clamp not found";
    case VIS_REASON_LOST: return "ribbon lost";
    case VIS_REASON_OCCLUDED: return "ribbon occluded";
    case VIS_REASON_NOISE: return "frame is noise";
    case VIS_REASON_NO_RIBBON: return "no ribbon in the frame";
    }
    return "unknown reason";
}
