/* family_film.c: a twin's protocol states, rendered and tracked into fit observations
 * (family.h).
 *
 * The twin is taken through the protocol by static solves (the shear at 1 mm/s is slow against
 * the strip's own dynamics until close to the snap, rod_quasi.h): the route to its upper state at
 * the first compression, then each frame's (Delta L, Delta W) in protocol order, in steps of at
 * most 0.01, halved on failure. Each state is drawn by the synthetic side camera that frames the
 * scene (twin_camera.h: the rig's 640 x 480 with its noise and blur; one camera for the whole
 * protocol, as on the rig) and measured by the tracker, as mock mode's camera does. The tracker's
 * calibration is twin_calib_for_scene's: during the compression the clamp points are where the
 * compression rail puts them (the runner knows the rail's position), so each compression frame
 * gets the calibration at its own Delta L and is acquired from scratch; the hold and shear
 * frames go through one tracker in order, with the shear rail's position for the depth
 * correction (the tracker's own default depth profile, as a trial's). */
#include "family.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rod_observe.h"
#include "rod_route.h"
#include "rod_snapshot.h"
#include "rod_solver.h"
#include "twin.h"

#define FILM_STEP 0.01      /* largest Delta L or Delta W between two static solves */
#define FILM_HALVINGS 12    /* cap on halvings of one step */

family_film_opts family_film_opts_default(const rod_scene *sc)
{
    return (family_film_opts){.n_compress = 20,
                              .dl_start = fmax(0.5 * sc->compression, sc->compression - 0.05),
                              .n_hold = 20,
                              .n_shear = 30,
                              .dw_stop = 0.0,
                              .width_px = 640,
                              .height_px = 480,
                              .noise_sigma = 2.0,
                              .blur_sigma_px = 0.8,
                              .seed = 1,
                              .n_shapes = 0,
                              .shape_points = 24};
}

void family_film_free(family_film *f)
{
    if (!f) return;
    free(f->obs);
    free(f->true_dz);
    free(f->true_a);
    free(f->true_shapes);
    free(f->tracked_shapes);
    f->obs = NULL;
    f->true_dz = f->true_a = NULL;
    f->true_shapes = f->tracked_shapes = NULL;
}

typedef struct film_ctx {
    const rod_scene *sc;
    rod *r;
    rod_solver *s;
    rod_snapshot tmp;
    rod_newton_opts nopt;
    double *k1;
    double dl, dw;          /* where the rod's equilibrium is */
    double dl_min;          /* the lowest compression with an upper state filmed (dl_start or above) */
    twin_shape shape;
    vis_renderer *ren;
    vis_camera cam;
    vis_frame *frame;
    vis_tracker *tracker;   /* the hold and shear tracker */
    int width_px, height_px;
} film_ctx;

static rod_status solve_at(film_ctx *c, double dl, double dw)
{
    rod_set_clamps(c->r, dl, dw);
    rod_frames_update(c->r);
    rod_newton_report rep;
    rod_status st = rod_newton_solve(c->r, c->s, &c->nopt, &rep);
    if (st != ROD_OK) return st;
    rod_obs o;
    rod_observe(c->r, c->k1, &o);
    return o.dz > 0.0 ? ROD_OK : ROD_ERR_BRANCH_LOST;
}

/* From the equilibrium at (c->dl, c->dw) to (dl, dw) by static solves. */
static rod_status step_to(film_ctx *c, double dl, double dw)
{
    double span = fmax(fabs(dl - c->dl), fabs(dw - c->dw));
    double t = 0.0, h = span > FILM_STEP ? FILM_STEP / span : 1.0;
    int halvings = 0;
    rod_status st = ROD_OK;
    while (t < 1.0) {
        double tn = fmin(1.0, t + h);
        rod_snapshot_save(c->r, &c->tmp);
        st = solve_at(c, c->dl + tn * (dl - c->dl), c->dw + tn * (dw - c->dw));
        if (st == ROD_OK) {
            t = tn;
            continue;
        }
        rod_snapshot_load(c->r, &c->tmp);
        if (++halvings > FILM_HALVINGS) return st;
        h *= 0.5;
    }
    c->dl = dl;
    c->dw = dw;
    return ROD_OK;
}

