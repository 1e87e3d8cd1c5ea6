/* rig_calib.h: the rig calibration record stored with every trial, and the conversions between
 * rail coordinates (mm) and the simulator's normalised Delta L and Delta W.
 *
 * Conventions (DESIGN.md section 3): Delta L = dl / l with dl > 0 when the clamps get CLOSER
 * (compression), Delta W = dw / l with dw the shear clamp's displacement along the simulator's +y;
 * l is the scene's free length (ribbon.length, m). A rail coordinate is the drive's own position
 * in mm. With z_c = compress_zero_mm, s_c = compress_sign, z_s = shear_zero_mm, s_s = shear_sign:
 *
 *     Delta L = s_c (compress_mm - z_c) / (1000 l)     compress_mm = z_c + s_c 1000 l Delta L
 *     Delta W = s_s (shear_mm   - z_s) / (1000 l)     shear_mm    = z_s + s_s 1000 l Delta W
 *     clamp gap (mm) = 1000 l (1 - Delta L) = gap_at_zero_mm + gap_per_mm * compress_mm
 *       with gap_at_zero_mm = 1000 l + s_c z_c and gap_per_mm = -s_c        (drivers/rail.h)
 *
 * So s_c = +1 when moving the compression rail toward larger positions closes the clamps, and
 * s_s = +1 when moving the shear rail toward larger positions moves the shear clamp toward +y.
 * The zero of the compression rail is MEASURED (the clamp gap equals the free length there), not
 * driven to: two creases of one sign cannot be clamped flat at Delta L = 0. A camera looking from
 * the back sees the ribbon mirrored, which flips the sign of the asymmetry A (not of Delta Z). */
#ifndef RIBBON_CONFIG_RIG_CALIB_H
#define RIBBON_CONFIG_RIG_CALIB_H

/* Which side of the rig the camera looks from. */
typedef enum rig_camera_side {
    RIG_CAMERA_FRONT = 0, /* on the -y side, looking along +y (vision.h's convention): A as seen */
    RIG_CAMERA_BACK       /* on the +y side: the image is mirrored, A changes sign */
} rig_camera_side;

typedef struct rig_calibration {
    double compress_zero_mm;     /* mm, compression rail position where the clamp gap equals the
                                    free length (Delta L = 0); measured, not driven to */
    double shear_zero_mm;        /* mm, shear rail position where the clamps are aligned (Delta W = 0) */
    int compress_sign;           /* +1 or -1, see above */
    int shear_sign;              /* +1 or -1, see above */
    rig_camera_side camera_side; /* front or back */
    double camera_time_offset_s; /* s, add to a frame's timestamp to get the rails' clock time */
} rig_calibration;

/* Rail position (mm) -> Delta L / Delta W, and back. length_m is the free length l (> 0). */
double rig_calib_dl(const rig_calibration *c, double length_m, double compress_mm);
double rig_calib_compress_mm(const rig_calibration *c, double length_m, double dl);
double rig_calib_dw(const rig_calibration *c, double length_m, double shear_mm);
double rig_calib_shear_mm(const rig_calibration *c, double length_m, double dw);
/* Clamp gap (mm) at a compression rail position. */
double rig_calib_gap_mm(const rig_calibration *c, double length_m, double compress_mm);
/* The drivers' gap model (rail_params.gap_at_zero_mm, gap_per_mm) this calibration implies. */
void rig_calib_gap_model(const rig_calibration *c, double length_m, double *gap_at_zero_mm,
                         double *gap_per_mm);
/* +1 for a front camera, -1 for a back camera: multiply the tracker's A by it. */
double rig_calib_a_sign(const rig_calibration *c);

const char *rig_camera_side_name(rig_camera_side s); /* "front" / "back" */

/* The record as compact JSON (malloc'd, free() it; NULL when out of memory):
 * {"compress_zero_mm":..,"shear_zero_mm":..,"compress_sign":1,"shear_sign":1,
 * "camera_side":"front","camera_time_offset_s":0,"free_length_mm":1000,"gap_at_zero_mm":..,
 * "gap_per_mm":-1}. The last three are derived from length_m (the scene's free length, m), for
 * readers of the store that do not load the scene. Non-finite numbers are written as null. */
char *rig_calib_json(const rig_calibration *c, double length_m);

#endif
