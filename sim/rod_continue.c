/* rod_continue.c: the path follower of rod_continue.h: corrector, tangent, stability of each
 * point, step control, event location and classification, branch switching.
 *
 * Workspace: everything (band Hessian, band LU, the bordering vectors, the snapshots of the
 * current point and of the event bracket, the events' modes and states) is allocated once in
 * rod_tracer_alloc; the stepping allocates only when a branch's point list grows. */
#include "rod_continue.h"
#include "rod_observe.h"
#include "rod_snapshot.h"
#include "rod_stability.h"
#include "rod_symmetry.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A point of the follower: state, load and unit tangent in Y (tq: n_free values). */
typedef struct cpoint {
    rod_snapshot snap;
    double lambda;
    double *tq, tl;
    int n_negative;
    int verified;
} cpoint;

struct rod_tracer {
    rod *r;
    rod_load load;
    rod_cont_opts o;
    int nf;
    double sq;              /* sqrt(n_free) */
    double *u;              /* unit of each free DOF (l or 1 rad) */
    double *H;              /* band Hessian (nf x (B + 1)) */
    gsl_matrix *lu;
    gsl_vector_uint *piv;
    double *g;              /* full gradient */
    double *R, *f, *a, *b, *qp, *v, *k1;
    double *kq, kl;         /* curvature of the path at cur in Y (quadratic predictor) */
    int have_k;             /* kq, kl valid: cur was reached by an accepted step from a previous point */
    double worst_res;       /* largest residual (over the force scale) of an accepted stalled corrector */
    rod_stab_ws *sw;
    cpoint cur, trial, next, lo, hi;
    rod_inertia inertia;    /* of the last assembled state */
    int corrector_iterations;
    char why[192];
    rod_event events[ROD_CONT_MAX_EVENTS];
    double *modes[ROD_CONT_MAX_EVENTS];
    cpoint estate[ROD_CONT_MAX_EVENTS];
    int nevents;
};

const char *rod_event_name(rod_event_kind k)
{
    switch (k) {
    case ROD_EVENT_SADDLE_NODE: return "saddle-node";
    case ROD_EVENT_PITCHFORK: return "pitchfork";
    case ROD_EVENT_BIFURCATION: return "bifurcation";
    case ROD_EVENT_UNCLASSIFIED: return "unclassified";
    }
    return "unclassified";
}

rod_cont_opts rod_cont_opts_default(void)
{
    rod_cont_opts o;
    o.ds = 0.01;
    o.ds_min = 1e-6;
    o.ds_max = 0.02;
    o.lambda_scale = 1.0;
    o.lambda_min = 0.0;
    o.lambda_max = 1.0;
    o.s_max = 3.0;
    o.max_steps = 600;
    o.max_corrector = 12;
    o.tolerance = 1e-6;
    o.max_locate = 60;
    o.locate_tol = 1e-5;
    o.max_negative = 2;
    o.eig_max_iter = 200;
    o.eig_tol = 1e-8;
    o.shift_rel = ROD_INERTIA_SHIFT_REL;
    o.turn_cos_min = 0.95;
    return o;
}

void rod_branch_free(rod_branch *b)
{
    free(b->points);
    b->points = NULL;
    b->n = b->cap = 0;
}

static int cpoint_alloc(const rod *r, int nf, cpoint *p)
{
    memset(p, 0, sizeof *p);
    p->tq = calloc((size_t)nf, sizeof(double));
    return p->tq && rod_snapshot_alloc(r, &p->snap);
}

static void cpoint_free(cpoint *p)
{
    free(p->tq);
    rod_snapshot_free(&p->snap);
}

static void cpoint_copy(const rod_tracer *t, const cpoint *from, cpoint *to)
{
    rod_snapshot_copy(&from->snap, &to->snap);
    memcpy(to->tq, from->tq, sizeof(double) * (size_t)t->nf);
    to->tl = from->tl;
    to->lambda = from->lambda;
    to->n_negative = from->n_negative;
    to->verified = from->verified;
}

void rod_tracer_free(rod_tracer *t)
{
    if (!t) return;
    free(t->u); free(t->H); free(t->g); free(t->R); free(t->f); free(t->a); free(t->b);
    free(t->qp); free(t->v); free(t->k1); free(t->kq);
    if (t->lu) gsl_matrix_free(t->lu);
    if (t->piv) gsl_vector_uint_free(t->piv);
    rod_stab_ws_free(t->sw);
    cpoint_free(&t->cur); cpoint_free(&t->trial); cpoint_free(&t->lo); cpoint_free(&t->hi);
    cpoint_free(&t->next);
    for (int e = 0; e < ROD_CONT_MAX_EVENTS; e++) {
        free(t->modes[e]);
        cpoint_free(&t->estate[e]);
    }
    free(t);
}

