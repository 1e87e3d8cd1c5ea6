/* mock_camera.h: mock mode's camera, which films a digital twin.
 *
 * The "ribbon" of a mock trial is the simulator itself (sim/rod_twin.h): each grab advances the
 * simulated rod to the grab's time with its clamps where the rails put them, turns the state into
 * a shape (twin_shape.h) and renders it through a fixed synthetic side camera (twin_camera.h). The
 * frames go through the same tracker and snap detector as a real camera's, so a mock trial has a
 * real snap for the vision to find. The twin starts at rest in the upper state at the mounting
 * compression (the compression rail's position when the trial starts). With mock_camera_feed_load
 * the twin's shear force also goes to the mock shear rail's load, the runner's second witness. */
#ifndef RIBBON_DAEMON_MOCK_CAMERA_H
#define RIBBON_DAEMON_MOCK_CAMERA_H

#include <stddef.h>
#include <stdint.h>

#include "rail.h"
#include "rod_snap_watch.h"
#include "scene.h"
#include "twin_camera.h"
#include "vision.h"

typedef struct mock_camera mock_camera;

/* sc: the scene at the twin's resolution (nodes, dt). dl_start: the mounting compression.
 * noise_sigma, blur_sigma_px: image degradations (0 = clean). The camera is the one
 * twin_render_params_for_scene frames; its calibration is twin_calib_for_scene's (trial_calib.c). */
int mock_camera_open(const rod_scene *sc, double dl_start, const twin_camera_params *cp, double noise_sigma,
                     double blur_sigma_px, uint64_t seed, mock_camera **out, char *why,
                     size_t why_len);
void mock_camera_close(mock_camera *mc);

/* trial_camera.grab: advances the twin to t_s (rail clock; the first grab is the twin's time 0)
 * under the clamp placement (dl, dw) and renders it into out. *t_frame = t_s. */
vis_status mock_camera_grab(void *ctx, double t_s, double dl, double dw, vis_frame *out, double *t_frame,
                            vis_error *err);

/* Feeds the twin's shear force (rod_twin_shear_force, N, along +Delta W) into the load of the mock
 * rail shear (rail_mock_set_load) after every grab, so a mock trial's shear drive reports a load
 * as a position-controlled drive with a force sensor would, and feels the snap. NULL stops it.
 * 0, or -1 with the reason when shear is not a mock rail. */
int mock_camera_feed_load(mock_camera *mc, rail *shear, char *why, size_t why_len);

/* The twin's current Delta Z (the truth the tracker should find), for tests and logs. */
double mock_camera_true_dz(mock_camera *mc);

/* The twin's own snap so far (rod_twin_snap: from its own states, every solver step) and its
 * Delta W now (either pointer may be NULL): the truth a trial's measurement is scored against. */
void mock_camera_truth(mock_camera *mc, rod_snap_report *snap, double *dw_now);

#endif
