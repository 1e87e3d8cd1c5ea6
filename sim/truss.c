/* truss.c: the double-mass von Mises truss model: energy with analytic gradient and Hessian,
 * statics (Newton with an eigenvalue shift and a line search, so it settles in a minimum),
 * Hessian eigen-analysis, and the paper's small-angle formulas beside them.
 *
 * Derivation of the kernel. Extend the configuration with the right support abscissa,
 * z = [x1, y1, x2, y2, D]. Every term of the energy is a function of three "link" vectors, each
 * a fixed linear map of z:
 *
 *   link  vector d = J z                 length      angle atan2(d_y, d_x)
 *   ----  -----------------------------  ----------  ---------------------
 *   0     (x1,      y1)                  l_L         theta_L
 *   1     (D - x2,  y2)                  l_R         theta_R
 *   2     (x2 - x1, y1 - y2)             l_C         dtheta
 *
 * For d = (a, b), r = |d|: dr/dd = d / r, d2r/dd2 = (I - d d^T / r^2) / r, and for
 * phi = atan2(b, a): dphi/dd = (-b, a) / r^2, d2phi/da2 = 2ab / r^4, d2phi/db2 = -2ab / r^4,
 * d2phi/dadb = (b^2 - a^2) / r^4. Pulled back to z: grad = J^T g_d, hess = J^T H_d J.
 * The energy is a sum of terms k/2 (v - v0)^2 with v a linear combination of those primitives:
 *
 *   U = 1/2 [(l_L - 1)^2 + (l_R - 1)^2 + (l_C - L2)^2]
 *     + k_t/2 [(theta_L + alpha_L)^2 + (theta_R + alpha_R)^2
 *              + (theta_L + s dtheta)^2 + (theta_R - s dtheta)^2],   k_t = Lambda alpha^2 / 3,
 *
 * s = +1 with the consistent signs, -1 with the paper's printed pair. Each term adds
 * k (v - v0) grad v to the gradient and k (grad v grad v^T + (v - v0) hess v) to the Hessian.
 * The load enters only through D = (2 + L2)(1 - mu alpha^2), so the load vector at fixed q is
 * d(dU/dq)/dmu = H_z[0..3][4] dD/dmu.
 *
 * The small-angle formulas: for psi_A = 0 and stiff springs the three springs carry one
 * compressive force, the end shortening is dl - l1 theta^2, and stationarity of
 * k_s (dl - l1 theta^2)^2 / 6 + k_t [(theta + alpha)^2 + theta^2] gives the paper's cubic
 * psi^3 + (2 Lambda - (2 + L2) mu) psi + Lambda = 0 (a1..a4 of the paper times 3/2). Its fold is
 * at psi = (Lambda/2)^(1/3); the antisymmetric stiffness vanishes at psi = L2 (L2 + 2) / 4 with the
 * consistent signs (with the printed signs at L2 (L2 + 2) / (4 (1 - 2 L2)) instead). */
#include "truss.h"
#include "truss_private.h"

#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define NZ 5 /* extended coordinates x1, y1, x2, y2, D */

int truss_newton_converged(const truss_newton_opts *o, double alpha, const double *dx,
                           const double *x, const double *scale, int n, double res_max)
{
    const double floor = 100.0 * DBL_EPSILON;
    if (!(res_max <= o->res_tol * alpha * alpha * alpha + floor))
        return 0;
    if (res_max <= floor)
        return 1; /* the residual is round-off: further steps only amplify noise */
    for (int i = 0; i < n; i++) {
        if (!(fabs(dx[i]) <= o->step_tol * alpha * alpha * scale[i] + 8.0 * DBL_EPSILON * fabs(x[i])))
            return 0;
    }
    return 1;
}

const char *truss_error_message(truss_error err)
{
    switch (err) {
    case TRUSS_OK: return "ok";
    case TRUSS_ERR_PARAM: return "invalid parameter";
    case TRUSS_ERR_NAN: return "NaN or Inf in a computed quantity";
    case TRUSS_ERR_MAX_ITER: return "iteration cap reached without convergence";
    case TRUSS_ERR_SINGULAR: return "singular linear system";
    case TRUSS_ERR_DIVERGED: return "left the model's range (a spring collapsed, or no descent)";
    case TRUSS_ERR_NO_UPPER: return "no stable upper state at the starting load";
    case TRUSS_ERR_NOT_FOUND: return "not found in the searched range";
    case TRUSS_ERR_GSL: return "a GSL routine failed";
    case TRUSS_ERR_NOMEM: return "out of memory";
    }
    return "unknown error";
}