rod_tracer *rod_tracer_alloc(rod *r, const rod_load *p, const rod_cont_opts *o)
{
    rod_tracer *t = calloc(1, sizeof *t);
    if (!t) return NULL;
    t->r = r;
    t->load = *p;
    t->o = *o;
    int nf = t->nf = rod_nfree(r);
    size_t n = (size_t)nf;
    t->sq = sqrt((double)nf);
    t->u = malloc(sizeof(double) * n);
    t->H = malloc(sizeof(double) * n * (ROD_BAND + 1));
    t->g = malloc(sizeof(double) * (size_t)r->ndof);
    t->R = malloc(sizeof(double) * n);
    t->f = malloc(sizeof(double) * n);
    t->a = malloc(sizeof(double) * n);
    t->b = malloc(sizeof(double) * n);
    t->qp = malloc(sizeof(double) * n);
    t->v = calloc(n, sizeof(double));
    t->k1 = malloc(sizeof(double) * (size_t)r->n);
    t->kq = calloc(n, sizeof(double));
    t->lu = gsl_matrix_alloc(n, 3 * ROD_BAND + 1);
    t->piv = gsl_vector_uint_alloc(n);
    t->sw = rod_stab_ws_alloc(nf);
    int ok = t->u && t->H && t->g && t->R && t->f && t->a && t->b && t->qp && t->v && t->k1 && t->kq && t->lu &&
             t->piv && t->sw;
    ok = ok && cpoint_alloc(r, nf, &t->cur) && cpoint_alloc(r, nf, &t->trial) && cpoint_alloc(r, nf, &t->lo) &&
         cpoint_alloc(r, nf, &t->hi) && cpoint_alloc(r, nf, &t->next);
    if (!ok) {
        rod_tracer_free(t);
        return NULL;
    }
    for (int k = 0; k < nf; k++) t->u[k] = ((k + ROD_FREE_BEGIN) % 4 == 3) ? 1.0 : r->length;
    return t;
}

double rod_tracer_worst_residual(const rod_tracer *t) { return t->worst_res; }

const rod_event *rod_tracer_events(const rod_tracer *t, int *n)
{
    *n = t->nevents;
    return t->events;
}

double rod_tracer_event_state(rod_tracer *t, int e)
{
    if (e < 0 || e >= t->nevents || !t->modes[e]) return NAN;
    rod_snapshot_load(t->r, &t->estate[e].snap);
    rod_load_apply(t->r, &t->load, t->estate[e].lambda);
    rod_frames_update(t->r);
    return t->estate[e].lambda;
}

const double *rod_tracer_mode(const rod_tracer *t, int e)
{
    return (e >= 0 && e < t->nevents) ? t->modes[e] : NULL;
}

/* ---- linear algebra at the current state ---- */

/* Residual R at the current q (frames must be up to date); returns max |R|, NAN if not finite. */
static double residual(rod_tracer *t)
{
    rod_gradient(t->r, t->g);
    double mx = 0.0;
    for (int k = 0; k < t->nf; k++) {
        double v = t->R[k] = t->g[k + ROD_FREE_BEGIN];
        if (!isfinite(v)) return NAN;
        mx = fmax(mx, fabs(v));
    }
    return mx;
}

/* Assembles H and f at the current state and factorises H by band LU. */
static rod_status assemble_factor(rod_tracer *t)
{
    int nf = t->nf, w = ROD_BAND + 1;
    memset(t->H, 0, sizeof(double) * (size_t)nf * (size_t)w);
    rod_hessian_add(t->r, 1.0, t->H);
    rod_load_vector(t->r, &t->load, t->f);
    /* GSL's band LU layout: row a holds A(a, a + j - 2B) in column j (B fill-in columns first);
     * written through the data pointer (gsl_matrix_set checks bounds per element). */
    gsl_matrix_set_zero(t->lu);
    double *L = t->lu->data;
    size_t tda = t->lu->tda;
    for (int a = 0; a < nf; a++)
        for (int k = 0; k <= ROD_BAND && a + k < nf; k++) {
            double v = t->H[a * w + k];
            if (!isfinite(v)) return ROD_ERR_NAN;
            L[(size_t)a * tda + (size_t)(2 * ROD_BAND + k)] = v;
            L[(size_t)(a + k) * tda + (size_t)(2 * ROD_BAND - k)] = v;
        }
    t->r->count.factorisations++;
    if (gsl_linalg_LU_band_decomp((size_t)nf, ROD_BAND, ROD_BAND, t->lu, t->piv) != GSL_SUCCESS)
        return ROD_ERR_SINGULAR;
    return ROD_OK;
}

