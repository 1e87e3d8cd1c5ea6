/* trial_cam_offset.h: the camera's time offset measured at the start of a shear (issue 34 C).
 *
 * A frame's stamp is not the instant it shows: a camera exposes before it stamps (or stamps at the
 * start of a readout), so what a frame shows happened `offset` from its mapped time (rail clock),
 * t_shown = t_frame + offset (offset < 0 for a camera that stamps after the exposure; the rig file's
 * calibration.camera_time_offset_s is the same quantity, configured). It is measured from what the
 * shear's start shows twice: the shear rail's reconstructed positions (its fresh readings, rail
 * clock) and the shear clamp's image position (found in each frame, vis_find_clamps), which starts
 * to move when the rail does.
 *
 * The model. The rail's readings give its standing position s0 (before the shear command) and its
 * cruise line s0 + v (t - t_r) (readings ramp_s after it first moved): t_r is the rail's virtual
 * start, the instant the cruise line leaves s0, the same for any constant acceleration before it.
 * The clamp's image point is projected on its direction of motion (hold mean -> the last frames),
 * q (px); with X(t) = max(0, v (t - t_r)) the rail's travel by that kinked path,
 *     q_j = a + b X(t_j + offset) + c X(t_j + offset)^2
 * for every frame outside the ramp (frames within ramp_s + search_s of t_r are not used): the
 * quadratic term takes the perspective of a clamp moving along the optical axis (its image moves as
 * D / (D + y)). For each offset on a grid the fit is linear least squares in (a, b, c); the offset
 * is the minimum of the residual sum of squares S, refined by the parabola through its grid
 * neighbours, and its standard deviation sqrt(2 sigma^2 / S''), sigma^2 = S / (n - 4): the
 * curvature of S is the Fisher information of the one nonlinear parameter (the linear ones
 * profiled out). Checked against synthetic series of known offset (test_trial_cam_offset).
 *
 * Storage: the caller sizes the series once (trial_cam_offset_alloc) before the trial's loop;
 * adding a frame or reading never allocates. */
#ifndef RIBBON_TRIAL_CAM_OFFSET_H
#define RIBBON_TRIAL_CAM_OFFSET_H

#include <stddef.h>

typedef struct trial_cam_offset_params {
    double search_s;   /* |offset| searched, s (0.1) */
    double step_s;     /* grid step of the search, s (2e-4) */
    double ramp_s;     /* the rail's acceleration is over this long after it first moved, s (0.25) */
    double min_motion_px; /* the clamp must move at least this far in the image, px (1) */
} trial_cam_offset_params;
trial_cam_offset_params trial_cam_offset_params_default(void);

typedef struct trial_cam_offset_fit {
    double offset_s;    /* t_shown = t_frame + offset_s, s */
    double sd_s;        /* its standard deviation, s */
    double rms_px;      /* residual of the fit, px */
    double motion_px;   /* the clamp's image motion over the frames used, px */
    double speed_mm_s;  /* the rail's cruise speed, mm/s */
    double t_start_s;   /* the rail's virtual start t_r (rail clock), s */
    int frames_used;    /* frames in the fit (standing and cruising) */
    int readings_used;  /* cruise readings in the rail's line */
} trial_cam_offset_fit;

typedef struct trial_cam_offset trial_cam_offset;

/* Room for max_frames frames and max_readings rail readings. NULL when out of memory. */
trial_cam_offset *trial_cam_offset_alloc(size_t max_frames, size_t max_readings);
void trial_cam_offset_free(trial_cam_offset *o);
void trial_cam_offset_clear(trial_cam_offset *o);
/* One frame: its mapped time (rail clock, s, as the runner stamps it, no offset applied) and the
 * two clamp points found in it (px). Ignored when full. */
void trial_cam_offset_add_frame(trial_cam_offset *o, double t_s, const double left_px[2], const double right_px[2]);
/* One fresh reading of the shear rail: its time (rail clock, s) and position (mm). */
void trial_cam_offset_add_reading(trial_cam_offset *o, double t_s, double shear_mm);
size_t trial_cam_offset_frames(const trial_cam_offset *o);

/* The fit (see above). t_cmd_s: when the shear was commanded (readings before it are the standing
 * position). 0 with the fit; -1 with the reason (too few frames or readings, a rail that did not
 * move or move steadily, a clamp that did not move in the image, an offset at the search's edge). */
int trial_cam_offset_estimate(const trial_cam_offset *o, double t_cmd_s, const trial_cam_offset_params *p,
                              trial_cam_offset_fit *out, char *why, size_t why_len);

#endif
