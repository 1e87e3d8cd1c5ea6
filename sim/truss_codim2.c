/* truss_codim2.c: the truss's ordering switch located directly as the point where its symmetric
 * branch's saddle-node and pitchfork coincide (truss.h, truss_codim2_find): the closed-form check
 * of the rod's codimension-2 location.
 *
 * Unknowns u = (x1, y1, mu, L2), the symmetric configuration q = (x1, y1, D - x1, y1) with
 * D = truss_support_right. Equations F(u) = (g . e1, g . e2, eig_min_sym, eig_min_anti), e1 and e2
 * the unit symmetric displacements (1, 0, -1, 0) / sqrt 2 and (0, 1, 0, 1) / sqrt 2, g the
 * gradient. The 4 x 4 Jacobian by central differences (steps 1e-7 (1 + |u_k|)), solved by GSL's
 * LU; converged when every |F_k| <= 1e-12 and the step <= 1e-12 (1 + |u|). */
#include "truss.h"

#include <gsl/gsl_linalg.h>
#include <math.h>
#include <string.h>

static truss_error eval(const truss_params *p0, const double u[4], double F[4], double q[4], truss_stability *st)
{
    truss_params p = *p0;
    p.l2 = u[3];
    if (!(p.l2 > 0.0) || !isfinite(u[0]) || !isfinite(u[1]) || !isfinite(u[2])) return TRUSS_ERR_DIVERGED;
    double D = truss_support_right(&p, u[2]);
    q[0] = u[0];
    q[1] = u[1];
    q[2] = D - u[0];
    q[3] = u[1];
    double g[4];
    truss_error e = truss_energy_eval(&p, u[2], q, NULL, g, NULL, NULL);
    if (e != TRUSS_OK) return e;
    if ((e = truss_stability_eval(&p, u[2], q, st)) != TRUSS_OK) return e;
    F[0] = (g[0] - g[2]) / M_SQRT2;
    F[1] = (g[1] + g[3]) / M_SQRT2;
    F[2] = st->eig_min_sym;
    F[3] = st->eig_min_anti;
    for (int k = 0; k < 4; k++)
        if (!isfinite(F[k])) return TRUSS_ERR_NAN;
    return TRUSS_OK;
}

truss_error truss_codim2_find(const truss_params *p, const truss_cont_opts *opts, truss_codim2 *out)
{
    memset(out, 0, sizeof *out);
    if (p->imperfection != 0.0) return TRUSS_ERR_PARAM;
    truss_branch b;
    truss_error e = truss_continue(p, opts, 0, &b);
    if (e != TRUSS_OK && e != TRUSS_ERR_NOT_FOUND) return e;
    if (!b.saddle_node.found) {
        truss_branch_free(&b);
        return TRUSS_ERR_NOT_FOUND;
    }
    double u[4] = {b.saddle_node.at.q[0], b.saddle_node.at.q[1], b.saddle_node.at.mu, p->l2}, F[4], q[4];
    truss_branch_free(&b);
    truss_stability st;
    for (int it = 0; it < 50; it++) {
        if ((e = eval(p, u, F, q, &st)) != TRUSS_OK) return e;
        double J[16], Fp[4], Fm[4], qq[4];
        truss_stability s2;
        for (int k = 0; k < 4; k++) {
            double h = 1e-7 * (1.0 + fabs(u[k])), up[4], um[4];
            memcpy(up, u, sizeof up);
            memcpy(um, u, sizeof um);
            up[k] += h;
            um[k] -= h;
            if ((e = eval(p, up, Fp, qq, &s2)) != TRUSS_OK || (e = eval(p, um, Fm, qq, &s2)) != TRUSS_OK) return e;
            for (int i = 0; i < 4; i++) J[4 * i + k] = (Fp[i] - Fm[i]) / (2.0 * h);
        }
        double du[4];
        gsl_matrix_view Jm = gsl_matrix_view_array(J, 4, 4);
        gsl_vector_view rhs = gsl_vector_view_array(F, 4), x = gsl_vector_view_array(du, 4);
        gsl_permutation *perm = gsl_permutation_alloc(4);
        if (!perm) return TRUSS_ERR_NOMEM;
        int sg;
        int bad = gsl_linalg_LU_decomp(&Jm.matrix, perm, &sg) != 0 || gsl_linalg_LU_solve(&Jm.matrix, perm, &rhs.vector, &x.vector) != 0;
        gsl_permutation_free(perm);
        if (bad) return TRUSS_ERR_SINGULAR;
        double big = 0.0, fmax_ = 0.0;
        for (int k = 0; k < 4; k++) {
            u[k] -= du[k];
            big = fmax(big, fabs(du[k]) / (1.0 + fabs(u[k])));
            fmax_ = fmax(fmax_, fabs(F[k]));
        }
        out->iterations = it + 1;
        if (big <= 1e-12 || (fmax_ <= 1e-12 && big <= 1e-9)) {
            if ((e = eval(p, u, F, q, &st)) != TRUSS_OK) return e;
            truss_params pp = *p;
            pp.l2 = u[3];
            out->l2 = u[3];
            out->mu = u[2];
            memcpy(out->q, q, sizeof out->q);
            double pa;
            truss_coords_psi(&pp, u[2], q, &out->psi_s, &pa);
            out->eig_sym = st.eig_min_sym;
            out->eig_anti = st.eig_min_anti;
            return TRUSS_OK;
        }
    }
    return TRUSS_ERR_MAX_ITER;
}
