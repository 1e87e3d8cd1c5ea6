/* twin_shape.c: a rod state as a vis_shape (see twin_shape.h for which nodes, frames, normals).
 *
 * Normal at a node: m1 of the edge before plus m1 of the edge after, minus its component along
 * the node tangent (the sum of the two unit edge tangents), normalised. On a smooth stretch the two
 * directors are nearly equal and this is their mean; at a crease they differ by the crease angle
 * and the result is the bisector, perpendicular to the bisecting tangent, as on the folded sheet.
 * The sum of the directors cannot vanish short of a 180 degree crease, which rod_scene_check
 * refuses; the edge-after director is the fallback all the same. */
#include "twin_shape.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

const char *twin_status_str(twin_status s)
{
    switch (s) {
    case TWIN_OK: return "ok";
    case TWIN_ERR_ARG: return "invalid argument";
    case TWIN_ERR_NOMEM: return "out of memory";
    case TWIN_ERR_VISION: return "vision module error";
    case TWIN_STOPPED: return "stopped by the frame callback";
    }
    return "unknown twin status";
}

static twin_status fail(twin_status st, char *why, size_t why_len, const char *msg)
{
    if (why && why_len) snprintf(why, why_len, "%s", msg);
    return st;
}

twin_status twin_shape_init(twin_shape *ts, const rod_scene *sc, twin_y_origin y, char *why,
                            size_t why_len)
{
    if (!ts || !sc) return fail(TWIN_ERR_ARG, why, why_len, "twin_shape_init: NULL shape or scene");
    ts->pos = ts->normal = NULL;
    if (sc->nodes < 5 || sc->nodes > 1000000)
        return fail(TWIN_ERR_ARG, why, why_len, "twin_shape_init: mesh.nodes must be 5..1000000");
    if (!(isfinite(sc->width) && sc->width > 0 && isfinite(sc->thickness) && sc->thickness > 0))
        return fail(TWIN_ERR_ARG, why, why_len,
                    "twin_shape_init: ribbon.width and ribbon.thickness must be finite and > 0");
    if (y != TWIN_Y_RIG && y != TWIN_Y_SIM)
        return fail(TWIN_ERR_ARG, why, why_len, "twin_shape_init: unknown y origin");
    size_t n = (size_t)sc->nodes - 2;
    double *pos = calloc(3 * n, sizeof *pos), *nor = calloc(3 * n, sizeof *nor);
    if (!pos || !nor) {
        free(pos);
        free(nor);
        return fail(TWIN_ERR_NOMEM, why, why_len, "twin_shape_init: out of memory");
    }
    ts->nodes = sc->nodes;
    ts->n = n;
    ts->y_origin = y;
    ts->pos = pos;
    ts->normal = nor;
    ts->view.n = n;
    ts->view.pos = pos;
    ts->view.normal = nor;
    ts->view.width_m = sc->width;
    ts->view.thickness_m = sc->thickness;
    return TWIN_OK;
}

void twin_shape_release(twin_shape *ts)
{
    if (!ts) return;
    free(ts->pos);
    free(ts->normal);
    ts->pos = ts->normal = NULL;
    ts->n = 0;
    ts->view.n = 0;
    ts->view.pos = ts->view.normal = NULL;
}

static void unit_tangent(const rod *r, int e, double t[3])
{
    const double *a = rod_x(r, e), *b = rod_x(r, e + 1);
    double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int j = 0; j < 3; j++) t[j] = len > 0 ? d[j] / len : 0.0;
}

static int normalise(double v[3])
{
    double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(len > 1e-12) || !isfinite(len)) return 0;
    for (int j = 0; j < 3; j++) v[j] /= len;
    return 1;
}

