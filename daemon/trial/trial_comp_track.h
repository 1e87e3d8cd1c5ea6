/* trial_comp_track.h: tracking the compression frames (issue 32 B): the camera calibration's
 * clamp points moved to where the compression rail puts them.
 *
 * The camera calibration's clamp points hold at the trial's compression only. During the
 * compression the runner knows the compression rail's position, so it knows the clamp gap
 * (rig_calib.h: 1000 l (1 - Delta L) mm): the compression clamp (the simulator's right clamp, at
 * +x; on the image's right for a front camera, its left for a back camera, whose image is
 * mirrored) lies farther from the fixed clamp, along the line through the two calibrated points,
 * by 1000 l (Delta L_target - Delta L) mm times the calibration's scale (px_per_mm). Each such
 * frame is measured by a fresh tracker with that calibration (acquired from scratch, as the family
 * benchmark's compression frames, daemon/family/family_film.c), from Delta L >= from_dl on (the
 * last part of the compression, where the strip is in its upper state). */
#ifndef RIBBON_TRIAL_COMP_TRACK_H
#define RIBBON_TRIAL_COMP_TRACK_H

#include "rig_calib.h"
#include "vision.h"

/* A live trial's share of the compression's time its compression frames may spend in their
 * trackers (trial_plan.comp_track_budget): the frames over it are stored untracked, so the loop
 * keeps the camera's pace whatever a fresh tracker costs (docs/trials.md: measured 640 x 480 and
 * 1280 x 720). */
#define TRIAL_COMP_TRACK_LIVE_BUDGET 0.5

/* The first Delta L of the compression tracked by default: the family benchmark's start,
 * max(0.5 c, c - 0.05) for the trial's compression c. */
double trial_comp_track_from_dl(double compression);

/* The calibration base (at the trial's compression dl_target) with its compression clamp point
 * moved to Delta L dl, for a strip of free length length_m. 0 and *out set; -1 (out untouched)
 * when the points cannot be placed: no scale, coincident clamp points, non-finite input, or a
 * Delta L beyond the target (the clamps closer than calibrated, by more than 1e-9). */
int trial_comp_track_calib(const vis_calib *base, rig_camera_side side, double length_m, double dl_target,
                           double dl, vis_calib *out);

/* Measures one compression frame at Delta L dl with a fresh tracker (params tp) on the moved
 * calibration. VIS_OK with *m filled (m->reason VIS_REASON_CLAMP_NOT_FOUND when the points cannot
 * be placed); another status with err set when the tracker fails. */
vis_status trial_comp_track_measure(const vis_track_params *tp, const vis_calib *base, rig_camera_side side,
                                    double length_m, double dl_target, double dl, const vis_frame *f,
                                    vis_measure *m, vis_error *err);

/* The same, and the tracker's traced centreline (vis_tracker_samples) before it is freed: up to
 * max_uv (u, v) pairs into uv, their count in *n_uv (0: none), and the moved calibration into *cal
 * (for mapping them to the plane, vis_calib_curve_to_plane). uv may be NULL (then *n_uv = 0). */
vis_status trial_comp_track_measure_curve(const vis_track_params *tp, const vis_calib *base, rig_camera_side side,
                                          double length_m, double dl_target, double dl, const vis_frame *f,
                                          vis_measure *m, double *uv, size_t max_uv, size_t *n_uv, vis_calib *cal,
                                          vis_error *err);

#endif
