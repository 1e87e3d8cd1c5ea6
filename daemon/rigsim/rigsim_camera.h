/* rigsim_camera.h: the rig simulator's camera: a GigE Vision device on 127.0.0.1 (Aravis's fake
 * GigE Vision camera) whose every image is the digital twin rendered at that instant.
 *
 * The twin has its own thread (a real-time priority when the process may): once per camera frame
 * it reads the controller's ACTUAL axis positions (rigsim_rails.h), extrapolates them at the axes'
 * velocity to that frame's send time (the camera's schedule, measured from its sends), turns them
 * into (Delta L, Delta W) with the rig file's calibration, advances the twin (the simulated rod,
 * daemon/twin/mock_camera.h) to the send time and renders it through the synthetic side camera at
 * the rig file's camera size and blur, early enough to be ready before the send; images sent older
 * than half a frame period are counted and noted (rigsim_camera_tick); the sensor's noise
 * (camera.noise_sigma) is added to each image as it is sent, so no two images are the same. So the ribbon
 * follows what the rails really did, not what ribbond commanded. The camera's fill (Aravis's
 * thread, at the frame rate ribbond sets through GenICam) copies the latest image and sets the
 * buffer's timestamp as it leaves (host real-time clock, ns): a slow twin step (the snap needs
 * more Newton iterations) never delays an image; the image is then older than its stamp, which
 * the truth log records. While nobody streams, the twin's clock pauses.
 * Truth log (CSV, one line per image sent): index, host monotonic time of the send, real-time clock
 * time (the camera's timestamp), the axes' actual positions at the send (mm), Delta L, Delta W,
 * the twin's Delta Z in the image, frozen, the twin time the image shows (s), and the image's age
 * at the send beyond the camera's delay (s: send time - delay - the time the twin was stepped to;
 * negative when rendered ahead), and the camera's delay (s: the image shows the instant send time -
 * delay - age). Faults: the camera stops (the device goes away) or the image freezes (the last
 * image is sent again) from a time on. */
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
/* 1 when the twin's thread got a real-time priority (SCHED_FIFO, below the rails' thread). */
int rigsim_camera_twin_realtime(const rigsim_camera *c);
/* One line: images sent and rendered, the twin thread's share of a core, the slowest render, how
 * many images were sent older than half a frame period and the oldest. */
void rigsim_camera_report(rigsim_camera *c, char *out, size_t n);
void rigsim_camera_stop(rigsim_camera *c);
/* The twin's own snap so far (rod_twin_snap, as of the last render) and its Delta W then: the
 * truth a rehearsal trial's measurement is scored against (twin_truth.h prints it). */
void rigsim_camera_twin_truth(rigsim_camera *c, rod_snap_report *snap, double *dw_now);

#endif