/* x <- K^-1 x with the current factorisation. */
static rod_status solve(rod_tracer *t, double *x)
{
    gsl_vector_view xv = gsl_vector_view_array(x, (size_t)t->nf);
    if (gsl_linalg_LU_band_svx(ROD_BAND, ROD_BAND, t->lu, t->piv, &xv.vector) != GSL_SUCCESS)
        return ROD_ERR_SINGULAR;
    for (int k = 0; k < t->nf; k++)
        if (!isfinite(x[k])) return ROD_ERR_SINGULAR;
    return ROD_OK;
}

/* Places the clamps at load lambda and transports the frames to the current q. */
static void set_state(rod_tracer *t, double lambda)
{
    rod_load_apply(t->r, &t->load, lambda);
    rod_frames_update(t->r);
}

/* ---- tangent and stability of a converged point ---- */

/* Tangent at the current (converged, assembled and factorised) state into p->tq, p->tl,
 * oriented to have a positive product with the orientation (oq, ol) in Y. */
static rod_status tangent(rod_tracer *t, cpoint *p, const double *oq, double ol)
{
    int nf = t->nf;
    memcpy(t->b, t->f, sizeof(double) * (size_t)nf);
    rod_status st = solve(t, t->b);
    if (st != ROD_OK) return st;
    double nn = 1.0 / (t->o.lambda_scale * t->o.lambda_scale);
    /* dq / dlambda = -b; in Y: -b_k / (u_k sq) per unit lambda, and 1 / lambda_scale. */
    for (int k = 0; k < nf; k++) {
        double y = -t->b[k] / (t->u[k] * t->sq);
        p->tq[k] = y;
        nn += y * y;
    }
    double inv = 1.0 / sqrt(nn);
    if (!isfinite(inv) || inv == 0.0) return ROD_ERR_SINGULAR;
    double dot = ol * inv / t->o.lambda_scale;
    for (int k = 0; k < nf; k++) {
        p->tq[k] *= inv;
        if (oq) dot += oq[k] * p->tq[k];
    }
    p->tl = inv / t->o.lambda_scale;
    if (dot < 0.0) {
        for (int k = 0; k < nf; k++) p->tq[k] = -p->tq[k];
        p->tl = -p->tl;
    }
    return ROD_OK;
}

static rod_status inertia(rod_tracer *t, int *n_negative)
{
    rod_status st = rod_inertia_eval(t->H, t->nf, t->o.shift_rel, t->sw, &t->inertia, t->why, sizeof t->why);
    *n_negative = t->inertia.n_negative;
    return st;
}

/* Fills a branch point from the current state of the rod. */
static void observe(rod_tracer *t, const cpoint *p, double s, rod_cont_point *out)
{
    rod_obs ob;
    rod_observe(t->r, t->k1, &ob);
    memset(out, 0, sizeof *out);
    out->lambda = p->lambda;
    rod_load_clamps(&t->load, p->lambda, &out->dl, &out->dw);
    out->dz = isfinite(ob.dz) ? ob.dz : 0.0;
    out->a = isfinite(ob.a) ? ob.a : 0.0;
    double e = rod_energy(t->r);
    out->energy = isfinite(e) ? e : 0.0;
    out->s = s;
    out->t_lambda = p->tl;
    out->n_negative = p->n_negative;
    out->stable = p->n_negative == 0;
    out->verified = p->verified;
}

/* ---- corrector ---- */

#define STALL_FACTOR 1e3

/* From base point p, corrects Y_p + h tau (tau = (tq, tl)) onto the branch with the constraint
 * tau . (Y - Y_pred) = 0. On success the rod holds the new state at *lambda_out and H is
 * assembled and factorised there; returns the status otherwise (the rod is then undefined:
 * callers reload a snapshot). */
