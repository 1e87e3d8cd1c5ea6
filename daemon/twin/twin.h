/* twin.h: the twin room's face: what the rest of the program uses of daemon/twin/ (the digital
 * twin as the camera sees it). Everything outside this folder includes this header only.
 *
 *   twin_shape.h    a simulated rod state as the vision's shape (centreline, width, twist)
 *   twin_depth.h    a prediction's shapes as the tracker's depth library
 *   twin_camera.h   the camera that frames a scene (render parameters, its calibration)
 *   twin_frames.h   the frame clock of a simulated run (which states become frames)
 *   mock_camera.h   mock mode's camera: the twin stepped with the mock rails' positions, rendered
 *   twin_truth.h    the twin's truth as text: its parameters and its own snap (events, logs) */
#ifndef RIBBON_TWIN_H
#define RIBBON_TWIN_H

#include "twin_shape.h"
#include "twin_depth.h"
#include "twin_camera.h"
#include "twin_frames.h"
#include "mock_camera.h"
#include "twin_truth.h"

#endif