twin_status twin_shape_from_rod(twin_shape *ts, const rod *r, char *why, size_t why_len)
{
    if (!ts || !r || !ts->pos) return fail(TWIN_ERR_ARG, why, why_len, "twin_shape_from_rod: NULL or released shape");
    if (r->n != ts->nodes) {
        if (why && why_len)
            snprintf(why, why_len, "twin_shape_from_rod: the rod has %d nodes, the shape was sized for %d",
                     r->n, ts->nodes);
        return TWIN_ERR_ARG;
    }
    const int N = r->n;
    const double y0 = ts->y_origin == TWIN_Y_RIG ? rod_x(r, 1)[1] : 0.0;
    for (int i = 1; i <= N - 2; i++) {
        const double *x = rod_x(r, i);
        double *p = ts->pos + 3 * (size_t)(i - 1), *nv = ts->normal + 3 * (size_t)(i - 1);
        p[0] = x[0];
        p[1] = x[1] - y0;
        p[2] = x[2];
        double te[3], tf[3], m1e[3], m1f[3], m2[3];
        unit_tangent(r, i - 1, te);
        unit_tangent(r, i, tf);
        rod_material_frame(r, i - 1, m1e, m2);
        rod_material_frame(r, i, m1f, m2);
        double t[3] = {te[0] + tf[0], te[1] + tf[1], te[2] + tf[2]};
        double m[3] = {m1e[0] + m1f[0], m1e[1] + m1f[1], m1e[2] + m1f[2]};
        if (normalise(t)) {
            double d = m[0] * t[0] + m[1] * t[1] + m[2] * t[2];
            for (int j = 0; j < 3; j++) m[j] -= d * t[j];
        }
        if (!normalise(m)) {
            for (int j = 0; j < 3; j++) m[j] = m1f[j];
            normalise(m);
        }
        for (int j = 0; j < 3; j++) nv[j] = m[j];
        if (!isfinite(p[0] + p[1] + p[2] + nv[0] + nv[1] + nv[2])) {
            if (why && why_len)
                snprintf(why, why_len, "twin_shape_from_rod: node %d has a non-finite position or frame", i);
            return TWIN_ERR_ARG;
        }
    }
    return TWIN_OK;
}

twin_status twin_shape_lerp(twin_shape *out, const twin_shape *a, const twin_shape *b, double w,
                            char *why, size_t why_len)
{
    if (!out || !a || !b || !out->pos || !a->pos || !b->pos)
        return fail(TWIN_ERR_ARG, why, why_len, "twin_shape_lerp: NULL or released shape");
    if (a->n != b->n || out->n != a->n)
        return fail(TWIN_ERR_ARG, why, why_len, "twin_shape_lerp: shapes of different sizes");
    if (!(w >= 0.0 && w <= 1.0))
        return fail(TWIN_ERR_ARG, why, why_len, "twin_shape_lerp: weight outside [0, 1]");
    for (size_t k = 0; k < 3 * a->n; k++) out->pos[k] = (1.0 - w) * a->pos[k] + w * b->pos[k];
    for (size_t i = 0; i < a->n; i++) {
        double m[3];
        for (int j = 0; j < 3; j++) m[j] = (1.0 - w) * a->normal[3 * i + j] + w * b->normal[3 * i + j];
        /* Nearly opposite normals (not a physical step) fall back to the nearer state's. */
        if (!normalise(m))
            for (int j = 0; j < 3; j++) m[j] = (w < 0.5 ? a : b)->normal[3 * i + j];
        for (int j = 0; j < 3; j++) out->normal[3 * i + j] = m[j];
    }
    return TWIN_OK;
}

size_t twin_shape_depth_profile(const vis_shape *sh, double *frac, double *depth_rel)
{
    if (!sh || !sh->pos || sh->n < 2 || !frac || !depth_rel)
        return 0;
    const double *p = sh->pos;
    const size_t n = sh->n;
    const double y0 = p[1], shear = p[3 * (n - 1) + 1] - y0;
    if (!(fabs(shear) >= TWIN_DEPTH_MIN_SHEAR_M))
        return 0;
    double len = 0.0;
    frac[0] = 0.0;
    for (size_t i = 1; i < n; i++) {
        const double dx = p[3 * i] - p[3 * i - 3], dy = p[3 * i + 1] - p[3 * i - 2], dz = p[3 * i + 2] - p[3 * i - 1];
        len += sqrt(dx * dx + dy * dy + dz * dz);
        frac[i] = len;
    }
    if (!(len > 0.0))
        return 0;
    for (size_t i = 0; i < n; i++) {
        frac[i] = i + 1 == n ? 1.0 : frac[i] / len;
        depth_rel[i] = (p[3 * i + 1] - y0) / shear;
        if (i > 0 && !(frac[i] > frac[i - 1]))
            return 0; /* coincident nodes: not a profile */
    }
    return n;
}