static rod_status correct(rod_tracer *t, const cpoint *p, const double *tq, double tl, const double *kq, double kl,
                          double h, double *lambda_out)
{
    rod *r = t->r;
    int nf = t->nf;
    const rod_cont_opts *o = &t->o;
    rod_snapshot_load(r, &p->snap);
    double h2 = 0.5 * h * h;
    for (int k = 0; k < nf; k++) {
        t->qp[k] = r->q[k + ROD_FREE_BEGIN] + (h * tq[k] + (kq ? h2 * kq[k] : 0.0)) * t->u[k] * t->sq;
        r->q[k + ROD_FREE_BEGIN] = t->qp[k];
    }
    double lp = p->lambda + (h * tl + (kq ? h2 * kl : 0.0)) * o->lambda_scale, lambda = lp;
    set_state(t, lambda);
    double tol = o->tolerance * r->force_scale;
    t->corrector_iterations = 0;
    rod_status st;
    double hist[3] = {INFINITY, INFINITY, INFINITY}, res0 = INFINITY;
    int have_lu = 0; /* a factorisation of an iterate of this corrector is in t->lu */
    int fresh;       /* this iteration factorised (else a chord step: t->b is still K^-1 f) */
    for (int it = 0;; it++) {
        double res = residual(t);
        if (isnan(res)) {
            snprintf(t->why, sizeof t->why, "non-finite residual in the corrector");
            return ROD_ERR_NAN;
        }
        /* Constraint residual c = tau . (Y - Y_pred). */
        double c = tl * (lambda - lp) / o->lambda_scale;
        for (int k = 0; k < nf; k++) c += tq[k] * (r->q[k + ROD_FREE_BEGIN] - t->qp[k]) / (t->u[k] * t->sq);
        if (res <= tol && fabs(c) <= 1e-10 * (h > 0 ? h : 1.0)) break;
        /* Stalled: within STALL_FACTOR of the tolerance and not halving over three iterations.
         * This happens only next to a critical point, where the Hessian (the symmetric part of
         * the frame-transported Jacobian, rod_bend.c) no longer contracts the error along the
         * nearly singular mode. The state is accepted and the residual recorded. */
        if (res <= STALL_FACTOR * tol && res > 0.5 * hist[0] && it >= 3) {
            t->worst_res = fmax(t->worst_res, res / r->force_scale);
            break;
        }
        /* Diverging: undamped Newton from a predictor too far from the branch grows the
         * residual past where it started; the step is redone shorter at once instead of
         * spending the whole iteration cap. */
        if (it == 0) res0 = res;
        else if (res > 2.0 * res0 && res > STALL_FACTOR * tol) {
            snprintf(t->why, sizeof t->why, "corrector diverged (residual %.3g of the force scale after %d iterations)",
                     res / r->force_scale, it);
            return ROD_ERR_MAXITER;
        }
        hist[0] = hist[1];
        hist[1] = hist[2];
        hist[2] = res;
        if (it >= o->max_corrector) {
            snprintf(t->why, sizeof t->why, "corrector did not converge in %d iterations (residual %.3g of the force scale)",
                     o->max_corrector, res / r->force_scale);
            return ROD_ERR_MAXITER;
        }
        /* Chord tail: within STALL_FACTOR of the tolerance, and while the residual keeps
         * falling at least fourfold per iteration, the factorisation of an earlier iterate is
         * kept (the remaining correction is small); otherwise, and always at the accepted
         * state, where the tangent and the inertia need it, the Hessian is assembled again. */
        fresh = 0;
        if (!have_lu || res > STALL_FACTOR * tol || res > 0.25 * hist[1]) {
            if ((st = assemble_factor(t)) != ROD_OK) {
                snprintf(t->why, sizeof t->why, "singular Jacobian in the corrector");
                return st;
            }
            have_lu = 1;
            fresh = 1;
        }
        t->corrector_iterations++;
        r->count.newton_iterations++;
        /* b = K^-1 f changes only with the factorisation (a chord step keeps the last one). */
        for (int k = 0; k < nf; k++) t->a[k] = -t->R[k];
        if (fresh) memcpy(t->b, t->f, sizeof(double) * (size_t)nf);
        if ((st = solve(t, t->a)) != ROD_OK || (fresh && (st = solve(t, t->b)) != ROD_OK)) {
            snprintf(t->why, sizeof t->why, "singular Jacobian in the corrector");
            return st;
        }
        double ta = 0.0, tb = 0.0;
        for (int k = 0; k < nf; k++) {
            double w = tq[k] / (t->u[k] * t->sq);
            ta += w * t->a[k];
            tb += w * t->b[k];
        }
        double den = tl / o->lambda_scale - tb;
        double dl = (-c - ta) / den;
        if (!isfinite(dl)) {
            snprintf(t->why, sizeof t->why, "bordered system singular in the corrector");
            return ROD_ERR_SINGULAR;
        }
        double step = (dl / o->lambda_scale) * (dl / o->lambda_scale);
        for (int k = 0; k < nf; k++) {
            double d = t->a[k] - dl * t->b[k];
            r->q[k + ROD_FREE_BEGIN] += d;
            step += (d / (t->u[k] * t->sq)) * (d / (t->u[k] * t->sq));
        }
        lambda += dl;
        set_state(t, lambda);
        step = sqrt(step);
        if (!isfinite(step)) {
            snprintf(t->why, sizeof t->why, "non-finite corrector step");
            return ROD_ERR_NAN;
        }
        /* At the round-off floor a tiny step that leaves the residual just above tol is
         * convergence (as in rod_solver.c). */
        if (step < 1e-12 && res <= 1e3 * tol) {
            double res2 = residual(t);
            if (isnan(res2)) return ROD_ERR_NAN;
            break;
        }
    }
    /* Every exit above leaves a state whose Hessian is not yet assembled. */
    if ((st = assemble_factor(t)) != ROD_OK) {
        snprintf(t->why, sizeof t->why, "singular Jacobian at the corrected point");
        return st;
    }
    /* Jump guard: the corrector must stay within the step length of the predictor. */
    double dev = (lambda - lp) / o->lambda_scale;
    dev *= dev;
    for (int k = 0; k < nf; k++) {
        double d = (r->q[k + ROD_FREE_BEGIN] - t->qp[k]) / (t->u[k] * t->sq);
        dev += d * d;
    }
    if (sqrt(dev) > fmax(fabs(h), 1e-12)) {
        snprintf(t->why, sizeof t->why, "corrector moved %.3g from the predictor (step %.3g): left the branch",
                 sqrt(dev), h);
        return ROD_ERR_BRANCH_LOST;
    }
    *lambda_out = lambda;
    return ROD_OK;
}

