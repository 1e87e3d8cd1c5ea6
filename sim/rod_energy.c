/* rod_energy.c: assembles the potential energy, its gradient over all DOFs, and its Hessian
 * over the free DOFs into symmetric band storage.
 *
 * Assembly is O(N) and allocation-free: each element's local block is a contiguous slice of q
 * (rod_kernels.h), so its Hessian lands inside the band of half-width ROD_BAND. Only the terms
 * the scene uses are evaluated (no gravity work without gravity); counters record what ran.
 * Rigid creases need no separate term: a rigid crease is the natural curvature and raised
 * stiffness of the bending term at its node, so "fold" evaluations are counted as bend
 * evaluations at the two crease nodes. A compliant crease is its own term (rod_hinge.c), which
 * replaces the kappa1 part of the bending term at its node and is counted as "hinge". */
#include "rod_kernels.h"
#include "vec3.h"

#include <string.h>

double rod_energy(rod *r)
{
    double E = 0.0;
    int n = r->n;
    if (r->terms.stretch)
        for (int j = 0; j < n - 1; j++) E += rod_stretch_element(r, j, NULL, NULL);
    for (int i = 1; i < n - 1; i++) {
        if (r->terms.bend || (r->terms.hinge && (i == r->fold_node[0] || i == r->fold_node[1])))
            E += rod_bend_element(r, i, NULL, NULL);
        if (r->terms.twist) E += rod_twist_element(r, i, NULL, NULL);
    }
    if (r->terms.gravity)
        for (int i = 0; i < n; i++) E -= r->mass[4 * i] * v3_dot(r->gravity, rod_x(r, i));
    return E;
}

static void count_terms(rod *r)
{
    int n = r->n;
    if (r->terms.stretch) r->count.stretch_evals += (uint64_t)(n - 1);
    if (r->terms.bend) r->count.bend_evals += (uint64_t)(n - 2);
    if (r->terms.twist) r->count.twist_evals += (uint64_t)(n - 2);
    if (r->terms.fold) r->count.fold_evals += 2;
    if (r->terms.hinge) r->count.hinge_evals += 2;
    if (r->terms.gravity) r->count.gravity_evals += (uint64_t)n;
}

/* The node element's 11 local DOFs [x_{i-1}, th_{i-1}, x_i, th_i, x_{i+1}] in terms of
 * (e, f, th_e, th_f) with e = x_i - x_{i-1}, f = x_{i+1} - x_i:
 *     g_{x_{i-1}} = -g_e,  g_{x_i} = g_e - g_f,  g_{x_{i+1}} = g_f,
 *     H_{x_{i-1} x_i} = -H_ee + H_ef,  H_{x_i x_i} = H_ee - H_ef - H_fe + H_ff, ...
 * (rod_local_from_ef does the same with a generic table; this is its unrolled form). */
static void ef_to_local(const double g8[8], double H8[8][8], double g[11], double H[11][11])
{
    for (int k = 0; k < 3; k++) {
        g[k] = -g8[k];
        g[4 + k] = g8[k] - g8[3 + k];
        g[8 + k] = g8[3 + k];
    }
    g[3] = g8[6];
    g[7] = g8[7];
    if (!H) return;
    /* Upper triangle only (band storage needs no more). */
    for (int p = 0; p < 3; p++) {
        for (int q = 0; q < 3; q++) {
            double E = H8[p][q], F = H8[3 + p][3 + q], X = H8[p][3 + q], Xt = H8[3 + p][q];
            H[p][q] = E;
            H[p][4 + q] = -E + X;
            H[p][8 + q] = -X;
            H[4 + p][4 + q] = E - X - Xt + F;
            H[4 + p][8 + q] = X - F;
            H[8 + p][8 + q] = F;
        }
        double e6 = H8[p][6], f6 = H8[3 + p][6], e7 = H8[p][7], f7 = H8[3 + p][7];
        H[p][3] = -e6;
        H[p][7] = -e7;
        H[3][4 + p] = e6 - f6;
        H[3][8 + p] = f6;
        H[4 + p][7] = e7 - f7;
        H[7][8 + p] = f7;
    }
    H[3][3] = H8[6][6];
    H[3][7] = H8[6][7];
    H[7][7] = H8[7][7];
}

