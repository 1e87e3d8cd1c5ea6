/* trial_runner.h: one trial on the rails, as a state machine driven one camera frame at a time.
 *
 *   idle -> compressing -> holding -> checking -> shearing -> snapped -> returning -> done
 *                                        |           `-> (shear limit, no snap) -> returning
 *                                        `-> failed (vision does not see the upper state)
 *   any state -> aborted (abort asked: both rails stop where they are)
 *   any state -> failed  (rail fault: both rails stop, emergency stop of the healthy one)
 *
 * Every loop iteration: poll both rails through rail_pair_poll (a fault of either stops both),
 * convert their positions to (Delta L, Delta W) with the rig calibration, grab the camera frame of
 * this instant (trial_camera: a real camera, or mock mode's digital twin that renders the simulated
 * ribbon where the rails put it), measure it with the tracker, hand the sample, the video frame
 * and every state change and event to the sink (the daemon stores them), feed the snap detector,
 * then take the state machine's next step. Rails move only by commands from here; each state has
 * a time limit; a time limit or a refused command ends the trial as failed with the reason.
 * One thread owns a trial (the rails are not thread-safe); trial_runner_abort may be called from
 * any thread. The runner allocates nothing per frame.
 * Live trials (trial_runner_set_live, rig mode): the same loop, but each iteration takes the next
 * captured frame (trial_capture.h) with its camera time mapped onto the rail clock, and the rails'
 * latest statuses from their polling thread (trial_rail_poller.h), so neither a slow poll nor a
 * slow stage delays a frame's stamp. Frames the loop is too far behind for are stored untracked.
 *
 * Second witness (plan.torque_witness): position-controlled rails do not feel the snap, but a drive
 * that reports a load (torque, following error; mock mode: the twin's shear force) does. From the
 * start of the shear, every fresh shear reading with a load is compared with the one before: once
 * TRIAL_WITNESS_MIN_READINGS readings are in, a change of more than plan.load_jump times the range
 * (max - min) of the loads read so far in this shear is the witness event, at the Delta W of the
 * reading before the jump. In shearing it stops the shear like a camera snap does (the camera keeps
 * watching the pathway); after a camera snap it is still watched for TRIAL_WITNESS_LATE_POLLS shear
 * polls plus two frames, since a load reading may lag the camera, and the event names both. A snap
 * only the witness saw ends the trial snapped at the witness's Delta W, regime "unknown". */
#ifndef RIBBON_DAEMON_TRIAL_RUNNER_H
#define RIBBON_DAEMON_TRIAL_RUNNER_H

#include <math.h>
#include <stdatomic.h>
#include <stddef.h>

#include "rail.h"
#include "rig_calib.h"
#include "trial_cam_watch.h"
#include "trial_calibrate.h"
#include "trial_comp_track.h"
#include "trial_capture.h"
#include "trial_rail_poller.h"
#include "scene.h"
#include "snap_detect.h"
#include "vision.h"

#define TRIAL_WITNESS_MIN_READINGS 5 /* shear readings with a load before a jump may count */
#define TRIAL_WITNESS_LATE_POLLS 2   /* shear polls after a camera snap the witness is watched */

typedef enum trial_state {
    TRIAL_IDLE = 0,
    TRIAL_COMPRESSING,
    TRIAL_HOLDING,
    TRIAL_CHECKING,
    TRIAL_SHEARING,
    TRIAL_SNAPPED,
    TRIAL_RETURNING,
    TRIAL_DONE,
    TRIAL_ABORTED,
    TRIAL_FAILED,
    TRIAL_STATE_COUNT
} trial_state;

const char *trial_state_name(trial_state s);
/* 1 for done, aborted and failed. */
int trial_state_final(trial_state s);

