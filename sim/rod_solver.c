/* rod_solver.c: Newton with a backtracking line search on the free DOFs (see rod_solver.h).
 *
 * Convergence: max |R| <= tolerance * EI1 / l^2 (the scene's bending force scale), or, when the
 * residual sits at the floor of round-off from the stiff terms, a full Newton step smaller than
 * 1e-9 l in every position and 1e-7 rad in every twist angle while the residual is below 1e3
 * times the tolerance (every such exit checks it) (a tiny step along a stiff stretching direction can
 * still carry a large force); near a solution the error after a Newton step is second order in
 * the step, and the residual reported is the one computed after it. (The paper scene's creases, 1e4 times
 * stiffer than the ribbon, put the round-off floor of |R| near 1e-5 E I1 / l^2, above the default
 * tolerance, so most solves end this way; with the dynamics' predictor, after one iteration.)
 * Every iteration is capped and every failure has a named reason; a NaN anywhere in the
 * residual stops the solve with ROD_ERR_NAN instead of propagating. */
#include "rod_solver.h"
#include "rod_band.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct frames {
    double *q, (*d1)[3], (*d2)[3], (*tref)[3], *mref;
} frames;

struct rod_solver {
    int ndof, nfree;
    double *g;        /* full gradient (ndof) */
    double *res;      /* free residual (nfree) */
    double *H;        /* symmetric band (nfree x (ROD_BAND + 1)), factorised in place */
    double *Hraw;     /* Hessian of E alone at the state of the last residual that asked for it */
    int hraw_valid;   /* Hraw belongs to the current q (cleared whenever q changes) */
    gsl_matrix *LU;   /* general band for LU (nfree x (3 ROD_BAND + 1)) */
    gsl_vector_uint *piv;
    int fact;         /* factors of the last Jacobian of this solve: 0 none, 1 LDL^T in H, 2 LU */
    int shifted;      /* those factors are of a diagonally shifted Jacobian (steps are not Newton's) */
    double *dq;       /* Newton step (nfree) */
    frames base;      /* state at the start of the solve / iteration */
    frames slot[ROD_SOLVER_SLOTS];
};

static int frames_alloc(frames *f, int ndof, int n)
{
    f->q = malloc(sizeof(double) * (size_t)ndof);
    f->d1 = malloc(sizeof(double[3]) * (size_t)n);
    f->d2 = malloc(sizeof(double[3]) * (size_t)n);
    f->tref = malloc(sizeof(double[3]) * (size_t)n);
    f->mref = malloc(sizeof(double) * (size_t)n);
    return f->q && f->d1 && f->d2 && f->tref && f->mref;
}

static void frames_free(frames *f)
{
    free(f->q); free(f->d1); free(f->d2); free(f->tref); free(f->mref);
}

static void frames_save(const rod *r, frames *f)
{
    size_t n = (size_t)r->n;
    memcpy(f->q, r->q, sizeof(double) * (size_t)r->ndof);
    memcpy(f->d1, r->d1, sizeof(double[3]) * n);
    memcpy(f->d2, r->d2, sizeof(double[3]) * n);
    memcpy(f->tref, r->tref, sizeof(double[3]) * n);
    memcpy(f->mref, r->mref, sizeof(double) * n);
}

/* Restores frames only (not q) when with_q is 0. */
static void frames_load(rod *r, const frames *f, int with_q)
{
    size_t n = (size_t)r->n;
    if (with_q) memcpy(r->q, f->q, sizeof(double) * (size_t)r->ndof);
    memcpy(r->d1, f->d1, sizeof(double[3]) * n);
    memcpy(r->d2, f->d2, sizeof(double[3]) * n);
    memcpy(r->tref, f->tref, sizeof(double[3]) * n);
    memcpy(r->mref, f->mref, sizeof(double) * n);
}