#define CURVE_MAX 2048 /* most traced centreline points taken from the tracker */

/* Renders the rod's state and measures it with t (fresh: NULL, a tracker for this Delta L is
   made). With curve, the tracked centreline mapped to the plane (over l) goes there and *n_curve
   says how many points (0: none). */
static int film_frame(film_ctx *c, vis_tracker *t, vis_measure *m, double *curve, int *n_curve, char *why,
                      size_t why_len)
{
    vis_calib own_cal = vis_calib_default();
    char err[256] = "";
    vis_error ve = {0};
    if (twin_shape_from_rod(&c->shape, c->r, err, sizeof err) != TWIN_OK) {
        snprintf(why, why_len, "family film: %s", err);
        return -1;
    }
    if (vis_renderer_draw(c->ren, &c->shape.view, c->frame, NULL, &ve) != VIS_OK) {
        snprintf(why, why_len, "family film: render: %s", ve.message);
        return -1;
    }
    vis_tracker *own = NULL;
    if (!t) {
        rod_scene at = *c->sc;
        at.compression = c->dl;
        vis_calib cal;
        vis_track_params tp = vis_track_params_default();
        tp.length_mm = 1e3 * c->sc->length;
        if (twin_calib_for_scene(&at, &c->cam, &cal, err, sizeof err) != TWIN_OK) {
            snprintf(why, why_len, "family film: calibration: %s", err);
            return -1;
        }
        own_cal = cal;
        own = t = vis_tracker_create(&tp, &cal, &ve);
        if (!t) {
            snprintf(why, why_len, "family film: tracker: %s", ve.message);
            return -1;
        }
    }
    vis_status vs = vis_tracker_process(t, c->frame, 1e3 * c->dw * c->sc->length, m, &ve);
    if (curve) {
        *n_curve = 0;
        if (vs == VIS_OK && own && m->reason == VIS_REASON_NONE) {
            double uv[2 * CURVE_MAX];
            size_t nc = vis_tracker_samples(own, uv, CURVE_MAX);
            if (nc > CURVE_MAX) nc = CURVE_MAX;
            vis_calib_curve_to_plane(&own_cal, c->width_px, c->height_px, 1e3 * c->sc->length, uv, (int)nc, curve);
            *n_curve = (int)nc;
        }
    }
    vis_tracker_free(own);
    if (vs != VIS_OK) {
        snprintf(why, why_len, "family film: track: %s", ve.message);
        return -1;
    }
    return 0;
}

