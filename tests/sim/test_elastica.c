/* test_elastica: the post-buckled clamped-clamped ribbon (no folds, no shear, no gravity,
 * N = 101) against the closed-form inextensible elastica, at Delta L = 0.1 and 0.3.
 *
 * Why: the arch is the state every creased scene starts from and Delta Z is what the paper and
 * the rig measure. This checks the large-rotation bending of the discrete rod (not just its
 * linearisation, which test_euler_buckling covers), the route to the upper state, the
 * normalisation of Delta L and Delta Z by the free length l, and rod_observe's midpoint.
 *
 * Closed form (first clamped-clamped mode). With the tangent angle theta(s), the elastica
 * theta'' + lambda^2 sin theta = 0 (lambda^2 = P / EI) has the solution
 * sin(theta / 2) = k sn(lambda s, k), k = sin(alpha / 2), alpha the largest tangent angle. The
 * clamped ends and the midpoint (theta = 0 there) with inflections at l/4 and 3l/4 make the
 * free length one full period: lambda l = 4 K(k). Then with cos theta = 1 - 2 k^2 sn^2 and
 * sin theta = 2 k sn dn, and int_0^K sn^2 = (K - E) / k^2:
 *     Delta L = 1 - x(l) / l = 2 (1 - E(k) / K(k)),
 *     Delta Z = z(l/2) / l = (2 k / lambda) (cn(0) - cn(2K)) / l = k / K(k).
 * (Not 2 k / K: small k gives Delta Z = 2 k / pi and Delta L = k^2, which matches the linear
 * mode z = H (1 - cos 2 pi s) / 2 with Delta L = pi^2 H^2 / 4 at H = 2 k / pi.) The test also
 * integrates the elastica ODE from the clamp with that k and checks the closed form against it,
 * so a wrong formula cannot pass silently. GSL's complete elliptic integrals take the modulus k.
 * Delta L is solved for k by bisection. The discrete model is slightly extensible (strain
 * ~ P / EA ~ 1e-5) and its discretisation error at N = 101 is ~1e-4 when the clamp sits at the
 * clamp point; the tolerance on Delta Z is 0.5%, which a clamp acting half an edge outside the
 * clamp points (an elastica of length l + h: +0.5% to +0.6% here) fails. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>

#include <gsl/gsl_mode.h>
#include <gsl/gsl_sf_ellint.h>

#include <gsl/gsl_errno.h>

#include "rod.h"
#include "rod_observe.h"
#include "rod_route.h"
#include "rod_solver.h"

#define DZ_REL_TOL 0.005     /* |Delta Z / closed form - 1| */
#define ODE_REL_TOL 1e-8     /* closed form against its own ODE integration */
#define PLANAR_TOL 1e-9      /* max |y| / l of the equilibrium (no shear: it must stay planar) */

static double ratio_EK(double k)
{
    return gsl_sf_ellint_Ecomp(k, GSL_PREC_DOUBLE) / gsl_sf_ellint_Kcomp(k, GSL_PREC_DOUBLE);
}

/* Modulus k of the first clamped-clamped mode at end-shortening dl: 2 (1 - E/K) = dl,
 * increasing in k on (0, 1). */
