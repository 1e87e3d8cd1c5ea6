// vis_internal.hpp: private glue shared by the vision module's C++ files.
//
// Owns the concrete layout of the opaque vis_frame, the error helpers and the boundary macro that
// turns every C++ exception into a vis_status plus message. Every extern "C" entry point wraps its
// body in VIS_GUARD so that nothing thrown by OpenCV or the standard library crosses vision.h.
#ifndef RIBBON_VIS_INTERNAL_HPP
#define RIBBON_VIS_INTERNAL_HPP

#include "vis_core.h"

#include <opencv2/core.hpp>
#include <cmath>
#include <new>
#include <string>

struct vis_frame {
    cv::Mat mat;  // CV_8UC1 or CV_8UC3, continuous or not
};

namespace vis {

// Fill `err` (if any) and return `code`.
vis_status fail(vis_error *err, vis_status code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
void ok(vis_error *err);

inline bool finite(double x) { return std::isfinite(x); }

// A grey view of a frame (shares data when already grey).
cv::Mat grey_of(const cv::Mat &m);

}  // namespace vis

// Boundary: run the body (the variadic part, so commas inside it are fine), map exceptions to statuses. `onfail` is the value returned on exception.
#define VIS_GUARD(err, onfail, ...)                                                         \
    try {                                                                                    \
        __VA_ARGS__                                                                          \
    } catch (const std::bad_alloc &) {                                                       \
        vis::fail((err), VIS_ERR_NOMEM, "out of memory");                                    \
        return onfail;                                                                       \
    } catch (const cv::Exception &e) {                                                       \
        vis::fail((err), VIS_ERR_INTERNAL, "OpenCV: %s", e.what());                          \
        return onfail;                                                                       \
    } catch (const std::exception &e) {                                                      \
        vis::fail((err), VIS_ERR_INTERNAL, "%s", e.what());                                  \
        return onfail;                                                                       \
    } catch (...) {                                                                          \
        vis::fail((err), VIS_ERR_INTERNAL, "unknown exception");                             \
        return onfail;                                                                       \
    }

#endif