/* Everything a trial needs to know, filled from the rig file by the daemon. */
typedef struct trial_plan {
    rod_scene scene;             /* specimen and protocol: length, compression, shear_rate, shear_max */
    rig_calibration calib;       /* rails <-> Delta L, Delta W; camera side; time offset (rig_calib.h) */
    double compress_speed_mm_s;  /* speed of the compression move */
    double return_speed_mm_s;    /* speed of both rails on the way back */
    double hold_s;               /* time held at the target compression before the check */
    double upper_dz_min;         /* Delta Z the camera must see to start shearing */
    double post_snap_s;          /* longest recording after the snap */
    double min_quality;          /* tracker quality below which a frame counts as unmeasured */
    snap_params snap;            /* online detection (snap_speed, asym_threshold from the scene) */
    double fps;                  /* frames per second of the loop */
    int paced_by_camera;         /* 1: the camera blocks until its next frame; 0: the runner sleeps
                                    on the rails' clock (mock mode, real or virtual) */
    int torque_witness;          /* 1: the shear rail's load (rail_status.load) is a second witness */
    double load_jump;            /* witness threshold, fraction of the load range seen in the shear */
    int frozen_frames;           /* live camera: identical frames in a row that are a frozen image
                                    when a rail moved frozen_move_mm since the first (0 = the
                                    defaults, TRIAL_FROZEN_FRAMES, TRIAL_FROZEN_MOVE_MM) */
    double frozen_move_mm;
    double clamp_tol_mm;         /* > 0: frames are tracked only while the compress rail is within
                                    this of the trial's compression, where the camera calibration's
                                    clamp points are (the session: trial_clamp_tol_mm); others are
                                    stored untracked with the reason "clamp not found". 0: every
                                    frame is tracked */
    double comp_track_from_dl;   /* > 0 (with clamp_tol_mm > 0): compression frames at Delta L at or
                                    above this are tracked with the clamp points moved to where the
                                    compression rail puts them (trial_comp_track.h; the session:
                                    trial_comp_track_from_dl); 0: they are stored untracked */
    vis_calib comp_calib;        /* the camera calibration (clamp points at the trial's compression)
                                    that comp_track_from_dl's frames are placed from */
    double comp_track_budget;    /* > 0 (live trials): a compression frame is tracked only while the
                                    time the compression frames' trackers took stays within this
                                    share of the (monotonic) time since the first of them; the others
                                    are stored untracked (not_tracked 3). 0: every one is tracked */
    double cam_offset_window_s;  /* > 0: the camera's time offset is measured over this much of the
                                    shear's start (trial_cam_watch.h); 0: not measured */
    int cam_offset_measure;      /* 1: the measured offset replaces calib.camera_time_offset_s for
                                    the rest of the trial (camera.time_offset = measure) */
    double cam_clamp_px[2][2];   /* the camera calibration's clamp points (left, right; u, v), px:
                                    where the offset's watch looks for the jaws */
} trial_plan;

/* How near its target a rail counts as arrived (holding starts there), mm. */
#define TRIAL_RAIL_ARRIVED_MM 0.05
/* The compress rail's distance from the trial's compression within which the calibration's clamp
 * points hold: half a pixel, and never less than a rail that has arrived may be off; 0 (no rule)
 * without a scale. The live runner and replays use this one rule. */
static inline double trial_clamp_tol_mm(double px_per_mm)
{
    return px_per_mm > 0 ? fmax(0.5 / px_per_mm, TRIAL_RAIL_ARRIVED_MM) : 0.0;
}

/* A camera as the runner sees it: the frame of time t_s (rail clock) with the clamps at (dl, dw).
 * A real camera ignores dl and dw and blocks until its next frame, returning its time in *t_frame;
 * mock mode's twin advances the simulated ribbon to t_s under those clamp positions and renders it. */
typedef struct trial_camera {
    vis_status (*grab)(void *ctx, double t_s, double dl, double dw, vis_frame *out, double *t_frame,
                       vis_error *err);
    void *ctx;
} trial_camera;

/* One stored sample. kind 0: a fresh rail reading (no frame); kind 1: a camera frame with the rail
 * positions at its time. Measurements are valid only when reason is VIS_REASON_NONE. */
typedef struct trial_sample {
    int kind;
    int not_tracked;             /* kind 1 in a live trial: 1 = skipped (the loop was behind), 2 =
                                    dropped by the pipeline (not in the video), 3 = a compression
                                    frame over plan.comp_track_budget; no measurement */
    long frame;
    double t_s;
    double compress_mm, shear_mm, dl, dw;
    int measured;
    double dz, a, quality;
    vis_reason reason;
} trial_sample;

/* Where the runner's output goes. Every callback is optional; a callback that returns non-zero
 * (e.g. the store refused a write) fails the trial with the reason it wrote. */
