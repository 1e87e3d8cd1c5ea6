/* test_euler_buckling: the clamped-clamped Euler buckling load of the discrete rod against the
 * closed form P_cr = 4 pi^2 E I1 / l^2 (I1 = w b^3 / 12, l the free length between the clamp
 * points, DESIGN.md section 3).
 *
 * Why: this is the one load every later result (the arch, the creased states, the snaps) sits
 * on. It checks at once the soft bending stiffness and its direction (the ribbon must buckle out
 * of plane, toward the surface normal, not in its stiff plane or by twisting), the geometric
 * stiffness of the stretching term, the clamp boundary conditions and the normalisation of l.
 *
 * How: a ribbon without folds, N = 101, no gravity, clamped straight at end-shortening dl with
 * the free nodes spread uniformly on the straight segment. The straight state is an exact
 * equilibrium at any dl (checked), with axial force P = EA * strain = EA * dl. The free-DOF
 * Hessian (rod_hessian_add, GSL's symmetric band layout) is factorised as L D L^T without
 * pivoting; by Sylvester's law of inertia the number of non-positive pivots is the number of
 * non-positive eigenvalues, so bisection on dl finds where it first stops being positive
 * definite. Just past that point a dense eigen-solve must show exactly one negative eigenvalue
 * whose mode is out of plane (z) and symmetric under s -> 1 - s: the first clamped-clamped mode
 * z ~ 1 - cos(2 pi s). The discretisation error at N = 101 is about 3e-4, so the tolerance is
 * 1%; a clamp that acts half an edge outside the clamp points (effective length l + h, 2% off at
 * N = 101) fails, and so would taking l as the whole discrete rod (l + 2 h, 4% off). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_eigen.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_vector.h>

#include <gsl/gsl_errno.h>

#include "rod.h"

#define PCR_REL_TOL 0.01      /* |P_cr / (4 pi^2 EI1 / l^2) - 1| */
#define MODE_Z_FRACTION 0.999 /* share of the critical mode's squared norm in z displacements */
#define MODE_SYM_TOL 1e-6     /* max |z_i - z_{N-1-i}| over max |z| for the critical mode */
#define EQUIL_REL_TOL 1e-8    /* straight state's free gradient over EA (round-off scale) */

/* Places the straight compressed state: clamps at end-shortening dl, free nodes uniform. */
static void place_straight(rod *r, double dl)
{
    rod_set_clamps(r, dl, 0.0);
    double span = r->length * (1.0 - dl);
    for (int i = 2; i < r->n - 2; i++) {
        double *x = rod_x(r, i);
        x[0] = span * r->s_node[i];
        x[1] = 0.0;
        x[2] = 0.0;
    }
    for (int i = 1; i < r->n - 2; i++) r->q[4 * i + 3] = 0.0;
    rod_frames_update(r);
}

/* Number of non-positive pivots of the L D L^T factorisation (no pivoting) of the symmetric
 * band matrix B (n rows, half-bandwidth p, row i holding A(i, i + k) at B[i (p + 1) + k]).
 * B is overwritten. A zero pivot counts as non-positive and ends the count there. */
static int nonpositive_pivots(double *B, int n, int p)
{
    int w = p + 1, count = 0;
    for (int j = 0; j < n; j++) {
        double d = B[j * w];
        if (!(d > 0.0)) {
            count++;
            if (d == 0.0) return count + 1000000; /* singular: flagged as not PD */
        }
        /* Eliminate column j from the trailing block: A(i, k) -= A(j, i) A(j, k) / d. */
        int last = j + p < n - 1 ? j + p : n - 1;
        for (int i = j + 1; i <= last; i++) {
            double lji = B[j * w + (i - j)] / d;
            for (int k = i; k <= last; k++) B[i * w + (k - i)] -= lji * B[j * w + (k - j)];
        }
    }
    return count;
}

static int count_at(rod *r, double dl, double *B)
{
    int nf = rod_nfree(r), w = ROD_BAND + 1;
    place_straight(r, dl);
    memset(B, 0, sizeof(double) * (size_t)nf * (size_t)w);
    rod_hessian_add(r, 1.0, B);
    return nonpositive_pivots(B, nf, ROD_BAND);
}

