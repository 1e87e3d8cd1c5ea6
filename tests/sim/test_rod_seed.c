/* test_rod_seed: continuation of the upper state in the crease position and angle (sim/rod_seed.c)
 * against independent computations: the remap onto the same mesh is the identity; the state
 * continued from Gamma 0.13 to 0.19 (across changes of the segments' node counts) and from
 * phi 90 to 100 deg is the equilibrium the route reaches from the flat ribbon, to the solver's
 * tolerance; and where the route loses the upper state (phi 95 deg, Gamma 0.05, the README's
 * former crosses) continuation stops before it with the evidence of a vanishing state: its lowest
 * Hessian eigenvalue falls by more than a factor of 100 towards zero. N = 61, seconds. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdlib.h>

#include "cfg_error.h"
#include "rod_route.h"
#include "rod_seed.h"
#include "rod_solver.h"
#include "scene_file.h"

#include "seed_scene_kit.h"

static double max_diff(const rod *a, const rod *b)
{
    double d = 0.0;
    for (int k = 0; k < a->ndof; k++) d = fmax(d, fabs(a->q[k] - b->q[k]));
    return d / a->length;
}

static void test_remap_onto_the_same_mesh_is_the_identity(void **state)
{
    (void)state;
    rod_scene sc = scene(90.0, 0.13);
    rod_solver *s = NULL;
    rod *a = routed(&sc, &s), *b = NULL;
    assert_int_equal(rod_alloc(&sc, &b, NULL, 0), ROD_OK);
    assert_int_equal(rod_seed_remap(a, b, sc.compression), ROD_OK);
    assert_true(max_diff(a, b) < 1e-14);
    rod_scene other = sc;
    other.nodes = 41;
    rod *c = NULL;
    assert_int_equal(rod_alloc(&other, &c, NULL, 0), ROD_OK);
    assert_int_equal(rod_seed_remap(a, c, sc.compression), ROD_ERR_SCENE);
    rod_free(a);
    rod_free(b);
    rod_free(c);
    rod_solver_free(s);
}

static void continued_equals_route(double phi0, double g0, double phi1, double g1)
{
    rod_scene from = scene(phi0, g0), to = scene(phi1, g1);
    rod_solver *s = NULL;
    rod *a = routed(&from, &s), *want = routed(&to, &s), *got = NULL;
    rod_seed_report rep;
    assert_int_equal(rod_seed_continue(a, &from, &to, s, &got, &rep), ROD_OK);
    assert_non_null(got);
    assert_true(rep.reached == 1.0);
    assert_int_equal(rod_seed_is_stable(got), 1);
    double d = max_diff(got, want);
    print_message("(%g, %g) -> (%g, %g): %d solves, max |q - q_route| = %.2e l\n", phi0, g0, phi1, g1, rep.solves,
                  d);
    assert_true(d < 1e-9);
    rod_free(a);
    rod_free(want);
    rod_free(got);
    rod_solver_free(s);
}

static void test_continued_states_are_the_route_states(void **state)
{
    (void)state;
    continued_equals_route(90.0, 0.13, 90.0, 0.19); /* n_out 7 -> 11 over the path */
    continued_equals_route(90.0, 0.19, 90.0, 0.13);
    continued_equals_route(90.0, 0.16, 100.0, 0.16);
}

static void test_losing_the_state_is_located_with_its_evidence(void **state)
{
    (void)state;
    rod_scene from = scene(95.0, 0.0778), to = scene(95.0, 0.05);
    rod_solver *s = NULL;
    rod *a = routed(&from, &s), *got = NULL;
    /* The route itself loses it there. */
    rod *r = NULL;
    assert_int_equal(rod_alloc(&to, &r, NULL, 0), ROD_OK);
    rod_route_report rr = {0};
    assert_int_equal(rod_route_to_state(r, s, &to, +1, &rr), ROD_ERR_BRANCH_LOST);
    rod_seed_report rep;
    assert_int_equal(rod_seed_continue(a, &from, &to, s, &got, &rep), ROD_ERR_BRANCH_LOST);
    assert_null(got);
    print_message("lost at Gamma %.4f: lowest eigenvalue %.3g -> %.3g\n", rep.gamma_reached, rep.eig_start,
                  rep.eig_last);
    assert_true(rep.reached > 0.0 && rep.reached < 1.0);
    assert_true(rep.gamma_reached < 0.0778 && rep.gamma_reached > 0.05);
    assert_true(rep.eig_start > 0.0 && rep.eig_last > 0.0 && rep.eig_last < 0.01 * rep.eig_start);
    rod_free(a);
    rod_free(r);
    rod_solver_free(s);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_remap_onto_the_same_mesh_is_the_identity),
        cmocka_unit_test(test_continued_states_are_the_route_states),
        cmocka_unit_test(test_losing_the_state_is_located_with_its_evidence),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
