// camera_model.hpp: private pinhole-projection helpers (camera.cpp) used by the renderer.
#ifndef RIBBON_VIS_CAMERA_MODEL_HPP
#define RIBBON_VIS_CAMERA_MODEL_HPP

#include "vis_internal.hpp"
#include "vis_render.h"

namespace vis {
bool camera_valid(const vis_camera &c, vis_error *err);
// World point (m) to pixels; false when the point is behind the camera.
bool camera_project(const vis_camera &c, const double p[3], double uv[2]);
}  // namespace vis

#endif
