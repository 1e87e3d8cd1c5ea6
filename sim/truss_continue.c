/* truss_continue.c: the symmetric branch of the truss in the load mu, its two events, and the
 * L2 at which their order switches.
 *
 * Design. The perfect model is mirror-symmetric, so the symmetric branch is followed inside the
 * symmetric subspace q = (a, b, D(mu) - a, b): unknowns u = (a, b, mu), residual
 * F = (dU/dq . (1, 0, -1, 0), dU/dq . (0, 1, 0, 1)) (the derivatives of U along the subspace at
 * fixed load). Restricting keeps the pitchfork from pulling the corrector off the branch (in the
 * full space the continuation matrix is singular at a branch point) and makes the symmetric
 * branch exact, not merely symmetric to round-off.
 *
 * Scaling. Along the branch y ~ alpha psi and the shortening of x ~ alpha^2, so arclength is
 * measured in X = (a / alpha^2, b / alpha, mu), where every coordinate moves by O(1).
 *
 * Pseudo-arclength: tangent tau from [dF/dX; tau_prev^T] tau = (0, 0, 1), normalised (the start
 * tangent points to decreasing mu: releasing the compression); predictor X + ds tau; corrector
 * Newton on (F(X), tau . (X - X_pred)) = 0 with a 3 x 3 LU. ds grows by 1.5 after an easy
 * corrector (<= 4 iterations) with a tangent that turned little, halves after a failed corrector
 * or a tangent that turned by more than about 15 degrees, within [ds_min, ds_max].
 *
 * Events, from the full Hessian split into its symmetric and antisymmetric 2 x 2 blocks (exact on
 * this branch, since H commutes with the mirror map): the saddle-node is where the lowest
 * symmetric eigenvalue changes sign (a turning point in mu), the pitchfork where the lowest
 * antisymmetric one does. Each is located by the Illinois false-position method on the step
 * length h from the last point before the sign change (the point reached by correcting
 * X_k + h tau_k), to locate_tol in h. The critical mode of the full Hessian at the located point
 * gives the cross-check: parity +1 and non-zero load projection at a saddle-node, parity -1 and
 * zero projection at a pitchfork.
 *
 * Release order: starting from the stable upper state, psi_S decreases monotonically along the
 * branch (upper part, then past the fold the middle part toward psi_S -> 0+, mu -> infinity), so
 * the event met first is the one with the larger psi_S; the switch function of L2 is
 * psi_S(pitchfork) - psi_S(saddle-node). */
#include "truss.h"
#include "truss_private.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A step is refused when the tangent turns by more than about 15 degrees over it, and the next
 * one may grow only when it turned by less than about 6 degrees. */
#define TANGENT_COS_MIN 0.966
#define TANGENT_COS_GROW 0.995

const char *truss_event_name(truss_event_type t)
{
    switch (t) {
    case TRUSS_EVENT_SADDLE_NODE: return "saddle-node";
    case TRUSS_EVENT_PITCHFORK: return "pitchfork";
    case TRUSS_EVENT_NONE: return "none";
    }
    return "none";
}

truss_cont_opts truss_cont_opts_default(void)
{
    truss_cont_opts o;
    o.mu_start = 1.0;
    o.mu_max = 20.0;
    o.psi_min = 1e-3;
    o.ds = 0.02;
    o.ds_min = 1e-8;
    o.ds_max = 0.1;
    o.max_steps = 20000;
    o.max_locate_iter = 200;
    o.locate_tol = 1e-11;
    o.newton = truss_newton_opts_default();
    return o;
}

/* State on the branch: scaled unknowns X and the tangent there. */
typedef struct cont_state {
    double X[3];
    double tau[3];
} cont_state;

typedef struct cont_ctx {
    const truss_params *p;
    const truss_cont_opts *o;
    double w[3];  /* X = u * w */
    double xs[3]; /* Newton step scales: the tolerance on X is step_tol itself */
} cont_ctx;

