/* rod_energy.c: assembles the potential energy, its gradient over all DOFs, and its Hessian
 * over the free DOFs into symmetric band storage.
 *
 * Assembly is O(N) and allocation-free: each element's local block is a contiguous slice of q
 * (rod_kernels.h), so its Hessian lands inside the band of half-width ROD_BAND. Only the terms
 * the scene uses are evaluated (no gravity work without gravity); counters record what ran.
 * Folds need no separate term: a crease is the natural curvature and raised stiffness of the
 * bending term at its node, so "fold" evaluations are counted as bend evaluations at the two
 * crease nodes. */
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
        if (r->terms.bend) E += rod_bend_element(r, i, NULL, NULL);
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
    if (r->terms.gravity) r->count.gravity_evals += (uint64_t)n;
}

void rod_gradient(rod *r, double *g)
{
    int n = r->n;
    memset(g, 0, sizeof(double) * (size_t)r->ndof);
    double gs[6], gl[11];
    for (int j = 0; j < n - 1 && r->terms.stretch; j++) {
        rod_stretch_element(r, j, gs, NULL);
        for (int k = 0; k < 3; k++) {
            g[4 * j + k] += gs[k];
            g[4 * (j + 1) + k] += gs[3 + k];
        }
    }
    for (int i = 1; i < n - 1; i++) {
        double *gi = g + 4 * (i - 1);
        if (r->terms.bend) {
            rod_bend_element(r, i, gl, NULL);
            for (int k = 0; k < 11; k++) gi[k] += gl[k];
        }
        if (r->terms.twist) {
            rod_twist_element(r, i, gl, NULL);
            for (int k = 0; k < 11; k++) gi[k] += gl[k];
        }
    }
    if (r->terms.gravity)
        for (int i = 0; i < n; i++)
            for (int k = 0; k < 3; k++) g[4 * i + k] -= r->mass[4 * i] * r->gravity[k];
    count_terms(r);
}

/* Adds s * Hl (local, starting at global DOF g0, size m) into the free band. */
static void band_add(const rod *r, double s, int g0, int m, const double *Hl, double *H)
{
    const int w = ROD_BAND + 1;
    for (int a = 0; a < m; a++) {
        int fa = g0 + a - ROD_FREE_BEGIN;
        if (fa < 0 || g0 + a >= r->free_end) continue;
        for (int b = a; b < m; b++) {
            int fb = g0 + b - ROD_FREE_BEGIN;
            if (fb < 0 || g0 + b >= r->free_end) continue;
            H[fa * w + (fb - fa)] += s * Hl[a * m + b];
        }
    }
}

void rod_hessian_add(rod *r, double s, double *H)
{
    int n = r->n;
    double Hs[6][6], Hl[11][11], gs[6], gl[11];
    for (int j = 0; j < n - 1 && r->terms.stretch; j++) {
        rod_stretch_element(r, j, gs, Hs);
        /* Stretch local DOFs are x_j (3) and x_{j+1} (3): not contiguous (th_j sits between),
         * so add the blocks one by one. */
        double blk[3][3];
        for (int bi = 0; bi < 2; bi++)
            for (int bj = bi; bj < 2; bj++) {
                for (int p = 0; p < 3; p++)
                    for (int q = 0; q < 3; q++) blk[p][q] = Hs[3 * bi + p][3 * bj + q];
                int r0 = 4 * (j + bi), c0 = 4 * (j + bj);
                for (int p = 0; p < 3; p++)
                    for (int q = 0; q < 3; q++) {
                        int gr = r0 + p, gc = c0 + q;
                        if (gr > gc) continue;
                        int fr = gr - ROD_FREE_BEGIN, fc = gc - ROD_FREE_BEGIN;
                        if (fr < 0 || gc >= r->free_end || gr >= r->free_end) continue;
                        H[fr * (ROD_BAND + 1) + (fc - fr)] += s * blk[p][q];
                    }
            }
    }
    for (int i = 1; i < n - 1; i++) {
        if (r->terms.bend) {
            rod_bend_element(r, i, gl, Hl);
            band_add(r, s, 4 * (i - 1), 11, &Hl[0][0], H);
        }
        if (r->terms.twist) {
            rod_twist_element(r, i, gl, Hl);
            band_add(r, s, 4 * (i - 1), 11, &Hl[0][0], H);
        }
    }
    r->count.hessian_assemblies++;
}

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