rod_solver *rod_solver_alloc(const rod *r)
{
    rod_solver *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->ndof = r->ndof;
    s->nfree = rod_nfree(r);
    s->g = malloc(sizeof(double) * (size_t)s->ndof);
    s->res = malloc(sizeof(double) * (size_t)s->nfree);
    s->H = malloc(sizeof(double) * (size_t)s->nfree * (ROD_BAND + 1));
    s->Hraw = malloc(sizeof(double) * (size_t)s->nfree * (ROD_BAND + 1));
    s->dq = malloc(sizeof(double) * (size_t)s->nfree);
    s->LU = gsl_matrix_alloc((size_t)s->nfree, 3 * ROD_BAND + 1);
    s->piv = gsl_vector_uint_alloc((size_t)s->nfree);
    int ok = s->g && s->res && s->H && s->Hraw && s->dq && s->LU && s->piv && frames_alloc(&s->base, r->ndof, r->n);
    for (int k = 0; k < ROD_SOLVER_SLOTS; k++) ok = ok && frames_alloc(&s->slot[k], r->ndof, r->n);
    if (!ok) {
        rod_solver_free(s);
        return NULL;
    }
    return s;
}

void rod_solver_free(rod_solver *s)
{
    if (!s) return;
    free(s->g); free(s->res); free(s->H); free(s->Hraw); free(s->dq);
    if (s->LU) gsl_matrix_free(s->LU);
    if (s->piv) gsl_vector_uint_free(s->piv);
    frames_free(&s->base);
    for (int k = 0; k < ROD_SOLVER_SLOTS; k++) frames_free(&s->slot[k]);
    free(s);
}

const double *rod_solver_gradient(const rod_solver *s) { return s->g; }

void rod_state_save(const rod *r, rod_solver *s, int k) { frames_save(r, &s->slot[k]); }
void rod_state_restore(rod *r, const rod_solver *s, int k) { frames_load(r, &s->slot[k], 1); }

rod_newton_opts rod_newton_opts_static(const rod_scene *scene)
{
    rod_newton_opts o;
    memset(&o, 0, sizeof o);
    o.tolerance = scene->tolerance;
    o.max_iterations = scene->max_iterations;
    o.positive_definite = 0;
    return o;
}

/* Residual at the current q (frames transported from the solve's base). Returns max |R| or
 * NAN when anything is not finite; *l2 receives |R|_2 (the line search's merit: the Newton
 * direction is a descent direction for |R|_2, not for max |R|). With_hessian also assembles
 * the Hessian of E at q into Hraw in the same pass over the elements (they share the geometry):
 * worth it where a Newton iteration is expected to follow, as at the start of a solve. */
static double residual_h(rod *r, rod_solver *s, const rod_newton_opts *o, double *l2, int with_hessian)
{
    frames_load(r, &s->base, 0);
    rod_frames_update(r);
    if (with_hessian) {
        memset(s->Hraw, 0, sizeof(double) * (size_t)s->nfree * (ROD_BAND + 1));
        rod_gradient_hessian(r, s->g, 1.0, s->Hraw);
    } else {
        rod_gradient(r, s->g);
    }
    s->hraw_valid = with_hessian;
    double mx = 0.0, ss = 0.0;
    for (int a = 0; a < s->nfree; a++) {
        int k = a + ROD_FREE_BEGIN;
        double v = s->g[k];
        if (o->c1 != 0.0) v += o->c1 * r->mass[k] * (r->q[k] - o->q_n[k]);
        if (o->c2 != 0.0) v -= o->c2 * r->mass[k] * o->v_n[k];
        s->res[a] = v;
        if (!isfinite(v)) return NAN;
        mx = fmax(mx, fabs(v));
        ss += v * v;
    }
    if (o->c1 != 0.0 && o->damped) r->count.damping_evals++;
    *l2 = sqrt(ss);
    return mx;
}

/* Incremental potential whose gradient is R: E(q) + c1/2 |q - q_n|_M^2 - c2 v_n . M q. */
static double residual(rod *r, rod_solver *s, const rod_newton_opts *o, double *l2)
{
    return residual_h(r, s, o, l2, 0);
}

