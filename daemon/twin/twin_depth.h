/* twin_depth.h: a prediction's shapes as the tracker's depth library (vis_depth_library): the
 * states of a simulated run, thinned, each as its depth profile (twin_shape_depth_profile) with
 * its x-z projection, its shear, Delta Z and A as the camera sees them (docs/vision.md, "Depth").
 *
 * Fed from rod_predict's per-step callback (twin_depth_add); a state is kept when its projected
 * Delta Z or A moved by TWIN_DEPTH_STEP_DZ / TWIN_DEPTH_STEP_A, or its shear by
 * TWIN_DEPTH_STEP_SHEAR_MM, since the last one kept, up to TWIN_DEPTH_MAX_SHAPES. States below
 * TWIN_DEPTH_MIN_SHEAR_M of shear have no profile to give and are skipped. Owns its arrays. */
#ifndef RIBBON_DAEMON_TWIN_DEPTH_H
#define RIBBON_DAEMON_TWIN_DEPTH_H

#include <stddef.h>

#include "rod_protocol.h"
#include "twin_shape.h"
#include "vision.h"

#define TWIN_DEPTH_STEP_DZ 0.002
#define TWIN_DEPTH_STEP_A 0.005
#define TWIN_DEPTH_STEP_SHEAR_MM 0.5
#define TWIN_DEPTH_MAX_SHAPES 20000

typedef struct twin_depth {
    twin_shape ts;           /* the state being converted */
    double length_mm;        /* the scene's free length */
    size_t n, cap;           /* shapes kept, room for */
    double *shear_mm, *dz, *a;  /* n each */
    double *frac, *rel;      /* n x ts.n */
    double *xz;              /* n x ts.n x 2: the x-z projection, mm from the left clamp point */
    int full;                /* 1 once TWIN_DEPTH_MAX_SHAPES were kept (later states dropped) */
} twin_depth;

/* Sizes the collector for the scene (rig frame: left clamp on y = 0). On failure nothing needs
 * releasing. */
twin_status twin_depth_init(twin_depth *d, const rod_scene *sc, char *why, size_t why_len);
/* Keeps the rod's state if it moved enough since the last one kept (see above). TWIN_ERR_NOMEM
 * when the arrays cannot grow (the shapes kept so far stay usable). */
twin_status twin_depth_add(twin_depth *d, const rod_sample *s, const rod *r, char *why, size_t why_len);
/* The shapes kept, as the tracker takes them (points into d; valid until the next add or release). */
vis_depth_library twin_depth_library(const twin_depth *d);
void twin_depth_release(twin_depth *d);

#endif
