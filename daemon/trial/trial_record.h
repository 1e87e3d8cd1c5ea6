/* trial_record.h: the record kept with each trial so that it can be understood and replayed
 * without the rig file: the rig calibration (rails <-> Delta L, Delta W; camera side; camera time
 * offset), the camera calibration the tracker used, the saved video's region of interest and frame
 * rate, the free length, the snap detection settings and the scene's creases (pair angle and
 * position, the hinge: fold_hinge_stiffness in N m/rad or "rigid"). Stored as JSON in the trial row
 * (trials.calibration_json); parsed back by replay (trial_record.c). Also the one mapping of a
 * snap's outcome to the regime the store keeps. */
#ifndef RIBBON_TRIAL_RECORD_H
#define RIBBON_TRIAL_RECORD_H

#include <stddef.h>

#include "rig_config.h"
#include "snap_detect.h"
#include "store.h"
#include "trial_video.h"
#include "vision.h"

/* The record as JSON text (malloc'ed), or NULL with why. */
char *trial_record_json(const rig_config *cfg, const vis_calib *cal, trial_roi roi, char *why, size_t why_len);

/* What replay needs back from a record. */
typedef struct trial_record {
    rig_calibration calib;
    vis_calib camera;      /* in the full frame's pixels */
    trial_roi roi;         /* the video's region inside the full frame */
    double fps;
    double length_m;
    double width_m;        /* the ribbon's width, m; 0 in records from before it was kept */
    double compression;    /* Delta L of the trial */
    snap_params snap;
    double min_quality;
} trial_record;
int trial_record_parse(const char *json, trial_record *out, char *why, size_t why_len);
/* The record's camera calibration in the saved video's pixels (moved by its region of interest). The
 * principal point is moved too; records from before trial_camera_setup gave it (negative: the image's
 * centre) keep it negative, so their replays take the cropped video's centre. */
void trial_record_video_calib(const trial_record *rec, vis_calib *out);
/* The tracker's parameters for the record's video (`video_cal` from trial_record_video_calib): the
 * known length, and sized to the ribbon's face as the trial's tracker was
 * (vis_track_params_for_ribbon); the defaults for a record without the width. */
vis_track_params trial_record_track_params(const trial_record *rec, const vis_calib *video_cal);

/* The regime stored for a snap: no snap; unknown when only the load witness saw it (no frames to
 * read the pathway from) or the frames cannot tell it (pass seen_by_camera = 0 then: snap_detect.h,
 * SNAP_REGIME_UNDECIDED); else asymmetric or symmetric. Predictions and replays see every snap
 * (seen_by_camera = snapped). */
store_regime trial_regime_of(int snapped, int seen_by_camera, int asymmetric);

#endif
