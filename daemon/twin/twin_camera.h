/* twin_camera.h: the synthetic side camera that films a simulated trial, and its calibration.
 *
 * Owns the choice of one fixed camera for a scene's whole protocol (the rig's camera does not
 * move during a trial either), so every frame of a render or of a mock-mode trial shares one
 * calibration, and the tracker sees what it would see on the rig.
 *
 * The box the ribbon can occupy. The free length l is (nearly) inextensible, so every point P of
 * it satisfies |P - A| + |P - B| <= l with A, B the clamp points: the ribbon stays inside the
 * spheroid with foci at the clamps and major axis l. At compression Delta L and no shear the clamps
 * are d = l (1 - Delta L) apart, and the spheroid's trace on the camera's x-z plane is the
 * ellipse centred at (d / 2, 0) with semi-axes l / 2 along x and
 *     h = (l / 2) sqrt(1 - (1 - Delta L)^2)
 * along z (0.433 l at Delta L = 0.5, 0.357 l at 0.3): the highest the arch, or the lowest the
 * snapped state, can ever be (two straight halves meeting at the apex). Shear moves the foci
 * apart, which only shrinks the minor axes and keeps the x extent within d / 2 +- l / 2, so the
 * unsheared box bounds the whole protocol: x in [d/2 - l/2, d/2 + l/2], z in [-h, h]
 * (h at least 0.05 l, so an uncompressed scene is framed too). The flat clamps keep real shapes
 * well inside it: the paper scene's upper arch is 0.37 l high and its snapped state 0.23 l deep.
 *
 * Distance: the camera looks along the ribbon's width, so a wide ribbon seen from close by shows
 * its near and far edges at different heights (perspective thickening of about z w / D for a
 * point z off the axis). The automatic distance max(5 l, 50 w) keeps that to a few pixels: 10 m
 * for the paper's 1 m x 0.2 m ribbon, 1 m for the 200 x 5 mm PET specimen (the rig's). */
#ifndef RIBBON_DAEMON_TWIN_CAMERA_H
#define RIBBON_DAEMON_TWIN_CAMERA_H

#include "scene.h"
#include "twin_shape.h"
#include "vision.h"

typedef struct twin_camera_params {
    int width_px;        /* image width, pixels (640) */
    int height_px;       /* image height, pixels (480) */
    double distance_m;   /* camera centre to the plane y = 0, metres (0 = automatic: max(5 l, 50 w)) */
    double tilt_rad;     /* pitch, positive looks down onto the ribbon, radians (0) */
    double fill;         /* share of the tighter image side the box fills, (0, 1] (0.9) */
} twin_camera_params;

twin_camera_params twin_camera_params_default(void);

/* The box the ribbon can occupy over the whole protocol (see above), in the plane y = 0, metres:
 * box = {x0, x1, z0, z1}. */
void twin_scene_box(const rod_scene *sc, double box[4]);

/* A camera that frames twin_scene_box for the scene. */
twin_status twin_camera_for_scene(const rod_scene *sc, const twin_camera_params *p, vis_camera *cam,
                                  char *why, size_t why_len);

/* Renderer parameters around that camera: vis_render_params_default() with the camera set and the
 * clamp jaws scaled to the scene (0.08 l long, 0.06 l high, as the 15 x 12 mm jaws at l = 0.2 m). */
twin_status twin_render_params_for_scene(const rod_scene *sc, const twin_camera_params *p,
                                         vis_render_params *rp, char *why, size_t why_len);

/* The calibration that matches `cam` for this scene: clamp points at zero shear and the scene's
 * compression, (0, 0, 0) and (l (1 - Delta L), 0, 0), scale, distance and tilt from the camera.
 * Track the frames with shear_mm = the right clamp's y in mm (TWIN_Y_RIG shapes), i.e. dw l. */
twin_status twin_calib_for_scene(const rod_scene *sc, const vis_camera *cam, vis_calib *c, char *why,
                                 size_t why_len);

#endif