static void test_buckling_load(void **state)
{
    (void)state;
    rod_scene sc = rod_scene_default();
    sc.fold_angle_deg = 0.0;
    sc.nodes = 101;
    sc.gravity[0] = sc.gravity[1] = sc.gravity[2] = 0.0;
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&sc, &r, err, sizeof err), ROD_OK);
    assert_false(r->terms.fold);
    assert_false(r->terms.gravity);

    double l = sc.length;
    double EI1 = sc.youngs_modulus * sc.width * pow(sc.thickness, 3) / 12.0;
    double P_euler = 4.0 * M_PI * M_PI * EI1 / (l * l);
    double dl_euler = P_euler / r->EA; /* the closed-form critical shortening */
    int nf = rod_nfree(r), w = ROD_BAND + 1;
    double *B = malloc(sizeof(double) * (size_t)nf * (size_t)w);
    double *g = malloc(sizeof(double) * (size_t)r->ndof);
    assert_non_null(B);
    assert_non_null(g);

    /* The straight state is an equilibrium: free gradient at round-off of the axial force. */
    place_straight(r, 0.5 * dl_euler);
    rod_gradient(r, g);
    double gmax = 0.0;
    for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) gmax = fmax(gmax, fabs(g[k]));
    print_message("straight state at dl = %.3e: max free |grad| = %.3e N (EA = %.3e N)\n",
                  0.5 * dl_euler, gmax, r->EA);
    assert_true(gmax < EQUIL_REL_TOL * r->EA);

    /* Bracket: positive definite unloaded, not at twice the closed-form load. */
    double lo = 0.0, hi = 2.0 * dl_euler;
    assert_int_equal(count_at(r, lo, B), 0);
    assert_true(count_at(r, hi, B) > 0);
    for (int it = 0; it < 60; it++) {
        double mid = 0.5 * (lo + hi);
        if (count_at(r, mid, B) == 0) lo = mid; else hi = mid;
    }
    double dl_cr = 0.5 * (lo + hi);

    /* Axial force from the actual edge strain (a middle free edge). */
    place_straight(r, dl_cr);
    int j = r->n / 2;
    const double *xa = rod_x(r, j), *xb = rod_x(r, j + 1);
    double len = sqrt((xb[0] - xa[0]) * (xb[0] - xa[0]) + (xb[1] - xa[1]) * (xb[1] - xa[1]) +
                      (xb[2] - xa[2]) * (xb[2] - xa[2]));
    double P_cr = -r->EA * (len / r->len0[j] - 1.0);
    double ratio = P_cr / P_euler;
    print_message("dl_cr = %.6e, P_cr = %.6e N, 4 pi^2 EI1 / l^2 = %.6e N, ratio = %.6f\n", dl_cr,
                  P_cr, P_euler, ratio);
    /* Diagnostic: the length a continuous clamped-clamped rod would need to buckle at P_cr. A
     * clamp acting at the middle of the clamped edges instead of the clamp points gives l + h. */
    print_message("effective length l sqrt(P_euler / P_cr) = %.6f l (free length 1, l + h = %.6f l)\n",
                  sqrt(1.0 / ratio), 1.0 + r->h_clamp / l);
    assert_true(fabs(ratio - 1.0) < PCR_REL_TOL);

    /* The critical mode, just past the load: one negative eigenvalue, out of plane, symmetric. */
    place_straight(r, dl_cr * (1.0 + 1e-3));
    memset(B, 0, sizeof(double) * (size_t)nf * (size_t)w);
    rod_hessian_add(r, 1.0, B);
    gsl_matrix *A = gsl_matrix_calloc((size_t)nf, (size_t)nf);
    gsl_matrix *V = gsl_matrix_alloc((size_t)nf, (size_t)nf);
    gsl_vector *ev = gsl_vector_alloc((size_t)nf);
    gsl_eigen_symmv_workspace *ws = gsl_eigen_symmv_alloc((size_t)nf);
    assert_true(A && V && ev && ws);
    for (int a = 0; a < nf; a++)
        for (int k = 0; k < w && a + k < nf; k++) {
            gsl_matrix_set(A, (size_t)a, (size_t)(a + k), B[a * w + k]);
            gsl_matrix_set(A, (size_t)(a + k), (size_t)a, B[a * w + k]);
        }
    assert_int_equal(gsl_eigen_symmv(A, ev, V, ws), 0);
    gsl_eigen_symmv_sort(ev, V, GSL_EIGEN_SORT_VAL_ASC);
    int negative = 0;
    for (int a = 0; a < nf; a++) negative += gsl_vector_get(ev, (size_t)a) < 0.0;
    print_message("past the load: %d negative eigenvalue(s); lowest two %.3e, %.3e\n", negative,
                  gsl_vector_get(ev, 0), gsl_vector_get(ev, 1));
    assert_int_equal(negative, 1);

    /* Mode components by node: z displacement share and symmetry z_i = z_{N-1-i}. */
    double *z = calloc((size_t)r->n, sizeof(double));
    assert_non_null(z);
    double zz = 0.0, all = 0.0, zmax = 0.0;
    for (int a = 0; a < nf; a++) {
        int k = a + ROD_FREE_BEGIN;
        double v = gsl_matrix_get(V, (size_t)a, 0);
        all += v * v;
        if (k % 4 == 2) {
            zz += v * v;
            z[k / 4] = v;
            zmax = fmax(zmax, fabs(v));
        }
    }
    double asym = 0.0;
    for (int i = 0; i < r->n; i++) asym = fmax(asym, fabs(z[i] - z[r->n - 1 - i]));
    asym /= zmax;
    int mid = r->mid_node;
    assert_true(mid > 0);
    print_message("critical mode: z share %.9f, asymmetry %.3e, z(mid) / max|z| = %.6f\n",
                  zz / all, asym, fabs(z[mid]) / zmax);
    assert_true(zz / all > MODE_Z_FRACTION);
    assert_true(asym < MODE_SYM_TOL);
    /* First clamped-clamped mode 1 - cos(2 pi s): largest at the midpoint, one sign throughout. */
    assert_true(fabs(z[mid]) / zmax > 0.999);
    for (int i = 2; i < r->n - 2; i++) assert_true(z[i] * z[mid] >= 0.0);

    free(z);
    gsl_eigen_symmv_free(ws);
    gsl_vector_free(ev);
    gsl_matrix_free(V);
    gsl_matrix_free(A);
    free(g);
    free(B);
    rod_free(r);
}

int main(void)
{
    gsl_set_error_handler_off(); /* the solver handles GSL's failures by return codes */
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_buckling_load),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