truss_params truss_params_default(void)
{
    truss_params p;
    p.lambda = 0.1;
    p.alpha = 0.1;
    p.l2 = 0.8;
    p.imperfection = 0.0;
    p.printed_signs = 0;
    return p;
}

truss_error truss_params_check(const truss_params *p, char *msg, size_t msglen)
{
    const char *field = NULL;
    const char *why = NULL;
    if (!(isfinite(p->lambda) && p->lambda > 0.0 && p->lambda <= 100.0)) {
        field = "lambda"; why = "must be finite, > 0 and <= 100";
    } else if (!(isfinite(p->alpha) && p->alpha > 0.0 && p->alpha <= 0.5)) {
        field = "alpha"; why = "must be finite and in (0, 0.5] rad";
    } else if (!(isfinite(p->l2) && p->l2 > 0.0 && p->l2 <= 100.0)) {
        field = "l2"; why = "must be finite, > 0 and <= 100";
    } else if (!(isfinite(p->imperfection) && fabs(p->imperfection) < 1.0)) {
        field = "imperfection"; why = "must be finite with |imperfection| < 1";
    } else if (p->printed_signs != 0 && p->printed_signs != 1) {
        field = "printed_signs"; why = "must be 0 or 1";
    }
    if (field == NULL)
        return TRUSS_OK;
    if (msg != NULL && msglen > 0)
        snprintf(msg, msglen, "truss parameter %s %s", field, why);
    return TRUSS_ERR_PARAM;
}

double truss_support_right(const truss_params *p, double mu)
{
    return (2.0 + p->l2) * (1.0 - mu * p->alpha * p->alpha);
}

/* One link: its 2 x 5 map J (rows d_x, d_y) and the primitives' derivatives in z. */
typedef struct link_prims {
    double len, ang;
    double g_len[NZ], g_ang[NZ];
    double h_len[NZ][NZ], h_ang[NZ][NZ];
} link_prims;

static const double link_map[3][2][NZ] = {
    {{1, 0, 0, 0, 0}, {0, 1, 0, 0, 0}},   /* left:   (x1, y1) */
    {{0, 0, -1, 0, 1}, {0, 0, 0, 1, 0}},  /* right:  (D - x2, y2) */
    {{-1, 0, 1, 0, 0}, {0, 1, 0, -1, 0}}, /* middle: (x2 - x1, y1 - y2) */
};

/* A spring compressed below this fraction of its natural length counts as collapsed: the
 * joint angle there is ill-defined and the model has left its range. */
#define LINK_COLLAPSE 1e-3

static int link_eval(int k, const double z[NZ], double rest, int want_hess, link_prims *lp)
{
    const double(*J)[NZ] = link_map[k];
    double a = 0.0, b = 0.0;
    for (int i = 0; i < NZ; i++) {
        a += J[0][i] * z[i];
        b += J[1][i] * z[i];
    }
    double r2 = a * a + b * b;
    double r = sqrt(r2);
    if (!(r > LINK_COLLAPSE * rest))
        return -1;
    lp->len = r;
    lp->ang = atan2(b, a);
    double gl[2] = {a / r, b / r};
    double ga[2] = {-b / r2, a / r2};
    for (int i = 0; i < NZ; i++) {
        lp->g_len[i] = J[0][i] * gl[0] + J[1][i] * gl[1];
        lp->g_ang[i] = J[0][i] * ga[0] + J[1][i] * ga[1];
    }
    if (!want_hess)
        return 0;
    double r4 = r2 * r2;
    double hl[2][2] = {{(1.0 - a * a / r2) / r, -a * b / (r2 * r)},
                       {-a * b / (r2 * r), (1.0 - b * b / r2) / r}};
    double ha[2][2] = {{2.0 * a * b / r4, (b * b - a * a) / r4},
                       {(b * b - a * a) / r4, -2.0 * a * b / r4}};
    for (int i = 0; i < NZ; i++) {
        for (int j = 0; j < NZ; j++) {
            double sl = 0.0, sa = 0.0;
            for (int m = 0; m < 2; m++) {
                for (int n = 0; n < 2; n++) {
                    sl += J[m][i] * hl[m][n] * J[n][j];
                    sa += J[m][i] * ha[m][n] * J[n][j];
                }
            }
            lp->h_len[i][j] = sl;
            lp->h_ang[i][j] = sa;
        }
    }
    return 0;
}

