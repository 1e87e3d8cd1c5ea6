/* rod_load.c: the clamp load path and its load vector (see rod_load.h).
 *
 * Clamp velocities per unit lambda, from rod_set_clamps: on the shear path nodes 0 and 1 move by
 * -l/2 and nodes N-2 and N-1 by +l/2 along y; on the compression path nodes N-2 and N-1 move by
 * -l along x. The element Hessians are full symmetric local matrices, so the free-by-clamped
 * coupling is read from them directly. */
#include "rod_load.h"
#include "rod_kernels.h"

#include <string.h>

void rod_load_clamps(const rod_load *p, double lambda, double *dl, double *dw)
{
    *dl = p->kind == ROD_LOAD_SHEAR ? p->dl : lambda;
    *dw = p->kind == ROD_LOAD_SHEAR ? lambda : p->dw;
}

void rod_load_apply(rod *r, const rod_load *p, double lambda)
{
    double dl, dw;
    rod_load_clamps(p, lambda, &dl, &dw);
    rod_set_clamps(r, dl, dw);
}

/* Velocity of global DOF k per unit lambda (0 for free DOFs and clamp angles). */
static double clamp_velocity(const rod *r, const rod_load *p, int k)
{
    int n = r->n, node = k / 4, comp = k % 4;
    if (comp == 3) return 0.0;
    int left = node == 0 || node == 1, right = node == n - 2 || node == n - 1;
    if (!left && !right) return 0.0;
    if (p->kind == ROD_LOAD_SHEAR) return comp == 1 ? (left ? -0.5 : 0.5) * r->length : 0.0;
    return (right && comp == 0) ? -r->length : 0.0;
}

static int is_free(const rod *r, int k) { return k >= ROD_FREE_BEGIN && k < r->free_end; }

void rod_load_vector(const rod *r, const rod_load *p, double *f)
{
    int n = r->n;
    memset(f, 0, sizeof(double) * (size_t)rod_nfree(r));
    /* Stretch of edge j couples x_j and x_{j+1}. */
    for (int j = 0; j < n - 1; j++) {
        if (!r->terms.stretch) break;
        int touches = 0, dof[6];
        for (int a = 0; a < 6; a++) {
            dof[a] = 4 * (j + a / 3) + a % 3;
            touches |= clamp_velocity(r, p, dof[a]) != 0.0;
        }
        int has_free = is_free(r, dof[0]) || is_free(r, dof[3]);
        if (!touches || !has_free) continue;
        double g[6], H[6][6];
        rod_stretch_element(r, j, g, H);
        for (int a = 0; a < 6; a++) {
            if (!is_free(r, dof[a])) continue;
            for (int b = 0; b < 6; b++) f[dof[a] - ROD_FREE_BEGIN] += H[a][b] * clamp_velocity(r, p, dof[b]);
        }
    }
    /* Bend and twist of node i couple q[4 (i - 1) .. 4 (i - 1) + 10]. */
    for (int i = 1; i < n - 1; i++) {
        int g0 = 4 * (i - 1), touches = 0, has_free = 0;
        for (int a = 0; a < ROD_NODE_LOCAL; a++) {
            touches |= clamp_velocity(r, p, g0 + a) != 0.0;
            has_free |= is_free(r, g0 + a);
        }
        if (!touches || !has_free) continue;
        double g[11], H[11][11];
        for (int term = 0; term < 2; term++) {
            if (term == 0 && !r->terms.bend && !(r->terms.hinge && (i == r->fold_node[0] || i == r->fold_node[1])))
                continue;
            if (term == 1 && !r->terms.twist) continue;
            if (term == 0) rod_bend_element(r, i, g, H);
            else rod_twist_element(r, i, g, H);
            for (int a = 0; a < ROD_NODE_LOCAL; a++) {
                if (!is_free(r, g0 + a)) continue;
                for (int b = 0; b < ROD_NODE_LOCAL; b++)
                    f[g0 + a - ROD_FREE_BEGIN] += H[a][b] * clamp_velocity(r, p, g0 + b);
            }
        }
    }
}
