/* test_rod_stability: the stability tools of the continuation against independent references.
 *
 *   inertia      negative-eigenvalue count from the band LDL^T (with its shifted verification)
 *                against dense eigenvalues (gsl_eigen_symm) on: random symmetric band matrices
 *                of known mixed inertia, Hessians of randomly deformed folded rods, and Hessians
 *                at unstable equilibria reached by continuation (1 and 3 negative eigenvalues).
 *   eigenpair    the shift-invert eigenpair nearest a shift against the dense eigen-solve
 *                (value and vector up to sign).
 *   load vector  dR/dlambda from the Hessian coupling block against central differences of the
 *                gradient when the clamps move (shear and compression paths), at an equilibrium.
 *   parity       the C2 parity of constructed symmetric and antisymmetric displacements.
 * Small N throughout (dense eigenvalues are O(n^3)). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rod_continue.h"
#include "rod_load.h"
#include "rod_route.h"
#include "rod_snapshot.h"
#include "rod_solver.h"
#include "rod_stability.h"
#include "rod_symmetry.h"

#define EIG_REL_TOL 1e-7     /* shift-invert eigenvalue vs dense, relative to max(|lambda|, 1e-6 |A|) */
#define VEC_TOL 1e-5         /* 1 - |v . v_dense| */
#define LOAD_REL_TOL 1e-5    /* load vector vs central differences, relative to its max entry */

static unsigned long long rng = 88172645463325252ULL;
static double urand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* Dense eigenvalues (ascending) of the band matrix; returns the count below zero. */
static int dense_eigs(const double *B, int n, double *eval, double *evec)
{
    const int w = ROD_BAND + 1;
    gsl_matrix *A = gsl_matrix_calloc((size_t)n, (size_t)n);
    gsl_vector *ev = gsl_vector_alloc((size_t)n);
    gsl_matrix *V = gsl_matrix_alloc((size_t)n, (size_t)n);
    gsl_eigen_symmv_workspace *ws = gsl_eigen_symmv_alloc((size_t)n);
    assert_true(A && ev && V && ws);
    for (int a = 0; a < n; a++)
        for (int k = 0; k < w && a + k < n; k++) {
            gsl_matrix_set(A, (size_t)a, (size_t)(a + k), B[a * w + k]);
            gsl_matrix_set(A, (size_t)(a + k), (size_t)a, B[a * w + k]);
        }
    assert_int_equal(gsl_eigen_symmv(A, ev, V, ws), 0);
    gsl_eigen_symmv_sort(ev, V, GSL_EIGEN_SORT_VAL_ASC);
    int neg = 0;
    for (int a = 0; a < n; a++) {
        eval[a] = gsl_vector_get(ev, (size_t)a);
        neg += eval[a] < 0.0;
        if (evec)
            for (int b = 0; b < n; b++) evec[(size_t)a * (size_t)n + (size_t)b] = gsl_matrix_get(V, (size_t)b, (size_t)a);
    }
    gsl_eigen_symmv_free(ws);
    gsl_matrix_free(V);
    gsl_vector_free(ev);
    gsl_matrix_free(A);
    return neg;
}

static void check_inertia(const double *B, int n, const char *what)
{
    rod_stab_ws *w = rod_stab_ws_alloc(n);
    double *ev = malloc(sizeof(double) * (size_t)n);
    assert_true(w && ev);
    rod_inertia in;
    char why[128];
    assert_int_equal(rod_inertia_eval(B, n, ROD_INERTIA_SHIFT_REL, w, &in, why, sizeof why), ROD_OK);
    int dense = dense_eigs(B, n, ev, NULL);
    print_message("%-34s n %4d: band %d (verified %d, near-singular %d), dense %d; lowest %.3e %.3e\n", what, n,
                  in.n_negative, in.verified, in.near_singular, dense, ev[0], ev[1]);
    assert_int_equal(in.n_negative, dense);
    free(ev);
    rod_stab_ws_free(w);
}