static void x_to_q(const cont_ctx *c, const double X[3], double q[4], double *mu)
{
    double a = X[0] / c->w[0], b = X[1] / c->w[1];
    *mu = X[2];
    double D = truss_support_right(c->p, *mu);
    q[0] = a;
    q[1] = b;
    q[2] = D - a;
    q[3] = b;
}

/* Residual F (2) and its Jacobian dF/dX (2 x 3, row-major) at X. */
static truss_error cont_residual(const cont_ctx *c, const double X[3], double F[2], double JF[6])
{
    double q[4], mu;
    x_to_q(c, X, q, &mu);
    double g[4], h[16], gmu[4];
    truss_error e = truss_energy_eval(c->p, mu, q, NULL, g, h, gmu);
    if (e != TRUSS_OK)
        return e;
    static const double pa[4] = {1, 0, -1, 0}, pb[4] = {0, 1, 0, 1};
    const double dD = -(2.0 + c->p->l2) * c->p->alpha * c->p->alpha;
    /* dq/dmu at fixed (a, b) is (0, 0, dD, 0); total d g / d mu = H[:,2] dD + gmu */
    double gm[4];
    for (int i = 0; i < 4; i++)
        gm[i] = h[4 * i + 2] * dD + gmu[i];
    const double *P[2] = {pa, pb};
    for (int r = 0; r < 2; r++) {
        double f = 0.0, ja = 0.0, jb = 0.0, jm = 0.0;
        for (int i = 0; i < 4; i++) {
            f += P[r][i] * g[i];
            jm += P[r][i] * gm[i];
            for (int j = 0; j < 4; j++) {
                ja += P[r][i] * h[4 * i + j] * pa[j];
                jb += P[r][i] * h[4 * i + j] * pb[j];
            }
        }
        F[r] = f;
        JF[3 * r + 0] = ja / c->w[0];
        JF[3 * r + 1] = jb / c->w[1];
        JF[3 * r + 2] = jm / c->w[2];
    }
    return TRUSS_OK;
}

/* Solve the 3 x 3 system A x = b in place (A row-major, destroyed). */
static truss_error solve3(double A[9], double b[3], double x[3])
{
    size_t perm_data[3];
    gsl_permutation perm = {3, perm_data};
    gsl_matrix_view av = gsl_matrix_view_array(A, 3, 3);
    gsl_vector_view bv = gsl_vector_view_array(b, 3);
    gsl_vector_view xv = gsl_vector_view_array(x, 3);
    int sign = 0;
    if (gsl_linalg_LU_decomp(&av.matrix, &perm, &sign) != GSL_SUCCESS)
        return TRUSS_ERR_GSL;
    double amax = 0.0, pmin = INFINITY;
    for (int i = 0; i < 3; i++) {
        pmin = fmin(pmin, fabs(A[4 * i]));
        for (int j = 0; j < 3; j++)
            amax = fmax(amax, fabs(A[3 * i + j]));
    }
    if (!(pmin > 1e-14 * amax))
        return TRUSS_ERR_SINGULAR;
    if (gsl_linalg_LU_solve(&av.matrix, &perm, &bv.vector, &xv.vector) != GSL_SUCCESS)
        return TRUSS_ERR_SINGULAR;
    for (int i = 0; i < 3; i++) {
        if (!isfinite(x[i]))
            return TRUSS_ERR_NAN;
    }
    return TRUSS_OK;
}

/* Unit tangent at X, oriented along tau_prev. */
static truss_error cont_tangent(const cont_ctx *c, const double X[3], const double tau_prev[3],
                                double tau[3])
{
    double F[2], JF[6];
    truss_error e = cont_residual(c, X, F, JF);
    if (e != TRUSS_OK)
        return e;
    double A[9] = {JF[0], JF[1], JF[2], JF[3], JF[4], JF[5], tau_prev[0], tau_prev[1], tau_prev[2]};
    double b[3] = {0.0, 0.0, 1.0};
    e = solve3(A, b, tau);
    if (e != TRUSS_OK)
        return e;
    double n = sqrt(tau[0] * tau[0] + tau[1] * tau[1] + tau[2] * tau[2]);
    if (!(n > 0.0) || !isfinite(n))
        return TRUSS_ERR_SINGULAR;
    for (int i = 0; i < 3; i++)
        tau[i] /= n;
    return TRUSS_OK;
}

