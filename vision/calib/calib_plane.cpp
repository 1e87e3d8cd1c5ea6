/* calib_plane.cpp: the tracker's centreline (pixels) mapped back into the rig's plane y = 0 through
 * the calibration's camera model (vis_calib.h): the inverse of the projection the tracker's view
 * model makes (vision/track/view_model.cpp, view_to_metric), with no depth (no shear). Owned here
 * because it is the calibration's camera model; the family benchmark's films and the fit beside a
 * trial both take the strip's shape through it (issue 32 A/B). */
#include <cmath>

#include "vis_calib.h"

extern "C" void vis_calib_curve_to_plane(const vis_calib *cal, int w, int h, double length_mm, const double *uv,
                                         int n, double *xz)
{
    const bool given = cal->principal_px[0] >= 0 && cal->principal_px[1] >= 0;
    const double pu = given ? cal->principal_px[0] : 0.5 * (w - 1);
    const double pv = given ? cal->principal_px[1] : 0.5 * (h - 1);
    const double ppmm = cal->px_per_mm, D = cal->camera_distance_mm, ct = std::cos(cal->camera_tilt_rad),
                 st = std::sin(cal->camera_tilt_rad);
    double x0 = 0.0, z0 = 0.0;
    for (int i = -1; i < n; i++) {
        const double u = i < 0 ? cal->clamp_left_px[0] : uv[2 * i], v = i < 0 ? cal->clamp_left_px[1] : uv[2 * i + 1];
        const double du = u - pu, dv = v - pv;
        double x, z;
        if (!(D > 0)) {
            x = du / ppmm;
            z = -dv / ppmm;
        } else {
            const double F = ppmm * D, dir_y = F * ct - dv * st, dir_z = -F * st - dv * ct;
            const double lambda = (D * ct) / dir_y;
            x = lambda * du;
            z = D * st + lambda * dir_z;
        }
        if (i < 0) {
            x0 = x;
            z0 = z;
            continue;
        }
        xz[2 * i] = (x - x0) / length_mm;
        xz[2 * i + 1] = (z - z0) / length_mm;
    }
}