static double modulus_for(double dl)
{
    double lo = 0.0, hi = 1.0 - 1e-12;
    for (int it = 0; it < 200; it++) {
        double mid = 0.5 * (lo + hi);
        if (2.0 * (1.0 - ratio_EK(mid)) < dl) lo = mid; else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* Integrates theta'' = -lambda^2 sin theta, x' = cos theta, z' = sin theta over s in [0, 1]
 * (l = 1) from the clamp with theta'(0) = 2 k lambda, lambda = 4 K(k) (RK4), and returns
 * Delta L, the midpoint height and theta(1). */
static void elastica_ode(double k, double *dl, double *dz, double *theta_end)
{
    double lam = 4.0 * gsl_sf_ellint_Kcomp(k, GSL_PREC_DOUBLE), l2 = lam * lam;
    int n = 20000;
    double h = 1.0 / n, y[4] = {0.0, 2.0 * k * lam, 0.0, 0.0}, zm = 0.0;
    for (int i = 0; i < n; i++) {
        double kk[4][4], t[4];
        for (int st = 0; st < 4; st++) {
            const double c = st == 0 ? 0.0 : (st == 3 ? 1.0 : 0.5);
            for (int j = 0; j < 4; j++) t[j] = y[j] + (st == 0 ? 0.0 : c * h * kk[st - 1][j]);
            kk[st][0] = t[1];
            kk[st][1] = -l2 * sin(t[0]);
            kk[st][2] = cos(t[0]);
            kk[st][3] = sin(t[0]);
        }
        for (int j = 0; j < 4; j++)
            y[j] += h / 6.0 * (kk[0][j] + 2.0 * kk[1][j] + 2.0 * kk[2][j] + kk[3][j]);
        if (i + 1 == n / 2) zm = y[3];
    }
    *dl = 1.0 - y[2];
    *dz = zm;
    *theta_end = y[0];
}

static void check_at(double dl)
{
    double k = modulus_for(dl);
    double K = gsl_sf_ellint_Kcomp(k, GSL_PREC_DOUBLE);
    double dz_cf = k / K;
    double dl_ode, dz_ode, th_end;
    elastica_ode(k, &dl_ode, &dz_ode, &th_end);
    print_message("Delta L = %.2f: k = %.9f (alpha = %.4f deg); ODE check: Delta L %.9f, "
                  "Delta Z %.9f vs k/K %.9f, theta(l) %.1e\n",
                  dl, k, 2.0 * asin(k) * 180.0 / M_PI, dl_ode, dz_ode, dz_cf, th_end);
    assert_true(fabs(dl_ode - dl) < ODE_REL_TOL);
    assert_true(fabs(dz_ode - dz_cf) < ODE_REL_TOL);
    assert_true(fabs(th_end) < 1e-6);

    rod_scene sc = rod_scene_default();
    sc.fold_angle_deg = 0.0;
    sc.nodes = 101;
    sc.gravity[0] = sc.gravity[1] = sc.gravity[2] = 0.0;
    sc.compression = dl;
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&sc, &r, err, sizeof err), ROD_OK);
    assert_false(r->terms.fold);
    rod_solver *s = rod_solver_alloc(r);
    assert_non_null(s);
    rod_route_report rep = {0};
    rod_status st = rod_route_to_state(r, s, &sc, +1, &rep);
    print_message("route: %s, %d solves, %d Newton iterations, residual %.2e\n",
                  rod_status_message(st), rep.solves, rep.newton_iterations, rep.residual_rel);
    assert_int_equal(st, ROD_OK);

    double *k1 = malloc(sizeof(double) * (size_t)r->n);
    assert_non_null(k1);
    rod_obs ob;
    rod_observe(r, k1, &ob);
    double ymax = 0.0;
    for (int i = 0; i < r->n; i++) ymax = fmax(ymax, fabs(rod_x(r, i)[1]));
    double gap = rod_x(r, r->n - 2)[0] - rod_x(r, 1)[0];
    double rel = ob.dz / dz_cf - 1.0;
    /* Diagnostic: the closed form if the clamps acted at the middles of the clamped edges (an
     * elastica of length l + h over the gap l (1 - Delta L) + h), an O(h) misplacement. */
    double he = r->h_clamp / r->length, ke = modulus_for(dl / (1.0 + he));
    print_message("(closed form with the clamps at the clamped edges' middles: %.6f)\n",
                  (1.0 + he) * ke / gsl_sf_ellint_Kcomp(ke, GSL_PREC_DOUBLE));
    print_message("Delta L = %.2f (gap %.6f l): Delta Z measured %.6f, closed form %.6f, "
                  "relative error %+.3e (max |y| %.1e)\n",
                  dl, gap / r->length, ob.dz, dz_cf, rel, ymax / r->length);
    assert_true(fabs(gap / r->length - (1.0 - dl)) < 1e-12);
    assert_true(ymax / r->length < PLANAR_TOL);
    assert_true(fabs(rel) < DZ_REL_TOL);

    free(k1);
    rod_solver_free(s);
    rod_free(r);
}

static void test_dl_01(void **state)
{
    (void)state;
    check_at(0.1);
}

static void test_dl_03(void **state)
{
    (void)state;
    check_at(0.3);
}

int main(void)
{
    gsl_set_error_handler_off(); /* the solver handles GSL's failures by return codes */
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dl_01),
        cmocka_unit_test(test_dl_03),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
