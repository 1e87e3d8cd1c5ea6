/* rod_critical.c: the augmented systems of rod_critical.h: parameters applied to a rod, the
 * block test functions by bordering, their derivatives by differences of the analytic Hessian,
 * and Newton with block elimination on the band LU.
 *
 * Workspace: two band Hessians (the state's and a perturbed one), the band LU, and the vectors of
 * one Newton iteration, all allocated in rod_crit_alloc; the iteration allocates nothing. */
#include "rod_critical.h"
#include "rod_load.h"
#include "rod_snapshot.h"
#include "rod_stability.h"
#include "rod_symmetry.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define W (ROD_BAND + 1)
#define MAXM 2
/* Residual (over E I1 / l^2) above which Newton first restores equilibrium (see rod_crit_solve). */
#define PHASE1_RES 1e-2

struct rod_crit {
    rod *r;
    rod_crit_opts o;
    int nf;
    double *H, *Hp, *Hm;     /* band Hessian at the state, and at two perturbed states */
    gsl_matrix *lu;
    gsl_vector_uint *piv;
    double *g;               /* full gradient */
    double *R;               /* free residual */
    double *v[2], *w[2];     /* bordering vectors and solutions, [0] even, [1] odd */
    double gval[2];          /* test functions */
    double *a[MAXM];         /* grad_q of the selected test functions */
    double *Rp[MAXM], *Y[MAXM];
    double *z, *t1, *t2;
    double *old_s, *old_q;   /* scratch of rod_crit_move_gamma */
    double *step;            /* Newton step in q */
    int old_out;
    rod_snapshot base;
    rod_stab_ws *sw;         /* inertia of the reported state */
    double scale;            /* max |K_ii| */
    int phase1_cap;          /* iterations after which a solve still far from equilibrium fails */
};

rod_crit_opts rod_crit_opts_default(void)
{
    rod_crit_opts o;
    o.tolerance = 1e-6;
    o.step_tol = 1e-9;
    o.max_iterations = 40;
    o.eps_q = 1e-7;
    o.eps_p = 1e-8;
    o.max_dp[ROD_PAR_DW] = 0.05;
    o.max_dp[ROD_PAR_GAMMA] = 0.02;
    o.max_dp[ROD_PAR_PHI] = 0.05;
    o.max_dp[ROD_PAR_DL] = 0.05;
    return o;
}

void rod_params_apply(rod *r, const double *p)
{
    /* Rigid (terms.fold) and compliant (terms.hinge) creases alike move with Gamma and phi: with
     * only terms.fold tested here, a compliant scene's Gamma and phi were silently ignored, its
     * test functions did not change along the boundary's search and no codim-2 point was found. */
    if (r->terms.fold || r->terms.hinge) {
        rod_mesh_set(r, p[ROD_PAR_GAMMA], r->fold_outer_edges);
        rod_set_fold_angle(r, p[ROD_PAR_PHI], 0.0);
    }
    rod_set_clamps(r, p[ROD_PAR_DL], p[ROD_PAR_DW]);
    rod_frames_update(r);
}

void rod_crit_move_gamma(rod_crit *c, const double *p, int n_out)
{
    rod *r = c->r;
    int n = r->n;
    if (!r->terms.fold && !r->terms.hinge) {
        rod_params_apply(r, p);
        return;
    }
    memcpy(c->old_s, r->s_node, sizeof(double) * (size_t)n);
    memcpy(c->old_q, r->q, sizeof(double) * (size_t)r->ndof);
    c->old_out = r->fold_outer_edges;
    r->fold_outer_edges = n_out;
    rod_mesh_set(r, p[ROD_PAR_GAMMA], n_out);
    const double *oq = c->old_q;
    /* Segment-wise: a node at fraction f of its segment (clamp-crease, crease-crease,
     * crease-clamp) takes the old state at fraction f of the same segment, so the creases stay
     * on the kinks. */
    int ob[4], nb[4];
    int oo = c->old_out, no = n_out, ne = n - 3;
    ob[0] = 1; ob[1] = 1 + oo; ob[2] = 1 + ne - oo; ob[3] = 1 + ne;
    nb[0] = 1; nb[1] = 1 + no; nb[2] = 1 + ne - no; nb[3] = 1 + ne;
    for (int seg = 0; seg < 3; seg++) {
        int on = ob[seg + 1] - ob[seg], nn = nb[seg + 1] - nb[seg];
        for (int i = nb[seg]; i <= nb[seg + 1]; i++) {
            if (i < 2 || i > n - 3) continue;
            double f = (double)(i - nb[seg]) / nn * on;
            int j = (int)floor(f);
            if (j >= on) j = on - 1;
            double t = f - j;
            int a0 = ob[seg] + j;
            for (int k = 0; k < 3; k++) r->q[4 * i + k] = (1.0 - t) * oq[4 * a0 + k] + t * oq[4 * (a0 + 1) + k];
        }
        for (int e2 = nb[seg]; e2 < nb[seg + 1]; e2++) {
            if (e2 < 1 || e2 > n - 3) continue;
            double f = ((double)(e2 - nb[seg]) + 0.5) / nn * on - 0.5;
            if (f < 0.0) f = 0.0;
            if (f > on - 1) f = on - 1;
            int j = (int)floor(f);
            if (j >= on - 1) j = on > 1 ? on - 2 : 0;
            double t = on > 1 ? f - j : 0.0;
            int a0 = ob[seg] + j, a1 = on > 1 ? a0 + 1 : a0;
            r->q[4 * e2 + 3] = (1.0 - t) * oq[4 * a0 + 3] + t * oq[4 * a1 + 3];
        }
    }
    rod_params_apply(r, p);
}

