/* rod_dynamics.c: the implicit Euler step with moving clamps (see rod_dynamics.h). */
#include "rod_dynamics.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Slot of the solver's state storage that holds the state before a pending step. */
#define DYN_SLOT 1

rod_status rod_dyn_open(rod_dyn *d, const rod_scene *sc, char *why, size_t why_len)
{
    memset(d, 0, sizeof *d);
    rod_status st = rod_alloc(sc, &d->r, why, why_len);
    if (st != ROD_OK) return st;
    size_t nd = (size_t)d->r->ndof;
    d->s = rod_solver_alloc(d->r);
    d->q_n = malloc(sizeof(double) * nd);
    d->v = calloc(nd, sizeof(double));
    d->v_prev = calloc(nd, sizeof(double));
    d->g_old = calloc(nd, sizeof(double));
    if (!d->s || !d->q_n || !d->v || !d->v_prev || !d->g_old) {
        rod_dyn_close(d);
        if (why) snprintf(why, why_len, "out of memory allocating the dynamics workspace");
        return ROD_ERR_ALLOC;
    }
    d->mu = sc->damping;
    d->dl = sc->compression;
    d->no = rod_newton_opts_static(sc);
    d->no.q_n = d->q_n;
    d->no.v_n = d->v;
    d->no.positive_definite = 1;
    d->no.damped = d->mu > 0.0; /* a scene without damping counts none */
    return ROD_OK;
}

void rod_dyn_close(rod_dyn *d)
{
    free(d->q_n);
    free(d->v);
    free(d->v_prev);
    free(d->g_old);
    rod_solver_free(d->s);
    rod_free(d->r);
    memset(d, 0, sizeof *d);
}

void rod_dyn_start(rod_dyn *d, double dl, double dw)
{
    size_t nd = (size_t)d->r->ndof;
    memcpy(d->g_old, rod_solver_gradient(d->s), sizeof(double) * nd);
    memset(d->v, 0, sizeof(double) * nd);
    memset(d->v_prev, 0, sizeof(double) * nd);
    d->h_prev = 0.0;
    d->dl = dl;
    d->dw = dw;
    d->h = 0.0;
    d->kinetic = 0.0;
}

rod_status rod_dyn_try(rod_dyn *d, double h, double dl, double dw, rod_newton_report *nr)
{
    rod *r = d->r;
    memcpy(d->q_n, r->q, sizeof(double) * (size_t)r->ndof);
    rod_state_save(r, d->s, DYN_SLOT);
    rod_set_clamps(r, dl, dw);
    /* Predictor (see rod_dynamics.h): a better start saves Newton iterations; the converged
     * step does not depend on it beyond the tolerance. */
    if (d->h_prev > 0.0) {
        double c = h / d->h_prev;
        for (int k = ROD_FREE_BEGIN; k < r->free_end; k++)
            r->q[k] += h * (d->v[k] + c * (d->v[k] - d->v_prev[k]));
    } else {
        for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) r->q[k] += h * d->v[k];
    }
    d->no.c1 = 1.0 / (h * h) + d->mu / h;
    d->no.c2 = 1.0 / h;
    rod_status st = rod_newton_solve(r, d->s, &d->no, nr);
    if (st != ROD_OK) {
        rod_state_restore(r, d->s, DYN_SLOT);
        d->h = 0.0;
        return st;
    }
    d->h = h;
    d->dl_new = dl;
    d->dw_new = dw;
    return ROD_OK;
}

void rod_dyn_reject(rod_dyn *d)
{
    if (d->h > 0.0) rod_state_restore(d->r, d->s, DYN_SLOT);
    d->h = 0.0;
}

void rod_dyn_accept(rod_dyn *d)
{
    rod *r = d->r;
    double h = d->h;
    if (!(h > 0.0)) return;
    const double *g = rod_solver_gradient(d->s);
    double kin = 0.0, dis = 0.0, work = 0.0;
    memcpy(d->v_prev, d->v, sizeof(double) * (size_t)r->ndof);
    d->h_prev = h;
    for (int k = 0; k < r->ndof; k++) {
        d->v[k] = (r->q[k] - d->q_n[k]) / h;
        if (k >= ROD_FREE_BEGIN && k < r->free_end) {
            kin += 0.5 * r->mass[k] * d->v[k] * d->v[k];
            dis += d->mu * r->mass[k] * d->v[k] * d->v[k] * h;
        } else {
            /* Work of the prescribed DOFs: 1/2 (g_old + g_new) . (q - q_n), trapezoidal rule. */
            work += 0.5 * (d->g_old[k] + g[k]) * (r->q[k] - d->q_n[k]);
        }
    }
    d->kinetic = kin;
    d->work += work;
    d->damped += dis;
    memcpy(d->g_old, g, sizeof(double) * (size_t)r->ndof);
    d->dl = d->dl_new;
    d->dw = d->dw_new;
    d->h = 0.0;
}
