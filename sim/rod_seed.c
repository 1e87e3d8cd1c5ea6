/* rod_seed.c: continuation of a stable state in the crease angle and position (see rod_seed.h). */
#include "rod_seed.h"
#include "rod_observe.h"
#include "rod_stability.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SEED_MIN_STEP_LOG2 10   /* smallest step: 2^-10 of the nominal one */
#define SEED_LOOSE 1e-3         /* residual of intermediate states over E I1 / l^2 (as the route) */
#define SEED_GAMMA_STEP 0.01    /* nominal steps: at most this much in Gamma ... */
#define SEED_PHI_STEP_DEG 5.0   /* ... and in the crease angle per step */
#define SEED_SOLVES_PER_STEP 40 /* cap on solves, per nominal step */

/* Segment k (0, 1, 2) of arc length s over l and the position in it, for a rod whose creases are
 * at s_node[fold_node[0]] and s_node[fold_node[1]] (one segment when there are none). */
static void segment_of(const rod *r, double s, int *k, double *t)
{
    double a = r->fold_node[0] >= 0 ? r->s_node[r->fold_node[0]] : 1.0;
    double b = r->fold_node[1] >= 0 ? r->s_node[r->fold_node[1]] : 1.0;
    if (s <= a || a >= 1.0) {
        *k = 0;
        *t = s / a;
    } else if (s <= b) {
        *k = 1;
        *t = (s - a) / (b - a);
    } else {
        *k = 2;
        *t = (s - b) / (1.0 - b);
    }
}

static double segment_point(const rod *r, int k, double t)
{
    double a = r->fold_node[0] >= 0 ? r->s_node[r->fold_node[0]] : 1.0;
    double b = r->fold_node[1] >= 0 ? r->s_node[r->fold_node[1]] : 1.0;
    if (k == 0) return t * a;
    if (k == 1) return a + t * (b - a);
    return b + t * (1.0 - b);
}

/* Index i of the free-length interval [s_node[i], s_node[i + 1]] that holds s (1 <= i <= n - 3). */
static int interval_of(const rod *r, double s)
{
    int lo = 1, hi = r->n - 2;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (r->s_node[mid] <= s) lo = mid; else hi = mid;
    }
    return lo;
}

rod_status rod_seed_remap(const rod *src, rod *dst, double dl)
{
    if (src->n != dst->n || src->length != dst->length) return ROD_ERR_SCENE;
    int n = dst->n;
    /* Free nodes 2 .. n - 3: positions interpolated in src at the same place of their segment. */
    for (int i = 2; i < n - 2; i++) {
        int k;
        double t;
        segment_of(dst, dst->s_node[i], &k, &t);
        double s = segment_point(src, k, t);
        int j = interval_of(src, s);
        double w = (s - src->s_node[j]) / (src->s_node[j + 1] - src->s_node[j]);
        const double *xa = rod_x(src, j), *xb = rod_x(src, j + 1);
        double *x = rod_x(dst, i);
        for (int c = 0; c < 3; c++) x[c] = (1.0 - w) * xa[c] + w * xb[c];
    }
    /* Edges: twist angle and frames of the src edge holding the same relative midpoint. */
    for (int e = 0; e < n - 1; e++) {
        double sm = 0.5 * (dst->s_node[e] + dst->s_node[e + 1]);
        int j;
        if (e == 0 || e == n - 2) {
            j = e; /* the clamped edges */
        } else {
            int k;
            double t;
            segment_of(dst, fmin(fmax(sm, 0.0), 1.0), &k, &t);
            j = interval_of(src, segment_point(src, k, t));
        }
        dst->q[4 * e + 3] = src->q[4 * j + 3];
        memcpy(dst->d1[e], src->d1[j], sizeof dst->d1[e]);
        memcpy(dst->d2[e], src->d2[j], sizeof dst->d2[e]);
        memcpy(dst->tref[e], src->tref[j], sizeof dst->tref[e]);
    }
    for (int i = 0; i < n; i++) {
        int k, j = i;
        double t;
        if (i > 1 && i < n - 2) {
            segment_of(dst, dst->s_node[i], &k, &t);
            double s = segment_point(src, k, t);
            j = interval_of(src, s);
            if (s - src->s_node[j] > src->s_node[j + 1] - s) j++;
        }
        dst->mref[i] = src->mref[j];
    }
    rod_set_clamps(dst, dl, 0.0);
    rod_frames_update(dst);
    return ROD_OK;
}

/* Lowest eigenvalue of the Hessian over E I1 / l^2 (NAN when it cannot be computed). */
static double lowest_eigenvalue(rod *r)
{
    int nf = rod_nfree(r);
    double *H = calloc((size_t)nf * (ROD_BAND + 1), sizeof(double));
    double *v = calloc((size_t)nf, sizeof(double));
    rod_stab_ws *w = rod_stab_ws_alloc(nf);
    double out = NAN;
    if (H && v && w) {
        rod_hessian_add(r, 1.0, H);
        rod_eigpair ep;
        if (rod_eig_nearest(H, nf, 0.0, 200, 1e-10, w, v, &ep, NULL, 0) == ROD_OK)
            out = ep.value * r->length * r->length / r->EI1[0];
    }
    free(H);
    free(v);
    rod_stab_ws_free(w);
    return out;
}