/* Random symmetric band matrices with about a fifth of the diagonal negative, diagonal entries
 * spread over three decades (as between the rod's stiff positions and soft angles) and band
 * noise of order one: indefinite, with pivots of both signs; the dense eigen-solve is the
 * reference. */
static void test_inertia_random_band(void **state)
{
    (void)state;
    const int n = 120, w = ROD_BAND + 1;
    double *B = calloc((size_t)n * w, sizeof(double));
    assert_non_null(B);
    for (int trial = 0; trial < 20; trial++) {
        for (int a = 0; a < n; a++)
            for (int k = 0; k < w; k++) {
                double v = a + k < n ? (urand() - 0.5) : 0.0;
                if (k == 0) v = (urand() < 0.2 ? -1.0 : 1.0) * (0.05 + 2.0 * urand()) * (1.0 + 1e3 * (a % 4 != 3));
                B[a * w + k] = v;
            }
        check_inertia(B, n, "random band matrix");
    }
    free(B);
}

static rod *paper_rod(int nodes, double gamma)
{
    rod_scene s = rod_scene_default();
    s.nodes = nodes;
    s.fold_position = gamma;
    s.fold_angle_deg = -90.0;
    s.fold_angle_rel = 0.0;
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&s, &r, err, sizeof err), ROD_OK);
    return r;
}

static void hessian(rod *r, double *B)
{
    memset(B, 0, sizeof(double) * (size_t)rod_nfree(r) * (ROD_BAND + 1));
    rod_hessian_add(r, 1.0, B);
}

static void test_inertia_deformed_rods(void **state)
{
    (void)state;
    for (int trial = 0; trial < 8; trial++) {
        rod *r = paper_rod(21, 0.13 + 0.02 * (trial % 3));
        rod_place_arch(r, 0.3, trial % 2 ? 1 : -1);
        double h = r->length / (r->n - 3);
        for (int step = 1; step <= 4; step++) {
            for (int k = ROD_FREE_BEGIN; k < r->free_end; k++)
                r->q[k] += (k % 4 == 3 ? 0.3 : 0.2 * h) * (urand() - 0.5);
            rod_frames_update(r);
        }
        int nf = rod_nfree(r);
        double *B = malloc(sizeof(double) * (size_t)nf * (ROD_BAND + 1));
        assert_non_null(B);
        hessian(r, B);
        check_inertia(B, nf, "deformed folded rod (no equilibrium)");
        free(B);
        rod_free(r);
    }
}

/* Unstable equilibria from the continuation: Gamma = 0.13 at N = 31, stopped once more than
 * max_negative eigenvalues are negative; the rod is left at that equilibrium. */
static void test_inertia_unstable_equilibria(void **state)
{
    (void)state;
    const int maxneg[2] = {0, 2};
    for (int c = 0; c < 2; c++) {
        rod_scene s = rod_scene_default();
        s.nodes = 31;
        s.fold_angle_rel = 0.0;
        rod *r = NULL;
        char err[256];
        assert_int_equal(rod_alloc(&s, &r, err, sizeof err), ROD_OK);
        rod_solver *sv = rod_solver_alloc(r);
        assert_non_null(sv);
        assert_int_equal(rod_route_to_state(r, sv, &s, +1, NULL), ROD_OK);
        rod_cont_opts o = rod_cont_opts_default();
        o.max_negative = maxneg[c];
        rod_load load = {ROD_LOAD_SHEAR, s.compression, 0.0};
        rod_tracer *t = rod_tracer_alloc(r, &load, &o);
        assert_non_null(t);
        rod_branch b = {0};
        assert_int_equal(rod_trace_branch(t, 0.0, +1, &b), ROD_OK);
        print_message("branch ended: %s\n", b.end_reason);
        assert_true(b.n > 2);
        assert_int_equal(b.points[b.n - 1].n_negative, maxneg[c] + 1);
        int nf = rod_nfree(r);
        double *B = malloc(sizeof(double) * (size_t)nf * (ROD_BAND + 1));
        double *g = malloc(sizeof(double) * (size_t)r->ndof);
        assert_true(B && g);
        rod_frames_update(r);
        rod_gradient(r, g);
        double gmax = 0.0;
        for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) gmax = fmax(gmax, fabs(g[k]));
        assert_true(gmax < 1e-3 * r->force_scale); /* an equilibrium */
        hessian(r, B);
        check_inertia(B, nf, "unstable equilibrium (continuation)");
        free(g);
        free(B);
        rod_branch_free(&b);
        rod_tracer_free(t);
        rod_solver_free(sv);
        rod_free(r);
    }
}

