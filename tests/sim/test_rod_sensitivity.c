/* test_rod_sensitivity.c: the equilibrium's sensitivities to the strip parameters
 * (sim/rod_sensitivity.h, issue 32 A) against finite differences of re-solved equilibria: for
 * each parameter, dq/du from one banded solve on the factorised Hessian and d(observable)/du by
 * the chain rule, against (q(u + h) - q(u - h)) / 2h with each side solved by Newton from the
 * equilibrium. PET strip at N = 31 with gravity on, compliant unequal creases (angles, positions
 * and each crease's own hinge), sheared to
 * Delta W 0.1 at Delta L 0.3 (a state without symmetry, so every parameter moves it). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fit_scene_kit.h"
#include "rod_observe.h"
#include "rod_route.h"
#include "rod_sensitivity.h"
#include "rod_snapshot.h"
#include "rod_solver.h"

static void solve(rod *r, rod_solver *s, const rod_scene *sc, double dl, double dw)
{
    rod_set_clamps(r, dl, dw);
    rod_frames_update(r);
    rod_newton_opts no = rod_newton_opts_static(sc);
    no.tolerance = 1e-10;
    no.positive_definite = 1;
    no.max_iterations = 100;
    rod_newton_report rep;
    assert_int_equal(rod_newton_solve(r, s, &no, &rep), ROD_OK);
}

static void sensitivities_match_re_solved_equilibria(void **state)
{
    (void)state;
    rod_scene sc = fit_kit_pet(31);
    sc.fold_angle_left_deg = -88.0;
    sc.fold_angle_right_deg = -91.0;
    sc.fold_position_left = 0.2;
    sc.fold_position_right = 0.78;
    sc.fold_hinge_stiffness_left = 3e-3; /* each crease its own hinge */
    sc.fold_hinge_stiffness_right = 4e-3;
    const double dl = 0.3, dw = 0.1;
    rod *r = NULL;
    char why[256];
    assert_int_equal(rod_alloc(&sc, &r, why, sizeof why), ROD_OK);
    rod_solver *s = rod_solver_alloc(r);
    rod_route_report rep = {0};
    assert_int_equal(rod_route_to_state(r, s, &sc, +1, &rep), ROD_OK);
    double reached;
    assert_int_equal(rod_follow_shear(r, s, &sc, dl, 0.0, dw, 0.02, &reached, &rep), ROD_OK);
    rod_fit_base b;
    rod_fit_base_init(&b, r, &sc);
    double u[ROD_FIT_NKEYS];
    rod_fit_scene_values(&sc, u);
    rod_fit_apply(r, &b, u);
    solve(r, s, &sc, dl, dw);

    int nf = rod_nfree(r);
    double *dq[ROD_FIT_NKEYS], *qp = malloc(sizeof(double) * (size_t)r->ndof), *k1 = malloc(sizeof(double) * (size_t)r->n);
    for (int j = 0; j < ROD_FIT_NKEYS; j++) dq[j] = malloc(sizeof(double) * (size_t)nf);
    int use[ROD_FIT_NKEYS];
    for (int j = 0; j < ROD_FIT_NKEYS; j++) use[j] = 1;
    rod_obs d[ROD_FIT_NKEYS];
    rod_sens_ws *w = rod_sens_alloc(r);
    int neg = -1;
    assert_int_equal(rod_sens_eval(w, r, &b, u, use, dl, dw, dq, d, &neg), ROD_OK);
    assert_int_equal(neg, 0);

    rod_snapshot eq;
    assert_true(rod_snapshot_alloc(r, &eq));
    rod_snapshot_save(r, &eq);
    const double hfd[ROD_FIT_NKEYS] = {0.02, 0.02, 2e-5, 2e-5, 2e-3, 2e-3, 0.0, 2e-3, 2e-3};
    for (int j = 0; j < ROD_FIT_NKEYS; j++) {
        if (!rod_fit_key_strip((rod_fit_key)j)) continue; /* the camera's offset: test_rod_fit */
        double up[ROD_FIT_NKEYS];
        rod_obs op, om;
        memcpy(up, u, sizeof up);
        up[j] = u[j] + hfd[j];
        rod_snapshot_load(r, &eq);
        rod_fit_apply(r, &b, up);
        solve(r, s, &sc, dl, dw);
        memcpy(qp, r->q, sizeof(double) * (size_t)r->ndof);
        rod_observe(r, k1, &op);
        up[j] = u[j] - hfd[j];
        rod_snapshot_load(r, &eq);
        rod_fit_apply(r, &b, up);
        solve(r, s, &sc, dl, dw);
        rod_observe(r, k1, &om);
        double err = 0.0, mag = 0.0;
        for (int i = 0; i < nf; i++) {
            double fd = (qp[ROD_FREE_BEGIN + i] - r->q[ROD_FREE_BEGIN + i]) / (2.0 * hfd[j]);
            /* positions over l and angles in rad are both order-one numbers here */
            double sc_i = ((ROD_FREE_BEGIN + i) % 4 == 3) ? 1.0 : 1.0 / sc.length;
            err = fmax(err, fabs(fd - dq[j][i]) * sc_i);
            mag = fmax(mag, fabs(fd) * sc_i);
        }
        double fz = (op.dz - om.dz) / (2.0 * hfd[j]), fa = (op.a - om.a) / (2.0 * hfd[j]);
        double fzc = (op.dz_cam - om.dz_cam) / (2.0 * hfd[j]), fac = (op.a_cam - om.a_cam) / (2.0 * hfd[j]);
        printf("%-24s |dq/du| %.3e  rel err %.1e   dZ/du %+.5e (fd %+.5e)  dA/du %+.5e (fd %+.5e)  dA_cam/du %+.5e (fd %+.5e)\n",
               rod_fit_key_name(j), mag, err / mag, d[j].dz, fz, d[j].a, fa, d[j].a_cam, fac);
        assert_true(mag > 0.0);
        assert_true(err <= 1e-4 * mag);
        const double got[4] = {d[j].dz, d[j].a, d[j].a_cam, d[j].dz_cam}, fd[4] = {fz, fa, fac, fzc};
        for (int a = 0; a < 4; a++) assert_true(fabs(got[a] - fd[a]) <= 1e-4 * fmax(fabs(fd[a]), 1e-3 * mag));
    }
    rod_snapshot_free(&eq);
    rod_sens_free(w);
    for (int j = 0; j < ROD_FIT_NKEYS; j++) free(dq[j]);
    free(qp);
    free(k1);
    rod_solver_free(s);
    rod_free(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(sensitivities_match_re_solved_equilibria),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