int rod_seed_is_stable(rod *r)
{
    int nf = rod_nfree(r);
    double *H = calloc((size_t)nf * (ROD_BAND + 1), sizeof(double));
    rod_stab_ws *w = rod_stab_ws_alloc(nf);
    int stable = -1;
    if (H && w) {
        rod_inertia in;
        char why[160];
        rod_hessian_add(r, 1.0, H);
        if (rod_inertia_eval(H, nf, ROD_INERTIA_SHIFT_REL, w, &in, why, sizeof why) == ROD_OK)
            stable = in.n_negative == 0;
    }
    free(H);
    rod_stab_ws_free(w);
    return stable;
}

static rod_scene scene_at(const rod_scene *a, const rod_scene *b, double p)
{
    rod_scene sc = *b;
    sc.fold_angle_deg = a->fold_angle_deg + p * (b->fold_angle_deg - a->fold_angle_deg);
    sc.fold_position = a->fold_position + p * (b->fold_position - a->fold_position);
    if (p >= 1.0) {
        sc.fold_angle_deg = b->fold_angle_deg;
        sc.fold_position = b->fold_position;
    }
    return sc;
}

rod_status rod_seed_continue(const rod *from, const rod_scene *from_sc, const rod_scene *to_sc, rod_solver *s,
                             rod **out, rod_seed_report *rep)
{
    return rod_seed_continue_keep(from, from_sc, to_sc, s, out, rep, NULL, NULL);
}

rod_status rod_seed_continue_keep(const rod *from, const rod_scene *from_sc, const rod_scene *to_sc, rod_solver *s,
                                  rod **out, rod_seed_report *rep, rod **last_out, rod_scene *last_sc)
{
    if (last_out) *last_out = NULL;
    rod_seed_report local;
    if (!rep) rep = &local;
    memset(rep, 0, sizeof *rep);
    *out = NULL;
    rep->phi_reached = from_sc->fold_angle_deg;
    rep->gamma_reached = from_sc->fold_position;
    if (from_sc->nodes != to_sc->nodes || from_sc->length != to_sc->length ||
        from_sc->compression != to_sc->compression || from->n != to_sc->nodes ||
        (from_sc->fold_angle_deg == 0.0) != (to_sc->fold_angle_deg == 0.0))
        return ROD_ERR_SCENE;
    double dl = to_sc->compression;
    int nsteps = (int)ceil(fmax(fabs(to_sc->fold_position - from_sc->fold_position) / SEED_GAMMA_STEP,
                                fabs(to_sc->fold_angle_deg - from_sc->fold_angle_deg) / SEED_PHI_STEP_DEG));
    if (nsteps < 1) nsteps = 1;
    double p = 0.0, dp = 1.0 / nsteps, dp_max = 2.0 / nsteps, dp_min = ldexp(1.0 / nsteps, -SEED_MIN_STEP_LOG2);
    int max_solves = SEED_SOLVES_PER_STEP * nsteps;
    double *k1 = malloc(sizeof(double) * (size_t)from->n);
    if (!k1) return ROD_ERR_ALLOC;
    rod *cur = NULL;       /* last solved state (NULL: still `from`) */
    const rod *last = from;
    rod_obs ob;
    rod_observe(from, k1, &ob);
    double dz_last = ob.dz;
    rod_status st = ROD_OK;
    while (p < 1.0) {
        if (rep->solves >= max_solves) {
            st = ROD_ERR_ROUTE_CAP;
            break;
        }
        double pn = fmin(1.0, p + dp);
        if (1.0 - pn < 0.25 * dp) pn = 1.0;
        rod_scene sc = scene_at(from_sc, to_sc, pn);
        rod *trial = NULL;
        st = rod_alloc(&sc, &trial, NULL, 0);
        if (st != ROD_OK) break;
        rod_seed_remap(last, trial, dl);
        rod_newton_opts o = rod_newton_opts_static(&sc);
        o.positive_definite = 1;
        if (pn < 1.0) o.tolerance = fmax(o.tolerance, SEED_LOOSE);
        rod_newton_report nr;
        st = rod_newton_solve(trial, s, &o, &nr);
        rep->solves++;
        rep->newton_iterations += nr.iterations;
        if (st == ROD_OK) {
            rod_observe(trial, k1, &ob);
            /* A jump in Delta Z far beyond the step's: Newton slid onto another state. */
            if (!(fabs(ob.dz - dz_last) <= 0.02 + 2.0 * (pn - p))) st = ROD_ERR_BRANCH_LOST;
        }
        if (st == ROD_OK && rod_seed_is_stable(trial) == 0) {
            /* A negative eigenvalue: the followed stable state lost its stability within the
             * step (an eigenvalue crossed zero), or Newton converged to a saddle nearby. */
            st = ROD_ERR_BRANCH_LOST;
        }
        if (st == ROD_OK) {
            rod_free(cur);
            cur = trial;
            last = cur;
            dz_last = ob.dz;
            p = pn;
            rep->phi_reached = sc.fold_angle_deg;
            rep->gamma_reached = sc.fold_position;
            if (last_sc) *last_sc = sc;
            if (nr.iterations <= 5) dp = fmin(1.5 * dp, dp_max);
            continue;
        }
        rep->last_failure = st;
        rod_free(trial);
        if (0.5 * dp < dp_min) {
            st = ROD_ERR_BRANCH_LOST;
            break;
        }
        dp *= 0.5;
        st = ROD_OK;
    }
    free(k1);
    rep->reached = p;
    if (st != ROD_OK || p < 1.0) {
        if (st == ROD_OK) st = ROD_ERR_BRANCH_LOST;
        rep->eig_start = lowest_eigenvalue((rod *)from);
        rep->eig_last = cur ? lowest_eigenvalue(cur) : rep->eig_start;
        if (last_out) *last_out = cur;
        else rod_free(cur);
        return st;
    }
    *out = cur;
    return ROD_OK;
}
