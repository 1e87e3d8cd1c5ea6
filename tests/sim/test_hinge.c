/* test_hinge: compliant creases (sim/rod_hinge.c) against closed forms.
 *
 * Why: a crease is a hinge of rest angle phi and rotational stiffness k (N m/rad) whose energy
 * depends on its turning angle alone; the strip around it bends with its own stiffness E I1. A
 * model whose crease stiffness depends on the mesh (the rigid crease's E I1 factor / dl_hat)
 * converges to the wrong strip; these checks pin the physics and show the discretisation error
 * falling at the scheme's order (second) as N grows.
 *
 * 1. End moment. A planar strip of length l, clamped at s = 0, loaded by a pure end moment M:
 *    its curvature is M / E I1 everywhere, and each hinge turns by its rest angle plus M / k. Two
 *    hinges at unequal positions (0.3 and 0.8 l; rest angles 40 and 0 deg), so the tangent angle
 *    is theta(s) = M s / EI + (phi + M/k) [s > 0.3 l] + (M/k) [s > 0.8 l] and the total end
 *    rotation is M l / EI + phi + 2 M / k. The rod's right clamp is placed at the end of that
 *    closed-form shape with that end rotation (the DER's clamps are prescribed displacements: a
 *    pure moment then needs no force there), Newton relaxes the free DOFs from the closed-form
 *    shape, and the test measures (a) each hinge's turn, phi + (psi - phi) k_eff / k in the model
 *    (psi the crease node's turning angle, rod_hinge.c: the share of psi - phi the hinge takes), against phi + M / k;
 *    (b) the strip's moment E I1 psi / dl_hat midway between the hinges against M; (c) the force
 *    the right clamp needs, against 0 (relative to M / l): a wrong strip stiffness or hinge
 *    turn would put the prescribed end elsewhere and show as a force. N = 21, 41, 81, 161: errors
 *    and observed orders printed; the order must be near 2 and the finest error small.
 *
 * 2. Buckling of a clamped-clamped column with two rotational springs. Hinges of stiffness k and
 *    zero rest angle at a and l - a; the critical load P = EI mu^2 from w'''' + mu^2 w'' = 0 on
 *    the three pieces (w = A + B x + C cos mu x + D sin mu x each) with w = w' = 0 at both ends
 *    and, at each hinge, w, w'' (moment) and the transverse force EI w''' + P w' continuous
 *    (w' jumps, so w''' jumps with it: taking w''' continuous instead, as for a beam without
 *    axial load, gives a load 6% low) and the slope jump w'(+) - w'(-) = EI w'' / k: twelve homogeneous equations whose determinant vanishes at the
 *    critical mu (derived here; the same formulation as the elastically restrained members of
 *    Wang, Wang & Reddy, "Exact Solutions for Buckling of Structural Members", CRC 2004, and of
 *    Timoshenko & Gere, "Theory of Elastic Stability", ch. 2). The determinant's first sign
 *    change is bracketed on a scan and bisected; k -> infinity must give 4 pi^2 EI / l^2 (checks
 *    the equations). The DER's critical load is where the straight state's free Hessian stops
 *    being positive definite (Sylvester inertia of its L D L^T factors, bisected in Delta L as in
 *    test_euler_buckling), with the axial force read from the edge strain. k = 5 EI / l at
 *    a = 0.15 l (at a = 0.25 l the first mode has no moment at the hinges), N = 21 .. 161.
 *
 * 3. Unequal creases in the prediction. A strip like the shipped rig's specimen (creases of 88
 *    and 91 deg at 0.12 and 0.85 of the free length, compliant hinges) is predicted end to end
 *    (the mock scene at N = 31, fast): nodes sit on both creases, the run snaps, Delta Z is read at
 *    arc length 1/2 between nodes. The analyses that need the C2-symmetric scene (continuation's
 *    classification, sweeps, the boundary) refuse it with a reason naming the key. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_permutation.h>

#include "rod.h"
#include "rod_bifurcation.h"
#include "rod_protocol.h"
#include "rod_solver.h"

#define MOMENT_FINE_TOL 1e-5   /* finest mesh (N = 161): hinge turn error over phi + M/k, moment
                                  error over M */