typedef struct trial_sink {
    int (*state)(void *user, trial_state s, double t_s, const char *why);
    int (*event)(void *user, double t_s, const char *kind, const char *message);
    int (*sample)(void *user, const trial_sample *s, char *why, size_t why_len);
    int (*frame)(void *user, const vis_frame *f, long index, char *why, size_t why_len);
    void *user;
} trial_sink;

typedef struct trial_result {
    trial_state final;           /* done, aborted or failed */
    char reason[256];            /* why it ended (failures and aborts), "" when done */
    int snapped;                 /* the camera or the load witness saw a snap */
    double snap_dw;              /* valid when snapped: the camera's onset, else the witness's */
    int asymmetric;
    char regime[16];             /* "asymmetric", "symmetric", "no snap", or "unknown" (a snap only
                                    the load witness saw: the camera saw no pathway; or one whose
                                    frames cannot tell: regime_undecided) */
    int regime_undecided;        /* the camera saw the snap but its frames cannot tell the regime
                                    (snap_detect.h): regime "unknown", stored as not measured */
    int vision_snapped;          /* the camera saw the snap */
    int load_witnessed;          /* the shear load jumped (plan.torque_witness) */
    double load_dw;              /* valid when load_witnessed: Delta W of the last reading before
                                    the jump */
    double peak_abs_a;
    double upper_dz;             /* Delta Z seen by the check */
    long frames, measured_frames, rail_readings;
    double duration_s;           /* rail-clock time of the trial */
    /* Live trials (trial_runner_set_live): snap-to-stop latency, from the detection frame's own
     * time to the shear stop command's return and to the first shear reading standing still; NaN
     * when not measured (no camera snap, or the rail was not seen standing). */
    double stop_cmd_latency_s, stop_stand_latency_s;
    long skipped_frames, dropped_frames;
    /* The camera's time offset measured at the shear's start (plan.cam_offset_window_s) and its
     * standard deviation, s; NaN when not measured. */
    double camera_offset_s, camera_offset_sd_s;
} trial_result;

typedef struct trial_runner {
    trial_plan plan;
    rail *compress, *shear;      /* borrowed */
    trial_camera cam;
    vis_tracker *tracker;        /* borrowed */
    trial_sink sink;
    atomic_int abort_requested;
    char abort_reason[128];
    /* live state, for status requests (read under the daemon's lock) */
    _Atomic trial_state state;
    double t0;
    vis_frame *frame;
    snap_detect det;
    /* Live pipeline (rig mode): frames from the capture ring, rails from the poller (borrowed). */
    trial_capture *capture;
    trial_rail_poller *poller;
    trial_cam_watch *cam_watch;  /* the camera's offset at the shear's start (plan.cam_offset_window_s) */
    trial_calibrate *calib;      /* the fit beside the trial (borrowed; NULL = none) */
} trial_runner;

/* Rig mode: frames come from the capture pipeline (camera timestamps, in order, never paced by the
 * loop) instead of cam.grab, and the rails' statuses from the poller thread; every rail command is
 * made under the poller's lock. Call after init, before run. */
void trial_runner_set_live(trial_runner *tr, trial_capture *capture, trial_rail_poller *poller);

/* The fit beside the trial (trial_calibrate.h): the runner feeds it the measured frames, starts it
 * when the hold ends, polls it once a frame and, when the trial is done, ends it after the rails
 * stopped; after a failure or an abort the caller ends it (trial_calibrate_end(c, t, 1), or
 * trial_calibrate_free), after storing the final status. Call after init, before run. */
void trial_runner_set_calibrate(trial_runner *tr, trial_calibrate *calib);

/* Prepares a runner (allocates its frame). The rails, camera and tracker stay the caller's. */
int trial_runner_init(trial_runner *tr, const trial_plan *plan, rail *compress, rail *shear,
                      trial_camera cam, vis_tracker *tracker, trial_sink sink, char *why, size_t why_len);
void trial_runner_free(trial_runner *tr);

/* Runs the trial to its end (done, aborted or failed). Rails are always left stopped. */
void trial_runner_run(trial_runner *tr, trial_result *out);

/* From any thread: ask the running trial to stop (rails stop, trial ends aborted). */
void trial_runner_abort(trial_runner *tr, const char *reason);

#endif
