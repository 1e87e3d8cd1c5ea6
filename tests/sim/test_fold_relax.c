/* test_fold_relax: a crease of angle phi is a turn of the centreline by phi toward the surface
 * normal, in the plane of tangent and normal (DESIGN.md section 3, "Folds are out-of-plane
 * creases"), for phi = 30, 90 and -90 deg.
 *
 * Why: the paper mixes two director conventions; putting the natural curvature on the wrong
 * component (in-plane, kappa2), with the wrong sign, or with the wrong angle-curvature relation
 * (kappa1_hat = 2 tan(phi / 2) for the discrete rod) would bend the ribbon in its own plane, the
 * other way, or by the wrong angle, and every creased prediction would be wrong with it.
 *
 * How: the rod is always clamped at both ends, so the test builds the exact creased geometry
 * itself. One crease only (the scene's crease at Gamma keeps its natural curvature and raised
 * stiffness, the one at 1 - Gamma is removed by hand), nodes at their rest arc lengths on the
 * ideal broken line: along +x up to the crease node, then along d = (cos phi, 0, sin phi), which
 * is the tangent turned by phi toward the normal m1 = +z (kappa1 > 0 turns the tangent toward m1).
 * The far clamped nodes are written into q on that turned line (rod_set_clamps would put them on
 * the x axis), all twist angles 0; rod_frames_update transports the frames onto the new edges.
 * Checks: (a) this is an equilibrium: the free-DOF gradient is round-off relative to EI1 / l^2
 * (all strains and curvatures equal their rest values, so the energy is its global minimum 0);
 * (b) after a random perturbation of every free DOF, a static Newton solve (minimising, positive
 * definite) returns to the same broken line: the tangents on both sides of the crease lie in the
 * x-z plane (no y component), turn by phi within 1e-6 rad, and the surface normal after the crease
 * is the transported +z, (-sin phi, 0, cos phi), untwisted.
 * The perturbation is small (1e-4 of an edge in position, 1e-2 rad in twist) because this ribbon
 * is extremely slender (EA l^2 / EI1 ~ 1e7): random strains above ~3e-6 already load parts of it
 * beyond the Euler load, the Hessian there is indefinite, and the minimising Newton, whose shift
 * sigma diag|J| stops at sigma = 10, reports a singular system from about 2e-4 of an edge on. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "rod.h"
#include "rod_solver.h"

#define GRAD_ROUNDOFF 100.0  /* max free |grad| at the exact crease, in units of the stretching
                                term's round-off EA eps l / h (positions of size l, edges h); that
                                is about 1e-5 EI1 / l^2 here, a wrong crease gives ~1e7 EI1 / l^2 */
#define TURN_TOL 1e-6        /* rad, |turn - phi| and the out-of-plane (y) tangent components */
#define POS_TOL 1e-9         /* max node distance from the broken line, over l */
#define PERTURB_X 1e-4       /* random perturbation of positions, as a fraction of an edge */
#define PERTURB_TH 1e-2      /* random perturbation of the twist angles, rad */

static double urand(unsigned long long *st)
{
    *st ^= *st << 13; *st ^= *st >> 7; *st ^= *st << 17;
    return (double)(*st >> 11) / 9007199254740992.0;
}

static void unit_edge(const rod *r, int j, double t[3])
{
    const double *a = rod_x(r, j), *b = rod_x(r, j + 1);
    double e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double n = sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    for (int k = 0; k < 3; k++) t[k] = e[k] / n;
}