#define FORCE_FINE_TOL 3e-4    /* finest mesh: the clamp force over M / l */
#define BUCKLE_FINE_TOL 1e-3   /* finest mesh: |P_DER / P_exact - 1| */
#define ORDER_MIN 1.7          /* observed order between the two finest meshes */

static const int MESHES[] = {21, 41, 81, 161};
#define N_MESHES ((int)(sizeof MESHES / sizeof MESHES[0]))

/* ---- 1. end moment ----------------------------------------------------------------------- */

#define A_LEFT 0.3
#define A_RIGHT 0.8
#define PHI_LEFT_DEG 40.0

/* Position along the closed-form shape at arc length s (over l): the integral of
 * (cos theta, sin theta) with theta = kap s + jumps. */
static void shape_at(double s, double kap, double jl, double jr, double *x, double *z)
{
    double bounds[4] = {0.0, A_LEFT, A_RIGHT, 1.0}, c[3] = {0.0, jl, jl + jr};
    *x = *z = 0.0;
    for (int p = 0; p < 3; p++) {
        double s0 = bounds[p], s1 = fmin(bounds[p + 1], s);
        if (s1 <= s0) break;
        *x += (sin(kap * s1 + c[p]) - sin(kap * s0 + c[p])) / kap;
        *z += (cos(kap * s0 + c[p]) - cos(kap * s1 + c[p])) / kap;
    }
}

typedef struct moment_err {
    double turn_left, turn_right, moment, force;
} moment_err;

static moment_err end_moment(int nodes)
{
    rod_scene sc = rod_scene_default();
    sc.nodes = nodes;
    sc.fold_angle_deg = PHI_LEFT_DEG;
    sc.fold_angle_right_deg = 0.0;
    sc.fold_position_left = A_LEFT;
    sc.fold_position_right = A_RIGHT;
    sc.fold_angle_rel = 0.0;
    sc.tolerance = 1e-7;
    double l = sc.length, EI = sc.youngs_modulus * sc.width * pow(sc.thickness, 3) / 12.0;
    double k = 2.0 * EI / l, M = 0.5 * EI / l, phi = PHI_LEFT_DEG * M_PI / 180.0;
    sc.fold_hinge_stiffness = k;
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&sc, &r, err, sizeof err), ROD_OK);
    assert_true(r->terms.hinge && !r->terms.fold);
    int n = r->n, cl = r->fold_node[0], cr = r->fold_node[1];
    assert_true(fabs(r->s_node[cl] - A_LEFT) < 1e-15 && fabs(r->s_node[cr] - A_RIGHT) < 1e-15);

    /* The closed-form shape, in units of l (l = 1 here, kept for clarity). */
    double kap = M * l / EI, jl = phi + M / k, jr = M / k, theta_end = kap + jl + jr;
    for (int i = 1; i <= n - 2; i++) {
        double *x = rod_x(r, i), xx, zz;
        shape_at(r->s_node[i], kap, jl, jr, &xx, &zz);
        x[0] = l * xx;
        x[1] = 0.0;
        x[2] = l * zz;
    }
    double *x0 = rod_x(r, 0), *xe = rod_x(r, n - 1), *xb = rod_x(r, n - 2);
    x0[0] = -r->len0[0];
    x0[1] = x0[2] = 0.0;
    xe[0] = xb[0] + r->len0[n - 2] * cos(theta_end);
    xe[1] = 0.0;
    xe[2] = xb[2] + r->len0[n - 2] * sin(theta_end);
    for (int i = 0; i < n - 1; i++) r->q[4 * i + 3] = 0.0;
    rod_frames_update(r);

    rod_solver *s = rod_solver_alloc(r);
    assert_non_null(s);
    rod_newton_opts o = rod_newton_opts_static(&sc);
    o.positive_definite = 1;
    rod_newton_report nr;
    assert_int_equal(rod_newton_solve(r, s, &o, &nr), ROD_OK);

    double *k1 = malloc(sizeof(double) * (size_t)n);
    assert_non_null(k1);
    rod_kappa1(r, k1);
    double turn[2];
    for (int h = 0; h < 2; h++) {
        int i = r->fold_node[h];
        double psi = 2.0 * atan(0.5 * k1[i]);
        turn[h] = r->fold_phi[h] + (psi - r->fold_phi[h]) * rod_hinge_share(r, i);
    }
    int mid = (cl + cr) / 2;
    double m_strip = EI * 2.0 * atan(0.5 * k1[mid]) / r->vor0[mid];
    const double *g = rod_solver_gradient(s);
    double F[3];
    for (int c = 0; c < 3; c++) F[c] = g[4 * (n - 2) + c] + g[4 * (n - 1) + c];
    moment_err e = {fabs(turn[0] - jl) / jl, fabs(turn[1] - jr) / jr, fabs(m_strip - M) / M,
                    sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]) * l / M};
    print_message("N = %3d: hinge turns %.8f (phi + M/k = %.8f), %.8f (M/k = %.8f); strip moment "
                  "%.8e (M = %.8e); clamp force %.2e M/l; %d Newton iterations\n",
                  nodes, turn[0], jl, turn[1], jr, m_strip, M, e.force, nr.iterations);
    free(k1);
    rod_solver_free(s);
    rod_free(r);
    return e;
}