/* Corrector from X0 + h tau0; writes the converged point to X and its iteration count. */
static truss_error cont_correct(const cont_ctx *c, const double X0[3], const double tau0[3],
                                double h, double X[3], int *iters)
{
    double Xp[3], x[3];
    for (int i = 0; i < 3; i++)
        Xp[i] = x[i] = X0[i] + h * tau0[i];
    for (int it = 1; it <= c->o->newton.max_iter; it++) {
        double F[2], JF[6];
        truss_error e = cont_residual(c, x, F, JF);
        if (e != TRUSS_OK)
            return e;
        double arc = 0.0;
        for (int i = 0; i < 3; i++)
            arc += tau0[i] * (x[i] - Xp[i]);
        double A[9] = {JF[0], JF[1], JF[2], JF[3], JF[4], JF[5], tau0[0], tau0[1], tau0[2]};
        double b[3] = {-F[0], -F[1], -arc};
        double dx[3];
        e = solve3(A, b, dx);
        if (e != TRUSS_OK)
            return e;
        double dmax = fmax(fabs(dx[0]), fmax(fabs(dx[1]), fabs(dx[2])));
        double fmaxv = fmax(fabs(F[0]), fabs(F[1]));
        /* a corrector step larger than the arclength step means it is jumping branches */
        if (dmax > 1.0 + 10.0 * fabs(h))
            return TRUSS_ERR_DIVERGED;
        for (int i = 0; i < 3; i++)
            x[i] += dx[i];
        if (truss_newton_converged(&c->o->newton, c->p->alpha, dx, x, c->xs, 3, fmaxv)) {
            for (int i = 0; i < 3; i++)
                X[i] = x[i];
            if (iters != NULL)
                *iters = it;
            return TRUSS_OK;
        }
    }
    return TRUSS_ERR_MAX_ITER;
}

static truss_error point_fill(const cont_ctx *c, const double X[3], double s, truss_point *pt)
{
    memset(pt, 0, sizeof *pt);
    x_to_q(c, X, pt->q, &pt->mu);
    truss_coords_psi(c->p, pt->mu, pt->q, &pt->psi_s, &pt->psi_a);
    pt->psi_a = 0.0; /* exact on the symmetric branch; atan2 round-off otherwise */
    pt->s = s;
    return truss_stability_eval(c->p, pt->mu, pt->q, &pt->stab);
}

static double event_value(const truss_point *pt, truss_event_type t)
{
    return t == TRUSS_EVENT_SADDLE_NODE ? pt->stab.eig_min_sym : pt->stab.eig_min_anti;
}

/* Illinois false position on h in (0, h1] for a sign change of the event's test function
 * between the point (X0, f0) and the one reached with step h1 (f1). */