static void check_fold(double phi_deg, unsigned long long seed)
{
    rod_scene sc = rod_scene_default();
    sc.fold_angle_deg = phi_deg;
    sc.fold_angle_rel = 0.0;
    sc.fold_position = 0.3;
    sc.nodes = 51;
    sc.gravity[0] = sc.gravity[1] = sc.gravity[2] = 0.0;
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&sc, &r, err, sizeof err), ROD_OK);
    assert_true(r->terms.fold);
    int n = r->n, c = r->fold_node[0], c2 = r->fold_node[1];
    assert_true(c > 1 && c < n - 2);
    double phi = phi_deg * M_PI / 180.0, l = r->length;
    assert_true(fabs(r->kap1_hat[c] - 2.0 * tan(0.5 * phi)) < 1e-14);
    /* Keep the crease at Gamma only. */
    r->kap1_hat[c2] = 0.0;
    r->EI1[c2] = r->EI1[0];

    /* The ideal broken line, clamps included. */
    double d[3] = {cos(phi), 0.0, sin(phi)};
    double *line = malloc(sizeof(double) * (size_t)r->ndof);
    double *g = malloc(sizeof(double) * (size_t)r->ndof);
    double *k1 = malloc(sizeof(double) * (size_t)n);
    assert_true(line && g && k1);
    double xc = l * r->s_node[c];
    for (int i = 0; i < n; i++) {
        double *x = rod_x(r, i);
        if (i <= c) {
            x[0] = l * r->s_node[i]; x[1] = 0.0; x[2] = 0.0;
        } else {
            double a = l * (r->s_node[i] - r->s_node[c]);
            x[0] = xc + a * d[0]; x[1] = 0.0; x[2] = a * d[2];
        }
        if (i < n - 1) r->q[4 * i + 3] = 0.0;
    }
    rod_frames_update(r);
    memcpy(line, r->q, sizeof(double) * (size_t)r->ndof);

    /* (a) equilibrium at the exact crease. */
    rod_gradient(r, g);
    double gmax = 0.0;
    for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) gmax = fmax(gmax, fabs(g[k]));
    rod_kappa1(r, k1);
    double h = l * (r->s_node[2] - r->s_node[1]);
    double roundoff = DBL_EPSILON * r->EA * l / h;
    print_message("phi = %+.0f deg: crease node %d, kappa1 %.15f (2 tan(phi/2) %.15f), "
                  "max free |grad| = %.2e EI1/l^2 = %.2f x round-off, energy %.2e J\n",
                  phi_deg, c, k1[c], 2.0 * tan(0.5 * phi), gmax / r->force_scale,
                  gmax / roundoff, rod_energy(r));
    assert_true(gmax < GRAD_ROUNDOFF * roundoff);

    /* (b) perturb every free DOF, relax by static Newton. */
    unsigned long long st = seed;
    for (int k = ROD_FREE_BEGIN; k < r->free_end; k++)
        r->q[k] += (k % 4 == 3 ? PERTURB_TH : PERTURB_X * h) * (2.0 * urand(&st) - 1.0);
    rod_frames_update(r);
    rod_solver *s = rod_solver_alloc(r);
    assert_non_null(s);
    rod_newton_opts o = rod_newton_opts_static(&sc);
    o.positive_definite = 1;
    /* The minimising Newton takes 20 to 40 shifted steps from here (see above); the cap is
     * raised so this test checks where it converges, not how fast. */
    o.max_iterations = 200;
    rod_newton_report rep;
    rod_status stt = rod_newton_solve(r, s, &o, &rep);
    print_message("  Newton from the perturbed state: %s, %d iterations, residual %.2e\n",
                  rod_status_message(stt), rep.iterations, rep.residual_rel);
    assert_int_equal(stt, ROD_OK);

    double dpos = 0.0;
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) dpos = fmax(dpos, fabs(rod_x(r, i)[k] - line[4 * i + k]));
    double tb[3], ta[3], ymax = 0.0;
    for (int j = 0; j < n - 1; j++) {
        double t[3];
        unit_edge(r, j, t);
        ymax = fmax(ymax, fabs(t[1]));
    }
    unit_edge(r, c - 1, tb);
    unit_edge(r, c, ta);
    double turn = atan2(ta[2], ta[0]) - atan2(tb[2], tb[0]);
    double m1[3], m2[3];
    rod_material_frame(r, c, m1, m2);
    double nerr = fmax(fabs(m1[0] + sin(phi)), fmax(fabs(m1[1]), fabs(m1[2] - cos(phi))));
    print_message("  relaxed: turn %+.12f deg, error %.2e rad, max |t_y| %.2e, "
                  "max |x - line| / l %.2e, normal error %.2e\n",
                  turn * 180.0 / M_PI, fabs(turn - phi), ymax, dpos / l, nerr);
    assert_true(fabs(turn - phi) < TURN_TOL);
    assert_true(ymax < TURN_TOL);
    assert_true(dpos / l < POS_TOL);
    assert_true(nerr < TURN_TOL);

    rod_solver_free(s);
    free(k1);
    free(g);
    free(line);
    rod_free(r);
}

static void test_fold_30(void **state)
{
    (void)state;
    check_fold(30.0, 88172645463325252ULL);
}

static void test_fold_90(void **state)
{
    (void)state;
    check_fold(90.0, 1234567ULL);
}

static void test_fold_minus_90(void **state)
{
    (void)state;
    check_fold(-90.0, 987654321ULL);
}

int main(void)
{
    gsl_set_error_handler_off(); /* the solver handles GSL's failures by return codes */
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fold_30),
        cmocka_unit_test(test_fold_90),
        cmocka_unit_test(test_fold_minus_90),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