/* Adds k/2 (v - v0)^2 with v = sum_t w[t] * prim(link[t], is_angle[t]). */
typedef struct term_part {
    int link;
    int is_angle;
    double w;
} term_part;

static void term_add(const link_prims lp[3], double k, double v0, const term_part *parts, int nparts,
                     double *energy, double g[NZ], double h[NZ][NZ], int want_hess)
{
    double v = -v0;
    double gv[NZ] = {0};
    for (int t = 0; t < nparts; t++) {
        const link_prims *L = &lp[parts[t].link];
        v += parts[t].w * (parts[t].is_angle ? L->ang : L->len);
        for (int i = 0; i < NZ; i++)
            gv[i] += parts[t].w * (parts[t].is_angle ? L->g_ang[i] : L->g_len[i]);
    }
    *energy += 0.5 * k * v * v;
    for (int i = 0; i < NZ; i++)
        g[i] += k * v * gv[i];
    if (!want_hess)
        return;
    for (int i = 0; i < NZ; i++) {
        for (int j = 0; j < NZ; j++) {
            double hv = 0.0;
            for (int t = 0; t < nparts; t++) {
                const link_prims *L = &lp[parts[t].link];
                hv += parts[t].w * (parts[t].is_angle ? L->h_ang[i][j] : L->h_len[i][j]);
            }
            h[i][j] += k * (gv[i] * gv[j] + v * hv);
        }
    }
}

truss_error truss_energy_eval(const truss_params *p, double mu, const double q[4], double *energy,
                              double grad[4], double hess[16], double grad_mu[4])
{
    double z[NZ] = {q[0], q[1], q[2], q[3], truss_support_right(p, mu)};
    for (int i = 0; i < NZ; i++) {
        if (!isfinite(z[i]))
            return TRUSS_ERR_NAN;
    }
    int want_hess = (hess != NULL || grad_mu != NULL);
    link_prims lp[3];
    for (int k = 0; k < 3; k++) {
        if (link_eval(k, z, k == 2 ? p->l2 : 1.0, want_hess, &lp[k]) != 0)
            return TRUSS_ERR_DIVERGED;
    }
    const double kt = p->lambda * p->alpha * p->alpha / 3.0;
    const double s = p->printed_signs ? -1.0 : 1.0;
    const double alpha_l = p->alpha * (1.0 + 0.5 * p->imperfection);
    const double alpha_r = p->alpha * (1.0 - 0.5 * p->imperfection);

    double u = 0.0;
    double g[NZ] = {0};
    double h[NZ][NZ];
    memset(h, 0, sizeof h);
    /* stretching: k_s = 1, natural lengths 1, 1, L2 */
    term_part sl[1] = {{0, 0, 1.0}};
    term_part sr[1] = {{1, 0, 1.0}};
    term_part sc[1] = {{2, 0, 1.0}};
    term_add(lp, 1.0, 1.0, sl, 1, &u, g, h, want_hess);
    term_add(lp, 1.0, 1.0, sr, 1, &u, g, h, want_hess);
    term_add(lp, 1.0, p->l2, sc, 1, &u, g, h, want_hess);
    /* supports: rest angle -alpha, i.e. (theta + alpha)^2 */
    term_part bl[1] = {{0, 1, 1.0}};
    term_part br[1] = {{1, 1, 1.0}};
    term_add(lp, kt, -alpha_l, bl, 1, &u, g, h, want_hess);
    term_add(lp, kt, -alpha_r, br, 1, &u, g, h, want_hess);
    /* inner joints: theta_L + s dtheta and theta_R - s dtheta */
    term_part jl[2] = {{0, 1, 1.0}, {2, 1, s}};
    term_part jr[2] = {{1, 1, 1.0}, {2, 1, -s}};
    term_add(lp, kt, 0.0, jl, 2, &u, g, h, want_hess);
    term_add(lp, kt, 0.0, jr, 2, &u, g, h, want_hess);

    if (!isfinite(u))
        return TRUSS_ERR_NAN;
    for (int i = 0; i < NZ; i++) {
        if (!isfinite(g[i]))
            return TRUSS_ERR_NAN;
        for (int j = 0; j < NZ && want_hess; j++) {
            if (!isfinite(h[i][j]))
                return TRUSS_ERR_NAN;
        }
    }
    if (energy != NULL)
        *energy = u;
    if (grad != NULL) {
        for (int i = 0; i < 4; i++)
            grad[i] = g[i];
    }
    if (hess != NULL) {
        for (int i = 0; i < 4; i++) {
            for (int j = 0; j < 4; j++)
                hess[4 * i + j] = h[i][j];
        }
    }
    if (grad_mu != NULL) {
        const double dD_dmu = -(2.0 + p->l2) * p->alpha * p->alpha;
        for (int i = 0; i < 4; i++)
            grad_mu[i] = h[i][4] * dD_dmu;
    }
    return TRUSS_OK;
}