static truss_error event_locate(const cont_ctx *c, const cont_state *st0, const truss_point *pt0,
                                double h1, const truss_point *pt1, truss_event_type type,
                                truss_event *ev)
{
    double ha = 0.0, fa = event_value(pt0, type);
    double hb = h1, fb = event_value(pt1, type);
    truss_point best = fabs(fa) < fabs(fb) ? *pt0 : *pt1;
    double best_f = fmin(fabs(fa), fabs(fb));
    int side = 0;
    int it;
    for (it = 0; it < c->o->max_locate_iter; it++) {
        if (fabs(hb - ha) < c->o->locate_tol)
            break;
        double hm = (ha * fb - hb * fa) / (fb - fa);
        if (!(hm > fmin(ha, hb) && hm < fmax(ha, hb)))
            hm = 0.5 * (ha + hb);
        double X[3];
        truss_error e = cont_correct(c, st0->X, st0->tau, hm, X, NULL);
        if (e != TRUSS_OK)
            return e;
        truss_point pm;
        e = point_fill(c, X, pt0->s + hm, &pm);
        if (e != TRUSS_OK)
            return e;
        double fm = event_value(&pm, type);
        if (fabs(fm) <= best_f) {
            best = pm;
            best_f = fabs(fm);
        }
        if (fm == 0.0) {
            ha = hb = hm;
            break;
        }
        if ((fm > 0.0) == (fa > 0.0)) {
            ha = hm;
            fa = fm;
            if (side == -1)
                fb *= 0.5;
            side = -1;
        } else {
            hb = hm;
            fb = fm;
            if (side == 1)
                fa *= 0.5;
            side = 1;
        }
    }
    if (it >= c->o->max_locate_iter)
        return TRUSS_ERR_MAX_ITER;
    ev->found = 1;
    ev->type = type;
    ev->at = best;
    return TRUSS_OK;
}

static truss_error branch_push(truss_branch *b, size_t *cap, const truss_point *pt)
{
    if (b->n == *cap) {
        size_t nc = *cap ? 2 * *cap : 64;
        truss_point *np = realloc(b->points, nc * sizeof *np);
        if (np == NULL)
            return TRUSS_ERR_NOMEM;
        b->points = np;
        *cap = nc;
    }
    b->points[b->n++] = *pt;
    return TRUSS_OK;
}

void truss_branch_free(truss_branch *b)
{
    if (b == NULL)
        return;
    free(b->points);
    b->points = NULL;
    b->n = 0;
}

static truss_error cont_opts_check(const truss_cont_opts *o)
{
    if (!isfinite(o->mu_start) || !isfinite(o->mu_max) || !(o->mu_max > o->mu_start))
        return TRUSS_ERR_PARAM;
    if (!(o->psi_min > 0.0) || !isfinite(o->psi_min))
        return TRUSS_ERR_PARAM;
    if (!(o->ds_min > 0.0) || !(o->ds_max >= o->ds_min) || !(o->ds >= o->ds_min) || !(o->ds <= o->ds_max))
        return TRUSS_ERR_PARAM;
    if (o->max_steps <= 0 || o->max_locate_iter <= 0 || !(o->locate_tol > 0.0))
        return TRUSS_ERR_PARAM;
    if (o->newton.max_iter <= 0 || !(o->newton.step_tol > 0.0) || !(o->newton.res_tol > 0.0))
        return TRUSS_ERR_PARAM;
    return TRUSS_OK;
}

