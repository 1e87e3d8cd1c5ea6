/* trial_calib.h: the record kept with each trial so that it can be understood and replayed
 * without the rig file: the rig calibration (rails <-> Delta L, Delta W; camera side; camera time
 * offset), the camera calibration the tracker used, the saved video's region of interest and frame
 * rate, the free length and the snap detection settings. Stored as JSON in the trial row
 * (trials.calibration_json); parsed back by replay. Also the trial's config text (the rig file and
 * the scene file as they were, plus the operator's note). */
#ifndef RIBBON_DAEMON_TRIAL_CALIB_H
#define RIBBON_DAEMON_TRIAL_CALIB_H

#include <stddef.h>

#include "rig_config.h"
#include "snap_detect.h"
#include "store.h"
#include "trial_runner.h"
#include "trial_video.h"
#include "vision.h"

/* The camera calibration, frame size and video region of a trial of this rig: mock mode computes
 * the synthetic camera's calibration; rig mode loads camera.calibration. */
int trial_camera_setup(const rig_config *cfg, vis_calib *cal, int *width, int *height, trial_roi *roi,
                       char *why, size_t why_len);

/* The record as JSON text (malloc'ed), or NULL with why. */
char *trial_calib_json(const rig_config *cfg, const vis_calib *cal, trial_roi roi, char *why, size_t why_len);

/* What replay needs back from a record. */
typedef struct trial_record {
    rig_calibration calib;
    vis_calib camera;      /* in the full frame's pixels */
    trial_roi roi;         /* the video's region inside the full frame */
    double fps;
    double length_m;
    double compression;    /* Delta L of the trial */
    snap_params snap;
    double min_quality;
} trial_record;
int trial_record_parse(const char *json, trial_record *out, char *why, size_t why_len);
/* The record's camera calibration in the saved video's pixels (moved by its region of interest). */
void trial_record_video_calib(const trial_record *rec, vis_calib *out);

/* Trial times (s) at which a stored trial entered the checking, shearing and returning states,
 * from its state events; NaN for a state it never entered. */
void trial_state_times(store *st, int64_t id, double *t_check, double *t_shear, double *t_return);

/* The specimen record (store) a rig file describes: [specimen] and the scene's geometry. */
void trial_specimen_from_config(const rig_config *cfg, store_specimen *sp);

/* "# rig file PATH" + its text + "# scene file PATH" + its text (+ "# note: ..."), malloc'ed;
 * NULL when out of memory (a file that cannot be read is noted in the text instead). */
char *trial_config_text(const rig_config *cfg, const char *note);

#endif
