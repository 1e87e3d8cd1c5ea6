/* twin_camera.c: one fixed camera and its calibration per scene (the reasoning is in
 * twin_camera.h: the inextensible ribbon stays inside a spheroid around its clamp points). */
#include "twin_camera.h"

#include <math.h>
#include <stdio.h>

twin_camera_params twin_camera_params_default(void)
{
    twin_camera_params p;
    p.width_px = 640;
    p.height_px = 480;
    p.distance_m = 0.0;
    p.tilt_rad = 0.0;
    p.fill = 0.9;
    return p;
}

void twin_scene_box(const rod_scene *sc, double box[4])
{
    const double l = sc->length, d = l * (1.0 - sc->compression);
    const double c = 1.0 - sc->compression;
    const double h = fmax(0.5 * l * sqrt(fmax(0.0, 1.0 - c * c)), 0.05 * l);
    box[0] = 0.5 * d - 0.5 * l;
    box[1] = 0.5 * d + 0.5 * l;
    box[2] = -h;
    box[3] = h;
}

static twin_status scene_ok(const rod_scene *sc, char *why, size_t why_len)
{
    if (!sc) {
        if (why && why_len) snprintf(why, why_len, "twin camera: NULL scene");
        return TWIN_ERR_ARG;
    }
    if (!(isfinite(sc->length) && sc->length > 0 && isfinite(sc->width) && sc->width > 0 &&
          isfinite(sc->compression) && sc->compression >= 0 && sc->compression < 1)) {
        if (why && why_len)
            snprintf(why, why_len, "twin camera: the scene needs ribbon.length > 0, ribbon.width > 0 and "
                                  "protocol.compression in [0, 1)");
        return TWIN_ERR_ARG;
    }
    return TWIN_OK;
}

twin_status twin_camera_for_scene(const rod_scene *sc, const twin_camera_params *p, vis_camera *cam,
                                  char *why, size_t why_len)
{
    twin_status st = scene_ok(sc, why, why_len);
    if (st != TWIN_OK) return st;
    if (!p || !cam) {
        if (why && why_len) snprintf(why, why_len, "twin camera: NULL parameters or camera");
        return TWIN_ERR_ARG;
    }
    if (!(isfinite(p->distance_m) && p->distance_m >= 0 && isfinite(p->fill) && p->fill > 0 &&
          p->fill <= 1 && isfinite(p->tilt_rad) && fabs(p->tilt_rad) < 1.2)) {
        if (why && why_len)
            snprintf(why, why_len, "twin camera: distance_m must be >= 0, fill in (0, 1], |tilt_rad| < 1.2");
        return TWIN_ERR_ARG;
    }
    vis_camera c = vis_camera_default();
    c.width_px = p->width_px;
    c.height_px = p->height_px;
    c.distance_m = p->distance_m > 0 ? p->distance_m : fmax(5.0 * sc->length, 50.0 * sc->width);
    c.tilt_rad = p->tilt_rad;
    double box[4];
    twin_scene_box(sc, box);
    vis_error ve;
    if (vis_camera_fit(&c, box[0], box[1], box[2], box[3], p->fill, &ve) != VIS_OK) {
        if (why && why_len) snprintf(why, why_len, "twin camera: %s", ve.message);
        return TWIN_ERR_VISION;
    }
    *cam = c;
    return TWIN_OK;
}

twin_status twin_render_params_for_scene(const rod_scene *sc, const twin_camera_params *p,
                                         vis_render_params *rp, char *why, size_t why_len)
{
    if (!rp) {
        if (why && why_len) snprintf(why, why_len, "twin camera: NULL render parameters");
        return TWIN_ERR_ARG;
    }
    vis_render_params r = vis_render_params_default();
    twin_status st = twin_camera_for_scene(sc, p, &r.camera, why, why_len);
    if (st != TWIN_OK) return st;
    r.clamp_length_m = 0.08 * sc->length;
    r.clamp_height_m = 0.06 * sc->length;
    *rp = r;
    return TWIN_OK;
}

twin_status twin_calib_for_scene(const rod_scene *sc, const vis_camera *cam, vis_calib *c, char *why,
                                 size_t why_len)
{
    twin_status st = scene_ok(sc, why, why_len);
    if (st != TWIN_OK) return st;
    if (!cam || !c) {
        if (why && why_len) snprintf(why, why_len, "twin camera: NULL camera or calibration");
        return TWIN_ERR_ARG;
    }
    const double left[3] = {0.0, 0.0, 0.0};
    const double right[3] = {sc->length * (1.0 - sc->compression), 0.0, 0.0};
    vis_calib k = vis_calib_default();
    vis_error ve;
    if (vis_calib_from_camera(&k, cam, left, right, &ve) != VIS_OK) {
        if (why && why_len) snprintf(why, why_len, "twin camera: %s", ve.message);
        return TWIN_ERR_VISION;
    }
    *c = k;
    return TWIN_OK;
}