void rod_crit_free(rod_crit *c)
{
    if (!c) return;
    free(c->H); free(c->Hp); free(c->Hm); free(c->g); free(c->R); free(c->z); free(c->t1); free(c->t2);
    free(c->old_s); free(c->old_q); free(c->step);
    for (int k = 0; k < 2; k++) { free(c->v[k]); free(c->w[k]); }
    for (int k = 0; k < MAXM; k++) { free(c->a[k]); free(c->Rp[k]); free(c->Y[k]); }
    if (c->lu) gsl_matrix_free(c->lu);
    if (c->piv) gsl_vector_uint_free(c->piv);
    rod_snapshot_free(&c->base);
    rod_stab_ws_free(c->sw);
    free(c);
}

rod_crit *rod_crit_alloc(rod *r, const rod_crit_opts *o)
{
    rod_crit *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->r = r;
    c->o = o ? *o : rod_crit_opts_default();
    c->phase1_cap = c->o.max_iterations;
    int nf = c->nf = rod_nfree(r);
    size_t n = (size_t)nf;
    c->H = malloc(sizeof(double) * n * W);
    c->Hp = malloc(sizeof(double) * n * W);
    c->Hm = malloc(sizeof(double) * n * W);
    c->g = malloc(sizeof(double) * (size_t)r->ndof);
    c->R = malloc(sizeof(double) * n);
    c->z = malloc(sizeof(double) * n);
    c->t1 = malloc(sizeof(double) * n);
    c->t2 = malloc(sizeof(double) * n);
    c->old_s = malloc(sizeof(double) * (size_t)r->n);
    c->old_q = malloc(sizeof(double) * (size_t)r->ndof);
    c->step = malloc(sizeof(double) * n);
    int ok = c->H && c->Hp && c->Hm && c->g && c->R && c->z && c->t1 && c->t2 && c->old_s && c->old_q && c->step;
    for (int k = 0; k < 2; k++) {
        c->v[k] = calloc(n, sizeof(double));
        c->w[k] = calloc(n, sizeof(double));
        ok = ok && c->v[k] && c->w[k];
    }
    for (int k = 0; k < MAXM; k++) {
        c->a[k] = malloc(sizeof(double) * n);
        c->Rp[k] = malloc(sizeof(double) * n);
        c->Y[k] = malloc(sizeof(double) * n);
        ok = ok && c->a[k] && c->Rp[k] && c->Y[k];
    }
    c->lu = gsl_matrix_alloc(n, 3 * ROD_BAND + 1);
    c->piv = gsl_vector_uint_alloc(n);
    c->sw = rod_stab_ws_alloc(nf);
    ok = ok && c->lu && c->piv && c->sw && rod_snapshot_alloc(r, &c->base);
    if (!ok) {
        rod_crit_free(c);
        return NULL;
    }
    return c;
}

/* ---- linear algebra at the state ---- */

/* Gradient (R) and Hessian at the rod's current state, K factorised by band LU. */
static rod_status assemble_factor_shift(rod_crit *c, double shift);
static rod_status assemble_factor(rod_crit *c) { return assemble_factor_shift(c, 0.0); }

/* As assemble_factor, with K - shift I factorised (H keeps K). */
static rod_status assemble_factor_shift(rod_crit *c, double shift)
{
    int nf = c->nf;
    memset(c->H, 0, sizeof(double) * (size_t)nf * W);
    rod_gradient_hessian(c->r, c->g, 1.0, c->H);
    c->scale = 0.0;
    for (int k = 0; k < nf; k++) {
        c->R[k] = c->g[k + ROD_FREE_BEGIN];
        if (!isfinite(c->R[k])) return ROD_ERR_NAN;
        c->scale = fmax(c->scale, fabs(c->H[(size_t)k * W]));
    }
    /* GSL's band LU layout: row a holds A(a, a + j - 2B) in column j (as rod_continue.c). */
    gsl_matrix_set_zero(c->lu);
    double *L = c->lu->data;
    size_t tda = c->lu->tda;
    for (int a = 0; a < nf; a++)
        for (int k = 0; k <= ROD_BAND && a + k < nf; k++) {
            double v = c->H[(size_t)a * W + (size_t)k];
            if (!isfinite(v)) return ROD_ERR_NAN;
            if (k == 0) v -= shift;
            L[(size_t)a * tda + (size_t)(2 * ROD_BAND + k)] = v;
            L[(size_t)(a + k) * tda + (size_t)(2 * ROD_BAND - k)] = v;
        }
    c->r->count.factorisations++;
    if (gsl_linalg_LU_band_decomp((size_t)nf, ROD_BAND, ROD_BAND, c->lu, c->piv) != GSL_SUCCESS)
        return ROD_ERR_SINGULAR;
    return ROD_OK;
}

/* x <- P_even K^-1 x (sign > 0) or P_odd K^-1 x. */
static rod_status solve_proj(rod_crit *c, int sign, double *x)
{
    gsl_vector_view xv = gsl_vector_view_array(x, (size_t)c->nf);
    if (gsl_linalg_LU_band_svx(ROD_BAND, ROD_BAND, c->lu, c->piv, &xv.vector) != GSL_SUCCESS)
        return ROD_ERR_SINGULAR;
    for (int k = 0; k < c->nf; k++)
        if (!isfinite(x[k])) return ROD_ERR_SINGULAR;
    rod_mode_project(c->r, sign, x, c->t2);
    return ROD_OK;
}

