/* rig_calib.c: rail mm <-> Delta L / Delta W for one rig calibration (formulas in rig_calib.h).
 * Pure arithmetic, no allocation; the JSON form of the record is rig_config.c's (it needs the
 * loaded file to say where the record came from). */
#include "rig_calib.h"

double rig_calib_dl(const rig_calibration *c, double length_m, double compress_mm)
{
    return c->compress_sign * (compress_mm - c->compress_zero_mm) / (1000.0 * length_m);
}

double rig_calib_compress_mm(const rig_calibration *c, double length_m, double dl)
{
    return c->compress_zero_mm + c->compress_sign * 1000.0 * length_m * dl;
}

double rig_calib_dw(const rig_calibration *c, double length_m, double shear_mm)
{
    return c->shear_sign * (shear_mm - c->shear_zero_mm) / (1000.0 * length_m);
}

double rig_calib_shear_mm(const rig_calibration *c, double length_m, double dw)
{
    return c->shear_zero_mm + c->shear_sign * 1000.0 * length_m * dw;
}

double rig_calib_gap_mm(const rig_calibration *c, double length_m, double compress_mm)
{
    return 1000.0 * length_m * (1.0 - rig_calib_dl(c, length_m, compress_mm));
}

void rig_calib_gap_model(const rig_calibration *c, double length_m, double *gap_at_zero_mm,
                         double *gap_per_mm)
{
    /* gap = 1000 l - s_c (x - z_c) = (1000 l + s_c z_c) + (-s_c) x */
    if (gap_at_zero_mm) *gap_at_zero_mm = 1000.0 * length_m + c->compress_sign * c->compress_zero_mm;
    if (gap_per_mm) *gap_per_mm = -(double)c->compress_sign;
}

double rig_calib_a_sign(const rig_calibration *c)
{
    return c->camera_side == RIG_CAMERA_BACK ? -1.0 : 1.0;
}

const char *rig_camera_side_name(rig_camera_side s)
{
    return s == RIG_CAMERA_BACK ? "back" : "front";
}