/* Corrects from p along its own tangent by h into q (state, load, tangent oriented along p's,
 * inertia). The rod holds q's state afterwards, assembled. */
static rod_status step_to(rod_tracer *t, const cpoint *p, double h, cpoint *q)
{
    double lambda;
    int quad = p == &t->cur && t->have_k;
    rod_status st = correct(t, p, p->tq, p->tl, quad ? t->kq : NULL, t->kl, h, &lambda);
    if (st != ROD_OK) return st;
    q->lambda = lambda;
    if ((st = tangent(t, q, p->tq, p->tl)) != ROD_OK) {
        snprintf(t->why, sizeof t->why, "singular tangent system");
        return st;
    }
    if ((st = inertia(t, &q->n_negative)) != ROD_OK) return st;
    q->verified = t->inertia.verified;
    rod_snapshot_save(t->r, &q->snap);
    return ROD_OK;
}

static int append(rod_branch *b, const rod_cont_point *pt)
{
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 64;
        rod_cont_point *np = realloc(b->points, cap * sizeof *np);
        if (!np) return 0;
        b->points = np;
        b->cap = cap;
    }
    b->points[b->n++] = *pt;
    return 1;
}

/* ---- events ---- */

static rod_event_kind classify(double parity, int fold)
{
    if (parity <= -0.9) return ROD_EVENT_PITCHFORK;
    if (fold) return ROD_EVENT_SADDLE_NODE;
    if (parity >= 0.9) return ROD_EVENT_BIFURCATION;
    return ROD_EVENT_UNCLASSIFIED;
}

/* Eigenvalue nearest zero of the Hessian assembled at the rod's current state (t->H, as
 * assemble_factor and step_to leave it) into *value, with v as start vector and result. */
static rod_status eig_here(rod_tracer *t, double *v, double *value)
{
    rod_eigpair ep;
    rod_status st = rod_eig_nearest(t->H, t->nf, 0.0, t->o.eig_max_iter, t->o.eig_tol, t->sw, v, &ep, t->why,
                                    sizeof t->why);
    *value = ep.value;
    return st;
}

/* Eigenpair nearest zero at the state of c (reloaded and reassembled) into v. */
static rod_status critical_eig(rod_tracer *t, const cpoint *c, double *v, double *value)
{
    rod_snapshot_load(t->r, &c->snap);
    rod_load_apply(t->r, &t->load, c->lambda);
    rod_frames_update(t->r);
    rod_status st = assemble_factor(t);
    if (st != ROD_OK) return st;
    return eig_here(t, v, value);
}

/* Next trial step length in the bracket (hlo, hhi): the secant root of the critical eigenvalue
 * (mu_lo, mu_hi: its values at the ends, ok when they have opposite signs), kept at least eps
 * inside the bracket, so that once the root is known to eps the next trial lands on its other
 * side and closes the bracket to about eps; bisection when the secant is not usable or when the
 * last two trials did not halve the bracket (the guarantee of convergence). */
static double locate_next(double hlo, double hhi, double mu_lo, double mu_hi, int secant_ok, double eps)
{
    double w = hhi - hlo, hm = 0.5 * (hlo + hhi);
    if (!secant_ok || !isfinite(mu_lo) || !isfinite(mu_hi) || !((mu_lo > 0.0) != (mu_hi > 0.0)) || w <= 2.0 * eps)
        return hm;
    double r = hlo + w * mu_lo / (mu_lo - mu_hi);
    if (!isfinite(r)) return hm;
    return fmin(fmax(r, hlo + eps), hhi - eps);
}