static double potential(rod *r, const rod_newton_opts *o)
{
    double phi = rod_energy(r);
    for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) {
        if (o->c1 != 0.0) phi += 0.5 * o->c1 * r->mass[k] * (r->q[k] - o->q_n[k]) * (r->q[k] - o->q_n[k]);
        if (o->c2 != 0.0) phi -= o->c2 * r->mass[k] * o->v_n[k] * r->q[k];
    }
    return phi;
}

static void assemble(rod *r, rod_solver *s, const rod_newton_opts *o, double shift)
{
    int nf = s->nfree, w = ROD_BAND + 1;
    if (!s->hraw_valid) {
        memset(s->Hraw, 0, sizeof(double) * (size_t)nf * (size_t)w);
        rod_hessian_add(r, 1.0, s->Hraw);
        s->hraw_valid = 1;
    }
    memcpy(s->H, s->Hraw, sizeof(double) * (size_t)nf * (size_t)w);
    if (o->c1 != 0.0)
        for (int a = 0; a < nf; a++) s->H[a * w] += o->c1 * r->mass[a + ROD_FREE_BEGIN];
    if (shift > 0.0)
        for (int a = 0; a < nf; a++) s->H[a * w] += shift * fabs(s->H[a * w]);
    for (int a = 0; a < nf; a++) s->dq[a] = -s->res[a];
}

/* Solves J dq = -res with J = c1 M + H. In minimising mode an indefinite J is shifted by
 * sigma diag|J| (sigma = 1e-4, 1e-3, ... up to 10) until LDL^T has positive pivots, which
 * makes dq a descent direction of the incremental potential (a stable equilibrium is a minimum);
 * otherwise, or when no shift helps, LU with partial pivoting solves the unshifted system. */
static rod_status linear_solve(rod *r, rod_solver *s, const rod_newton_opts *o)
{
    int nf = s->nfree, w = ROD_BAND + 1;
    gsl_vector_view x = gsl_vector_view_array(s->dq, (size_t)nf);
    if (o->positive_definite) {
        double shift = 0.0;
        for (int attempt = 0; attempt < 7; attempt++) {
            assemble(r, s, o, shift);
            r->count.factorisations++;
            if (rod_band_ldlt_decomp(s->H, nf) == 0) {
                int ok = 1;
                for (int a = 0; a < nf; a++)
                    if (!(s->H[a * w] > 0.0)) { ok = 0; break; }
                if (ok) {
                    rod_band_ldlt_solve(s->H, nf, s->dq);
                    s->fact = 1;
                    s->shifted = shift > 0.0;
                    return ROD_OK;
                }
            }
            shift = shift == 0.0 ? 1e-4 : shift * 10.0;
        }
        /* Far from any minimum a diagonal shift may not reach definiteness (diagonal entries
         * that nearly cancel): fall back to the unshifted LU step, checked by the line search. */
    }
    assemble(r, s, o, 0.0);
    r->count.factorisations++;
    s->fact = 0;
    s->shifted = 0;
    /* General band layout: LU(i, 2 B + j - i) = A(i, j) (A symmetric here). */
    gsl_matrix_set_zero(s->LU);
    for (int a = 0; a < nf; a++)
        for (int k = 0; k <= ROD_BAND && a + k < nf; k++) {
            double v = s->H[a * w + k];
            gsl_matrix_set(s->LU, (size_t)a, (size_t)(2 * ROD_BAND + k), v);
            gsl_matrix_set(s->LU, (size_t)(a + k), (size_t)(2 * ROD_BAND - k), v);
        }
    if (gsl_linalg_LU_band_decomp((size_t)nf, ROD_BAND, ROD_BAND, s->LU, s->piv) != GSL_SUCCESS)
        return ROD_ERR_SINGULAR;
    if (gsl_linalg_LU_band_svx(ROD_BAND, ROD_BAND, s->LU, s->piv, &x.vector) != GSL_SUCCESS)
        return ROD_ERR_SINGULAR;
    for (int a = 0; a < nf; a++)
        if (!isfinite(s->dq[a])) return ROD_ERR_SINGULAR;
    s->fact = 2;
    return ROD_OK;
}

