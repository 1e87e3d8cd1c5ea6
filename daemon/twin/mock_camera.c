/* mock_camera.c: the digital twin filmed by a synthetic camera (see mock_camera.h). */
#include "mock_camera.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rail_mock.h"
#include "rod_twin.h"
#include "twin_shape.h"

struct mock_camera {
    rod_twin *twin;
    twin_shape shape;
    vis_renderer *ren;
    int started;
    double t0;
    rail *load_rail;  /* borrowed: the mock shear rail that reports the twin's shear force */
};

int mock_camera_open(const rod_scene *sc, double dl_start, const twin_camera_params *cp, double noise_sigma,
                     double blur_sigma_px, uint64_t seed, mock_camera **out, char *why,
                     size_t why_len)
{
    *out = NULL;
    mock_camera *mc = calloc(1, sizeof *mc);
    if (!mc) {
        snprintf(why, why_len, "mock camera: out of memory");
        return -1;
    }
    char err[256] = "";
    vis_render_params rp;
    vis_error ve = {0};
    if (twin_render_params_for_scene(sc, cp, &rp, err, sizeof err) != TWIN_OK ||
        twin_shape_init(&mc->shape, sc, TWIN_Y_RIG, err, sizeof err) != TWIN_OK) {
        snprintf(why, why_len, "mock camera: %s", err);
        goto fail;
    }
    rp.noise_sigma = noise_sigma;
    rp.blur_sigma_px = blur_sigma_px;
    rp.seed = seed;
    mc->ren = vis_renderer_create(&rp, &ve);
    if (!mc->ren) {
        snprintf(why, why_len, "mock camera: %s", ve.message);
        goto fail;
    }
    if (rod_twin_open(sc, dl_start, &mc->twin, err, sizeof err) != ROD_OK) {
        snprintf(why, why_len, "mock ribbon: %s", err);
        goto fail;
    }
    *out = mc;
    return 0;
fail:
    mock_camera_close(mc);
    return -1;
}

void mock_camera_close(mock_camera *mc)
{
    if (!mc) return;
    rod_twin_close(mc->twin);
    twin_shape_release(&mc->shape);
    vis_renderer_free(mc->ren);
    free(mc);
}

vis_status mock_camera_grab(void *ctx, double t_s, double dl, double dw, vis_frame *out, double *t_frame,
                            vis_error *err)
{
    mock_camera *mc = ctx;
    if (!mc->started) {
        mc->started = 1;
        mc->t0 = t_s;
    }
    char msg[256] = "";
    double t = t_s - mc->t0;
    if (t < rod_twin_time(mc->twin)) t = rod_twin_time(mc->twin);
    if (rod_twin_advance(mc->twin, t, dl, dw, msg, sizeof msg) != ROD_OK ||
        twin_shape_from_rod(&mc->shape, rod_twin_rod(mc->twin), msg, sizeof msg) != TWIN_OK) {
        if (err) {
            err->code = VIS_ERR_INTERNAL;
            snprintf(err->message, sizeof err->message, "mock ribbon: %.200s", msg);
        }
        return VIS_ERR_INTERNAL;
    }
    if (mc->load_rail && rail_mock_set_load(mc->load_rail, rod_twin_shear_force(mc->twin)) != RAIL_OK) {
        if (err) {
            err->code = VIS_ERR_INTERNAL;
            snprintf(err->message, sizeof err->message, "mock ribbon: shear load: %.200s",
                     rail_last_error(mc->load_rail));
        }
        return VIS_ERR_INTERNAL;
    }
    *t_frame = t_s;
    return vis_renderer_draw(mc->ren, &mc->shape.view, out, NULL, err);
}

int mock_camera_feed_load(mock_camera *mc, rail *shear, char *why, size_t why_len)
{
    mc->load_rail = NULL;
    if (!shear) return 0;
    if (rail_mock_set_load(shear, rod_twin_shear_force(mc->twin)) != RAIL_OK) {
        snprintf(why, why_len, "mock camera: cannot feed the shear force to rail %s: %.200s",
                 rail_get_params(shear)->name, rail_last_error(shear));
        return -1;
    }
    mc->load_rail = shear;
    return 0;
}

double mock_camera_true_dz(mock_camera *mc)
{
    rod_obs o;
    rod_twin_observe(mc->twin, &o);
    return o.dz_cam;
}

void mock_camera_truth(mock_camera *mc, rod_snap_report *snap, double *dw_now)
{
    if (snap) rod_twin_snap(mc->twin, snap);
    if (dw_now) *dw_now = rod_twin_dw(mc->twin);
}