/* Locates the change of n_negative between t->cur and the accepted step q (at arclength h from
 * cur; the rod holds q's state with its Hessian assembled, as step_to leaves it), classifies it
 * and records it. Location: safeguarded secant (regula falsi) on the critical eigenvalue along
 * the step length, each trial point corrected onto the branch from cur; which side a trial lies
 * on is decided by its verified negative count, the eigenvalue only chooses where to try.
 * Typically 3-5 trials instead of bisection's 15. Returns 0, recording nothing, when the bracket
 * did not close and may_refuse is set; 1 otherwise. Leaves the rod in an undefined state (the
 * caller reloads). */
static int locate_event(rod_tracer *t, rod_branch *b, const cpoint *q, double h, double s_cur, int may_refuse)
{
    if (t->nevents >= ROD_CONT_MAX_EVENTS) return 1;
    rod_event *e = &t->events[t->nevents];
    memset(e, 0, sizeof *e);
    e->branch = b->id;
    e->index = (int)b->n - 1;
    e->n_negative_before = t->cur.n_negative;
    e->n_negative_after = q->n_negative;
    double *v = t->v;
    memset(v, 0, sizeof(double) * (size_t)t->nf);
    double mu_lo = NAN, mu_hi = NAN, mu;
    if (eig_here(t, v, &mu) == ROD_OK) mu_hi = mu;
    cpoint_copy(t, &t->cur, &t->lo);
    cpoint_copy(t, q, &t->hi);
    if (critical_eig(t, &t->lo, v, &mu) == ROD_OK) mu_lo = mu;
    double hlo = 0.0, hhi = h, eps = 0.4 * t->o.locate_tol, w_prev = INFINITY;
    int located = 0, secant_ok = 1;
    for (int it = 0; it < t->o.max_locate; it++) {
        if (fabs(t->hi.lambda - t->lo.lambda) <= t->o.locate_tol * t->o.lambda_scale &&
            hhi - hlo <= 10.0 * t->o.locate_tol) {
            located = 1;
            break;
        }
        double w0 = hhi - hlo;
        double hm = locate_next(hlo, hhi, mu_lo, mu_hi, secant_ok, eps);
        if (step_to(t, &t->cur, hm, &t->trial) != ROD_OK) break;
        int have_mu = eig_here(t, v, &mu) == ROD_OK;
        int lo_side = t->trial.n_negative == t->cur.n_negative;
        if (lo_side) {
            cpoint_copy(t, &t->trial, &t->lo);
            hlo = hm;
            mu_lo = have_mu ? mu : NAN;
        } else {
            cpoint_copy(t, &t->trial, &t->hi);
            hhi = hm;
            mu_hi = have_mu ? mu : NAN;
        }
        secant_ok = have_mu && hhi - hlo <= 0.5 * w_prev;
        w_prev = w0;
    }
    /* A bracket that does not close, because the trial points inside the step cannot be
     * corrected onto the branch, means the step left it: typically it jumped over a sharp fold
     * (a pitchfork unfolded by an imperfection) onto the nearby disconnected branch. The caller
     * redoes the step shorter. */
    if (!located && may_refuse) return 0;
    e->located = located;
    e->lambda_width = fabs(t->hi.lambda - t->lo.lambda);
    /* The mode at hi (with f assembled there) and, when the bracket start's eigenvalue was not
     * computed, the one at lo first. */
    if (!isfinite(mu_lo) && critical_eig(t, &t->lo, v, &mu) == ROD_OK) mu_lo = mu;
    rod_status s2 = critical_eig(t, &t->hi, v, &mu);
    if (s2 == ROD_OK) mu_hi = mu;
    if (s2 != ROD_OK || !isfinite(mu_lo)) e->located = 0;
    e->eig_before = isfinite(mu_lo) ? mu_lo : 0.0;
    e->eig_after = isfinite(mu_hi) ? mu_hi : 0.0;
    /* The rod is at hi with f assembled there: parity and load projection of the mode. */
    double fn = 0.0, vf = 0.0;
    for (int k = 0; k < t->nf; k++) {
        fn += t->f[k] * t->f[k];
        vf += v[k] * t->f[k];
    }
    e->parity = rod_mode_parity(t->r, v);
    e->load_projection = fn > 0.0 ? fabs(vf) / sqrt(fn) : 0.0;
    e->fold = (t->lo.tl > 0.0) != (t->hi.tl > 0.0);
    e->kind = classify(e->parity, e->fold);
    /* On a C2-symmetric branch a turning point's critical mode is even: the load path of a
     * symmetric state cannot turn on an odd mode. An odd mode nearest zero at a symmetric fold
     * means a pitchfork lies just past it on the unstable side (within about 2e-3 in Gamma of the
     * codim-2 point, measured at N = 61): the eigenvalue that crossed is the even one, and the
     * event is the saddle-node. (An imperfect pitchfork, the limit point of an asymmetric state,
     * keeps its classification.) */
    if (e->fold && e->kind == ROD_EVENT_PITCHFORK && rod_state_asymmetry(t->r) < 1e-9) e->kind = ROD_EVENT_SADDLE_NODE;
    rod_snapshot_load(t->r, &t->lo.snap);
    rod_load_apply(t->r, &t->load, t->lo.lambda);
    rod_frames_update(t->r);
    observe(t, &t->lo, s_cur + hlo, &e->at);
    e->at.lambda = 0.5 * (t->lo.lambda + t->hi.lambda);
    rod_load_clamps(&t->load, e->at.lambda, &e->at.dl, &e->at.dw);
    /* Keep the mode and the state for branch switching. */
    int k = t->nevents;
    if (!t->modes[k]) t->modes[k] = malloc(sizeof(double) * (size_t)t->nf);
    if (!t->estate[k].tq && !cpoint_alloc(t->r, t->nf, &t->estate[k])) {
        cpoint_free(&t->estate[k]);
        free(t->modes[k]);
        t->modes[k] = NULL;
    }
    if (t->modes[k]) {
        memcpy(t->modes[k], v, sizeof(double) * (size_t)t->nf);
        cpoint_copy(t, &t->lo, &t->estate[k]);
    }
    t->nevents++;
    return 1;
}