static double order(double e_coarse, double e_fine) { return log(e_coarse / e_fine) / log(2.0); }

static void test_end_moment(void **state)
{
    (void)state;
    moment_err e[N_MESHES];
    for (int m = 0; m < N_MESHES; m++) e[m] = end_moment(MESHES[m]);
    for (int m = 1; m < N_MESHES; m++)
        print_message("N %3d -> %3d: observed orders: left turn %.2f, right turn %.2f, moment %.2f, "
                      "force %.2f\n",
                      MESHES[m - 1], MESHES[m], order(e[m - 1].turn_left, e[m].turn_left),
                      order(e[m - 1].turn_right, e[m].turn_right), order(e[m - 1].moment, e[m].moment),
                      order(e[m - 1].force, e[m].force));
    const moment_err *f = &e[N_MESHES - 1], *c = &e[N_MESHES - 2];
    print_message("finest: turn errors %.2e %.2e, moment %.2e, force %.2e\n", f->turn_left, f->turn_right,
                  f->moment, f->force);
    assert_true(f->turn_left < MOMENT_FINE_TOL && f->turn_right < MOMENT_FINE_TOL);
    assert_true(f->moment < MOMENT_FINE_TOL && f->force < FORCE_FINE_TOL);
    assert_true(order(c->turn_left, f->turn_left) > ORDER_MIN);
    assert_true(order(c->turn_right, f->turn_right) > ORDER_MIN);
}

/* ---- 2. buckling with rotational springs -------------------------------------------------- */

/* The 12 x 12 matrix of the three-piece column (l = 1; xi = k l / EI, hinges at a and 1 - a) at
 * mu: rows are the conditions, columns (A, B, C, D) of each piece. */
static double column_det(double mu, double a, double xi, gsl_matrix *A, gsl_permutation *p)
{
    gsl_matrix_set_zero(A);
    /* w and its derivatives of piece j's basis (1, x, cos mu x, sin mu x) at x: d = 0..3. */
#define BASIS(d, x, out)                                                                           \
    do {                                                                                           \
        double cs = cos(mu * (x)), sn = sin(mu * (x));                                             \
        double vals[4][4] = {{1.0, (x), cs, sn},                                                   \
                             {0.0, 1.0, -mu * sn, mu * cs},                                        \
                             {0.0, 0.0, -mu * mu * cs, -mu * mu * sn},                             \
                             {0.0, 0.0, mu * mu * mu * sn, -mu * mu * mu * cs}};                   \
        memcpy((out), vals[(d)], sizeof(double) * 4);                                              \
    } while (0)
    double b[4];
    int row = 0;
    /* Clamped at x = 0 (piece 0) and x = 1 (piece 2): w = w' = 0. */
    for (int d = 0; d < 2; d++) {
        BASIS(d, 0.0, b);
        for (int c = 0; c < 4; c++) gsl_matrix_set(A, (size_t)row, (size_t)c, b[c]);
        row++;
        BASIS(d, 1.0, b);
        for (int c = 0; c < 4; c++) gsl_matrix_set(A, (size_t)row, (size_t)(8 + c), b[c]);
        row++;
    }
    double xs[2] = {a, 1.0 - a};
    for (int h = 0; h < 2; h++) {
        int left = 4 * h, right = 4 * (h + 1);
        double x = xs[h], b2[4];
        /* w, w'' and the transverse force EI w''' + P w' continuous: left - right = 0 (w' jumps,
         * so w''' jumps too: the force, not w''', is what carries across the hinge). */
        static const int conts[3] = {0, 2, 3};
        for (int q = 0; q < 3; q++) {
            BASIS(conts[q], x, b);
            if (conts[q] == 3) {
                BASIS(1, x, b2);
                for (int c = 0; c < 4; c++) b[c] += mu * mu * b2[c];
            }
            for (int c = 0; c < 4; c++) {
                gsl_matrix_set(A, (size_t)row, (size_t)(left + c), b[c]);
                gsl_matrix_set(A, (size_t)row, (size_t)(right + c), -b[c]);
            }
            row++;
        }
        /* Slope jump: w'(+) - w'(-) - w''/xi = 0 (w'' from either side; the left one). */
        BASIS(1, x, b);
        BASIS(2, x, b2);
        for (int c = 0; c < 4; c++) {
            gsl_matrix_set(A, (size_t)row, (size_t)(right + c), b[c]);
            gsl_matrix_set(A, (size_t)row, (size_t)(left + c), -b[c] - b2[c] / xi);
        }
        row++;
    }
#undef BASIS
    int sgn;
    gsl_linalg_LU_decomp(A, p, &sgn);
    return gsl_linalg_LU_det(A, sgn);
}