static int film_setup(film_ctx *c, const rod_scene *twin, const family_film_opts *o, char *why, size_t why_len)
{
    char err[256] = "";
    vis_error ve = {0};
    twin_camera_params cp = twin_camera_params_default();
    cp.width_px = o->width_px;
    cp.height_px = o->height_px;
    vis_render_params rp;
    if (twin_render_params_for_scene(twin, &cp, &rp, err, sizeof err) != TWIN_OK ||
        twin_shape_init(&c->shape, twin, TWIN_Y_RIG, err, sizeof err) != TWIN_OK) {
        snprintf(why, why_len, "family film: %s", err);
        return -1;
    }
    c->cam = rp.camera;
    c->width_px = o->width_px;
    c->height_px = o->height_px;
    rp.noise_sigma = o->noise_sigma;
    rp.blur_sigma_px = o->blur_sigma_px;
    rp.seed = o->seed;
    c->ren = vis_renderer_create(&rp, &ve);
    c->frame = vis_frame_alloc(o->width_px, o->height_px, 1, &ve);
    if (!c->ren || !c->frame) {
        snprintf(why, why_len, "family film: %s", ve.message);
        return -1;
    }
    vis_calib cal;
    vis_track_params tp = vis_track_params_default();
    tp.length_mm = 1e3 * twin->length;
    if (twin_calib_for_scene(twin, &c->cam, &cal, err, sizeof err) != TWIN_OK) {
        snprintf(why, why_len, "family film: calibration: %s", err);
        return -1;
    }
    c->tracker = vis_tracker_create(&tp, &cal, &ve);
    if (!c->tracker) {
        snprintf(why, why_len, "family film: tracker: %s", ve.message);
        return -1;
    }
    if (rod_alloc(twin, &c->r, why, why_len) != ROD_OK) return -1;
    c->s = rod_solver_alloc(c->r);
    c->k1 = malloc(sizeof(double) * (size_t)c->r->n);
    if (!c->s || !c->k1 || !rod_snapshot_alloc(c->r, &c->tmp)) {
        snprintf(why, why_len, "family film: out of memory");
        return -1;
    }
    c->nopt = rod_newton_opts_static(twin);
    c->nopt.positive_definite = 1;
    rod_scene first = *twin;
    first.compression = o->n_compress > 0 ? o->dl_start : twin->compression;
    rod_route_report rep = {0};
    rod_status st = rod_route_to_state(c->r, c->s, &first, +1, &rep);
    if (st != ROD_OK && first.compression < twin->compression) {
        /* No upper state at the first compression (a soft strip with steep creases sags into the
           lower one under gravity): reach it at the full compression and walk back down as far
           as it goes; the compression is filmed from there. */
        first.compression = twin->compression;
        rep = (rod_route_report){0};
        st = rod_route_to_state(c->r, c->s, &first, +1, &rep);
        if (st == ROD_OK) {
            c->dl = twin->compression;
            c->dw = 0.0;
            double h = 0.005;
            while (c->dl - h >= o->dl_start - 1e-12 && step_to(c, c->dl - h, 0.0) == ROD_OK) continue;
            c->dl_min = c->dl;
            return 0;
        }
    }
    if (st != ROD_OK) {
        snprintf(why, why_len, "family film: no upper state at Delta L %.4f: %s", first.compression,
                 rod_status_message(st));
        return -1;
    }
    c->dl = c->dl_min = first.compression;
    c->dw = 0.0;
    return 0;
}

static void film_release(film_ctx *c)
{
    rod_snapshot_free(&c->tmp);
    free(c->k1);
    rod_solver_free(c->s);
    rod_free(c->r);
    vis_tracker_free(c->tracker);
    vis_frame_free(c->frame);
    vis_renderer_free(c->ren);
    twin_shape_release(&c->shape);
}

