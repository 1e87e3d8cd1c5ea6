/* rod_twin.c: the rail-driven rod of mock mode (see rod_twin.h). */
#include "rod_twin.h"
#include "rod_dynamics.h"
#include "rod_route.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct rod_twin {
    rod_dyn dyn;
    double t;         /* s, time of the current state */
    double dt;        /* s, largest step */
    double *k1;       /* scratch for rod_observe */
    long halvings;
    rod_snap_watch watch; /* the twin's own snap, fed every accepted step */
};

/* After every accepted state: the snap watch sees it (an O(N) observation). */
static void twin_watch(rod_twin *tw)
{
    rod_obs o;
    rod_observe(tw->dyn.r, tw->k1, &o);
    rod_snap_watch_add(&tw->watch, tw->t, tw->dyn.dw, &o);
}

rod_status rod_twin_open(const rod_scene *sc, double dl_start, rod_twin **out, char *why, size_t why_len)
{
    *out = NULL;
    if (!(dl_start >= 0.0 && dl_start < 1.0)) {
        if (why) snprintf(why, why_len, "mounting compression Delta L = %g is outside [0, 1)", dl_start);
        return ROD_ERR_SCENE;
    }
    rod_scene s = *sc;
    s.compression = dl_start;
    rod_twin *tw = calloc(1, sizeof *tw);
    if (!tw) {
        if (why) snprintf(why, why_len, "out of memory allocating the twin");
        return ROD_ERR_ALLOC;
    }
    rod_status st = rod_dyn_open(&tw->dyn, &s, why, why_len);
    if (st != ROD_OK) {
        free(tw);
        return st;
    }
    tw->k1 = malloc(sizeof(double) * (size_t)tw->dyn.r->n);
    if (!tw->k1) {
        rod_twin_close(tw);
        if (why) snprintf(why, why_len, "out of memory allocating the twin");
        return ROD_ERR_ALLOC;
    }
    tw->dt = sc->dt;
    rod_route_report rr = {0};
    st = rod_route_to_state(tw->dyn.r, tw->dyn.s, &s, +1, &rr);
    if (st != ROD_OK) {
        if (why)
            snprintf(why, why_len, "twin: could not reach the upper state at Delta L = %g (%s, %.0f%% of the route done)",
                     dl_start, rod_status_message(st), 100.0 * rr.reached);
        rod_twin_close(tw);
        return st;
    }
    rod_dyn_start(&tw->dyn, dl_start, 0.0);
    rod_snap_watch_init(&tw->watch, sc->snap_speed, sc->asym_threshold, 2.0);
    twin_watch(tw);
    *out = tw;
    return ROD_OK;
}

void rod_twin_close(rod_twin *tw)
{
    if (!tw) return;
    rod_dyn_close(&tw->dyn);
    free(tw->k1);
    free(tw);
}

rod_status rod_twin_advance(rod_twin *tw, double t_to, double dl, double dw, char *why, size_t why_len)
{
    if (!isfinite(t_to) || !isfinite(dl) || !isfinite(dw) || t_to < tw->t) {
        if (why) snprintf(why, why_len, "twin: bad advance to t = %g s, Delta L = %g, Delta W = %g (now t = %g s)",
                          t_to, dl, dw, tw->t);
        return ROD_ERR_SCENE;
    }
    double span = t_to - tw->t;
    if (span <= 0.0) return ROD_OK;
    double dl0 = tw->dyn.dl, dw0 = tw->dyn.dw, t0 = tw->t;
    /* Steps of at most dt that land exactly on t_to; a failed step is halved (a cap of 10). */
    long n = (long)ceil(span / tw->dt - 1e-9);
    if (n < 1) n = 1;
    double h_full = span / (double)n, done = 0.0, h = h_full;
    int level = 0;
    long cap = 4 * n * 1024 + 16, iter = 0;
    while (done < span * (1.0 - 1e-12)) {
        if (++iter > cap) {
            if (why) snprintf(why, why_len, "twin: step cap reached between t = %g and %g s", t0, t_to);
            return ROD_ERR_TIME_LIMIT;
        }
        if (h > span - done) h = span - done;
        double f = (done + h) / span;
        rod_newton_report nr;
        rod_status st = rod_dyn_try(&tw->dyn, h, dl0 + f * (dl - dl0), dw0 + f * (dw - dw0), &nr);
        if (st != ROD_OK) {
            tw->halvings++;
            if (++level > 10) {
                if (why)
                    snprintf(why, why_len, "twin: time step failed at t = %.4f s, Delta W = %.6f even at %g s: %s",
                             t0 + done, dw0 + done / span * (dw - dw0), h, rod_status_message(st));
                return st;
            }
            h *= 0.5;
            continue;
        }
        rod_dyn_accept(&tw->dyn);
        done += h;
        tw->t = t0 + done;
        twin_watch(tw);
        if (level > 0) {
            level--;
            h = fmin(2.0 * h, h_full);
        }
    }
    tw->t = t_to;
    return ROD_OK;
}

double rod_twin_time(const rod_twin *tw) { return tw->t; }
double rod_twin_dw(const rod_twin *tw) { return tw->dyn.dw; }
const rod *rod_twin_rod(const rod_twin *tw) { return tw->dyn.r; }
double rod_twin_shear_force(const rod_twin *tw)
{
    /* g_old holds dE/dq of the last accepted state; the y entries of the clamp nodes are the
     * reactions across the ribbon. Nodes N-2, N-1 move by +x/2, nodes 0, 1 by -x/2. */
    const rod *r = tw->dyn.r;
    const double *g = tw->dyn.g_old;
    int n = r->n;
    double f = 0.5 * (g[4 * (n - 2) + 1] + g[4 * (n - 1) + 1] - g[1] - g[4 + 1]);
    return isfinite(f) ? f : 0.0;
}

void rod_twin_snap(const rod_twin *tw, rod_snap_report *out) { *out = tw->watch.r; }

double rod_twin_kinetic(const rod_twin *tw) { return tw->dyn.kinetic; }
long rod_twin_halvings(const rod_twin *tw) { return tw->halvings; }

void rod_twin_observe(rod_twin *tw, rod_obs *o) { rod_observe(tw->dyn.r, tw->k1, o); }