/* The chord step: J_old dq = -res with the factors of the last Jacobian of this solve. */
static void chord_solve(rod_solver *s)
{
    int nf = s->nfree;
    for (int a = 0; a < nf; a++) s->dq[a] = -s->res[a];
    if (s->fact == 1) {
        rod_band_ldlt_solve(s->H, nf, s->dq);
    } else {
        gsl_vector_view x = gsl_vector_view_array(s->dq, (size_t)nf);
        gsl_linalg_LU_band_svx(ROD_BAND, ROD_BAND, s->LU, s->piv, &x.vector);
    }
}

rod_status rod_newton_solve(rod *r, rod_solver *s, const rod_newton_opts *o, rod_newton_report *rep)
{
    int nf = s->nfree;
    double fs = r->force_scale, tol = o->tolerance * fs;
    /* base anchors the frames: it is the start state, then each accepted iterate. */
    frames_save(r, &s->base);
    double l2 = 0.0, nl2 = 0.0;
    double res = residual_h(r, s, o, &l2, 1);
    double phi0 = NAN; /* potential at the base, computed only when the line search needs it */
    rod_status st = ROD_OK;
    int it = 0;
    double last_step = INFINITY; /* positions moved by the last accepted iteration (full steps only) */
    s->fact = 0;
    s->shifted = 0;
    if (rep) memset(rep, 0, sizeof *rep);
    if (isnan(res)) st = ROD_ERR_NAN;
    while (st == ROD_OK && res > tol) {
        if (it >= o->max_iterations) { st = ROD_ERR_MAXITER; break; }
        it++;
        r->count.newton_iterations++;
        /* Chord (modified Newton) step after a short full step: the Jacobian has hardly changed,
         * so its factors still give a step that converges (linearly, at a rate of about the
         * relative change of J), for one band solve instead of an assembly and a factorisation.
         * Where it is not accepted by the line search a fresh Jacobian is used. Never with the
         * factors of a shifted Jacobian: the shift damps the soft modes that carry the
         * residual, and chord steps with it converged at a rate of 0.97 per iteration until the
         * cap (seen from an extrapolated start on the paper's arch, whose softest stiffness,
         * ~0.1 N/m, is below the geometric stiffness of the predictor's stretch errors). */
        int chord = s->fact != 0 && !s->shifted && last_step < 1e-6 * r->length;
        if (chord) chord_solve(s);
        else st = linear_solve(r, s, o);
        if (st != ROD_OK) break;
        int bad = 0;
        for (int a = 0; a < nf && chord; a++)
            if (!isfinite(s->dq[a])) bad = 1;
        if (bad) { /* retry this iteration with a fresh Jacobian */
            s->fact = 0;
            last_step = INFINITY;
            it--;
            r->count.newton_iterations--;
            continue;
        }
        /* Backtracking on max |R|. */
        double alpha = 1.0, step_max = 0.0, turn_max = 0.0;
        for (int a = 0; a < nf; a++) {
            if ((a + ROD_FREE_BEGIN) % 4 != 3) step_max = fmax(step_max, fabs(s->dq[a]));
            else turn_max = fmax(turn_max, fabs(s->dq[a]));
        }
        /* A tiny step says the residual is at the round-off floor only if it is a Newton step of
         * the unshifted Jacobian: the shift of an indefinite Jacobian (up to 10 diag|J|,
         * diag|J| ~ 1e9 E I1 / l^3 at a stiff 175 deg crease) shrinks the step along the soft
         * modes that carry the residual, so a shifted step below 1e-9 l was seen with
         * |R| = 0.6 E I1 / l^2, 140 x the floor. Nor does a chord step, converging only linearly,
         * say it. Such solves go on iterating. */
        int tiny = step_max < 1e-9 * r->length && turn_max < 1e-7 && !s->shifted;
        if (!chord && tiny && res <= 1e3 * tol) {
            /* Converged (see the top): take the step, whose error is second order in it, and
             * carry the frames along. One residual pass reports the residual actually reached
             * (and keeps the gradient for the clamp reactions that of this state); the state is
             * the same whatever it says. */
            for (int a = 0; a < nf; a++) r->q[a + ROD_FREE_BEGIN] += s->dq[a];
            frames_load(r, &s->base, 0);
            rod_frames_update(r);
            res = residual(r, s, o, &l2);
            if (isnan(res)) st = ROD_ERR_NAN;
            break;
        }
        int accepted = 0;
        for (int ls = 0; ls < 12; ls++) {
            for (int a = 0; a < nf; a++) {
                int k = a + ROD_FREE_BEGIN;
                r->q[k] = s->base.q[k] + alpha * s->dq[a];
            }
            double nr = residual(r, s, o, &nl2);
            int better = nl2 < l2;
            if (o->positive_definite && !(better && alpha == 1.0)) {
                /* Minimising: a full step that lowers |R| is taken as is (the common case near a
                 * minimum, and it saves an energy pass); otherwise the potential must not rise
                 * beyond round-off, and where it is flat to round-off the residual decides. */
                if (isnan(phi0)) {
                    for (int a = 0; a < nf; a++) r->q[a + ROD_FREE_BEGIN] = s->base.q[a + ROD_FREE_BEGIN];
                    frames_load(r, &s->base, 0);
                    phi0 = potential(r, o);
                    for (int a = 0; a < nf; a++) r->q[a + ROD_FREE_BEGIN] = s->base.q[a + ROD_FREE_BEGIN] + alpha * s->dq[a];
                    residual(r, s, o, &nl2);
                }
                double phi_new = potential(r, o);
                double slack = 1e-13 * fabs(phi0) + 1e-300;
                better = phi_new < phi0 - slack || (phi_new <= phi0 + slack && nl2 < l2);
                if (better) phi0 = phi_new;
            } else if (better) {
                phi0 = NAN; /* the potential at the new base is not known yet */
            }
            if (isfinite(nr) && (better || nr <= tol)) {
                res = nr;
                l2 = nl2;
                accepted = 1;
                break;
            }
            alpha *= 0.5;
        }
        if (!accepted && chord) {
            /* Back to the base and a fresh Jacobian. */
            for (int a = 0; a < nf; a++) r->q[a + ROD_FREE_BEGIN] = s->base.q[a + ROD_FREE_BEGIN];
            res = residual(r, s, o, &l2);
            s->fact = 0;
            last_step = INFINITY;
            phi0 = NAN;
            continue;
        }
        last_step = alpha == 1.0 ? step_max : INFINITY;
        if (!accepted) {
            /* At the round-off floor a tiny full step cannot reduce |R|: that is convergence. */
            if (tiny && res <= 1e3 * tol) {
                for (int a = 0; a < nf; a++) r->q[a + ROD_FREE_BEGIN] = s->base.q[a + ROD_FREE_BEGIN];
                res = residual(r, s, o, &l2);
                break;
            }
            st = ROD_ERR_LINESEARCH;
            break;
        }
        /* Re-anchor the frames at the accepted state. */
        frames_save(r, &s->base);
        if (alpha == 1.0 && tiny && res <= 1e3 * tol) {
            if (!chord) break;
            /* A chord step converges only linearly: its being short says little. The next
             * iteration takes a fresh Jacobian, whose step decides. */
            s->fact = 0;
            last_step = INFINITY;
        }
    }
    if (rep) {
        rep->iterations = it;
        rep->residual = res;
        rep->residual_rel = res / fs;
    }
    return st;
}
