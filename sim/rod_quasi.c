/* rod_quasi.c: the quasi-static start of the fast prediction (see rod_quasi.h).
 *
 * Memory: a ring of at most QS_RING states (q and frames), the static Hessian of one state, and
 * the two previous DOF vectors of the secant predictor: O(N), allocated once per call, nothing
 * inside the stepping loop. */
#include "rod_quasi.h"
#include "rod_band.h"
#include "rod_observe.h"
#include "rod_stability.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define QS_RING 18
#define QS_EIG_TOL 1e-2 /* inverse iteration: residual / |eigenvalue - shift| */

typedef struct qs_state {
    double *q, (*d1)[3], (*d2)[3], (*tref)[3], *mref;
    double dw, dz, a;
} qs_state;

static int state_alloc(qs_state *s, const rod *r)
{
    size_t n = (size_t)r->n;
    s->q = malloc(sizeof(double) * (size_t)r->ndof);
    s->d1 = malloc(sizeof(double[3]) * n);
    s->d2 = malloc(sizeof(double[3]) * n);
    s->tref = malloc(sizeof(double[3]) * n);
    s->mref = malloc(sizeof(double) * n);
    return s->q && s->d1 && s->d2 && s->tref && s->mref;
}

static void state_free(qs_state *s)
{
    free(s->q); free(s->d1); free(s->d2); free(s->tref); free(s->mref);
}

static void state_put(qs_state *s, const rod *r, double dw, double dz, double a)
{
    size_t n = (size_t)r->n;
    memcpy(s->q, r->q, sizeof(double) * (size_t)r->ndof);
    memcpy(s->d1, r->d1, sizeof(double[3]) * n);
    memcpy(s->d2, r->d2, sizeof(double[3]) * n);
    memcpy(s->tref, r->tref, sizeof(double[3]) * n);
    memcpy(s->mref, r->mref, sizeof(double) * n);
    s->dw = dw;
    s->dz = dz;
    s->a = a;
}

static void state_get(const qs_state *s, rod *r)
{
    size_t n = (size_t)r->n;
    memcpy(r->q, s->q, sizeof(double) * (size_t)r->ndof);
    memcpy(r->d1, s->d1, sizeof(double[3]) * n);
    memcpy(r->d2, s->d2, sizeof(double[3]) * n);
    memcpy(r->tref, s->tref, sizeof(double[3]) * n);
    memcpy(r->mref, s->mref, sizeof(double) * n);
}

/* 1 when the static Hessian at the current (converged, frames up to date) state is positive
 * definite: every pivot of its LDL^T is positive (exact for a definite matrix, and LDL^T without
 * pivoting is stable there). */
static int strict_minimum(rod *r, double *H, double *Hs)
{
    int nf = rod_nfree(r);
    memset(H, 0, sizeof(double) * (size_t)nf * (ROD_BAND + 1));
    rod_hessian_add(r, 1.0, H);
    /* Kept for the eigenvalue, mass-weighted: M^-1/2 H M^-1/2 has the squared vibration
     * frequencies as eigenvalues, in one unit for positions and twist angles alike. */
    const int w = ROD_BAND + 1;
    for (int a = 0; a < nf; a++)
        for (int k = 0; k < w && a + k < nf; k++)
            Hs[(size_t)a * w + k] = H[(size_t)a * w + k] / sqrt(r->mass[a + ROD_FREE_BEGIN] * r->mass[a + k + ROD_FREE_BEGIN]);
    if (rod_band_ldlt_decomp(H, nf) != 0) return 0;
    for (int a = 0; a < nf; a++)
        if (!(H[(size_t)a * (ROD_BAND + 1)] > 0.0)) return 0;
    return 1;
}

double rod_quasi_step(const rod_scene *sc)
{
    return fmin(QS_STEP, sc->shear_max / 20.0);
}

