/* test_newton_shifted_start: Newton from a start where the Jacobian is indefinite although the
 * solution is a stable minimum. On the paper's compressed arch the softest stiffness is about
 * 0.1 N/m, below the geometric stiffness that small stretch errors of an extrapolated start put
 * in the Jacobian, so the first factorisation needs the diagonal shift. The chord steps that
 * follow a short step must not reuse those shifted factors: with them Newton converged at a
 * rate of 0.97 per iteration and hit its cap (rod_solver.c). The start here is the parabola
 * through three static states of the paper scene's shear, extrapolated one step on, exactly
 * as the fast prediction's quasi-static start makes it (rod_quasi.c). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rod_dynamics.h"
#include "rod_route.h"

static void test_extrapolated_start(void **state)
{
    (void)state;
    rod_scene sc = rod_scene_default();
    rod_dyn d;
    char err[256] = "";
    assert_int_equal(rod_dyn_open(&d, &sc, err, sizeof err), ROD_OK);
    rod *r = d.r;
    rod_route_report rr;
    assert_int_equal(rod_route_to_state(r, d.s, &sc, +1, &rr), ROD_OK);
    rod_newton_opts o = rod_newton_opts_static(&sc);
    o.positive_definite = 1;
    size_t bytes = sizeof(double) * (size_t)r->ndof;
    double *q[3];
    for (int k = 0; k < 3; k++) q[k] = malloc(bytes);
    memcpy(q[0], r->q, bytes);
    const double step = 0.005, dl = sc.compression;
    rod_newton_report nr;
    /* Delta W = step from the affine shear of the nodes, 2 step from the secant. */
    for (int i = 2; i < r->n - 2; i++) rod_x(r, i)[1] += step * r->length * (r->s_node[i] - 0.5);
    rod_set_clamps(r, dl, step);
    assert_int_equal(rod_newton_solve(r, d.s, &o, &nr), ROD_OK);
    memcpy(q[1], r->q, bytes);
    for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) r->q[k] = 2.0 * q[1][k] - q[0][k];
    rod_set_clamps(r, dl, 2.0 * step);
    assert_int_equal(rod_newton_solve(r, d.s, &o, &nr), ROD_OK);
    memcpy(q[2], r->q, bytes);
    /* The parabola to 3 step. */
    for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) r->q[k] = 3.0 * q[2][k] - 3.0 * q[1][k] + q[0][k];
    rod_set_clamps(r, dl, 3.0 * step);
    rod_status st = rod_newton_solve(r, d.s, &o, &nr);
    printf("from the parabola: %s after %d iterations, residual %.3g of the force scale\n",
           rod_status_message(st), nr.iterations, nr.residual_rel);
    assert_int_equal(st, ROD_OK);
    assert_true(nr.iterations <= 12);
    for (int k = 0; k < 3; k++) free(q[k]);
    rod_dyn_close(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_extrapolated_start),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
