// view_model.cpp: how the tracker maps image points to the ribbon's plane and back.
//
// The camera is the renderer's pinhole (camera.cpp): it looks along +y at the point T where its
// optical axis meets the plane y = 0, from distance D along that axis, pitched down by `tilt`. A
// pixel defines a ray; the tracker intersects it with the plane y = depth (the depth of that part
// of the ribbon, from the shear rail position) and keeps the (x, z) of the intersection, in mm
// relative to T. With the camera axes r = (1, 0, 0), d = (0, -sin t, -cos t), f = (0, cos t, -sin t)
// and centre C = T + D (0, -cos t, sin t), pixel (u, v) has the ray direction
//     F f + (u - cu) r + (v - cv) d,     F = focal length in pixels = px_per_mm * D,
// and a point q = P - C projects back to (cu + F q.r / q.f, cv + F q.d / q.f).
// Without a camera distance (D = 0) the model is a plain scale: x = (u - cu) / px_per_mm,
// z = -(v - cv) / px_per_mm (no depth, no tilt).
#include "tracker_impl.hpp"

namespace vis {

Pt view_to_metric(const ViewModel &m, Pt uv, double depth)
{
    const double du = uv.x - m.principal.x, dv = uv.y - m.principal.y;
    if (!(m.D > 0))
        return Pt(du / m.ppmm, -dv / m.ppmm);
    const double ct = std::cos(m.tilt), st = std::sin(m.tilt), F = m.ppmm * m.D;
    const double dir_y = F * ct - dv * st, dir_z = -F * st - dv * ct;
    if (!(std::fabs(dir_y) > 1e-12))
        return Pt(NAN, NAN);  // a ray parallel to the plane: no intersection
    const double lambda = (depth + m.D * ct) / dir_y;
    return Pt(lambda * du, m.D * st + lambda * dir_z);
}

Pt view_to_image(const ViewModel &m, Pt xz, double depth)
{
    if (!(m.D > 0))
        return Pt(m.principal.x + xz.x * m.ppmm, m.principal.y - xz.y * m.ppmm);
    const double ct = std::cos(m.tilt), st = std::sin(m.tilt), F = m.ppmm * m.D;
    const double yc = -st * depth - ct * xz.y;
    const double zc = ct * depth + m.D - st * xz.y;
    if (!(zc > 1e-9))
        return Pt(NAN, NAN);  // behind the camera
    return Pt(m.principal.x + F * xz.x / zc, m.principal.y + F * yc / zc);
}

}  // namespace vis