truss_error truss_continue(const truss_params *p, const truss_cont_opts *opts, int keep_points,
                           truss_branch *out)
{
    memset(out, 0, sizeof *out);
    if (truss_params_check(p, NULL, 0) != TRUSS_OK || p->imperfection != 0.0)
        return TRUSS_ERR_PARAM;
    truss_error e = cont_opts_check(opts);
    if (e != TRUSS_OK)
        return e;
    /* the compression dl / l = mu alpha^2 must leave room between the supports */
    const double mu_max = fmin(opts->mu_max, TRUSS_COMPRESSION_MAX / (p->alpha * p->alpha));
    if (!(opts->mu_start < mu_max))
        return TRUSS_ERR_PARAM;
    const double ia2 = 1.0 / (p->alpha * p->alpha);
    cont_ctx c = {p, opts, {ia2, 1.0 / p->alpha, 1.0}, {ia2, ia2, ia2}};

    /* Upper state at mu_start: guess from the largest root of the small-angle cubic. */
    double roots[3];
    int nr = truss_analytic_psi_roots(p->lambda, p->l2, opts->mu_start, roots);
    double psi_guess = roots[nr == 3 ? 2 : 0];
    if (!(psi_guess > 0.0))
        psi_guess = sqrt((2.0 + p->l2) * opts->mu_start);
    double q[4];
    truss_config_guess(p, opts->mu_start, psi_guess, q);
    e = truss_statics_solve(p, opts->mu_start, q, &opts->newton, NULL);
    if (e != TRUSS_OK)
        return e;
    double D = truss_support_right(p, opts->mu_start);
    cont_state st;
    st.X[0] = 0.5 * (q[0] + D - q[2]) * c.w[0];
    st.X[1] = 0.5 * (q[1] + q[3]) * c.w[1];
    st.X[2] = opts->mu_start;
    /* polish in the symmetric subspace at fixed mu (tau = e_mu pins the load) */
    double e_mu[3] = {0.0, 0.0, 1.0};
    e = cont_correct(&c, st.X, e_mu, 0.0, st.X, NULL);
    if (e != TRUSS_OK)
        return e;
    truss_point pt;
    e = point_fill(&c, st.X, 0.0, &pt);
    if (e != TRUSS_OK)
        return e;
    if (!pt.stab.stable || !(pt.psi_s > 0.0))
        return TRUSS_ERR_NO_UPPER;
    double down[3] = {0.0, 0.0, -1.0};
    e = cont_tangent(&c, st.X, down, st.tau);
    if (e != TRUSS_OK)
        return e;

    size_t cap = 0;
    if (keep_points && (e = branch_push(out, &cap, &pt)) != TRUSS_OK)
        goto fail;

    double ds = opts->ds;
    out->end_reason = TRUSS_ERR_MAX_ITER;
    for (int step = 0; step < opts->max_steps; step++) {
        double X1[3];
        int iters = 0;
        e = cont_correct(&c, st.X, st.tau, ds, X1, &iters);
        if (e != TRUSS_OK) {
            if (ds * 0.5 < opts->ds_min) {
                out->end_reason = e;
                break;
            }
            ds *= 0.5;
            continue;
        }
        /* Step-size control on the turn of the tangent: a sharp fold (small Lambda) would
         * otherwise be overshot and the corrector could land on another branch. */
        double tau1[3];
        e = cont_tangent(&c, X1, st.tau, tau1);
        if (e != TRUSS_OK) {
            out->end_reason = e;
            break;
        }
        double turn = st.tau[0] * tau1[0] + st.tau[1] * tau1[1] + st.tau[2] * tau1[2];
        if (turn < TANGENT_COS_MIN && ds * 0.5 >= opts->ds_min) {
            ds *= 0.5;
            continue;
        }
        truss_point pt1;
        e = point_fill(&c, X1, pt.s + ds, &pt1);
        if (e != TRUSS_OK) {
            out->end_reason = e;
            break;
        }
        /* events between pt and pt1 */
        if (!out->saddle_node.found && (pt.stab.eig_min_sym > 0.0) != (pt1.stab.eig_min_sym > 0.0)) {
            e = event_locate(&c, &st, &pt, ds, &pt1, TRUSS_EVENT_SADDLE_NODE, &out->saddle_node);
            if (e != TRUSS_OK) {
                out->end_reason = e;
                break;
            }
            out->saddle_node.step = step;
        }
        if (!out->pitchfork.found && (pt.stab.eig_min_anti > 0.0) != (pt1.stab.eig_min_anti > 0.0)) {
            e = event_locate(&c, &st, &pt, ds, &pt1, TRUSS_EVENT_PITCHFORK, &out->pitchfork);
            if (e != TRUSS_OK) {
                out->end_reason = e;
                break;
            }
            out->pitchfork.step = step;
        }
        memcpy(st.X, X1, sizeof X1);
        memcpy(st.tau, tau1, sizeof tau1);
        pt = pt1;
        if (keep_points && (e = branch_push(out, &cap, &pt)) != TRUSS_OK)
            goto fail;
        if (out->saddle_node.found && out->pitchfork.found) {
            out->end_reason = TRUSS_OK;
            break;
        }
        if (pt.mu > mu_max || pt.psi_s < opts->psi_min || pt.mu < -mu_max) {
            out->end_reason = TRUSS_ERR_NOT_FOUND;
            break;
        }
        if (iters <= 4 && turn > TANGENT_COS_GROW)
            ds = fmin(ds * 1.5, opts->ds_max);
    }

    if (out->saddle_node.found && out->pitchfork.found)
        out->first = out->pitchfork.at.psi_s > out->saddle_node.at.psi_s ? TRUSS_EVENT_PITCHFORK
                                                                          : TRUSS_EVENT_SADDLE_NODE;
    else if (out->saddle_node.found)
        out->first = TRUSS_EVENT_SADDLE_NODE;
    else if (out->pitchfork.found)
        out->first = TRUSS_EVENT_PITCHFORK;
    /* Located events stay valid whatever ended the branch. A pitchfork not found means the
     * saddle-node came first (a pitchfork before it would lie on the part already followed).
     * The saddle-node itself must be found: without it the analysis is incomplete, and the
     * caller gets the reason the branch ended. */
    if (!out->saddle_node.found) {
        truss_error why = out->end_reason == TRUSS_OK ? TRUSS_ERR_NOT_FOUND : out->end_reason;
        truss_branch_free(out);
        return why;
    }
    return TRUSS_OK;

fail:
    truss_branch_free(out);
    return e;
}