static double dot(const double *a, const double *b, int n)
{
    double s = 0.0;
    for (int k = 0; k < n; k++) s += a[k] * b[k];
    return s;
}

static double norm(const double *a, int n) { return sqrt(dot(a, a, n)); }

/* Test function of block b (0 even, 1 odd) from the factors: w = P K^-1 v / (v^T P K^-1 v). */
static rod_status testfn(rod_crit *c, int b)
{
    int nf = c->nf;
    memcpy(c->w[b], c->v[b], sizeof(double) * (size_t)nf);
    rod_status st = solve_proj(c, b == 0 ? 1 : -1, c->w[b]);
    if (st != ROD_OK) return st;
    double d = dot(c->v[b], c->w[b], nf);
    if (!(fabs(d) > 0.0) || !isfinite(d)) return ROD_ERR_SINGULAR;
    for (int k = 0; k < nf; k++) c->w[b][k] /= d;
    c->gval[b] = -1.0 / d;
    return ROD_OK;
}

/* The next bordering vector: the normalised w (the critical mode's best estimate). */
static void update_border(rod_crit *c, int b)
{
    double n = norm(c->w[b], c->nf);
    if (n > 0.0 && isfinite(n))
        for (int k = 0; k < c->nf; k++) c->v[b][k] = c->w[b][k] / n;
}

/* out = D3E[w, w, .] along the unit direction of w times |w|^2, at the state in c->base. The two
 * Hessians are differenced entry by entry before the product with w, so the round-off is that of
 * the entries that change, not of the whole K w. */
static void third_along(rod_crit *c, const double *w, double *out)
{
    rod *r = c->r;
    int nf = c->nf;
    size_t nb = (size_t)nf * W;
    double wn = norm(w, nf), e = c->o.eps_q * r->length;
    memset(out, 0, sizeof(double) * (size_t)nf);
    if (!(wn > 0.0)) return;
    for (int s = -1; s <= 1; s += 2) {
        double *Hs = s > 0 ? c->Hp : c->Hm;
        rod_snapshot_load(r, &c->base);
        for (int k = 0; k < nf; k++) r->q[k + ROD_FREE_BEGIN] += s * e * w[k] / wn;
        rod_frames_update(r);
        memset(Hs, 0, sizeof(double) * nb);
        rod_hessian_add(r, 1.0, Hs);
    }
    for (size_t i = 0; i < nb; i++) c->Hp[i] -= c->Hm[i];
    rod_band_symv(c->Hp, nf, w, out);
    for (int k = 0; k < nf; k++) out[k] /= 2.0 * e * wn;
    rod_snapshot_load(r, &c->base);
}

/* Derivatives along parameter k at the state in c->base under p: dR/dp into Rp (may be NULL) and
 * d(-w_b^T K w_b)/dp for both blocks into gp[2]. */
static void param_diff(rod_crit *c, const double *p, rod_par k, double *Rp, double gp[2])
{
    rod *r = c->r;
    int nf = c->nf;
    size_t nb = (size_t)nf * W;
    double pp[ROD_NPAR], e = c->o.eps_p;
    memcpy(pp, p, sizeof pp);
    if (Rp) memset(Rp, 0, sizeof(double) * (size_t)nf);
    gp[0] = gp[1] = 0.0;
    for (int s = -1; s <= 1; s += 2) {
        double *Hs = s > 0 ? c->Hp : c->Hm;
        rod_snapshot_load(r, &c->base);
        pp[k] = p[k] + s * e;
        if (k == ROD_PAR_GAMMA) {
            rod_params_apply(r, p);
            rod_crit_move_gamma(c, pp, r->fold_outer_edges);
        } else {
            rod_params_apply(r, pp);
        }
        memset(Hs, 0, sizeof(double) * nb);
        rod_gradient_hessian(r, c->g, 1.0, Hs);
        if (Rp)
            for (int j = 0; j < nf; j++) Rp[j] += s * c->g[j + ROD_FREE_BEGIN] / (2.0 * e);
    }
    /* Entry by entry first (see third_along): a clamp or crease change touches few entries. */
    for (size_t i = 0; i < nb; i++) c->Hp[i] -= c->Hm[i];
    for (int b = 0; b < 2; b++) {
        rod_band_symv(c->Hp, nf, c->w[b], c->t1);
        gp[b] = -dot(c->w[b], c->t1, nf) / (2.0 * e);
    }
    rod_snapshot_load(r, &c->base);
    rod_params_apply(r, p);
}

/* Along the direction (dq, e_k) from the state in c->base under p (k < 0: dq alone), the
 * derivative of both test functions at fixed w, -d/dt w_b^T K(q + t dq, p + t e_k) w_b, into
 * out[2], by one central difference of the Hessian (entry by entry, as third_along). Taken along
 * the equilibrium's own response (dq = -K^-1 R_p) it is the total derivative directly, without
 * the cancellation of g_p - grad_q g . K^-1 R_p (both large where a parameter strains the stiff
 * edges at fixed q). The step is eps_p in the parameter, the q move held below eps_q l. */
