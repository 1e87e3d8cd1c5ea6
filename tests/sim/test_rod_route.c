/* test_rod_route: the route's step control (rod_route.c) when a trial goes wrong.
 *
 *   injected NaN   a NaN written into the trial state of one solve (the report's fault-injection
 *                  input) is a failed step: the route retries it and reaches the same upper state
 *                  as without the fault, with ROD_ERR_NAN recorded as the last failed solve. Both
 *                  a secant-predicted solve and the plain-predicted first solve of a stage.
 *   lost branch    phi 175 at Delta L 0.5 (the stable upper state loses its stability at about 80%
 *                  of the crease ramp): the route stops with ROD_ERR_BRANCH_LOST, a finite
 *                  residual, a finite state and a bounded number of solves. Before the minimum
 *                  step, the step shrank below one ulp of p and the secant's 0 / 0 wrote NaN into
 *                  every DOF (the route ended with ROD_ERR_NAN and no residual).
 * Scenes from config/scenes/paper-gamma013.ini through the real loader at N 61 (the base of
 * test_stiff_matrix; at the file's N 201 phi 175 stops at 88% of the ramp with Newton's iteration
 * cap instead, its last state not verified unstable). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdlib.h>

#include "cfg_error.h"
#include "rod_observe.h"
#include "rod_route.h"
#include "rod_solver.h"
#include "scene_file.h"

#define BASE_SCENE RIBBON_SOURCE_DIR "/config/scenes/paper-gamma013.ini"

typedef struct routed {
    rod_status st;
    rod_route_report rep;
    double dz;   /* Delta Z of the state left in the rod (l) */
    int finite;  /* every DOF of that state is finite */
} routed;

/* Loads the base scene at N 61 with at most one more override, runs the route to the upper state
 * with a NaN injected into solve `inject` (0: none). */
static routed run_route(const char *ovr1, int inject)
{
    const char *ovr[] = {"mesh.nodes=61", ovr1};
    rod_scene sc;
    cfg_error err;
    assert_int_equal(cfg_scene_load(BASE_SCENE, ovr, ovr1 ? 2 : 1, &sc, &err), CFG_OK);
    rod *r = NULL;
    char why[200];
    assert_int_equal(rod_alloc(&sc, &r, why, sizeof why), ROD_OK);
    rod_solver *s = rod_solver_alloc(r);
    assert_non_null(s);
    routed out = {0};
    out.rep.inject_nan_solve = inject;
    out.st = rod_route_to_state(r, s, &sc, +1, &out.rep);
    out.finite = 1;
    for (int k = 0; k < r->ndof; k++) out.finite = out.finite && isfinite(r->q[k]);
    double *k1 = malloc(sizeof(double) * (size_t)r->n);
    assert_non_null(k1);
    rod_obs ob;
    rod_observe(r, k1, &ob);
    out.dz = ob.dz;
    free(k1);
    rod_solver_free(s);
    rod_free(r);
    return out;
}

static void test_injected_nan(void **state)
{
    (void)state;
    routed ref = run_route(NULL, 0);
    assert_int_equal(ref.st, ROD_OK);
    /* Solve 1 is the arch (plain predictor), 2 the first compression step (plain), 3 the second
     * (secant), later ones secant-predicted in the compression or the crease ramp. */
    const int at[] = {2, 3, 6, ref.rep.solves - 2};
    for (size_t k = 0; k < sizeof at / sizeof at[0]; k++) {
        routed f = run_route(NULL, at[k]);
        print_message("NaN injected at solve %d of %d: status %d, %d solves, residual %.3g, dz %.9f (reference %.9f)\n",
                      at[k], ref.rep.solves, (int)f.st, f.rep.solves, f.rep.residual_rel, f.dz, ref.dz);
        assert_int_equal(f.st, ROD_OK);
        assert_true(f.finite);
        assert_true(isfinite(f.rep.residual_rel) && f.rep.residual_rel <= 1e-6);
        assert_true(fabs(f.dz - ref.dz) < 1e-6);
        assert_true(f.rep.solves <= ref.rep.solves + 4);
    }
}

static void test_lost_branch(void **state)
{
    (void)state;
    routed f = run_route("folds.angle_deg=-175", 0);
    print_message("phi 175: status %d (%s), last solve %d, %.1f%% of the stage, residual %.3g, %d solves\n", (int)f.st,
                  rod_status_message(f.st), (int)f.rep.last_failure, 100.0 * f.rep.reached, f.rep.residual_rel,
                  f.rep.solves);
    assert_int_equal(f.st, ROD_ERR_BRANCH_LOST);
    assert_true(f.finite);
    assert_true(isfinite(f.rep.residual_rel) && f.rep.residual_rel > 0.0);
    assert_true(f.rep.reached > 0.5 && f.rep.reached < 1.0);
    assert_true(f.rep.solves <= 40 * (1 + 20 + 20)); /* the cap per stage (rod_route.c) */
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_injected_nan),
        cmocka_unit_test(test_lost_branch),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