void truss_coords_psi(const truss_params *p, double mu, const double q[4], double *psi_s, double *psi_a)
{
    double D = truss_support_right(p, mu);
    double tl = atan2(q[1], q[0]);
    double tr = atan2(q[3], D - q[2]);
    if (psi_s != NULL)
        *psi_s = 0.5 * (tl + tr) / p->alpha;
    if (psi_a != NULL)
        *psi_a = 0.5 * (tl - tr) / p->alpha;
}

void truss_config_guess(const truss_params *p, double mu, double psi_s, double q[4])
{
    double th = p->alpha * psi_s;
    double D = truss_support_right(p, mu);
    q[0] = cos(th);
    q[1] = sin(th);
    q[2] = D - cos(th);
    q[3] = sin(th);
}

truss_newton_opts truss_newton_opts_default(void)
{
    truss_newton_opts o;
    o.max_iter = 50;
    o.step_tol = 1e-10;
    o.res_tol = 1e-8;
    return o;
}

/* Lowest and highest eigenvalue of a symmetric 4 x 4 (copied; w sized for 4). */
static truss_error eig_range(const double h[16], gsl_eigen_symm_workspace *w, double *lo, double *hi)
{
    double a[16], ev[4];
    memcpy(a, h, sizeof a);
    gsl_matrix_view av = gsl_matrix_view_array(a, 4, 4);
    gsl_vector_view evv = gsl_vector_view_array(ev, 4);
    if (gsl_eigen_symm(&av.matrix, &evv.vector, w) != GSL_SUCCESS)
        return TRUSS_ERR_GSL;
    *lo = *hi = ev[0];
    for (int i = 0; i < 4; i++) {
        if (!isfinite(ev[i]))
            return TRUSS_ERR_NAN;
        *lo = fmin(*lo, ev[i]);
        *hi = fmax(*hi, ev[i]);
    }
    return TRUSS_OK;
}

/* Solve A x = b for a 4 x 4 A (destroyed) by LU on the stack. */
static truss_error solve4(double a[16], double b[4], double x[4])
{
    size_t perm_data[4];
    gsl_permutation perm = {4, perm_data};
    gsl_matrix_view av = gsl_matrix_view_array(a, 4, 4);
    gsl_vector_view bv = gsl_vector_view_array(b, 4);
    gsl_vector_view xv = gsl_vector_view_array(x, 4);
    int sign = 0;
    if (gsl_linalg_LU_decomp(&av.matrix, &perm, &sign) != GSL_SUCCESS)
        return TRUSS_ERR_GSL;
    for (int i = 0; i < 4; i++) {
        if (!(fabs(a[5 * i]) > 0.0))
            return TRUSS_ERR_SINGULAR;
    }
    if (gsl_linalg_LU_solve(&av.matrix, &perm, &bv.vector, &xv.vector) != GSL_SUCCESS)
        return TRUSS_ERR_SINGULAR;
    for (int i = 0; i < 4; i++) {
        if (!isfinite(x[i]))
            return TRUSS_ERR_NAN;
    }
    return TRUSS_OK;
}