static void dir_diff(rod_crit *c, const double *p, const double *dq, double dq_sign, int k, double out[2])
{
    rod *r = c->r;
    int nf = c->nf;
    size_t nb = (size_t)nf * W;
    double qmax = 0.0;
    for (int j = 0; j < nf; j++) qmax = fmax(qmax, fabs(dq[j]));
    double e = k >= 0 ? c->o.eps_p : c->o.eps_q * r->length / fmax(qmax, 1e-300);
    if (k >= 0 && qmax * e > c->o.eps_q * r->length) e = c->o.eps_q * r->length / qmax;
    out[0] = out[1] = 0.0;
    if (k < 0 && !(qmax > 0.0)) return;
    double pp[ROD_NPAR];
    for (int s = -1; s <= 1; s += 2) {
        double *Hs = s > 0 ? c->Hp : c->Hm;
        rod_snapshot_load(r, &c->base);
        for (int j = 0; j < nf; j++) r->q[j + ROD_FREE_BEGIN] += s * e * dq_sign * dq[j];
        memcpy(pp, p, sizeof pp);
        if (k >= 0) pp[k] += s * e;
        if (k == ROD_PAR_GAMMA) {
            rod_frames_update(r);
            rod_crit_move_gamma(c, pp, r->fold_outer_edges);
        } else {
            rod_params_apply(r, pp);
        }
        memset(Hs, 0, sizeof(double) * nb);
        rod_hessian_add(r, 1.0, Hs);
    }
    for (size_t i = 0; i < nb; i++) c->Hp[i] -= c->Hm[i];
    for (int b = 0; b < 2; b++) {
        rod_band_symv(c->Hp, nf, c->w[b], c->t1);
        out[b] = -dot(c->w[b], c->t1, nf) / (2.0 * e);
    }
    rod_snapshot_load(r, &c->base);
    rod_params_apply(r, p);
}

/* Applies p at the rod's q, assembles and factorises, both test functions; saves the base. */
static rod_status eval_here(rod_crit *c, const double *p, char *why, size_t why_len)
{
    rod_state_symmetrize(c->r);
    rod_params_apply(c->r, p);
    rod_snapshot_save(c->r, &c->base);
    rod_status st = assemble_factor(c);
    if (st != ROD_OK) {
        if (why) snprintf(why, why_len, "the Hessian %s", st == ROD_ERR_NAN ? "is not finite" : "cannot be factorised");
        return st;
    }
    for (int b = 0; b < 2; b++)
        if ((st = testfn(c, b)) != ROD_OK) {
            if (why) snprintf(why, why_len, "the %s bordered system is singular", b == 0 ? "even" : "odd");
            return st;
        }
    return ROD_OK;
}

static double residual_rel(const rod_crit *c)
{
    double mx = 0.0;
    for (int k = 0; k < c->nf; k++) mx = fmax(mx, fabs(c->R[k]));
    return mx / c->r->force_scale;
}

/* Rayleigh quotient, residual and parity of the unit w's. */
static void fill_report(rod_crit *c, rod_crit_report *rep)
{
    int nf = c->nf;
    rep->residual_rel = residual_rel(c);
    rep->g_even = c->gval[0];
    rep->g_odd = c->gval[1];
    rep->scale = c->scale;
    rod_inertia in;
    rep->n_negative = rod_inertia_eval(c->H, nf, ROD_INERTIA_SHIFT_REL, c->sw, &in, NULL, 0) == ROD_OK ? in.below_minus : -1;
    for (int b = 0; b < 2; b++) {
        double n = norm(c->w[b], nf), *u = c->t1;
        for (int k = 0; k < nf; k++) u[k] = n > 0.0 ? c->w[b][k] / n : 0.0;
        rod_band_symv(c->H, nf, u, c->z);
        double mu = dot(u, c->z, nf), res = 0.0;
        for (int k = 0; k < nf; k++) res += (c->z[k] - mu * u[k]) * (c->z[k] - mu * u[k]);
        double par = rod_mode_parity(c->r, u);
        if (b == 0) {
            rep->eig_even = mu;
            rep->eig_res_even = sqrt(res);
            rep->parity_even = par;
        } else {
            rep->eig_odd = mu;
            rep->eig_res_odd = sqrt(res);
            rep->parity_odd = par;
        }
    }
}

/* ---- public ---- */

void rod_crit_set_mode(rod_crit *c, int sign, const double *v)
{
    int b = sign > 0 ? 0 : 1;
    memcpy(c->v[b], v, sizeof(double) * (size_t)c->nf);
    rod_mode_project(c->r, sign, c->v[b], c->t2);
    double n = norm(c->v[b], c->nf);
    if (n > 0.0)
        for (int k = 0; k < c->nf; k++) c->v[b][k] /= n;
}

rod_status rod_crit_modes(rod_crit *c, const double *p, rod_crit_report *rep, char *why, size_t why_len)
{
    int nf = c->nf;
    rod_params_apply(c->r, p);
    rod_status st = assemble_factor(c);
    if (st != ROD_OK) {
        if (why) snprintf(why, why_len, "the Hessian cannot be factorised for the critical modes");
        return st;
    }
    for (int b = 0; b < 2; b++) {
        int sign = b == 0 ? 1 : -1;
        double *v = c->v[b];
        /* A start with components on every mode: a fixed pseudo-random vector. */
        unsigned x = 12345u;
        for (int k = 0; k < nf; k++) {
            x = x * 1103515245u + 12345u;
            v[k] = ((double)(x >> 8) / 16777216.0) - 0.5;
        }
        rod_mode_project(c->r, sign, v, c->t2);
        double prev = INFINITY;
        for (int it = 0; it < 60; it++) {
            double n = norm(v, nf);
            if (!(n > 0.0) || !isfinite(n)) break;
            for (int k = 0; k < nf; k++) v[k] /= n;
            rod_band_symv(c->H, nf, v, c->z);
            double mu = dot(v, c->z, nf);
            if (fabs(mu - prev) <= 1e-12 * fabs(mu) + 1e-15 * c->scale) break;
            prev = mu;
            if ((st = solve_proj(c, sign, v)) != ROD_OK) {
                if (why) snprintf(why, why_len, "inverse iteration failed in the %s block", b ? "odd" : "even");
                return st;
            }
        }
        double n = norm(v, nf);
        if (!(n > 0.0) || !isfinite(n)) {
            if (why) snprintf(why, why_len, "no %s critical mode (zero vector)", b ? "odd" : "even");
            return ROD_ERR_SINGULAR;
        }
        for (int k = 0; k < nf; k++) v[k] /= n;
    }
    for (int b = 0; b < 2; b++)
        if ((st = testfn(c, b)) != ROD_OK) {
            if (why) snprintf(why, why_len, "the %s bordered system is singular", b ? "odd" : "even");
            return st;
        }
    if (rep) {
        memset(rep, 0, sizeof *rep);
        fill_report(c, rep);
    }
    return ROD_OK;
}

