/* trial.h: the trial room's face: what the rest of the program uses of daemon/trial/. Everything
 * outside this folder includes this header only; the other headers here are named after the file
 * that implements them and are the room's own.
 *
 *   snap_detect.h        the snap in a stream of measured frames (the simulator's definition)
 *   predict_ladder.h     the resolution ladder of a trial's prediction, its run-time estimate
 *   trial_runner.h       one trial on the rails as a state machine (rails, camera, tracker, sink)
 *   trial_video.h        the lossless, cropped video every trial keeps
 *   trial_transcode.h    a rig trial's raw video to FFV1 after the trial, verified bit for bit
 *   trial_transcoder.h   the daemon's background worker doing that, off the real-time path
 *   trial_record.h       the record stored with each trial (calibration, ROI, snap settings) and
 *                        the one mapping of a snap's outcome to a stored regime
 *   trial_err.h          the room's typed status (refused, not found, failed)
 *   trial_session.h      one trial from request to stored result, on its own thread
 *   trial_replay.h       a recording through the same pipeline again
 *   replay_job.h         a replay on a thread of its own inside ribbond
 *   trial_config_text.h  the configuration text stored with a trial, and its scene read back
 *   trial_pool.h         stored trials of one strip pooled into one fit's input
 * Used inside the room only: trial_prediction.h (the prediction beside a trial),
 * trial_camera_setup.h, trial_calibrate.h (the fit beside a trial),
 * trial_specimen.h, trial_publish.h (the session's hook
 * into the live page's bus). */
#ifndef RIBBON_TRIAL_H
#define RIBBON_TRIAL_H

#include "trial_err.h"
#include "snap_detect.h"
#include "predict_ladder.h"
#include "trial_runner.h"
#include "trial_capture.h"
#include "trial_video.h"
#include "trial_transcode.h"
#include "trial_transcoder.h"
#include "trial_record.h"
#include "trial_session.h"
#include "trial_replay.h"
#include "replay_job.h"
#include "trial_config_text.h"
#include "trial_pool.h"
#include "trial_calibrate.h"
#include "trial_camera_settings.h"

#endif
