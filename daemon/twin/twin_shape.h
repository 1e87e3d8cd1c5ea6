/* twin_shape.h: a simulated rod state as the vision module's vis_shape (the "digital twin" glue
 * between sim/ and vision/, used by `ribbonctl render` and by the daemon's mock mode).
 *
 * Owns the conversion only: which nodes, which frame, which normals. The caller owns the buffers:
 * a twin_shape is sized once for a scene (twin_shape_init) and refilled from every state without
 * allocating (twin_shape_from_rod), so it can sit in a frame loop.
 *
 * What a vis_shape gets from a rod of N nodes (sim/rod.h):
 * - points: the free length only, nodes 1 .. N-2, point 0 the left clamp point (node 1) and point
 *   N-3 the right clamp point (node N-2); the clamped edges 0 and N-2 lie outside the free length
 *   and are not part of the shape (the renderer draws the clamp jaws there);
 * - normals: at each node the normalised mean of the material director m1 (the surface normal,
 *   +z when the ribbon lies flat) of the two edges meeting there, made orthogonal to the mean of
 *   their unit tangents; at a crease the two edges' normals differ by the crease angle and the
 *   node gets the bisector;
 * - width and thickness from the scene; metres throughout.
 *
 * Frames. The simulator and the vision module share axes (x compression axis, y width and shear,
 * z up; the camera on the -y side looking along +y). They differ in where y = 0 is: the simulator
 * shears symmetrically (rod_set_clamps: left clamp point at y = -dw l / 2, right at +dw l / 2)
 * while the rig moves only the shear rail (left clamp fixed, right clamp at y = dw l), and the
 * tracker's depth model assumes the rig (left clamp on the plane y = 0, the right one at the shear
 * rail position). The two differ by a rigid translation along y (DESIGN.md section 3), which
 * TWIN_Y_RIG applies; TWIN_Y_SIM keeps the simulator's coordinates. */
#ifndef RIBBON_DAEMON_TWIN_SHAPE_H
#define RIBBON_DAEMON_TWIN_SHAPE_H

#include <stddef.h>

#include "rod.h"
#include "scene.h"
#include "vision.h"

/* Errors of the twin glue (twin_shape.h, twin_camera.h, twin_frames.h); a message says more. */
typedef enum twin_status {
    TWIN_OK = 0,
    TWIN_ERR_ARG,     /* NULL, mismatched sizes, non-finite or out-of-range input */
    TWIN_ERR_NOMEM,   /* allocation failed */
    TWIN_ERR_VISION,  /* the vision module refused (its message is passed on) */
    TWIN_STOPPED      /* a frame callback asked to stop: not a failure by itself */
} twin_status;

const char *twin_status_str(twin_status s);

/* Where y = 0 is (see the top of this file). */
typedef enum twin_y_origin {
    TWIN_Y_RIG = 0,   /* left clamp point on y = 0, right clamp point at y = dw l (the rig) */
    TWIN_Y_SIM        /* the simulator's frame: clamp points at y = -dw l / 2 and +dw l / 2 */
} twin_y_origin;

typedef struct twin_shape {
    int nodes;              /* N of the rods this shape takes */
    size_t n;               /* points: N - 2 */
    twin_y_origin y_origin;
    double *pos;            /* 3 n values, metres */
    double *normal;         /* 3 n values, unit vectors */
    vis_shape view;         /* points into pos / normal; width_m, thickness_m from the scene */
} twin_shape;

/* Sizes `ts` for the scene's mesh (sc->nodes >= 5) and takes the ribbon's width and thickness.
 * The shape holds no state until twin_shape_from_rod. On failure `ts` needs no release. */
twin_status twin_shape_init(twin_shape *ts, const rod_scene *sc, twin_y_origin y, char *why,
                            size_t why_len);
/* Frees the arrays (safe on a zeroed or released shape). */
void twin_shape_release(twin_shape *ts);

/* Fills `ts` from the rod's current state. The rod's reference frames must be current (they are
 * after every accepted step of the solver, e.g. in rod_predict's on_sample callback). Refuses a
 * rod of another size and a non-finite state. No allocation. */
twin_status twin_shape_from_rod(twin_shape *ts, const rod *r, char *why, size_t why_len);

/* out = (1 - w) a + w b point by point, normals renormalised (w in [0, 1]); the three shapes must
 * have the same size (out may be a or b). For frames between two solver steps. No allocation. */
twin_status twin_shape_lerp(twin_shape *out, const twin_shape *a, const twin_shape *b, double w,
                            char *why, size_t why_len);

/* Below this shear (metres) the depth over the shear is not defined well enough to be a profile. */
#define TWIN_DEPTH_MIN_SHEAR_M 1e-4

/* A shape's depth profile as vis_tracker_set_depth_profile takes it (sh: a twin_shape's view, or
 * any vis_shape): for each of the sh->n points its arc fraction along the centreline (from the
 * left clamp point) and its depth over the shear (y relative to the left clamp point over the
 * right one's). frac and depth_rel hold sh->n values. Returns the number of points, or 0 (nothing written worth using) when the shear is
 * below TWIN_DEPTH_MIN_SHEAR_M or the shape is degenerate. No allocation. */
size_t twin_shape_depth_profile(const vis_shape *sh, double *frac, double *depth_rel);

#endif
