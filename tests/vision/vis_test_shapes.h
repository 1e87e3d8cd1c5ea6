/* vis_test_shapes.h: analytic ribbon shapes for the vision tests (no simulator dependency).
 *
 * Every shape is a clamped-clamped planar curve in the x-z plane, sampled at n points equally spaced
 * in arc length, optionally carried out of plane by a shear profile y = dw (3 xi^2 - 2 xi^3) (xi the
 * arc fraction, flat at both clamps as a clamped ribbon is), with normals orthogonal to the tangent
 * and to the width direction (nearest to +y). Families:
 *   arch:      z = R (cos(phi) m1 + sin(phi) m2), m1 = (1 - cos(2 pi x / X)) / 2 the symmetric arch,
 *              m2 = sin(2 pi x / X) (1 - cos(2 pi x / X)) / 2 an antisymmetric clamped-compatible
 *              mode, x in [0, X], R such that the free length is l: phi = 0 up, pi down
 *   overhang:  tangent angle theta(s) = T sin(2 pi s / l); T > pi/2 turns it beyond vertical
 */
#ifndef VIS_TEST_SHAPES_H
#define VIS_TEST_SHAPES_H

#include "vision.h"

#define VT_MAXN 1024

typedef struct vt_shape {
    size_t n;
    double pos[3 * VT_MAXN];
    double normal[3 * VT_MAXN];
    vis_shape view;            /* points into pos/normal */
} vt_shape;

/* Shape from a dense planar curve (xd, zd), m <= 8192 points, resampled at n points equally spaced
 * in arc length, sheared by dw. */
void vt_from_dense(vt_shape *s, size_t n, const double *xd, const double *zd, size_t m, double dw);
void vt_arch(vt_shape *s, size_t n, double l, double X, double phi, double dw);
/* The same with another depth profile: y = dw depth(xi), xi the planar arc fraction (depth(0) = 0,
 * depth(1) = 1); vt_depth_cubic is the default's. */
double vt_depth_cubic(double xi);
void vt_from_dense_depth(vt_shape *s, size_t n, const double *xd, const double *zd, size_t m, double dw,
                         double (*depth)(double xi));
void vt_arch_depth(vt_shape *s, size_t n, double l, double X, double phi, double dw, double (*depth)(double xi));
void vt_overhang(vt_shape *s, size_t n, double l, double T, double dw);
/* Turn the strip about its tangent by psi(xi) radians at arc fraction xi (its face toward the
 * camera as psi grows from 0, the edge-on default): n' = cos(psi) n + sin(psi) (t x n). */
void vt_twist(vt_shape *s, double (*psi)(double xi, void *ctx), void *ctx);
/* Camera fitted around the shape with margin; 320 x 240 unless changed after. */
vis_render_params vt_render_params(const vt_shape *s, int w, int h);
/* Calibration matching the renderer's camera for this shape (clamp points at zero shear). */
vis_calib vt_calib(const vis_render_params *p, const vt_shape *s);

#endif