/* psi_S(pitchfork) - psi_S(saddle-node) at L2: positive when the pitchfork comes first. */
static truss_error switch_value(const truss_params *p0, const truss_cont_opts *o, double l2, double *f)
{
    truss_params p = *p0;
    p.l2 = l2;
    truss_branch b;
    truss_error e = truss_continue(&p, o, 0, &b);
    if (e != TRUSS_OK)
        return e;
    /* No pitchfork on the followed branch: the saddle-node comes first; count the pitchfork at
     * psi_S = 0 (where the small-angle one goes as L2 -> 0) to keep f of one sign there. */
    *f = (b.pitchfork.found ? b.pitchfork.at.psi_s : 0.0) - b.saddle_node.at.psi_s;
    truss_branch_free(&b);
    return TRUSS_OK;
}

truss_error truss_switch_find(const truss_params *p, const truss_cont_opts *opts, double l2_lo,
                              double l2_hi, double l2_tol, double *l2_switch)
{
    if (!(l2_lo > 0.0) || !(l2_hi > l2_lo) || !isfinite(l2_hi) || !(l2_tol > 0.0))
        return TRUSS_ERR_PARAM;
    double fa, fb;
    truss_error e = switch_value(p, opts, l2_lo, &fa);
    if (e != TRUSS_OK)
        return e;
    e = switch_value(p, opts, l2_hi, &fb);
    if (e != TRUSS_OK)
        return e;
    if ((fa > 0.0) == (fb > 0.0))
        return TRUSS_ERR_NOT_FOUND;
    double a = l2_lo, b = l2_hi;
    int side = 0;
    for (int it = 0; it < 200; it++) {
        double m = (a * fb - b * fa) / (fb - fa);
        if (!(m > a && m < b))
            m = 0.5 * (a + b);
        if (b - a < l2_tol) {
            *l2_switch = m;
            return TRUSS_OK;
        }
        double fm;
        e = switch_value(p, opts, m, &fm);
        if (e != TRUSS_OK)
            return e;
        if (fm == 0.0) {
            *l2_switch = m;
            return TRUSS_OK;
        }
        if ((fm > 0.0) == (fa > 0.0)) {
            a = m;
            fa = fm;
            if (side == -1)
                fb *= 0.5;
            side = -1;
        } else {
            b = m;
            fb = fm;
            if (side == 1)
                fa *= 0.5;
            side = 1;
        }
    }
    return TRUSS_ERR_MAX_ITER;
}