/* ---- the stepping loop ---- */

/* A step across which the count changed but whose event could not be located is redone at half
 * the length while it is longer than this many ds_min (then the event is kept, marked not
 * located). */
#define REFUSE_STEPS 16.0

static rod_status trace_from_cur(rod_tracer *t, rod_branch *b, double s0)
{
    t->have_k = 0;
    const rod_cont_opts *o = &t->o;
    double h = o->ds, s = s0;
    int steps = 0;
    rod_status st = ROD_OK;
    for (;;) {
        rod_cont_point *last = &b->points[b->n - 1];
        if (last->lambda < o->lambda_min || last->lambda > o->lambda_max) {
            snprintf(b->end_reason, sizeof b->end_reason, "left the load range [%g, %g] at %.6g", o->lambda_min,
                     o->lambda_max, last->lambda);
            return ROD_OK;
        }
        if (last->n_negative > o->max_negative) {
            snprintf(b->end_reason, sizeof b->end_reason, "more than %d negative eigenvalues at load %.6g",
                     o->max_negative, last->lambda);
            return ROD_OK;
        }
        if (s >= o->s_max) {
            snprintf(b->end_reason, sizeof b->end_reason, "arclength limit %g reached at load %.6g", o->s_max,
                     last->lambda);
            return ROD_OK;
        }
        if (steps++ >= o->max_steps) {
            snprintf(b->end_reason, sizeof b->end_reason, "step cap %d reached at load %.6g", o->max_steps,
                     last->lambda);
            return ROD_ERR_MAXITER;
        }
        st = step_to(t, &t->cur, h, &t->trial);
        double turn = 1.0;
        if (st == ROD_OK) {
            turn = t->trial.tl * t->cur.tl;
            for (int k = 0; k < t->nf; k++) turn += t->trial.tq[k] * t->cur.tq[k];
        }
        int jump = st == ROD_OK && abs(t->trial.n_negative - t->cur.n_negative) > 1;
        if (st != ROD_OK || ((turn < o->turn_cos_min || jump) && h > o->ds_min)) {
            if (h <= o->ds_min) {
                snprintf(b->end_reason, sizeof b->end_reason, "step fell below ds_min at load %.6g: %.100s",
                         last->lambda, t->why);
                return st != ROD_OK ? st : ROD_ERR_BRANCH_LOST;
            }
            h = fmax(0.5 * h, o->ds_min);
            continue;
        }
        int iters = t->corrector_iterations;
        cpoint_copy(t, &t->trial, &t->next);
        if (t->next.n_negative != t->cur.n_negative &&
            !locate_event(t, b, &t->next, h, s, h > REFUSE_STEPS * o->ds_min)) {
            h = fmax(0.5 * h, o->ds_min);
            continue;
        }
        rod_snapshot_load(t->r, &t->next.snap);
        s += h;
        rod_cont_point pt;
        observe(t, &t->next, s, &pt);
        if (!append(b, &pt)) {
            snprintf(b->end_reason, sizeof b->end_reason, "out of memory");
            return ROD_ERR_ALLOC;
        }
        for (int k = 0; k < t->nf; k++) t->kq[k] = (t->next.tq[k] - t->cur.tq[k]) / h;
        t->kl = (t->next.tl - t->cur.tl) / h;
        t->have_k = 1;
        cpoint_copy(t, &t->next, &t->cur);
        if (iters <= 5 && turn > 0.995) h = fmin(1.5 * h, o->ds_max);
    }
}

