// image_header.hpp: an image file's size from its header, and the check every image reader makes
// before decoding (see image_header.cpp).
#ifndef RIBBON_VIS_IMAGE_HEADER_HPP
#define RIBBON_VIS_IMAGE_HEADER_HPP

#include "vis_internal.hpp"

namespace vis {
// 1 with *w and *h from a PNG, JPEG, BMP or PNM header; 0 when the file has none of these
// headers (or a damaged one); -1 when it cannot be opened.
int image_header_size(const char *path, long *w, long *h);
// VIS_OK, or VIS_ERR_TOO_LARGE naming the size and the limit (VIS_MAX_IMAGE_SIDE,
// VIS_MAX_IMAGE_PIXELS in vision.h) when the header says the image is larger.
vis_status image_size_check(const char *path, vis_error *err);
}  // namespace vis

#endif