void rod_gradient_hessian(rod *r, double *g, double s, double *H)
{
    const int n = r->n, w = ROD_BAND + 1;
    const int lo = ROD_FREE_BEGIN, hi = r->free_end;
    if (g) memset(g, 0, sizeof(double) * (size_t)r->ndof);
    double g8[8], H8[8][8], gl[11], Hl[11][11];
    double gbuf[ROD_BAND + 1];
    /* Material frames of edges i-1 and i: each edge's is computed once and used by two nodes. */
    double mf[2][6];
    rod_material_frame(r, 0, mf[0], mf[0] + 3);
    for (int i = 1; i < n - 1; i++) {
        double *mfe = mf[(i - 1) & 1], *mff = mf[i & 1];
        rod_material_frame(r, i, mff, mff + 3);
        rod_node_ef(r, i, mfe, mff, g8, H ? H8 : NULL);
        ef_to_local(g8, H ? H8 : NULL, gl, H ? Hl : NULL);
        int g0 = 4 * (i - 1);
        if (g)
            for (int k = 0; k < 11; k++) g[g0 + k] += gl[k];
        if (!H) continue;
        if (g0 >= lo && g0 + 10 < hi) {
            /* Interior element: every local DOF is free. */
            double *Hr = H + (g0 - lo) * w;
            for (int a = 0; a < 11; a++, Hr += w) {
                for (int b = a; b < 11; b++) gbuf[b - a] = s * Hl[a][b];
                for (int k = 0; k < 11 - a; k++) Hr[k] += gbuf[k];
            }
        } else {
            for (int a = 0; a < 11; a++) {
                int ga = g0 + a;
                if (ga < lo || ga >= hi) continue;
                for (int b = a; b < 11; b++) {
                    int gb = g0 + b;
                    if (gb >= hi) continue;
                    H[(ga - lo) * w + (gb - ga)] += s * Hl[a][b];
                }
            }
        }
    }
    /* The last edge (N-2, between the right clamp point and its clamped end) has no node element
     * to carry its stretching; both its nodes are prescribed, so it adds to the reactions only. */
    if (g && r->terms.stretch) {
        double gs[6];
        rod_stretch_element(r, n - 2, gs, NULL);
        for (int k = 0; k < 3; k++) {
            g[4 * (n - 2) + k] += gs[k];
            g[4 * (n - 1) + k] += gs[3 + k];
        }
    }
    if (g && r->terms.gravity)
        for (int i = 0; i < n; i++)
            for (int k = 0; k < 3; k++) g[4 * i + k] -= r->mass[4 * i] * r->gravity[k];
    if (g) count_terms(r);
    if (H) r->count.hessian_assemblies++;
}

void rod_gradient(rod *r, double *g) { rod_gradient_hessian(r, g, 0.0, NULL); }

void rod_hessian_add(rod *r, double s, double *H) { rod_gradient_hessian(r, NULL, s, H); }

void rod_kappa1(const rod *r, double *k1)
{
    int n = r->n;
    k1[0] = k1[n - 1] = 0.0;
    for (int i = 1; i < n - 1; i++) {
        double e[3], f[3], te[3], tf[3], m1e[3], m2e[3], m1f[3], m2f[3];
        v3_sub(rod_x(r, i), rod_x(r, i - 1), e);
        v3_sub(rod_x(r, i + 1), rod_x(r, i), f);
        v3_scale(e, 1.0 / v3_norm(e), te);
        v3_scale(f, 1.0 / v3_norm(f), tf);
        rod_material_frame(r, i - 1, m1e, m2e);
        rod_material_frame(r, i, m1f, m2f);
        k1[i] = (v3_dot(m1e, tf) - v3_dot(m1f, te)) / (1.0 + v3_dot(te, tf));
    }
}