/* Smallest mu > 0 where the determinant changes sign, for l = 1: P_cr = EI mu^2. */
static double column_mu(double a, double xi)
{
    gsl_matrix *A = gsl_matrix_alloc(12, 12);
    gsl_permutation *p = gsl_permutation_alloc(12);
    assert_true(A && p);
    double lo = 1.0, dlo = column_det(lo, a, xi, A, p), hi = lo;
    int found = 0;
    for (int it = 0; it < 20000 && !found; it++) {
        hi = lo + 1e-3;
        double dhi = column_det(hi, a, xi, A, p);
        if ((dlo < 0) != (dhi < 0)) {
            found = 1;
            break;
        }
        lo = hi;
        dlo = dhi;
    }
    assert_true(found);
    for (int it = 0; it < 80; it++) {
        double mid = 0.5 * (lo + hi), dm = column_det(mid, a, xi, A, p);
        if ((dm < 0) == (dlo < 0)) {
            lo = mid;
            dlo = dm;
        } else {
            hi = mid;
        }
    }
    gsl_matrix_free(A);
    gsl_permutation_free(p);
    return 0.5 * (lo + hi);
}

/* Non-positive pivots of the L D L^T factorisation (no pivoting) of the symmetric band matrix B
 * (n rows, half-bandwidth p, row i holding A(i, i + k) at B[i (p + 1) + k]); overwritten. */
static int nonpositive_pivots(double *B, int n, int p)
{
    int w = p + 1, count = 0;
    for (int j = 0; j < n; j++) {
        double d = B[j * w];
        if (!(d > 0.0)) return count + (n - j);
        for (int k = 1; k < w && j + k < n; k++) {
            double l = B[j * w + k] / d;
            for (int m = k; m < w && j + m < n; m++) B[(j + k) * w + (m - k)] -= l * B[j * w + m];
            B[j * w + k] = l;
        }
    }
    (void)count;
    return 0;
}

static void place_straight(rod *r, double dl)
{
    rod_set_clamps(r, dl, 0.0);
    double span = r->length * (1.0 - dl);
    for (int i = 2; i < r->n - 2; i++) {
        double *x = rod_x(r, i);
        x[0] = span * r->s_node[i];
        x[1] = x[2] = 0.0;
    }
    for (int i = 1; i < r->n - 2; i++) r->q[4 * i + 3] = 0.0;
    rod_frames_update(r);
}

static int negative_at(rod *r, double dl, double *B)
{
    place_straight(r, dl);
    memset(B, 0, sizeof(double) * (size_t)rod_nfree(r) * (ROD_BAND + 1));
    rod_hessian_add(r, 1.0, B);
    return nonpositive_pivots(B, rod_nfree(r), ROD_BAND);
}