rod_status rod_trace_branch(rod_tracer *t, double lambda0, int direction, rod_branch *b)
{
    b->end_status = ROD_OK;
    b->end_reason[0] = '\0';
    set_state(t, lambda0);
    t->cur.lambda = lambda0;
    double res = residual(t);
    rod_status st = isnan(res) ? ROD_ERR_NAN : assemble_factor(t);
    if (st == ROD_OK) st = tangent(t, &t->cur, NULL, direction >= 0 ? 1.0 : -1.0);
    if (st == ROD_OK) st = inertia(t, &t->cur.n_negative);
    t->cur.verified = t->inertia.verified;
    if (st != ROD_OK) {
        snprintf(b->end_reason, sizeof b->end_reason, "cannot start at load %g: %s", lambda0,
                 rod_status_message(st));
        return b->end_status = st;
    }
    /* The start is the route's (or a caller's) converged state; Newton ends at the round-off
     * floor of stiff scenes only below 1e3 times the tolerance (rod_solver.c), so that is the
     * bound here too. */
    if (res > 1e3 * t->o.tolerance * t->r->force_scale) {
        snprintf(b->end_reason, sizeof b->end_reason, "the start is not an equilibrium (residual %.3g of the force scale)",
                 res / t->r->force_scale);
        return b->end_status = ROD_ERR_SCENE;
    }
    rod_snapshot_save(t->r, &t->cur.snap);
    rod_cont_point pt;
    observe(t, &t->cur, 0.0, &pt);
    if (!append(b, &pt)) return b->end_status = ROD_ERR_ALLOC;
    return b->end_status = trace_from_cur(t, b, 0.0);
}

rod_status rod_trace_switch(rod_tracer *t, int e, double sign, double offset, rod_branch *b)
{
    b->end_status = ROD_OK;
    b->end_reason[0] = '\0';
    if (e < 0 || e >= t->nevents || !t->modes[e]) {
        snprintf(b->end_reason, sizeof b->end_reason, "no stored mode for event %d", e);
        return b->end_status = ROD_ERR_SCENE;
    }
    int nf = t->nf;
    const cpoint *ps = &t->estate[e];
    /* Direction in Y: the mode, scaled, with no load component. */
    double *dir = t->a, nn = 0.0;
    for (int k = 0; k < nf; k++) {
        dir[k] = sign * t->modes[e][k] / (t->u[k] * t->sq);
        nn += dir[k] * dir[k];
    }
    nn = sqrt(nn);
    if (!(nn > 0.0)) {
        snprintf(b->end_reason, sizeof b->end_reason, "critical mode of event %d is zero", e);
        return b->end_status = ROD_ERR_SCENE;
    }
    /* The point list starts at the pitchfork. */
    rod_snapshot_load(t->r, &ps->snap);
    set_state(t, ps->lambda);
    rod_cont_point pt;
    observe(t, ps, 0.0, &pt);
    pt.n_negative = ps->n_negative;
    pt.stable = pt.n_negative == 0;
    pt.t_lambda = 0.0;
    if (!append(b, &pt)) return b->end_status = ROD_ERR_ALLOC;
    double *dq = malloc(sizeof(double) * (size_t)nf);
    if (!dq) return b->end_status = ROD_ERR_ALLOC;
    for (int k = 0; k < nf; k++) dq[k] = dir[k] / nn;
    double h = offset, lambda = 0.0;
    rod_status st = ROD_ERR_BRANCH_LOST;
    for (int attempt = 0; attempt < 8; attempt++, h *= 0.5) {
        st = correct(t, ps, dq, 0.0, NULL, 0.0, h, &lambda);
        if (st == ROD_OK) break;
    }
    if (st == ROD_OK) {
        t->cur.lambda = lambda;
        st = tangent(t, &t->cur, dq, 0.0);
    }
    if (st == ROD_OK) st = inertia(t, &t->cur.n_negative);
    t->cur.verified = t->inertia.verified;
    free(dq);
    if (st != ROD_OK) {
        snprintf(b->end_reason, sizeof b->end_reason, "could not leave the pitchfork along its mode: %.100s", t->why);
        return b->end_status = st;
    }
    rod_snapshot_save(t->r, &t->cur.snap);
    observe(t, &t->cur, h, &pt);
    if (!append(b, &pt)) return b->end_status = ROD_ERR_ALLOC;
    return b->end_status = trace_from_cur(t, b, h);
}
