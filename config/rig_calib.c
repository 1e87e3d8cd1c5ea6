/* rig_calib.c: rail mm <-> Delta L / Delta W for one rig calibration (formulas in rig_calib.h).
 * Pure arithmetic, no allocation, except the record's JSON form (jansson), which sits beside
 * the record it writes. */
#include "rig_calib.h"

#include <jansson.h>
#include <math.h>

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

static char *json_finish(json_t *o)
{
    if (!o) return NULL;
    char *s = json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
    json_decref(o);
    return s;
}

/* A number, or null when not finite (never NaN in JSON). */
static json_t *json_num(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

char *rig_calib_json(const rig_calibration *c, double length_m)
{
    if (!c) return NULL;
    double gap0, gap_per;
    rig_calib_gap_model(c, length_m, &gap0, &gap_per);
    json_t *o = json_object();
    if (!o) return NULL;
    int bad = 0;
    bad |= json_object_set_new(o, "compress_zero_mm", json_num(c->compress_zero_mm));
    bad |= json_object_set_new(o, "shear_zero_mm", json_num(c->shear_zero_mm));
    bad |= json_object_set_new(o, "compress_sign", json_integer(c->compress_sign));
    bad |= json_object_set_new(o, "shear_sign", json_integer(c->shear_sign));
    bad |= json_object_set_new(o, "camera_side",
                               json_string(rig_camera_side_name(c->camera_side)));
    bad |= json_object_set_new(o, "camera_time_offset_s", json_num(c->camera_time_offset_s));
    bad |= json_object_set_new(o, "free_length_mm", json_num(1000.0 * length_m));
    bad |= json_object_set_new(o, "gap_at_zero_mm", json_num(gap0));
    bad |= json_object_set_new(o, "gap_per_mm", json_num(gap_per));
    if (bad) {
        json_decref(o);
        return NULL;
    }
    return json_finish(o);
}