rod_status rod_crit_refine_mode(rod_crit *c, const double *p, int sign, const double *v0, double sigma, double *eig)
{
    int nf = c->nf, b = sign > 0 ? 0 : 1;
    double *v = c->v[b];
    rod_crit_set_mode(c, sign, v0);
    rod_params_apply(c->r, p);
    memset(c->H, 0, sizeof(double) * (size_t)nf * W);
    rod_gradient_hessian(c->r, c->g, 1.0, c->H);
    rod_band_symv(c->H, nf, v, c->z);
    double mu = dot(v, c->z, nf);
    /* Shifted a little past the Rayleigh quotient, so the factorisation is not singular. */
    double shift = isfinite(sigma) ? sigma : mu * (1.0 + 1e-3) + 1e-12;
    rod_status st = assemble_factor_shift(c, shift);
    if (st != ROD_OK) return st;
    for (int it = 0; it < 60; it++) {
        if ((st = solve_proj(c, sign, v)) != ROD_OK) return st;
        double n = norm(v, nf);
        if (!(n > 0.0) || !isfinite(n)) return ROD_ERR_SINGULAR;
        for (int k = 0; k < nf; k++) v[k] /= n;
    }
    rod_band_symv(c->H, nf, v, c->z);
    if (eig) *eig = dot(v, c->z, nf);
    return ROD_OK;
}

int rod_crit_set_phase1_cap(rod_crit *c, int cap)
{
    int old = c->phase1_cap;
    c->phase1_cap = cap;
    return old;
}

int rod_crit_set_cap(rod_crit *c, int cap)
{
    int old = c->o.max_iterations;
    c->o.max_iterations = cap;
    return old;
}

rod_status rod_crit_update_borders(rod_crit *c, const double *p)
{
    rod_status st = eval_here(c, p, NULL, 0);
    if (st != ROD_OK) return st;
    for (int b = 0; b < 2; b++) update_border(c, b);
    return ROD_OK;
}

rod_status rod_crit_eval(rod_crit *c, const double *p, rod_crit_report *rep, char *why, size_t why_len)
{
    rod_status st = eval_here(c, p, why, why_len);
    if (st == ROD_OK && rep) {
        memset(rep, 0, sizeof *rep);
        fill_report(c, rep);
    }
    return st;
}

rod_status rod_crit_testfn(rod_crit *c, const double *p, int sign, double *g)
{
    rod_params_apply(c->r, p);
    rod_status st = assemble_factor(c);
    if (st == ROD_OK) st = testfn(c, sign > 0 ? 0 : 1);
    *g = c->gval[sign > 0 ? 0 : 1];
    return st;
}

rod_status rod_crit_gradient(rod_crit *c, const double *p, int sign, rod_par k, double *out, double *gp)
{
    rod_status st = eval_here(c, p, NULL, 0);
    if (st != ROD_OK) return st;
    int b = sign > 0 ? 0 : 1;
    third_along(c, c->w[b], out);
    for (int j = 0; j < c->nf; j++) out[j] = -out[j];
    if (gp) {
        double g2[2];
        param_diff(c, p, k, NULL, g2);
        *gp = g2[b];
    }
    rod_snapshot_load(c->r, &c->base);
    return ROD_OK;
}

/* dR/dp_k at the state in c->base under p by central differences of the gradient, into Rp. */
static void param_grad(rod_crit *c, const double *p, rod_par k, double *Rp)
{
    rod *r = c->r;
    int nf = c->nf;
    double pp[ROD_NPAR], e = c->o.eps_p;
    memcpy(pp, p, sizeof pp);
    memset(Rp, 0, sizeof(double) * (size_t)nf);
    for (int s = -1; s <= 1; s += 2) {
        rod_snapshot_load(r, &c->base);
        pp[k] = p[k] + s * e;
        if (k == ROD_PAR_GAMMA) {
            rod_params_apply(r, p);
            rod_crit_move_gamma(c, pp, r->fold_outer_edges);
        } else {
            rod_params_apply(r, pp);
        }
        rod_gradient(r, c->g);
        for (int j = 0; j < nf; j++) Rp[j] += s * c->g[j + ROD_FREE_BEGIN] / (2.0 * e);
    }
    rod_snapshot_load(r, &c->base);
    rod_params_apply(r, p);
}

