// shape_truth.hpp: private ground-truth helpers (shape.cpp) shared with the renderer.
#ifndef RIBBON_VIS_SHAPE_TRUTH_HPP
#define RIBBON_VIS_SHAPE_TRUTH_HPP

#include "vis_internal.hpp"
#include "vis_render.h"

#include <vector>

namespace vis {
struct CurveTruth {
    double length;      // arc length, metres
    double height;      // midpoint height above the clamp line, metres
    double a;           // 2 theta(1/2) - theta(0) - theta(1), radians
    size_t mid_index;   // midpoint lies on segment [mid_index, mid_index + 1]
    double mid_weight;  // at this fraction of it
};
struct ShapeTruth {
    vis_truth truth;
    double mid3[3];     // 3D arc-length midpoint, metres
};
bool shape_valid(const vis_shape *s, vis_error *err);
CurveTruth curve_truth(const std::vector<double> &h, const std::vector<double> &z,
                       const std::vector<double> &seg);
ShapeTruth shape_truth(const vis_shape &sh);
}  // namespace vis

#endif