/* The DER's critical axial force, over EI / l^2, for hinges of stiffness xi EI / l at a. */
static double der_critical(int nodes, double a, double xi)
{
    rod_scene sc = rod_scene_default();
    sc.nodes = nodes;
    sc.fold_angle_deg = 1.0; /* creases present; their rest angles are set to 0 below */
    sc.fold_position = a;
    sc.fold_angle_rel = 0.0;
    double l = sc.length, EI = sc.youngs_modulus * sc.width * pow(sc.thickness, 3) / 12.0;
    sc.fold_hinge_stiffness = xi * EI / l;
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&sc, &r, err, sizeof err), ROD_OK);
    assert_true(r->terms.hinge);
    rod_set_crease_angles(r, 0.0, 0.0);
    double *B = malloc(sizeof(double) * (size_t)rod_nfree(r) * (ROD_BAND + 1));
    assert_non_null(B);
    double dl_euler = 4.0 * M_PI * M_PI * EI / (l * l) / r->EA;
    double lo = 0.0, hi = 1.5 * dl_euler;
    assert_int_equal(negative_at(r, lo, B), 0);
    assert_true(negative_at(r, hi, B) > 0);
    for (int it = 0; it < 60; it++) {
        double mid = 0.5 * (lo + hi);
        if (negative_at(r, mid, B) == 0) lo = mid;
        else hi = mid;
    }
    place_straight(r, 0.5 * (lo + hi));
    int j = r->n / 2;
    const double *xa = rod_x(r, j), *xb = rod_x(r, j + 1);
    double len = sqrt((xb[0] - xa[0]) * (xb[0] - xa[0]) + (xb[2] - xa[2]) * (xb[2] - xa[2]) +
                      (xb[1] - xa[1]) * (xb[1] - xa[1]));
    double P = -r->EA * (len / r->len0[j] - 1.0);
    free(B);
    rod_free(r);
    return P * l * l / EI;
}

static void test_column_with_springs(void **state)
{
    (void)state;
    /* The characteristic equation: rigid hinges give the clamped-clamped Euler load. */
    double mu_rigid = column_mu(0.25, 1e12);
    print_message("k -> infinity: mu^2 = %.10f (4 pi^2 = %.10f)\n", mu_rigid * mu_rigid, 4.0 * M_PI * M_PI);
    assert_true(fabs(mu_rigid * mu_rigid / (4.0 * M_PI * M_PI) - 1.0) < 1e-6);

    double a = 0.15, xi = 5.0, mu = column_mu(a, xi), exact = mu * mu;
    print_message("hinges k = %.1f EI/l at %.2f l and %.2f l: P_cr = %.8f EI/l^2 (%.4f of 4 pi^2)\n", xi, a,
                  1.0 - a, exact, exact / (4.0 * M_PI * M_PI));
    assert_true(exact < 4.0 * M_PI * M_PI);
    double err[N_MESHES];
    for (int m = 0; m < N_MESHES; m++) {
        double p = der_critical(MESHES[m], a, xi);
        err[m] = fabs(p / exact - 1.0);
        print_message("N = %3d: DER P_cr = %.8f EI/l^2, relative error %.3e%s\n", MESHES[m], p, err[m],
                      m ? "" : "");
        if (m) print_message("          observed order %.2f\n", order(err[m - 1], err[m]));
    }
    assert_true(err[N_MESHES - 1] < BUCKLE_FINE_TOL);
    assert_true(order(err[N_MESHES - 2], err[N_MESHES - 1]) > ORDER_MIN);
}

/* ---- 3. unequal creases ------------------------------------------------------------------- */

