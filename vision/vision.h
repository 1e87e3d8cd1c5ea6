/* vision.h: the C face of the vision module (C++17 and OpenCV 4.6 inside), for everything outside
 * vision/: it gathers the faces of vision's rooms, one folder each (docs/include-rules.md), so a
 * caller includes this header only. Inside vision/ a room includes its own face and the faces of
 * the rooms below it, never this header.
 *
 * It owns everything between a camera and two numbers per frame: frame sources (camera, video file,
 * image sequence, synthetic renderer) behind one interface, a synthetic renderer that draws a
 * simulated ribbon as a side view through a pinhole camera (with ground truth), an FFV1 video writer,
 * the tracker that measures the midpoint height Delta Z and the asymmetry A, and calibration.
 *
 * Design choices: every object is an opaque handle created by _create / _open functions and released by
 * _free / _close; every parameter set is a plain struct filled by a *_default() function, with units in
 * each field comment; every call that can fail returns a vis_status and fills an optional vis_error
 * with a human message (no C++ exception ever crosses this header; no global state; nothing exits).
 * The module does not know the simulator: a simulated state reaches it as a vis_shape (points and
 * normals in the simulator's frame), which the daemon fills.
 *
 * Conventions (DESIGN.md section 3, issue 5):
 * - World frame = simulator frame: x along the compression axis (left clamp point at x = 0), y along
 *   the ribbon width / shear direction, z up. Metres.
 * - The camera sits on the -y side at distance `distance_m` from the plane y = 0 and looks along +y,
 *   so it sees the x-z plane with x to the right and z up. Shear (+y) moves the right clamp away.
 * - Image: pixel (i, j) has its centre at (u, v) = (i, j) (OpenCV's convention); v points down.
 * - Arc length s runs from the left clamp in the image; angles are counterclockwise with z up.
 * - Delta Z = height of the arc-length midpoint above the line through the clamp points, over the free
 *   length l. A = 2 theta(1/2) - theta(0) - theta(1), theta the tangent angle. The *_cam variants use
 *   the curve projected orthographically on the x-z plane (what a distant side camera sees).
 */
#ifndef RIBBON_VISION_H
#define RIBBON_VISION_H

#include "vis_core.h"   /* vision/core/: statuses, reasons, the frame */
#include "vis_render.h" /* vision/render/: shape and ground truth, pinhole camera, renderer */
#include "vis_video.h"  /* vision/video/: lossless video writers, the synthetic video */
#include "vis_calib.h"  /* vision/calib/: calibration */
#include "vis_source.h" /* vision/source/: frame sources (cameras, video, images, synthetic) */
#include "vis_track.h"  /* vision/track/: tracker, clamps, pipe, whole videos, overlay, snap */

#endif