static void test_eig_nearest(void **state)
{
    (void)state;
    rod *r = paper_rod(21, 0.21);
    rod_place_arch(r, 0.4, 1);
    for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) r->q[k] += 1e-3 * (urand() - 0.5);
    rod_frames_update(r);
    int nf = rod_nfree(r);
    double *B = malloc(sizeof(double) * (size_t)nf * (ROD_BAND + 1));
    double *ev = malloc(sizeof(double) * (size_t)nf), *V = malloc(sizeof(double) * (size_t)nf * (size_t)nf);
    double *v = malloc(sizeof(double) * (size_t)nf);
    rod_stab_ws *w = rod_stab_ws_alloc(nf);
    assert_true(B && ev && V && v && w);
    hessian(r, B);
    dense_eigs(B, nf, ev, V);
    double scale = 0.0;
    for (int a = 0; a < nf; a++) scale = fmax(scale, fabs(ev[a]));
    /* Shifts: 0 and just off each of the four lowest eigenvalues. */
    for (int c = 0; c < 5; c++) {
        double sigma = c == 0 ? 0.0 : ev[c - 1] + 1e-3 * (ev[c] - ev[c - 1]);
        int best = 0;
        for (int a = 1; a < nf; a++)
            if (fabs(ev[a] - sigma) < fabs(ev[best] - sigma)) best = a;
        memset(v, 0, sizeof(double) * (size_t)nf);
        rod_eigpair ep;
        char why[160];
        rod_status st = rod_eig_nearest(B, nf, sigma, 500, 1e-10, w, v, &ep, why, sizeof why);
        if (st != ROD_OK) print_message("eig_nearest: %s\n", why);
        assert_int_equal(st, ROD_OK);
        double dot = 0.0;
        for (int a = 0; a < nf; a++) dot += v[a] * V[(size_t)best * (size_t)nf + (size_t)a];
        double rel = fabs(ep.value - ev[best]) / fmax(fabs(ev[best]), 1e-12 * scale);
        print_message("shift %+.4e: shift-invert %+.10e (%d it), dense %+.10e, rel %.1e, 1 - |v.v| %.1e\n", sigma,
                      ep.value, ep.iterations, ev[best], rel, 1.0 - fabs(dot));
        assert_true(rel < EIG_REL_TOL);
        assert_true(1.0 - fabs(dot) < VEC_TOL);
    }
    rod_stab_ws_free(w);
    free(v); free(V); free(ev); free(B);
    rod_free(r);
}