int family_film_run(const rod_scene *twin, const family_film_opts *o, family_film *out, char *why,
                    size_t why_len)
{
    memset(out, 0, sizeof *out);
    int nsh = o->dw_stop > 0.0 ? o->n_shear : 0;
    int total = o->n_compress + o->n_hold + nsh;
    if (o->n_compress < 0 || o->n_hold < 0 || nsh < 0 || total < 1 || !(o->dl_start > 0.0) ||
        o->dl_start > twin->compression || !(o->dw_stop >= 0.0)) {
        snprintf(why, why_len, "family film: bad frame counts or Delta L / Delta W range");
        return -1;
    }
    out->obs = calloc((size_t)total, sizeof *out->obs);
    out->true_dz = calloc((size_t)total, sizeof(double));
    out->true_a = calloc((size_t)total, sizeof(double));
    film_ctx c = {.sc = twin};
    int rc = -1;
    double s_shape = 0.0, m_shape_x = 0.0, m_shape_z = 0.0;
    double *curve = malloc(sizeof(double) * 2 * CURVE_MAX);
    int nsh_max = o->n_shapes > 0 ? o->n_shapes : 1;
    out->true_shapes = calloc((size_t)nsh_max, sizeof *out->true_shapes);
    out->tracked_shapes = calloc((size_t)nsh_max, sizeof *out->tracked_shapes);
    if (o->n_shapes < 0 || (o->n_shapes > 0 && (o->shape_points < 1 || o->shape_points > ROD_SHAPE_MAX_POINTS))) {
        snprintf(why, why_len, "family film: bad shape count or points per shape");
        goto done;
    }
    if (!out->obs || !out->true_dz || !out->true_a || !curve || !out->true_shapes || !out->tracked_shapes) {
        snprintf(why, why_len, "family film: out of memory");
        goto done;
    }
    if (film_setup(&c, twin, o, why, why_len) != 0) goto done;
    double sdz = 0, sa = 0, mdz = 0, ma = 0;
    for (int k = 0; k < total; k++) {
        double dl = twin->compression, dw = 0.0;
        int compressing = k < o->n_compress;
        if (compressing)
            dl = o->n_compress > 1 ? o->dl_start + (twin->compression - o->dl_start) * k / (o->n_compress - 1)
                                   : twin->compression;
        else if (k >= o->n_compress + o->n_hold)
            dw = o->dw_stop * (k - o->n_compress - o->n_hold + 1) / nsh;
        if (dl < c.dl_min - 1e-12) {
            out->below++;
            continue;
        }
        rod_status st = step_to(&c, dl, dw);
        if (st != ROD_OK) {
            snprintf(why, why_len, "family film: the twin has no upper state at Delta L %.4f, Delta W %.4f (%s)",
                     dl, dw, rod_status_message(st));
            goto done;
        }
        vis_measure m;
        /* A kept centreline: compression frame k at j (n_compress - 1) / (n_shapes - 1). */
        int keep = 0;
        for (int j = 0; compressing && j < o->n_shapes && !keep; j++)
            keep = k == (o->n_shapes > 1 ? (int)lround((double)j * (o->n_compress - 1) / (o->n_shapes - 1))
                                         : o->n_compress - 1);
        int n_curve = 0;
        if (film_frame(&c, compressing ? NULL : c.tracker, &m, keep ? curve : NULL, &n_curve, why, why_len) != 0)
            goto done;
        if (keep && m.reason == VIS_REASON_NONE && n_curve >= 2) {
            rod_fit_shape *ts = &out->true_shapes[out->nshapes], *ks = &out->tracked_shapes[out->nshapes];
            *ts = (rod_fit_shape){.dl = dl, .dw = dw, .k = o->shape_points};
            *ks = *ts;
            if (rod_shape_sample(c.r, o->shape_points, ts->xz) == 0 &&
                rod_shape_resample(curve, n_curve, o->shape_points, ks->xz) == 0) {
                for (int p = 0; p < 2 * o->shape_points; p++) {
                    double e = ks->xz[p] - ts->xz[p];
                    s_shape += e * e;
                    *(p % 2 ? &m_shape_z : &m_shape_x) += e;
                }
                out->nshapes++;
            }
        }
        if (m.reason != VIS_REASON_NONE) {
            out->lost++;
            continue;
        }
        rod_obs tr;
        rod_observe(c.r, c.k1, &tr);
        int i = out->n++;
        out->obs[i] = (rod_fit_obs){dl, dw, m.dz, m.a};
        out->true_dz[i] = tr.dz_cam;
        out->true_a[i] = tr.a_cam;
        mdz += m.dz - tr.dz_cam;
        ma += m.a - tr.a_cam;
        sdz += (m.dz - tr.dz_cam) * (m.dz - tr.dz_cam);
        sa += (m.a - tr.a_cam) * (m.a - tr.a_cam);
    }
    if (out->n > 0) {
        out->dz_mean = mdz / out->n;
        out->a_mean = ma / out->n;
        out->dz_rms = sqrt(sdz / out->n);
        out->a_rms = sqrt(sa / out->n);
    }
    if (out->nshapes > 0) {
        double np = 2.0 * o->shape_points * out->nshapes;
        out->shape_rms = sqrt(s_shape / np);
        out->shape_mean_x = 2.0 * m_shape_x / np;
        out->shape_mean_z = 2.0 * m_shape_z / np;
    }
    rc = 0;
done:
    free(curve);
    film_release(&c);
    if (rc != 0) family_film_free(out);
    return rc;
}
