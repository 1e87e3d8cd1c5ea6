/* rigsim_camera.h: the rig simulator's camera: a GigE Vision device on 127.0.0.1 (Aravis's fake
 * GigE Vision camera) whose every image is the digital twin at that image's own exposure instant.
 *
 * Three threads (docs/rig-realtime.md, "One state per frame"). The twin's solver (rigsim_twin.h)
 * steps the simulated rod with the controller's ACTUAL axis positions (rigsim_rails.h; up to a
 * render's lead and a frame period ahead of real time, extrapolated at the axes' velocity), lands
 * on every exposure instant of the camera's schedule and logs its state after every step. The
 * render thread knows that schedule exactly (Aravis's fake camera sends when the real-time clock
 * reaches a whole multiple of its frame period), takes the logged state of each exposure instant
 * (interpolated between two steps when the schedule moved) and renders it through the synthetic
 * side camera at the rig file's camera size and blur, ahead of its send. The send (Aravis's
 * thread, at the frame rate ribbond sets through GenICam) takes the newest image whose exposure
 * has come, adds the sensor's noise (camera.noise_sigma) and stamps it with that exposure's
 * instant plus the camera's delay (host real-time clock, ns). When the solver is behind real time
 * (the stiff snap on a loaded machine), the image shows the latest state there is and its stamp
 * says that state's instant: late, never passed off as new; the exposures that follow keep the
 * camera's rate, lagging their schedule and gaining a quarter period a frame back, so a snap
 * filmed late is filmed in as many images; a send waits up to 1.5 frame periods
 * for an image newer than the last, and only a machine that starved the threads longer makes it
 * send the last one again (counted, with the same stamp). Images sent more than half a frame
 * period after the instant they show are counted and noted (rigsim_camera_tick). While nobody
 * streams, the twin's clock pauses.
 * Truth log (CSV, one line per image sent): index, the camera's timestamp on the host's monotonic
 * and real-time clocks (mono_s, real_s), the axes' actual positions at that instant (mm), Delta L,
 * Delta W, the twin's Delta Z in the image, frozen, the twin time the image shows (s), image_age_s
 * (stamp - delay - the instant the image shows: 0 but for a frozen image), the camera's delay (s),
 * sent_mono_s (when the image left), state_exact (0: the solver was behind, the image shows an
 * earlier state than the schedule's) and solver_ahead_s (the solver's latest state against the
 * send: < 0 behind real time). Faults: the camera stops (the device goes away) or the image
 * freezes (the last image is sent again, stamped as it leaves) from a time on. */
#ifndef RIBBON_RIGSIM_CAMERA_H
#define RIBBON_RIGSIM_CAMERA_H

#include <stddef.h>

#include "rig_config.h"
#include "rigsim_rails.h"
#include "rod_snap_watch.h"

typedef struct rigsim_camera rigsim_camera;

typedef struct rigsim_camera_faults {
    double stop_after_s;   /* s after start, < 0 = off: the camera stops sending */
    double freeze_after_s; /* s after start, < 0 = off: the same image from then on */
    double lost_packets;   /* GVSP packets dropped at random, 0..1 (Aravis's gvsp-lost-ratio; the
                              fake camera does not resend): damaged or lost frames */
    double delay_s;        /* the camera's delay from exposure to timestamp, s (>= 0; 0 = none): each
                              image shows the twin (and the axes) this long before its stamp, as a
                              real camera's exposure precedes its timestamp (issue 34 C) */
    double tilt_rad;       /* the camera's pitch, radians (positive looks down; 0 = level): a tilted
                              camera sees the shear (along its optical axis) move the clamp in the
                              image; the calibration written says so */
} rigsim_camera_faults;

/* Serves the camera on 127.0.0.1 with serial number `serial`; sc is the scene at the twin's
 * resolution; dl_start the compression the specimen is mounted at. Writes the calibration that
 * matches it to calib_path (when not NULL). truth_path: the truth log (NULL = none). */
int rigsim_camera_start(const rig_config *cfg, const rod_scene *sc, double dl_start, rigsim_rails *rails,
                        const char *serial, const char *calib_path, const char *truth_path,
                        const rigsim_camera_faults *f, rigsim_camera **out, char *why, size_t why_len);
/* Call now and then from the main loop: applies the scheduled stop, and prints "twin: behind real
 * time: ..." (at most once a second) when images were sent older than half a frame period. 1 once
 * stopped. */
int rigsim_camera_tick(rigsim_camera *c);
long rigsim_camera_frames(rigsim_camera *c);
/* Fault on command: the camera stops sending at the next tick. */
void rigsim_camera_stop_sending(rigsim_camera *c);
/* Fault on command: the image freezes now (the same image is sent from now on). */
void rigsim_camera_freeze(rigsim_camera *c);
/* 1 when the render thread and the twin's solver got a real-time priority (SCHED_FIFO, below the
 * rails' thread, both on one core). */
int rigsim_camera_twin_realtime(const rigsim_camera *c);
/* One line: images sent and rendered, the render thread's and the solver's shares of a core, the
 * slowest render and solver step, how far the solver fell behind real time, the images that showed
 * an older state than their exposure's, repeated the previous one, or were sent older than half a
 * frame period (and the oldest). */
void rigsim_camera_report(rigsim_camera *c, char *out, size_t n);
void rigsim_camera_stop(rigsim_camera *c);
/* The twin's own snap so far (rod_twin_snap, as of the last render) and its Delta W then: the
 * truth a rehearsal trial's measurement is scored against (twin_truth.h prints it). */
void rigsim_camera_twin_truth(rigsim_camera *c, rod_snap_report *snap, double *dw_now);

#endif