/* Solves a 3 x 3 system by Gaussian elimination with partial pivoting; 0 when singular. */
static int solve3(double A[3][3], double b[3], double x[3])
{
    for (int col = 0; col < 3; col++) {
        int piv = col;
        for (int row = col + 1; row < 3; row++)
            if (fabs(A[row][col]) > fabs(A[piv][col])) piv = row;
        if (!(fabs(A[piv][col]) > 0.0) || !isfinite(A[piv][col])) return 0;
        if (piv != col) {
            for (int k = 0; k < 3; k++) {
                double t = A[col][k];
                A[col][k] = A[piv][k];
                A[piv][k] = t;
            }
            double t = b[col];
            b[col] = b[piv];
            b[piv] = t;
        }
        for (int row = col + 1; row < 3; row++) {
            double f = A[row][col] / A[col][col];
            for (int k = col; k < 3; k++) A[row][k] -= f * A[col][k];
            b[row] -= f * b[col];
        }
    }
    for (int row = 2; row >= 0; row--) {
        double t = b[row];
        for (int k = row + 1; k < 3; k++) t -= A[row][k] * x[k];
        x[row] = t / A[row][row];
        if (!isfinite(x[row])) return 0;
    }
    return 1;
}

/* One Newton step of the codim-2 system (R = 0, g_even = 0, g_odd = 0; free Delta W and Gamma)
 * at the base state: dp into dp[2], the q step into c->step.
 *
 * Next to the codim-2 point K's even block is singular, so every solve K^-1 f has a component
 * along the even critical mode of size (v.f) / lambda, and the plain Schur complement
 * g_p - grad_q g . K^-1 R_p is a rank-one part of size 1 / lambda plus the part that matters
 * (measured at N = 201: 1e3-1e5 against 1e2, and the two computed ways disagreed in sign):
 * Newton from it wandered. Deflated instead: each solve y = K^-1 f splits into
 * x = y - (v.y) w (bounded, v.x = 0) and (v.y) w, with w = K^-1 v / (v.K^-1 v) and v the even
 * border; the step is dq = x_z - sum_j x_j dp_j + mu w with one more unknown mu and the regular
 * row g mu + sum_j g (v.Y_j) dp_j = g (v.z) (g = g_even; g (v.y) is bounded). The test
 * functions' derivatives along each of the directions (-x_j, e_j), w and x_z are taken directly
 * by one difference of the Hessian each (dir_diff): along the equilibrium's own response they
 * are small, without the cancellation of the large fixed-q derivatives. */
static rod_status codim2_step(rod_crit *c, const double *p, const rod_par *free, const double *gsel, double *dp)
{
    int nf = c->nf;
    rod *r = c->r;
    rod_status st;
    const double *v0 = c->v[0], *w0 = c->w[0];
    double g0 = c->gval[0];
    for (int j = 0; j < 2; j++) {
        param_grad(c, p, free[j], c->Rp[j]);
        rod_mode_project(r, 1, c->Rp[j], c->t2);
        memcpy(c->Y[j], c->Rp[j], sizeof(double) * (size_t)nf);
        if ((st = solve_proj(c, 1, c->Y[j])) != ROD_OK) return st;
    }
    for (int k = 0; k < nf; k++) c->z[k] = -c->R[k];
    if ((st = solve_proj(c, 1, c->z)) != ROD_OK) return st;
    double zeta[3];
    double *x[3] = {c->Y[0], c->Y[1], c->z};
    for (int j = 0; j < 3; j++) {
        zeta[j] = dot(v0, x[j], nf);
        for (int k = 0; k < nf; k++) x[j][k] -= zeta[j] * w0[k];
    }
    double d0[2], d1[2], dw[2], dz[2];
    dir_diff(c, p, c->Y[0], -1.0, free[0], d0);
    dir_diff(c, p, c->Y[1], -1.0, free[1], d1);
    dir_diff(c, p, w0, 1.0, -1, dw);
    dir_diff(c, p, c->z, 1.0, -1, dz);
    double A[3][3], b[3], u[3];
    for (int i = 0; i < 2; i++) {
        A[i][0] = d0[i];
        A[i][1] = d1[i];
        A[i][2] = dw[i];
        b[i] = -gsel[i] - dz[i];
    }
    A[2][0] = g0 * zeta[0];
    A[2][1] = g0 * zeta[1];
    A[2][2] = g0;
    b[2] = g0 * zeta[2];
    /* Row 2 in the units of rows 0 and 1. */
    double s0 = fmax(fabs(A[0][0]), fmax(fabs(A[0][1]), fabs(A[1][1]))), s2 = fmax(fabs(A[2][0]), fabs(A[2][1]));
    if (s2 > 0.0 && s0 > 0.0) {
        for (int k = 0; k < 3; k++) A[2][k] *= s0 / s2;
        b[2] *= s0 / s2;
    }
    if (!solve3(A, b, u)) return ROD_ERR_SINGULAR;
    dp[0] = u[0];
    dp[1] = u[1];
    for (int k = 0; k < nf; k++) c->step[k] = c->z[k] - c->Y[0][k] * u[0] - c->Y[1][k] * u[1] + u[2] * w0[k];
    return ROD_OK;
}