static truss_error statics_iterate(const truss_params *p, double mu, double x[4],
                                   const truss_newton_opts *opts, gsl_eigen_symm_workspace *w,
                                   int *iterations)
{
    static const double unit[4] = {1.0, 1.0, 1.0, 1.0};
    for (int it = 1; it <= opts->max_iter; it++) {
        double u, g[4], h[16];
        truss_error e = truss_energy_eval(p, mu, x, &u, g, h, NULL);
        if (e != TRUSS_OK)
            return e;
        double lo, hi;
        if ((e = eig_range(h, w, &lo, &hi)) != TRUSS_OK)
            return e;
        /* Where H is not positive definite, shift it so its lowest eigenvalue becomes |lo|:
         * the step is then a descent direction and the iteration heads for a minimum. */
        double sigma = lo > 1e-12 * fabs(hi) ? 0.0 : 2.0 * fabs(lo) + 1e-12 * fabs(hi);
        for (int i = 0; i < 4; i++)
            h[5 * i] += sigma;
        double rhs[4] = {-g[0], -g[1], -g[2], -g[3]}, dx[4];
        if ((e = solve4(h, rhs, dx)) != TRUSS_OK)
            return e;
        /* Limit the step to a tenth of l1 so a poor guess cannot fold a spring through zero. */
        double dmax = 0.0, gmax = 0.0, slope = 0.0;
        for (int i = 0; i < 4; i++) {
            dmax = fmax(dmax, fabs(dx[i]));
            gmax = fmax(gmax, fabs(g[i]));
        }
        double lim = dmax > 0.1 ? 0.1 / dmax : 1.0;
        for (int i = 0; i < 4; i++) {
            dx[i] *= lim;
            slope += g[i] * dx[i];
        }
        double xt[4];
        for (int i = 0; i < 4; i++)
            xt[i] = x[i] + dx[i];
        if (lim == 1.0 && truss_newton_converged(opts, p->alpha, dx, xt, unit, 4, gmax)) {
            memcpy(x, xt, sizeof xt);
            if (iterations != NULL)
                *iterations = it;
            return TRUSS_OK;
        }
        /* Backtracking on the energy (Armijo, with a round-off allowance). Near a minimum the
         * energy change of a Newton step can fall below the round-off of U (small alpha): a
         * full step with a positive definite Hessian is then also taken when it reduces the
         * largest gradient component. */
        double t = 1.0;
        int ls;
        for (ls = 0; ls < 40; ls++) {
            for (int i = 0; i < 4; i++)
                xt[i] = x[i] + t * dx[i];
            double ut, gt[4];
            if (truss_energy_eval(p, mu, xt, &ut, gt, NULL, NULL) == TRUSS_OK) {
                if (ut <= u + 1e-4 * t * slope + 1e-13 * fabs(u))
                    break;
                double gtmax = 0.0;
                for (int i = 0; i < 4; i++)
                    gtmax = fmax(gtmax, fabs(gt[i]));
                if (ls == 0 && sigma == 0.0 && lim == 1.0 && gtmax < gmax)
                    break;
            }
            t *= 0.5;
        }
        if (ls == 40)
            return TRUSS_ERR_DIVERGED;
        memcpy(x, xt, sizeof xt);
    }
    return TRUSS_ERR_MAX_ITER;
}

truss_error truss_statics_solve(const truss_params *p, double mu, double q[4],
                                const truss_newton_opts *opts, int *iterations)
{
    if (!isfinite(mu) || opts->max_iter <= 0 || !(opts->step_tol > 0.0) || !(opts->res_tol > 0.0))
        return TRUSS_ERR_PARAM;
    gsl_eigen_symm_workspace *w = gsl_eigen_symm_alloc(4);
    if (w == NULL)
        return TRUSS_ERR_NOMEM;
    double x[4] = {q[0], q[1], q[2], q[3]};
    truss_error e = statics_iterate(p, mu, x, opts, w, iterations);
    gsl_eigen_symm_free(w);
    if (e == TRUSS_OK)
        memcpy(q, x, sizeof x);
    return e;
}

/* Lowest eigenvalue of the 2 x 2 block B^T H B for orthonormal columns b1, b2. */
static double block_min_eig(const double h[16], const double b1[4], const double b2[4])
{
    double hb1[4], hb2[4];
    for (int i = 0; i < 4; i++) {
        hb1[i] = hb2[i] = 0.0;
        for (int j = 0; j < 4; j++) {
            hb1[i] += h[4 * i + j] * b1[j];
            hb2[i] += h[4 * i + j] * b2[j];
        }
    }
    double a = 0.0, b = 0.0, c = 0.0;
    for (int i = 0; i < 4; i++) {
        a += b1[i] * hb1[i];
        b += b1[i] * hb2[i];
        c += b2[i] * hb2[i];
    }
    double m = 0.5 * (a + c);
    double r = hypot(0.5 * (a - c), b);
    return m - r;
}