static void check_load_vector(rod *r, const rod_load *p, double lambda, const char *what)
{
    int nf = rod_nfree(r);
    double *f = malloc(sizeof(double) * (size_t)nf), *gp = malloc(sizeof(double) * (size_t)r->ndof);
    double *gm = malloc(sizeof(double) * (size_t)r->ndof);
    rod_snapshot base;
    assert_true(f && gp && gm && rod_snapshot_alloc(r, &base));
    rod_load_apply(r, p, lambda);
    rod_frames_update(r);
    rod_snapshot_save(r, &base);
    rod_load_vector(r, p, f);
    double d = 1e-6, fmax_ = 0.0, err = 0.0;
    rod_load_apply(r, p, lambda + d);
    rod_frames_update(r);
    rod_gradient(r, gp);
    rod_snapshot_load(r, &base);
    rod_load_apply(r, p, lambda - d);
    rod_frames_update(r);
    rod_gradient(r, gm);
    rod_snapshot_load(r, &base);
    for (int k = 0; k < nf; k++) {
        double fd = (gp[k + ROD_FREE_BEGIN] - gm[k + ROD_FREE_BEGIN]) / (2.0 * d);
        fmax_ = fmax(fmax_, fabs(f[k]));
        err = fmax(err, fabs(fd - f[k]));
    }
    print_message("%s: max |f| %.4e, max |f - FD| %.3e (relative %.2e)\n", what, fmax_, err, err / fmax_);
    assert_true(fmax_ > 0.0);
    assert_true(err < LOAD_REL_TOL * fmax_);
    rod_snapshot_free(&base);
    free(f); free(gp); free(gm);
}

static void test_load_vector(void **state)
{
    (void)state;
    rod_scene s = rod_scene_default();
    s.nodes = 31;
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&s, &r, err, sizeof err), ROD_OK);
    rod_solver *sv = rod_solver_alloc(r);
    assert_non_null(sv);
    assert_int_equal(rod_route_to_state(r, sv, &s, +1, NULL), ROD_OK);
    double reached = 0.0;
    assert_int_equal(rod_follow_shear(r, sv, &s, s.compression, 0.0, 0.2, 0.05, &reached, NULL), ROD_OK);
    rod_load shear = {ROD_LOAD_SHEAR, s.compression, 0.0}, comp = {ROD_LOAD_COMPRESSION, 0.0, 0.2};
    check_load_vector(r, &shear, 0.2, "shear path at Delta W 0.2 (equilibrium)");
    check_load_vector(r, &comp, s.compression, "compression path at Delta L 0.5");
    rod_solver_free(sv);
    rod_free(r);
}

static void test_parity(void **state)
{
    (void)state;
    rod *r = paper_rod(21, 0.21);
    int nf = rod_nfree(r), n = r->n;
    double *v = calloc((size_t)nf, sizeof(double));
    assert_non_null(v);
    /* Even: node i and N-1-i get (dx, dy, dz) and (-dx, -dy, dz); odd: (dx, dy, dz) and (dx, dy, -dz). */
    for (int sym = 0; sym < 2; sym++) {
        memset(v, 0, sizeof(double) * (size_t)nf);
        for (int i = 2; i < n / 2; i++) {
            double d[3] = {urand() - 0.5, urand() - 0.5, urand() - 0.5};
            int m = n - 1 - i;
            for (int c = 0; c < 3; c++) {
                double sgn = (c < 2 ? -1.0 : 1.0) * (sym ? 1.0 : -1.0);
                v[4 * i + c - ROD_FREE_BEGIN] = d[c];
                v[4 * m + c - ROD_FREE_BEGIN] = sgn * d[c];
            }
        }
        if (!sym) {
            int mid = r->mid_node;
            v[4 * mid + 0 - ROD_FREE_BEGIN] = v[4 * mid + 1 - ROD_FREE_BEGIN] = 0.3; /* odd at the centre */
        } else {
            v[4 * r->mid_node + 2 - ROD_FREE_BEGIN] = 0.3;
        }
        double p = rod_mode_parity(r, v);
        print_message("%s displacement: parity %+.15f\n", sym ? "symmetric" : "antisymmetric", p);
        assert_true(fabs(p - (sym ? 1.0 : -1.0)) < 1e-14);
    }
    free(v);
    rod_free(r);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_inertia_random_band),
        cmocka_unit_test(test_inertia_deformed_rods),
        cmocka_unit_test(test_inertia_unstable_equilibria),
        cmocka_unit_test(test_eig_nearest),
        cmocka_unit_test(test_load_vector),
        cmocka_unit_test(test_parity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