rod_status rod_crit_solve(rod_crit *c, rod_crit_kind kind, const rod_par *free, double *p, rod_crit_report *rep,
                          char *why, size_t why_len)
{
    rod *r = c->r;
    int nf = c->nf, m = kind == ROD_CRIT_CODIM2 ? 2 : 1;
    int blk[MAXM];
    if (kind == ROD_CRIT_FOLD) blk[0] = 0;
    else if (kind == ROD_CRIT_PITCHFORK) blk[0] = 1;
    else { blk[0] = 0; blk[1] = 1; }
    if (rep) memset(rep, 0, sizeof *rep);
    rod_status st = ROD_ERR_MAXITER;
    char buf[160] = "";
    double prev_dp = INFINITY;
    /* Phase 1 on the pitchfork curve holds Delta W (the even block is regular there); next to
     * the codim-2 point the even block is nearly singular too, and a phase-1 step that cannot
     * reduce the residual switches to the fold-safe constraint for the rest of the solve. */
    int p1_hold_dw = 0;
    for (int it = 0; it < c->o.max_iterations; it++) {
        if ((st = eval_here(c, p, buf, sizeof buf)) != ROD_OK) break;
        if (rep) rep->iterations = it;
        double gsel[MAXM] = {0}, G[MAXM][MAXM] = {{0}};
        for (int i = 0; i < m; i++) gsel[i] = c->gval[blk[i]];
        double res0 = residual_rel(c);
        if (res0 > PHASE1_RES && it >= c->phase1_cap) {
            snprintf(buf, sizeof buf, "equilibrium not restored within %d iterations (residual %.3g)", c->phase1_cap, res0);
            st = ROD_ERR_MAXITER;
            break;
        }
        if (res0 > PHASE1_RES) {
            /* Phase 1, far from equilibrium (a parameter step strains the stiff edges): Newton on
             * R = 0 alone with Delta W free and the step orthogonal to the even critical mode,
             * [[K, f], [v_even^T, 0]], which stays regular at a fold; the test functions'
             * linearisation is not trusted there. */
            /* With Delta W held (no free parameter is Delta W: a fold in Gamma or phi at fixed
             * shear), the slack is the free parameter's own: its column dR/dp takes the load's
             * place, so the step stays regular at a fold in that parameter. */
            int slack = ROD_PAR_DW;
            if (m == 1 && free[0] != ROD_PAR_DW) slack = free[0];
            if (slack == ROD_PAR_DW) {
                rod_load shear = {ROD_LOAD_SHEAR, p[ROD_PAR_DL], 0.0};
                rod_load_vector(r, &shear, c->Rp[0]);
            } else {
                param_grad(c, p, (rod_par)slack, c->Rp[0]);
            }
            rod_mode_project(r, 1, c->Rp[0], c->t2);
            for (int k = 0; k < nf; k++) c->z[k] = -c->R[k];
            if ((st = solve_proj(c, 1, c->z)) != ROD_OK) break;
            memcpy(c->Y[0], c->Rp[0], sizeof(double) * (size_t)nf);
            if ((st = solve_proj(c, 1, c->Y[0])) != ROD_OK) break;
            double vy = dot(c->v[0], c->Y[0], nf), ddw = fabs(vy) > 0.0 ? dot(c->v[0], c->z, nf) / vy : 0.0;
            /* On the pitchfork curve the even block is regular: restore equilibrium at fixed
             * Delta W (holding v_even's component there would undo the step along the branch). */
            if (!isfinite(ddw) || p1_hold_dw) ddw = 0.0;
            /* A pitchfork in Gamma or phi (Delta W held): the even block is regular, so equilibrium is
             * restored at the fixed parameter (the even mode's constraint would push it along). */
            if (slack != ROD_PAR_DW && kind == ROD_CRIT_PITCHFORK) ddw = 0.0;
            ddw = fmax(-c->o.max_dp[slack], fmin(c->o.max_dp[slack], ddw));
            for (int k = 0; k < nf; k++) c->step[k] = c->z[k] - c->Y[0][k] * ddw;
            double pbase[ROD_NPAR];
            memcpy(pbase, p, sizeof pbase);
            double sc1 = 1.0;
            for (int bt = 0; bt < 8; bt++, sc1 *= 0.5) {
                rod_snapshot_load(r, &c->base);
                memcpy(p, pbase, sizeof pbase);
                if (slack == ROD_PAR_DW) {
                    p[ROD_PAR_DW] += sc1 * ddw;
                    rod_params_apply(r, p);
                    for (int k = 0; k < nf; k++) r->q[k + ROD_FREE_BEGIN] += sc1 * c->step[k];
                    rod_frames_update(r);
                } else {
                    /* As a Newton step below: q moved, then the parameter (Gamma along the mesh map). */
                    rod_params_apply(r, p);
                    for (int k = 0; k < nf; k++) r->q[k + ROD_FREE_BEGIN] += sc1 * c->step[k];
                    p[slack] += sc1 * ddw;
                    rod_frames_update(r);
                    if (slack == ROD_PAR_GAMMA) rod_crit_move_gamma(c, p, r->fold_outer_edges);
                    else rod_params_apply(r, p);
                }
                rod_gradient(r, c->g);
                double rn = 0.0;
                for (int k = 0; k < nf; k++) rn = fmax(rn, fabs(c->g[k + ROD_FREE_BEGIN]));
                rn /= r->force_scale;
                if (isfinite(rn) && rn < res0) break;
                if (bt == 7) p1_hold_dw = 0;
            }
            st = ROD_ERR_MAXITER;
            snprintf(buf, sizeof buf, "Newton cap %d reached far from equilibrium (residual %.3g)", c->o.max_iterations, res0);
            continue;
        }
        double dp[MAXM];
        if (m == 2) {
            if ((st = codim2_step(c, p, free, gsel, dp)) != ROD_OK) {
                snprintf(buf, sizeof buf, "singular codim-2 system");
                break;
            }
        } else {
        /* The Jacobian's borders at the base state. */
        for (int i = 0; i < m; i++) {
            third_along(c, c->w[blk[i]], c->a[i]);
            for (int j = 0; j < nf; j++) c->a[i][j] = -c->a[i][j];
            rod_mode_project(r, 1, c->a[i], c->t2);
        }
        for (int j = 0; j < m; j++) {
            double g2[2];
            param_diff(c, p, free[j], c->Rp[j], g2);
            rod_mode_project(r, 1, c->Rp[j], c->t2);
            for (int i = 0; i < m; i++) G[i][j] = g2[blk[i]];
        }
        /* Block elimination: K z = -R, K Y_j = R_p j (even parts). */
        for (int k = 0; k < nf; k++) c->z[k] = -c->R[k];
        if ((st = solve_proj(c, 1, c->z)) != ROD_OK) break;
        for (int j = 0; j < m; j++) {
            memcpy(c->Y[j], c->Rp[j], sizeof(double) * (size_t)nf);
            if ((st = solve_proj(c, 1, c->Y[j])) != ROD_OK) break;
        }
        if (st != ROD_OK) break;
        double S = G[0][0] - dot(c->a[0], c->Y[0], nf), rhs = -gsel[0] - dot(c->a[0], c->z, nf);
        if (!(fabs(S) > 0.0)) { st = ROD_ERR_SINGULAR; snprintf(buf, sizeof buf, "singular augmented system"); break; }
        dp[0] = rhs / S;
        for (int k = 0; k < nf; k++) c->step[k] = c->z[k] - c->Y[0][k] * dp[0];
        }
        double scale = 1.0, dpmax = 0.0;
        for (int j = 0; j < m; j++) {
            if (!isfinite(dp[j])) { st = ROD_ERR_NAN; break; }
            double lim = c->o.max_dp[free[j]];
            if (fabs(dp[j]) * scale > lim) scale = lim / fabs(dp[j]);
            dpmax = fmax(dpmax, fabs(dp[j]));
        }
        if (st == ROD_ERR_NAN) { snprintf(buf, sizeof buf, "non-finite Newton step"); break; }
        double res = residual_rel(c);
        /* Converged: residual within tolerance and a negligible step, or a step below 1e4 step_tol that no
         * longer shrinks (the test functions' round-off floor, ~1e-16 max |K_ii|, reached). */
        double dqmax = 0.0;
        for (int k = 0; k < nf; k++)
            dqmax = fmax(dqmax, fabs(c->step[k]) / (((k + ROD_FREE_BEGIN) % 4 == 3) ? 100.0 : r->length));
        /* The residual's own round-off floor (stiff creases put it near 1e-5 E I1 / l^2, as
         * rod_solver.c explains): below 1e3 tolerances with a full step under 1e-9 l (1e-7 rad)
         * it is converged; likewise below 1e2 of it with a step under 1e-6 l that the test functions' round-off keeps from
         * shrinking. */
        /* The round-off floor of g grows with max |K_ii| (stiffer meshes): the stall bounds scale
         * with it beyond 1e9 (N = 61 at the paper scene; N = 201 is 3.8e10). */
        double floor_f = fmax(1.0, c->scale / 1e9);
        int res_ok = res <= c->o.tolerance || (res <= 1e3 * c->o.tolerance && dqmax <= 1e-6 * floor_f);
        if (res_ok &&
            (dpmax <= c->o.step_tol || (it >= 2 && dpmax <= 1e4 * c->o.step_tol * floor_f && (dpmax >= 0.5 * prev_dp || it >= 6)))) {
            st = ROD_OK;
            break;
        }
        prev_dp = dpmax;
        /* The step, scaled down when a parameter would move too far; a change of Gamma moves the
         * nodes along the rod to the new mesh (rod_crit_move_gamma), the map the Gamma column of
         * the Jacobian was differenced along. Backtracking halves a step that makes the
         * residual more than four times worse (up to 4 times). */
        double pbase[ROD_NPAR];
        memcpy(pbase, p, sizeof pbase);
        for (int bt = 0; bt < 5; bt++, scale *= 0.5) {
            rod_snapshot_load(r, &c->base);
            memcpy(p, pbase, sizeof pbase);
            rod_params_apply(r, p);
            for (int k = 0; k < nf; k++) r->q[k + ROD_FREE_BEGIN] += scale * c->step[k];
            int moves_gamma = 0;
            for (int j = 0; j < m; j++) {
                p[free[j]] += scale * dp[j];
                moves_gamma |= free[j] == ROD_PAR_GAMMA;
            }
            rod_frames_update(r);
            if (moves_gamma) rod_crit_move_gamma(c, p, r->fold_outer_edges);
            else rod_params_apply(r, p);
            rod_gradient(r, c->g);
            double rn = 0.0;
            for (int k = 0; k < nf; k++) rn = fmax(rn, fabs(c->g[k + ROD_FREE_BEGIN]));
            rn /= r->force_scale;
            /* A straight step strains the edges it rotates (second order, stiff): phase 1 takes
             * that out, so only a step that blows up is shortened. */
            if (isfinite(rn) && (rn <= 4.0 * res || rn <= 1e8 * PHASE1_RES)) break;
        }
        for (int k = 0; k < nf; k++)
            if (!isfinite(r->q[k + ROD_FREE_BEGIN])) { st = ROD_ERR_NAN; break; }
        if (st == ROD_ERR_NAN) { snprintf(buf, sizeof buf, "non-finite state"); break; }
        rod_frames_update(r);
        /* The bordering vectors stay during a solve: updating them to w is a step of inverse
         * iteration, which drifts to whichever mode of the block is nearest zero, not
         * necessarily the critical one the caller started from. */
        st = ROD_ERR_MAXITER;
        snprintf(buf, sizeof buf, "Newton cap %d reached (residual %.3g, last parameter step %.3g)",
                 c->o.max_iterations, res, dpmax);
    }
    if (st == ROD_OK) {
        rod_snapshot_load(r, &c->base);
        if (rep) fill_report(c, rep);
    } else if (why) {
        snprintf(why, why_len, "%s", buf[0] ? buf : rod_status_message(st));
    }
    return st;
}
