/* vis_calib.h: the face of vision/calib/: the calibration that maps pixels to millimetres in the
 * rig's plane y = 0 and names the clamp points: from the clamps and their spacing, from a synthetic
 * camera, its file, its checks (calib.cpp), and from views of a checkerboard (calib_board.cpp).
 * Finding the clamps in a frame is the tracker's (vis_find_clamps, vis_track.h). */
#ifndef RIBBON_VIS_CALIB_H
#define RIBBON_VIS_CALIB_H

#include "vis_core.h"
#include "vis_render.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- calibration */

/* Maps pixels to millimetres in the plane y = 0 of the rig and names the clamp points. */
typedef struct vis_calib {
    double px_per_mm;          /* scale in the plane y = 0, pixels per millimetre */
    double clamp_left_px[2];   /* left clamp point (u, v) at zero shear, pixels */
    double clamp_right_px[2];  /* right clamp point (u, v) at zero shear, pixels */
    double principal_px[2];    /* principal point (u, v), pixels; negative = image centre */
    double camera_distance_mm; /* camera centre to where its optical axis meets the plane y = 0, mm;
                                  0 = unknown: no depth correction, no tilt */
    double camera_tilt_rad;    /* camera pitch, radians, positive looks down (as vis_camera) */
    int has_intrinsics;        /* 1 when camera_matrix and dist are valid (checkerboard) */
    double camera_matrix[9];   /* 3x3 row-major intrinsic matrix, pixels */
    double dist[5];            /* OpenCV distortion k1 k2 p1 p2 k3, dimensionless */
} vis_calib;

vis_calib vis_calib_default(void);
/* Scale from the two clamp points and their known spacing (mm) at zero shear. */
vis_status vis_calib_from_clamps(vis_calib *c, const double left_px[2], const double right_px[2],
                                 double spacing_mm, vis_error *err);
/* Intrinsics, distortion and scale from views of a checkerboard with `cols` x `rows` inner corners
 * and `square_mm` squares; the last view must show the board in the plane y = 0 (sets px_per_mm). */
vis_status vis_calib_from_checkerboard(vis_calib *c, const vis_frame *const *views, size_t n_views,
                                       int cols, int rows, double square_mm, vis_error *err);
/* The calibration that matches a synthetic camera (mock mode): clamp points projected at zero shear
 * from the world points `left_m`, `right_m` (metres; their y is ignored), scale and distance from
 * the camera, tilt included. */
vis_status vis_calib_from_camera(vis_calib *c, const vis_camera *cam, const double left_m[3],
                                 const double right_m[3], vis_error *err);
vis_status vis_calib_check(const vis_calib *c, vis_error *err);
vis_status vis_calib_save(const vis_calib *c, const char *path, vis_error *err);
vis_status vis_calib_load(vis_calib *c, const char *path, vis_error *err);
/* The tracker's centreline (n points uv: (u, v) pixels, as vis_tracker_curve gives them) in the plane
 * y = 0 at depth 0 (no shear), relative to the calibration's left clamp point, over the strip's
 * length: xz (2 n values), through the tracker's own view model (calib_plane.cpp), for a frame of
 * w x h pixels (the principal point's default). */
void vis_calib_curve_to_plane(const vis_calib *cal, int w, int h, double length_mm, const double *uv, int n,
                              double *xz);

#ifdef __cplusplus
}
#endif

#endif