truss_error truss_stability_eval(const truss_params *p, double mu, const double q[4],
                                 truss_stability *out)
{
    double h[16], gmu[4];
    truss_error e = truss_energy_eval(p, mu, q, NULL, NULL, h, gmu);
    if (e != TRUSS_OK)
        return e;
    memset(out, 0, sizeof *out);
    const double r = sqrt(0.5);
    const double s1[4] = {r, 0, -r, 0}, s2[4] = {0, r, 0, r};
    const double a1[4] = {r, 0, r, 0}, a2[4] = {0, r, 0, -r};
    out->eig_min_sym = block_min_eig(h, s1, s2);
    out->eig_min_anti = block_min_eig(h, a1, a2);

    double hcopy[16], eval[4], evec[16];
    memcpy(hcopy, h, sizeof h);
    gsl_matrix_view hv = gsl_matrix_view_array(hcopy, 4, 4);
    gsl_vector_view ev = gsl_vector_view_array(eval, 4);
    gsl_matrix_view vv = gsl_matrix_view_array(evec, 4, 4);
    gsl_eigen_symmv_workspace *w = gsl_eigen_symmv_alloc(4);
    if (w == NULL)
        return TRUSS_ERR_NOMEM;
    int rc = gsl_eigen_symmv(&hv.matrix, &ev.vector, &vv.matrix, w);
    gsl_eigen_symmv_free(w);
    if (rc != GSL_SUCCESS)
        return TRUSS_ERR_GSL;
    if (gsl_eigen_symmv_sort(&ev.vector, &vv.matrix, GSL_EIGEN_SORT_VAL_ASC) != GSL_SUCCESS)
        return TRUSS_ERR_GSL;
    int crit = 0;
    for (int i = 0; i < 4; i++) {
        if (!isfinite(eval[i]))
            return TRUSS_ERR_NAN;
        out->eig[i] = eval[i];
        if (eval[i] < 0.0)
            out->n_negative++;
        if (fabs(eval[i]) < fabs(eval[crit]))
            crit = i;
    }
    out->stable = out->n_negative == 0 && eval[0] > 0.0;
    out->mode_eig = eval[crit];
    for (int i = 0; i < 4; i++)
        out->mode[i] = evec[4 * i + crit];
    const double *v = out->mode;
    double sv[4] = {-v[2], v[3], -v[0], v[1]};
    double par = 0.0, proj = 0.0, gn = 0.0;
    for (int i = 0; i < 4; i++) {
        par += v[i] * sv[i];
        proj += v[i] * gmu[i];
        gn += gmu[i] * gmu[i];
    }
    out->mode_parity = par;
    out->load_projection = gn > 0.0 ? fabs(proj) / sqrt(gn) : 0.0;
    return TRUSS_OK;
}

/* ---- the paper's small-angle formulas ---- */

double truss_analytic_psi_sn(double lambda)
{
    return cbrt(0.5 * lambda);
}

double truss_analytic_psi_pf(double l2)
{
    return 0.25 * l2 * (l2 + 2.0);
}

double truss_analytic_mu_at_psi(double lambda, double l2, double psi)
{
    return (psi * psi * psi + 2.0 * lambda * psi + lambda) / ((2.0 + l2) * psi);
}

double truss_analytic_l2_star(double lambda)
{
    /* psi_PF(L2) = psi_SN  <=>  L2^2 + 2 L2 - 4 psi_SN = 0, positive root. */
    return 2.0 * sqrt(truss_analytic_psi_sn(lambda) + 0.25) - 1.0;
}

int truss_analytic_psi_roots(double lambda, double l2, double mu, double roots[3])
{
    /* psi^3 + P psi + Q = 0 (the paper's a4 psi^3 + (a2 - a3 mu) psi + a1 = 0 divided by a4). */
    const double P = 2.0 * lambda - (2.0 + l2) * mu;
    const double Q = lambda;
    const double disc = 0.25 * Q * Q + P * P * P / 27.0;
    if (disc < 0.0) {
        /* three real roots (P < 0 here), trigonometric form */
        double m = 2.0 * sqrt(-P / 3.0);
        double arg = 3.0 * Q / (P * m);
        arg = fmax(-1.0, fmin(1.0, arg));
        double th = acos(arg) / 3.0;
        for (int k = 0; k < 3; k++)
            roots[k] = m * cos(th - 2.0 * M_PI * k / 3.0);
        /* sort ascending */
        for (int i = 0; i < 3; i++) {
            for (int j = i + 1; j < 3; j++) {
                if (roots[j] < roots[i]) {
                    double t = roots[i];
                    roots[i] = roots[j];
                    roots[j] = t;
                }
            }
        }
        return 3;
    }
    double sq = sqrt(disc);
    roots[0] = cbrt(-0.5 * Q + sq) + cbrt(-0.5 * Q - sq);
    roots[1] = roots[2] = roots[0];
    return 1;
}