rod_status rod_quasi_follow(rod_dyn *d, const rod_scene *sc, double dl, double rate_dw, double dw_max,
                            rod_quasi_report *rep)
{
    return rod_quasi_follow_from(d, sc, dl, 0.0, rate_dw, dw_max, rep);
}

rod_status rod_quasi_follow_from(rod_dyn *d, const rod_scene *sc, double dl, double dw0, double rate_dw,
                                 double dw_max, rod_quasi_report *rep)
{
    rod *r = d->r;
    memset(rep, 0, sizeof *rep);
    double step = rod_quasi_step(sc);
    int back = (int)ceil(QS_BACK_TIME * rate_dw / step - 1e-9);
    if (back < 1) back = 1;
    if (back > QS_RING - 2) back = QS_RING - 2;
    int ring = back + 2;
    qs_state st[QS_RING];
    memset(st, 0, sizeof st);
    int nf = rod_nfree(r), ok = 1;
    double *H = malloc(sizeof(double) * (size_t)nf * (ROD_BAND + 1));
    double *k1 = malloc(sizeof(double) * (size_t)r->n);
    double *Hs = malloc(sizeof(double) * (size_t)nf * (ROD_BAND + 1));
    double *ev = calloc((size_t)nf, sizeof(double)), *ev2 = calloc((size_t)nf, sizeof(double));
    rod_stab_ws *ws = rod_stab_ws_alloc(nf);
    ok = H && k1 && Hs && ev && ev2 && ws;
    for (int k = 0; k < ring && ok; k++) ok = state_alloc(&st[k], r);
    if (!ok) {
        for (int k = 0; k < ring; k++) state_free(&st[k]);
        free(H); free(k1); free(Hs); free(ev); free(ev2);
        rod_stab_ws_free(ws);
        return ROD_ERR_ALLOC;
    }
    rod_newton_opts o = rod_newton_opts_static(sc);
    o.positive_definite = 1;
    rod_obs ob;
    rod_observe(r, k1, &ob);
    double e0 = rod_energy(r);
    /* count: states in the ring, the newest at index (count - 1) % ring. */
    long count = 0;
    state_put(&st[0], r, dw0, ob.dz, ob.a);
    count = 1;
    double dw = dw0, lam_prev = NAN, margin = QS_BACK_TIME * rate_dw;
    rep->back = back;
    for (int guard = 0; guard < 100000; guard++) {
        double dn = dw + step;
        if (dn > dw_max - step) break;
        const qs_state *s0 = &st[(count - 1) % ring];
        /* Predictor: the parabola through the last three states (error third order in the
         * step; with it the whole fast prediction of the paper scenes needed 8% and 12% fewer
         * factorisations than with the secant: 1992 against 2174, 1121 against 1278), the
         * secant through two, or the affine shear of the nodes. */
        if (count >= 3) {
            const qs_state *s1 = &st[(count - 2) % ring], *s2 = &st[(count - 3) % ring];
            for (int k = ROD_FREE_BEGIN; k < r->free_end; k++)
                r->q[k] = 3.0 * s0->q[k] - 3.0 * s1->q[k] + s2->q[k];
        } else if (count >= 2) {
            const qs_state *s1 = &st[(count - 2) % ring];
            for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) r->q[k] = 2.0 * s0->q[k] - s1->q[k];
        } else {
            for (int i = 2; i < r->n - 2; i++) rod_x(r, i)[1] += step * r->length * (r->s_node[i] - 0.5);
        }
        rod_set_clamps(r, dl, dn);
        rod_newton_report nr;
        rod_status ss = rod_newton_solve(r, d->s, &o, &nr);
        rep->solves++;
        int warn = ss != ROD_OK, near = 0;
        double lam = NAN;
        if (!warn) {
            rod_observe(r, k1, &ob);
            warn = !isfinite(ob.dz) || !isfinite(ob.a) || fabs(ob.dz - s0->dz) > 0.02 + 20.0 * step ||
                   !strict_minimum(r, H, Hs);
        }
        if (!warn) {
            /* Lowest squared frequency: inverse iteration converges to whichever mode dominates
             * its start, so it runs from the last eigenvector and from the built-in start (which
             * has components on every mode) and keeps the lower value; extrapolated linearly
             * to its zero: an estimate of the critical Delta W (early at a pitchfork, where it is
             * linear in Delta W; late by a factor 2 in distance at a saddle-node, where it goes
             * like a square root, hence the factor 2 on the margin).
             * The iteration is shifted to 0.9 times the last value: the convergence rate is
             * |lam1 - shift| / |lam2 - shift| instead of lam1 / lam2 (on the paper scenes 2-9
             * iterations instead of 20-40 at zero shift). The lowest eigenvalue stays the one
             * nearest the shift unless it fell by more than 20% (plus the gap to the second) in
             * one step; a fall of 20% per step extrapolates to zero 4 steps ahead, inside the
             * margin, so this phase is ending there anyway. The eigenvector is converged to 1e-2
             * of the shift distance, the eigenvalue (its error goes with the square of that) to
             * far better than the extrapolation needs. */
            rod_eigpair ep;
            double shift = isfinite(lam_prev) && lam_prev > 0.0 ? 0.9 * lam_prev : 0.0;
            if (rod_eig_nearest(Hs, nf, shift, 40, QS_EIG_TOL, ws, ev, &ep, NULL, 0) == ROD_OK) lam = ep.value;
            else memset(ev, 0, sizeof(double) * (size_t)nf);
            memcpy(ev2, ev, sizeof(double) * (size_t)nf);
            memset(ev, 0, sizeof(double) * (size_t)nf);
            if (rod_eig_nearest(Hs, nf, shift, 40, QS_EIG_TOL, ws, ev, &ep, NULL, 0) == ROD_OK && !(ep.value >= lam))
                lam = ep.value;
            else
                memcpy(ev, ev2, sizeof(double) * (size_t)nf);
            if (isfinite(lam) && isfinite(lam_prev) && lam < lam_prev) {
                double dwc = dn + lam * step / (lam_prev - lam);
                near = dwc - dn < 2.0 * margin + step;
            }
        }
        if (warn) {
            rep->dw_warning = dn;
            break;
        }
        dw = dn;
        lam_prev = lam;
        state_put(&st[count % ring], r, dn, ob.dz, ob.a);
        count++;
        rep->steps++;
        if (near) {
            rep->dw_warning = dn;
            back = 0; /* the estimate already holds the margin: start here */
            break;
        }
    }
    /* Go back by the margin after a hard warning (as far as the ring and the branch reach). */
    long j = count - 1 - back;
    if (j < 0) j = 0;
    if (j < count - ring) j = count - ring;
    const qs_state *sw = &st[j % ring];
    state_get(sw, r);
    rod_set_clamps(r, dl, sw->dw);
    rod_newton_report nr;
    rod_newton_solve(r, d->s, &o, &nr); /* at the stored solution: leaves the clamp reactions */
    rod_dyn_start(d, dl, sw->dw);
    d->work += rod_energy(r) - e0; /* quasi-static: the clamps' work went into elastic energy */
    if (j >= 1 && j > count - ring) {
        /* Quasi-static velocity: the secant of the branch in time. */
        const qs_state *sp = &st[(j - 1) % ring];
        double h = (sw->dw - sp->dw) / rate_dw;
        for (int k = 0; k < r->ndof; k++) d->v[k] = (sw->q[k] - sp->q[k]) / h;
        memcpy(d->v_prev, d->v, sizeof(double) * (size_t)r->ndof);
        d->h_prev = h;
        double kin = 0.0;
        for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) kin += 0.5 * r->mass[k] * d->v[k] * d->v[k];
        d->kinetic = kin;
    }
    rep->dw_switch = sw->dw;
    for (int k = 0; k < ring; k++) state_free(&st[k]);
    free(H); free(k1); free(Hs); free(ev); free(ev2);
    rod_stab_ws_free(ws);
    return ROD_OK;
}
