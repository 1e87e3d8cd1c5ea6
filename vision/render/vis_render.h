/* vis_render.h: the face of vision/render/, the synthetic side of the camera: a ribbon state in the
 * simulator's frame and its ground truth (shape.cpp), the pinhole camera that sees it (camera.cpp),
 * and the renderer that draws it as a side view (render.cpp). Frames, statuses: vis_core.h; the
 * world frame and image conventions: vision.h. */
#ifndef RIBBON_VIS_RENDER_H
#define RIBBON_VIS_RENDER_H

#include "vis_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- ribbon shape and ground truth */

/* A ribbon state in the simulator's frame: the free length only, point 0 at the left clamp point,
 * point n-1 at the right clamp point. Arrays are borrowed for the duration of the call. */
typedef struct vis_shape {
    size_t n;              /* number of centreline points, >= 3 */
    const double *pos;     /* 3n values: x, y, z of each point, metres */
    const double *normal;  /* 3n values: unit surface normal at each point (z-ish when flat) */
    double width_m;        /* ribbon width, metres (the band spans +-width/2 along normal x tangent) */
    double thickness_m;    /* ribbon thickness, metres (along the normal) */
} vis_shape;

typedef struct vis_truth {
    double length_m;       /* free length l: 3D arc length of the centreline, metres */
    double dz;             /* Delta Z from the 3D curve (midpoint height over the clamp line), / l */
    double a;              /* A from the 3D curve's tangent angle in its x-z projection... see below */
    double dz_cam;         /* Delta Z of the x-z projection (arc-length midpoint of the projection), / l */
    double a_cam;          /* A of the x-z projection, radians */
    double shear_m;        /* y of the right clamp point minus y of the left one, metres */
} vis_truth;
/* `a` is the paper's A: the tangent's elevation angle atan2(t_z, |t_xy|) integrated as
 * 2 theta(s=1/2) - theta(0) - theta(1) on the 3D curve (equal to a_cam when the curve is planar). */

vis_status vis_shape_truth(const vis_shape *shape, vis_truth *out, vis_error *err);

/* ---------------------------------------------------------------- pinhole camera */

typedef struct vis_camera {
    int width_px;          /* image width, pixels */
    int height_px;         /* image height, pixels */
    double focal_px;       /* focal length, pixels */
    double distance_m;     /* camera centre to the plane y = 0, metres (camera at y = -distance) */
    double tilt_rad;       /* pitch: positive looks down onto the scene, radians */
    double target_x_m;     /* the optical axis passes through (target_x, 0, target_z), metres */
    double target_z_m;
} vis_camera;

vis_camera vis_camera_default(void);
/* Project a world point (metres) to pixel coordinates. Fails if the point is behind the camera. */
vis_status vis_camera_project(const vis_camera *cam, const double p[3], double uv[2], vis_error *err);
/* Set focal_px and the target so that the box [x0,x1] x [z0,z1] (plane y = 0, metres) fills `fill`
 * (0..1) of the image width or height, whichever is tighter. */
vis_status vis_camera_fit(vis_camera *cam, double x0, double x1, double z0, double z1, double fill,
                          vis_error *err);

/* ---------------------------------------------------------------- synthetic renderer */

typedef struct vis_render_params {
    vis_camera camera;
    double background;        /* backdrop grey level, 0..255 */
    double ribbon;            /* ribbon grey level, 0..255 (darker or lighter than the backdrop) */
    double clamp;             /* clamp jaw grey level, 0..255 */
    double clamp_length_m;    /* jaw length along the ribbon, outside the free length, metres (0 = none) */
    double clamp_height_m;    /* jaw height across the ribbon, metres */
    double noise_sigma;       /* additive Gaussian noise, grey levels (0 = none) */
    double blur_sigma_px;     /* Gaussian optical blur, pixels (0 = none) */
    double light_gradient;    /* illumination changes by this fraction across the width (0 = even) */
    double vignette;          /* illumination falls by this fraction at the corners (0 = none) */
    int clutter;              /* number of random background shapes (0 = none) */
    int supersample;          /* anti-aliasing: samples per pixel side, 1..8 */
    uint64_t seed;            /* seed of the noise and clutter generator (no hidden global RNG) */
} vis_render_params;

vis_render_params vis_render_params_default(void);

/* Where the renderer put things, in pixels (the image-side ground truth of one frame). */
typedef struct vis_render_truth {
    vis_truth truth;          /* the shape's ground truth */
    double clamp_left_px[2];  /* projected left clamp point (u, v) */
    double clamp_right_px[2]; /* projected right clamp point (u, v) */
    double mid_px[2];         /* projected 3D arc-length midpoint (u, v) */
    double px_per_m;          /* focal_px / distance_m: the scale in the plane y = 0, pixels/metre */
} vis_render_truth;

typedef struct vis_renderer vis_renderer;
vis_renderer *vis_renderer_create(const vis_render_params *p, vis_error *err);
void vis_renderer_free(vis_renderer *r);
/* Draw one frame into `out` (reallocated to the camera size, 1 channel). `truth` may be NULL. */
vis_status vis_renderer_draw(vis_renderer *r, const vis_shape *shape, vis_frame *out,
                             vis_render_truth *truth, vis_error *err);

#ifdef __cplusplus
}
#endif

#endif
