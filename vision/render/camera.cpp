// camera.cpp: the pinhole camera of the synthetic renderer.
//
// The camera sits on the -y side of the rig and looks at the point (target_x, 0, target_z) from
// distance `distance_m`; `tilt_rad` pitches it so that it looks down onto the scene from above.
// Image axes: u along +x world, v down; the principal point is the image centre in OpenCV's
// pixel-centre convention, ((W-1)/2, (H-1)/2). No lens distortion: the tracker's calibration handles
// real lenses. With tilt 0 a point (x, y, z) lands at
//     u = cu + f (x - tx) / (D + y),   v = cv - f (z - tz) / (D + y),
// which is the model the tracker's depth correction inverts.
#include "vis_internal.hpp"

#include "camera_model.hpp"

namespace vis {

bool camera_valid(const vis_camera &c, vis_error *err)
{
    if (c.width_px < 8 || c.height_px < 8 || c.width_px > 8192 || c.height_px > 8192) {
        fail(err, VIS_ERR_ARG, "camera size %dx%d out of range (8..8192)", c.width_px, c.height_px);
        return false;
    }
    if (!finite(c.focal_px) || c.focal_px <= 0 || !finite(c.distance_m) || c.distance_m <= 0 ||
        !finite(c.tilt_rad) || std::fabs(c.tilt_rad) >= 1.5 || !finite(c.target_x_m) ||
        !finite(c.target_z_m)) {
        fail(err, VIS_ERR_ARG,
             "camera: focal_px and distance_m must be > 0, |tilt_rad| < 1.5, all finite");
        return false;
    }
    return true;
}

bool camera_project(const vis_camera &c, const double p[3], double uv[2])
{
    const double st = std::sin(c.tilt_rad), ct = std::cos(c.tilt_rad);
    // Camera centre, forward (f) and down (d) axes; right is +x.
    const double C[3] = {c.target_x_m, -c.distance_m * ct, c.target_z_m + c.distance_m * st};
    const double f[3] = {0.0, ct, -st};
    const double d[3] = {0.0, -st, -ct};  // f x (1,0,0)
    const double q[3] = {p[0] - C[0], p[1] - C[1], p[2] - C[2]};
    const double xc = q[0];
    const double yc = q[0] * d[0] + q[1] * d[1] + q[2] * d[2];
    const double zc = q[0] * f[0] + q[1] * f[1] + q[2] * f[2];
    if (!(zc > 1e-9))
        return false;
    uv[0] = 0.5 * (c.width_px - 1) + c.focal_px * xc / zc;
    uv[1] = 0.5 * (c.height_px - 1) + c.focal_px * yc / zc;
    return true;
}

}  // namespace vis

extern "C" vis_camera vis_camera_default(void)
{
    vis_camera c;
    c.width_px = 320;
    c.height_px = 240;
    c.focal_px = 1200.0;   // 0.2 m fills 240 px at 1 m
    c.distance_m = 1.0;
    c.tilt_rad = 0.0;
    c.target_x_m = 0.1;
    c.target_z_m = 0.0;
    return c;
}

extern "C" vis_status vis_camera_project(const vis_camera *cam, const double p[3], double uv[2],
                                         vis_error *err)
{
    if (!cam || !p || !uv)
        return vis::fail(err, VIS_ERR_ARG, "vis_camera_project: NULL argument");
    if (!vis::camera_valid(*cam, err))
        return VIS_ERR_ARG;
    if (!vis::finite(p[0]) || !vis::finite(p[1]) || !vis::finite(p[2]))
        return vis::fail(err, VIS_ERR_ARG, "vis_camera_project: point not finite");
    if (!vis::camera_project(*cam, p, uv))
        return vis::fail(err, VIS_ERR_ARG, "point (%g, %g, %g) m is behind the camera", p[0], p[1],
                         p[2]);
    vis::ok(err);
    return VIS_OK;
}

extern "C" vis_status vis_camera_fit(vis_camera *cam, double x0, double x1, double z0, double z1,
                                     double fill, vis_error *err)
{
    if (!cam)
        return vis::fail(err, VIS_ERR_ARG, "vis_camera_fit: NULL camera");
    if (!(x1 > x0) || !(z1 >= z0) || !(fill > 0 && fill <= 1) || !vis::finite(x0) ||
        !vis::finite(x1) || !vis::finite(z0) || !vis::finite(z1))
        return vis::fail(err, VIS_ERR_ARG, "vis_camera_fit: need x1 > x0, z1 >= z0, 0 < fill <= 1");
    if (!vis::camera_valid(*cam, err))
        return VIS_ERR_ARG;
    double f = fill * cam->width_px * cam->distance_m / (x1 - x0);
    if (z1 > z0)
        f = std::min(f, fill * cam->height_px * cam->distance_m / (z1 - z0));
    cam->focal_px = f;
    cam->target_x_m = 0.5 * (x0 + x1);
    cam->target_z_m = 0.5 * (z0 + z1);
    vis::ok(err);
    return VIS_OK;
}
