/* vis_core.h: the face of vision/core/, the room every other vision room stands on: what went wrong
 * (vis_status, vis_error, and vis_reason: why a frame has no measurement), the largest image any
 * reader decodes, and the frame (vis_frame: an 8-bit image owned by the library). Its C++ glue for
 * the rooms above (the frame's layout, the exception boundary) is vis_internal.hpp, and the check of
 * an image file's header before decoding is image_header.hpp. Conventions: vision.h. */
#ifndef RIBBON_VIS_CORE_H
#define RIBBON_VIS_CORE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- errors */

/* What went wrong, one code per kind of cause; the message in vis_error says which field or byte. */
typedef enum vis_status {
    VIS_OK = 0,
    VIS_ERR_ARG,         /* invalid argument: NULL, NaN/Inf, out of range, mismatched sizes */
    VIS_ERR_NOMEM,       /* allocation failed */
    VIS_ERR_IO,          /* file or device could not be opened, read or written */
    VIS_ERR_FORMAT,      /* content is damaged or not what was expected (video, image, calib file) */
    VIS_ERR_END,         /* end of a frame stream: not a failure, the normal way a loop stops */
    VIS_ERR_NOT_FOUND,   /* a pattern (checkerboard, clamp) was not found in the image */
    VIS_ERR_INTERNAL,    /* an unexpected exception inside OpenCV or the C++ runtime */
    VIS_ERR_TOO_LARGE    /* an image or video frame above VIS_MAX_IMAGE_SIDE / _PIXELS, refused
                            from its header before decoding */
} vis_status;

/* Largest image or video frame any reader decodes: a side, and the pixel count (64 Mpx: 8192 x
 * 8192). Larger ones are refused from their header (PNG, JPEG, BMP, PNM; a video's stream) with
 * VIS_ERR_TOO_LARGE before a decoder allocates for them. */
#define VIS_MAX_IMAGE_SIDE 16384
#define VIS_MAX_IMAGE_PIXELS 67108864.0

typedef struct vis_error {
    vis_status code;     /* same as the returned status */
    char message[256];   /* human-readable cause, NUL-terminated */
} vis_error;

const char *vis_status_str(vis_status s);

/* ---------------------------------------------------------------- frames */

/* An 8-bit image, 1 (grey) or 3 (BGR) channels, owned by the library. */
typedef struct vis_frame vis_frame;

vis_frame *vis_frame_alloc(int width_px, int height_px, int channels, vis_error *err);
void vis_frame_free(vis_frame *f);
int vis_frame_width(const vis_frame *f);
int vis_frame_height(const vis_frame *f);
int vis_frame_channels(const vis_frame *f);
size_t vis_frame_stride(const vis_frame *f);   /* bytes between rows */
uint8_t *vis_frame_data(vis_frame *f);         /* row-major pixels, `stride` bytes per row */
/* Copies src into dst (reallocated when its size or channels differ; no allocation otherwise). */
vis_status vis_frame_copy(const vis_frame *src, vis_frame *dst, vis_error *err);
/* Write/read an image file (format from the extension; PNG is lossless). Read resizes `f`. */
vis_status vis_frame_save(const vis_frame *f, const char *path, vis_error *err);
vis_status vis_frame_load(vis_frame *f, const char *path, vis_error *err);

/* ---------------------------------------------------------------- reasons
 * (the tracker's: why a frame has no measurement; their strings are error.cpp's, beside the
 * statuses') */

/* Why a frame has no measurement. */
typedef enum vis_reason {
    VIS_REASON_NONE = 0,       /* measured */
    VIS_REASON_UNREADABLE,     /* the frame could not be read or decoded */
    VIS_REASON_DARK,           /* the frame is (nearly) black: no contrast */
    VIS_REASON_SATURATED,      /* the frame is (nearly) saturated: no contrast */
    VIS_REASON_CLAMP_NOT_FOUND,/* the clamp points are unknown or outside the image */
    VIS_REASON_LOST,           /* no ribbon-like ridge joins the clamps */
    VIS_REASON_OCCLUDED,       /* the ridge is broken over part of its length */
    VIS_REASON_NOISE,          /* the frame is noise: neighbouring pixels unrelated, no structure */
    VIS_REASON_NO_RIBBON       /* no ribbon-like ridge leaves the clamps anywhere in the frame */
} vis_reason;
const char *vis_reason_str(vis_reason r);

#ifdef __cplusplus
}
#endif

#endif
