/* twin_depth.c: a prediction's shapes as the tracker's depth library (see twin_depth.h). */
#include "twin_depth.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static twin_status fail(twin_status st, char *why, size_t why_len, const char *msg)
{
    if (why && why_len) snprintf(why, why_len, "%s", msg);
    return st;
}

twin_status twin_depth_init(twin_depth *d, const rod_scene *sc, char *why, size_t why_len)
{
    if (!d || !sc) return fail(TWIN_ERR_ARG, why, why_len, "twin_depth_init: NULL collector or scene");
    memset(d, 0, sizeof *d);
    twin_status st = twin_shape_init(&d->ts, sc, TWIN_Y_RIG, why, why_len);
    if (st != TWIN_OK) return st;
    d->length_mm = sc->length * 1000.0;
    return TWIN_OK;
}

static int grow(twin_depth *d)
{
    const size_t cap = d->cap ? 2 * d->cap : 256, np = d->ts.n;
    double *p[6] = {d->shear_mm, d->dz, d->a, d->frac, d->rel, d->xz};
    const size_t per[6] = {1, 1, 1, np, np, 2 * np};
    for (int k = 0; k < 6; k++) {
        double *q = realloc(p[k], cap * per[k] * sizeof *q);
        if (!q) return -1; /* what was grown stays, with the old capacity */
        p[k] = q;
        switch (k) {
        case 0: d->shear_mm = q; break;
        case 1: d->dz = q; break;
        case 2: d->a = q; break;
        case 3: d->frac = q; break;
        case 4: d->rel = q; break;
        default: d->xz = q; break;
        }
    }
    d->cap = cap;
    return 0;
}

twin_status twin_depth_add(twin_depth *d, const rod_sample *s, const rod *r, char *why, size_t why_len)
{
    if (!d || !s || !r || !d->ts.pos) return fail(TWIN_ERR_ARG, why, why_len, "twin_depth_add: NULL argument");
    const double shear_mm = s->dw * d->length_mm;
    if (!(isfinite(shear_mm) && isfinite(s->dz_cam) && isfinite(s->a_cam)))
        return fail(TWIN_ERR_ARG, why, why_len, "twin_depth_add: a non-finite state");
    if (d->n > 0) {
        const size_t j = d->n - 1;
        if (fabs(s->dz_cam - d->dz[j]) < TWIN_DEPTH_STEP_DZ && fabs(s->a_cam - d->a[j]) < TWIN_DEPTH_STEP_A &&
            fabs(shear_mm - d->shear_mm[j]) < TWIN_DEPTH_STEP_SHEAR_MM)
            return TWIN_OK;
    }
    if (d->n >= TWIN_DEPTH_MAX_SHAPES) {
        d->full = 1;
        return TWIN_OK;
    }
    if (d->n == d->cap && grow(d)) return fail(TWIN_ERR_NOMEM, why, why_len, "twin_depth_add: out of memory");
    twin_status st = twin_shape_from_rod(&d->ts, r, why, why_len);
    if (st != TWIN_OK) return st;
    const size_t np = d->ts.n;
    if (twin_shape_depth_profile(&d->ts.view, d->frac + d->n * np, d->rel + d->n * np) != np) return TWIN_OK;
    for (size_t i = 0; i < np; i++)
        if (fabs(d->rel[d->n * np + i]) > VIS_DEPTH_REL_MAX) return TWIN_OK; /* a near-zero shear: no profile */
    const double *q = d->ts.pos;
    for (size_t i = 0; i < np; i++) {
        d->xz[2 * (d->n * np + i)] = (q[3 * i] - q[0]) * 1000.0;
        d->xz[2 * (d->n * np + i) + 1] = (q[3 * i + 2] - q[2]) * 1000.0;
    }
    d->shear_mm[d->n] = d->ts.pos[3 * (np - 1) + 1] * 1000.0;
    d->dz[d->n] = s->dz_cam;
    d->a[d->n] = s->a_cam;
    d->n++;
    return TWIN_OK;
}

vis_depth_library twin_depth_library(const twin_depth *d)
{
    vis_depth_library lib = {0, 0, NULL, NULL, NULL, NULL, NULL, NULL};
    if (!d || d->n == 0) return lib;
    lib.n_shapes = d->n;
    lib.n_points = d->ts.n;
    lib.shear_mm = d->shear_mm;
    lib.dz = d->dz;
    lib.a = d->a;
    lib.frac = d->frac;
    lib.depth_rel = d->rel;
    lib.xz_mm = d->xz;
    return lib;
}

void twin_depth_release(twin_depth *d)
{
    if (!d) return;
    twin_shape_release(&d->ts);
    free(d->shear_mm);
    free(d->dz);
    free(d->a);
    free(d->frac);
    free(d->rel);
    free(d->xz);
    memset(d, 0, sizeof *d);
}