static void test_unequal_creases_predicted(void **state)
{
    (void)state;
    rod_scene sc = rod_scene_default();
    /* The mock rig's PET strip (config/scenes/mock-gamma013.ini), coarse. */
    sc.length = 0.2;
    sc.width = 5e-3;
    sc.thickness = 0.25e-3;
    sc.youngs_modulus = 4e9;
    sc.shear_modulus = 4e9 / 2.76;
    sc.density = 1380.0;
    sc.nodes = 31;
    sc.dt = 2e-3;
    sc.shear_rate = 0.01;
    sc.shear_max = 0.6;
    sc.fold_angle_deg = -90.0;
    sc.fold_angle_left_deg = -88.0;
    sc.fold_angle_right_deg = -91.0;
    sc.fold_position_left = 0.12;
    sc.fold_position_right = 0.85;
    sc.fold_hinge_stiffness = 2.5e-3;
    rod *r = NULL;
    char why[512];
    assert_int_equal(rod_alloc(&sc, &r, why, sizeof why), ROD_OK);
    assert_true(r->s_node[r->fold_node[0]] == 0.12 && r->s_node[r->fold_node[1]] == 0.85);
    assert_true(r->mid_node < 0 && r->mid_w > 0.0 && r->mid_w < 1.0);
    assert_true(r->s_node[r->mid_edge] < 0.5 && r->s_node[r->mid_edge + 1] > 0.5);
    print_message("mesh: creases at nodes %d and %d, %d and %d outer edges; Delta Z between nodes %d and %d "
                  "(weight %.3f)\n",
                  r->fold_node[0], r->fold_node[1], r->fold_outer_edges, r->fold_outer_right, r->mid_edge,
                  r->mid_edge + 1, r->mid_w);
    rod_free(r);
    rod_predict_opts o = rod_predict_opts_fast(&sc);
    rod_prediction p;
    assert_int_equal(rod_predict(&sc, &o, &p, why, sizeof why), ROD_OK);
    print_message("88 / 91 deg at 0.12 / 0.85, k = 2.5e-3 N m/rad: snap Delta W %.4f, %s, peak |A| %.3f, "
                  "upper Delta Z %.4f, %llu hinge evaluations\n",
                  p.snap_dw, p.asymmetric ? "asymmetric" : "symmetric", p.peak_abs_a, p.dz_upper,
                  (unsigned long long)p.count.hinge_evals);
    assert_true(p.snapped && isfinite(p.snap_dw) && p.snap_dw > 0.0);
    assert_true(p.count.hinge_evals > 0 && p.count.fold_evals == 0);

    /* The symmetric analyses refuse it, naming the key. */
    rod_analysis_opts ao = rod_analysis_opts_classify();
    rod_analysis a;
    assert_int_equal(rod_bifurcation_analyse(&sc, &ao, &a, why, sizeof why), ROD_ERR_SCENE);
    print_message("continue: %s\n", why);
    assert_non_null(strstr(why, "folds.angle_right_deg"));
    sc.fold_angle_left_deg = sc.fold_angle_right_deg = NAN;
    assert_int_equal(rod_bifurcation_analyse(&sc, &ao, &a, why, sizeof why), ROD_ERR_SCENE);
    print_message("continue: %s\n", why);
    assert_non_null(strstr(why, "folds.position_right"));
}

/* A mirrored pair given by its own positions is the symmetric pair's mesh, to the last bit (the
 * C2-symmetric analyses depend on it), and the Delta Z midpoint stays the mesh's own. */
static void test_mirrored_pair_same_mesh(void **state)
{
    (void)state;
    const double gammas[] = {0.13, 0.21, 0.125, 0.3};
    for (int g = 0; g < 4; g++) {
        rod_scene a = rod_scene_default(), b;
        a.nodes = 60 + g; /* odd and even N */
        a.fold_position = gammas[g];
        b = a;
        b.fold_position_left = gammas[g];
        b.fold_position_right = 1.0 - gammas[g];
        rod *ra = NULL, *rb = NULL;
        char why[256];
        assert_int_equal(rod_alloc(&a, &ra, why, sizeof why), ROD_OK);
        assert_int_equal(rod_alloc(&b, &rb, why, sizeof why), ROD_OK);
        assert_memory_equal(ra->s_node, rb->s_node, sizeof(double) * (size_t)ra->n);
        assert_memory_equal(ra->vor0, rb->vor0, sizeof(double) * (size_t)ra->n);
        assert_int_equal(ra->fold_node[1], rb->fold_node[1]);
        assert_int_equal(ra->mid_node, rb->mid_node);
        assert_int_equal(ra->mid_edge, rb->mid_edge);
        for (int k = 1; k < ra->n - 1; k++) assert_true(ra->s_node[k] + ra->s_node[ra->n - 1 - k] == 1.0);
        rod_free(ra);
        rod_free(rb);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mirrored_pair_same_mesh),
        cmocka_unit_test(test_unequal_creases_predicted),
        cmocka_unit_test(test_end_moment),
        cmocka_unit_test(test_column_with_springs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
