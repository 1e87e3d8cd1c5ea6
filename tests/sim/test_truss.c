/* test_truss.c: statics, stability, continuation and classification of the reduced truss model
 * (sim/truss.h), checked against finite differences and against the paper's small-angle
 * formulas in the regime where those hold (small angles: alpha (Lambda/2)^(1/3) <= 0.1 rad). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "truss.h"

/* |a - b| <= tol, with both values in the failure message */
#define assert_close(a, b, tol)                                                                    \
    do {                                                                                           \
        double a_ = (a), b_ = (b), t_ = (tol);                                                     \
        if (!(fabs(a_ - b_) <= t_)) {                                                              \
            print_error("%s = %.12g, %s = %.12g, |diff| = %.3g > %.3g\n", #a, a_, #b, b_,          \
                        fabs(a_ - b_), t_);                                                        \
            fail();                                                                                \
        }                                                                                          \
    } while (0)

/* A few generic (asymmetric, compressed, not at equilibrium) configurations. */
static const double test_configs[3][4] = {
    {0.97, 0.13, 1.83, -0.05},
    {1.02, -0.08, 1.71, 0.11},
    {0.90, 0.30, 1.60, 0.25},
};

static void check_derivatives(const truss_params *p, double mu)
{
    for (int c = 0; c < 3; c++) {
        const double *q = test_configs[c];
        double u, g[4], h[16], gmu[4];
        assert_int_equal(truss_energy_eval(p, mu, q, &u, g, h, gmu), TRUSS_OK);
        double gscale = 0.0, hscale = 0.0;
        for (int i = 0; i < 4; i++) {
            gscale = fmax(gscale, fabs(g[i]));
            for (int j = 0; j < 4; j++)
                hscale = fmax(hscale, fabs(h[4 * i + j]));
        }
        const double eps = 1e-6;
        for (int i = 0; i < 4; i++) {
            double qp[4] = {q[0], q[1], q[2], q[3]}, qm[4] = {q[0], q[1], q[2], q[3]};
            qp[i] += eps;
            qm[i] -= eps;
            double up, um, gp[4], gm[4];
            assert_int_equal(truss_energy_eval(p, mu, qp, &up, gp, NULL, NULL), TRUSS_OK);
            assert_int_equal(truss_energy_eval(p, mu, qm, &um, gm, NULL, NULL), TRUSS_OK);
            /* gradient: central difference of the energy */
            assert_close(g[i], (up - um) / (2 * eps), 1e-7 * gscale + 1e-12);
            /* Hessian column i: central difference of the gradient */
            for (int j = 0; j < 4; j++)
                assert_close(h[4 * j + i], (gp[j] - gm[j]) / (2 * eps), 1e-7 * hscale);
        }
        /* load vector: d(dU/dq)/dmu at fixed q */
        const double emu = 1e-4;
        double gp[4], gm[4];
        assert_int_equal(truss_energy_eval(p, mu + emu, q, NULL, gp, NULL, NULL), TRUSS_OK);
        assert_int_equal(truss_energy_eval(p, mu - emu, q, NULL, gm, NULL, NULL), TRUSS_OK);
        double gmscale = 0.0;
        for (int j = 0; j < 4; j++)
            gmscale = fmax(gmscale, fabs(gmu[j]));
        assert_true(gmscale > 0.0);
        for (int j = 0; j < 4; j++)
            assert_close(gmu[j], (gp[j] - gm[j]) / (2 * emu), 1e-7 * gmscale);
    }
}

static void test_truss_derivatives_fd(void **state)
{
    (void)state;
    truss_params p = truss_params_default();
    check_derivatives(&p, 1.0);
    p.l2 = 0.4;
    p.imperfection = 0.3;
    check_derivatives(&p, 0.5);
    p.printed_signs = 1;
    p.alpha = 0.3;
    p.lambda = 0.7;
    check_derivatives(&p, 2.0);
}

static void test_truss_bad_input(void **state)
{
    (void)state;
    truss_params p = truss_params_default();
    char msg[128];
    assert_int_equal(truss_params_check(&p, msg, sizeof msg), TRUSS_OK);
    p.lambda = NAN;
    assert_int_equal(truss_params_check(&p, msg, sizeof msg), TRUSS_ERR_PARAM);
    assert_non_null(strstr(msg, "lambda"));
    p = truss_params_default();
    p.alpha = 0.0;
    assert_int_equal(truss_params_check(&p, msg, sizeof msg), TRUSS_ERR_PARAM);
    assert_non_null(strstr(msg, "alpha"));
    p = truss_params_default();
    p.l2 = INFINITY;
    assert_int_equal(truss_params_check(&p, msg, sizeof msg), TRUSS_ERR_PARAM);
    assert_non_null(strstr(msg, "l2"));

    /* NaN in, error out; a collapsed spring is an error, not a NaN */
    p = truss_params_default();
    double q[4] = {NAN, 0.1, 1.8, 0.1}, g[4];
    assert_int_equal(truss_energy_eval(&p, 1.0, q, NULL, g, NULL, NULL), TRUSS_ERR_NAN);
    double q0[4] = {0.0, 0.0, 1.8, 0.1};
    assert_int_equal(truss_energy_eval(&p, 1.0, q0, NULL, g, NULL, NULL), TRUSS_ERR_DIVERGED);

    /* the classification needs the perfect model */
    truss_cont_opts o = truss_cont_opts_default();
    truss_branch b;
    p.imperfection = 1e-3;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_ERR_PARAM);
    /* bad continuation options */
    p.imperfection = 0.0;
    o.max_steps = 0;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_ERR_PARAM);
    /* no upper state at too small a compression (below the saddle-node) */
    o = truss_cont_opts_default();
    o.mu_start = 0.1;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_ERR_NO_UPPER);
    /* a cap that is too small ends with a reason, not a hang or a wrong answer */
    o = truss_cont_opts_default();
    o.max_steps = 3;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_ERR_MAX_ITER);
}

static void test_truss_statics_equilibrium(void **state)
{
    (void)state;
    truss_params p = truss_params_default();
    p.imperfection = 0.02; /* asymmetric solve in the full space */
    double q[4];
    truss_config_guess(&p, 1.0, 1.6, q);
    truss_newton_opts no = truss_newton_opts_default();
    int it = 0;
    assert_int_equal(truss_statics_solve(&p, 1.0, q, &no, &it), TRUSS_OK);
    assert_true(it >= 1 && it <= no.max_iter);
    double g[4];
    assert_int_equal(truss_energy_eval(&p, 1.0, q, NULL, g, NULL, NULL), TRUSS_OK);
    for (int i = 0; i < 4; i++)
        assert_true(fabs(g[i]) < 1e-12);
    truss_stability st;
    assert_int_equal(truss_stability_eval(&p, 1.0, q, &st), TRUSS_OK);
    assert_true(st.stable);
    assert_int_equal(st.n_negative, 0);
    double psi_s, psi_a;
    truss_coords_psi(&p, 1.0, q, &psi_s, &psi_a);
    /* small-angle upper root at mu = 1 is about 1.62; the imperfection tilts it slightly */
    double roots[3];
    assert_int_equal(truss_analytic_psi_roots(p.lambda, p.l2, 1.0, roots), 3);
    assert_close(psi_s, roots[2], 0.02 * roots[2]);
    assert_true(fabs(psi_a) > 1e-5 && fabs(psi_a) < 0.05);
}

/* The full model's symmetric branch satisfies the paper's cubic as alpha -> 0. */
static void test_truss_branch_matches_cubic(void **state)
{
    (void)state;
    truss_params p = truss_params_default();
    p.alpha = 0.01;
    p.l2 = 0.4;
    truss_cont_opts o = truss_cont_opts_default();
    truss_branch b;
    assert_int_equal(truss_continue(&p, &o, 1, &b), TRUSS_OK);
    assert_true(b.n > 5);
    for (size_t i = 0; i < b.n; i++) {
        const truss_point *pt = &b.points[i];
        assert_true(isfinite(pt->mu) && isfinite(pt->psi_s));
        double mu_a = truss_analytic_mu_at_psi(p.lambda, p.l2, pt->psi_s);
        assert_close(pt->mu, mu_a, 1e-3 * mu_a);
        /* stable exactly while both blocks are positive */
        assert_int_equal(pt->stab.stable, pt->stab.eig_min_sym > 0.0 && pt->stab.eig_min_anti > 0.0);
    }
    /* mu decreases on the upper part and turns at the saddle-node: it is the branch's minimum */
    double mu_min = INFINITY;
    for (size_t i = 0; i < b.n; i++)
        mu_min = fmin(mu_min, b.points[i].mu);
    assert_true(b.saddle_node.at.mu <= mu_min + 1e-12);
    truss_branch_free(&b);
}

/* psi_SN within 2% of (Lambda/2)^(1/3) where the saddle-node angle alpha psi_SN <= 0.1 rad;
 * outside (alpha = 0.3, Lambda = 0.5: 0.19 rad) the asymptotic is off by more. */
static void test_truss_psi_sn_small_angle(void **state)
{
    (void)state;
    const double alphas[3] = {0.01, 0.1, 0.3};
    const double lambdas[3] = {0.02, 0.1, 0.5};
    truss_cont_opts o = truss_cont_opts_default();
    int checked = 0;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            truss_params p = truss_params_default();
            p.alpha = alphas[i];
            p.lambda = lambdas[j];
            p.l2 = 0.4;
            double psi_a = truss_analytic_psi_sn(p.lambda);
            truss_branch b;
            assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_OK);
            assert_true(b.saddle_node.found);
            double rel = fabs(b.saddle_node.at.psi_s / psi_a - 1.0);
            print_message("alpha %.2f Lambda %.2f: psi_SN %.6f, (Lambda/2)^(1/3) %.6f, rel %.2e\n",
                          p.alpha, p.lambda, b.saddle_node.at.psi_s, psi_a, rel);
            if (p.alpha * psi_a <= 0.1) {
                assert_true(rel < 0.02);
                checked++;
            }
            if (p.alpha <= 0.01)
                assert_true(rel < 1e-4); /* converges as alpha^2 */
            if (p.alpha == 0.3 && p.lambda == 0.5)
                assert_true(rel > 0.02); /* out of the regime, and the test can tell */
            /* at a saddle-node the critical mode is symmetric and loads the branch */
            assert_close(b.saddle_node.at.stab.mode_parity, 1.0, 1e-9);
            assert_true(b.saddle_node.at.stab.load_projection > 1e-4);
            assert_true(fabs(b.saddle_node.at.stab.mode_eig) < 1e-9);
            truss_branch_free(&b);
        }
    }
    assert_int_equal(checked, 7); /* all but alpha = 0.3 with Lambda = 0.1 (0.11 rad) and 0.5 */
}

static void test_truss_classification(void **state)
{
    (void)state;
    truss_params p = truss_params_default();
    truss_cont_opts o = truss_cont_opts_default();
    truss_branch b;

    /* L2 = 0.8: pitchfork first (asymmetric snap-through) */
    p.l2 = 0.8;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_OK);
    assert_true(b.pitchfork.found && b.saddle_node.found);
    assert_int_equal(b.first, TRUSS_EVENT_PITCHFORK);
    assert_true(b.pitchfork.at.mu > b.saddle_node.at.mu);
    /* psi_PF within 2% of L2 (L2 + 2) / 4 */
    double psi_pf = truss_analytic_psi_pf(p.l2);
    assert_close(b.pitchfork.at.psi_s, psi_pf, 0.02 * psi_pf);
    assert_close(b.pitchfork.at.stab.mode_parity, -1.0, 1e-9);
    assert_true(b.pitchfork.at.stab.load_projection < 1e-9);
    assert_true(fabs(b.pitchfork.at.stab.eig_min_anti) < 1e-9);
    assert_true(fabs(b.pitchfork.at.stab.mode_eig) < 1e-9);
    /* the upper state is stable before the pitchfork */
    assert_true(b.pitchfork.at.stab.eig_min_sym > 0.0);
    truss_branch_free(&b);

    /* L2 = 0.4: saddle-node first (symmetric snap-through); the pitchfork lies on the unstable
     * middle branch beyond the fold, at a larger mu */
    p.l2 = 0.4;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_OK);
    assert_true(b.pitchfork.found && b.saddle_node.found);
    assert_int_equal(b.first, TRUSS_EVENT_SADDLE_NODE);
    psi_pf = truss_analytic_psi_pf(p.l2);
    assert_close(b.pitchfork.at.psi_s, psi_pf, 0.02 * psi_pf);
    assert_true(b.saddle_node.at.stab.eig_min_anti > 0.0);
    assert_true(b.pitchfork.at.stab.eig_min_sym < 0.0);
    assert_close(b.pitchfork.at.stab.mode_parity, -1.0, 1e-9);
    truss_branch_free(&b);
}

static void test_truss_switch(void **state)
{
    (void)state;
    truss_params p = truss_params_default(); /* alpha = 0.1, Lambda = 0.1 */
    double l2_star = truss_analytic_l2_star(p.lambda);
    assert_close(l2_star, 0.5728, 1e-4); /* the paper's value, from its formulas */
    /* the analytic switch is where the two small-angle formulas meet */
    assert_close(truss_analytic_psi_pf(l2_star), truss_analytic_psi_sn(p.lambda), 1e-12);
    truss_cont_opts o = truss_cont_opts_default();
    double l2_switch = 0.0;
    assert_int_equal(truss_switch_find(&p, &o, 0.3, 1.0, 1e-7, &l2_switch), TRUSS_OK);
    print_message("l2_switch %.6f, l2_star %.6f\n", l2_switch, l2_star);
    assert_close(l2_switch, l2_star, 0.01);
    /* and the order does switch there */
    truss_branch b;
    p.l2 = l2_switch - 0.01;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_OK);
    assert_int_equal(b.first, TRUSS_EVENT_SADDLE_NODE);
    truss_branch_free(&b);
    p.l2 = l2_switch + 0.01;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_OK);
    assert_int_equal(b.first, TRUSS_EVENT_PITCHFORK);
    truss_branch_free(&b);
    /* a bracket without a switch is refused */
    p = truss_params_default();
    assert_int_equal(truss_switch_find(&p, &o, 0.7, 1.0, 1e-7, &l2_switch), TRUSS_ERR_NOT_FOUND);
}

/* The switch converges to the small-angle L2* as alpha -> 0 (alpha = 0.001 exercises the
 * round-off floors of the Newton tests), and a sharp fold (Lambda = 0.001) is not overshot. */
static void test_truss_switch_limits(void **state)
{
    (void)state;
    truss_cont_opts o = truss_cont_opts_default();
    truss_params p = truss_params_default();
    double l2_switch = 0.0;
    p.alpha = 0.001;
    assert_int_equal(truss_switch_find(&p, &o, 0.3, 1.0, 1e-8, &l2_switch), TRUSS_OK);
    assert_close(l2_switch, truss_analytic_l2_star(p.lambda), 1e-5);
    p.alpha = 0.1;
    p.lambda = 0.001;
    double l2_star = truss_analytic_l2_star(p.lambda);
    assert_close(l2_star, 0.1478, 1e-4);
    assert_int_equal(truss_switch_find(&p, &o, 0.25 * l2_star, 2.0 * l2_star, 1e-8, &l2_switch), TRUSS_OK);
    assert_close(l2_switch, l2_star, 1e-3);
    /* past that sharp fold the middle branch is followed down to its pitchfork */
    truss_branch b;
    p.l2 = 0.25 * l2_star;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_OK);
    assert_true(b.pitchfork.found);
    double psi_pf = truss_analytic_psi_pf(p.l2);
    assert_close(b.pitchfork.at.psi_s, psi_pf, 0.05 * psi_pf);
    assert_true(b.pitchfork.at.psi_s < b.saddle_node.at.psi_s);
    truss_branch_free(&b);
}

/* The paper's printed joint signs give a different model: its pitchfork sits at
 * psi = L2 (L2 + 2) / (4 (1 - 2 L2)) (1.2 at L2 = 0.4, not 0.24), and for L2 >= 1/2 its upper
 * state is never stable, so the paper's L2 = 0.8 case could not exist. */
static void test_truss_printed_signs(void **state)
{
    (void)state;
    truss_params p = truss_params_default();
    p.printed_signs = 1;
    p.alpha = 0.01;
    p.l2 = 0.4;
    truss_cont_opts o = truss_cont_opts_default();
    truss_branch b;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_OK);
    assert_true(b.pitchfork.found);
    double printed_pf = p.l2 * (p.l2 + 2.0) / (4.0 * (1.0 - 2.0 * p.l2));
    assert_close(b.pitchfork.at.psi_s, printed_pf, 0.02 * printed_pf);
    assert_true(fabs(b.pitchfork.at.psi_s - truss_analytic_psi_pf(p.l2)) > 0.5);
    truss_branch_free(&b);
    p.l2 = 0.8;
    assert_int_equal(truss_continue(&p, &o, 0, &b), TRUSS_ERR_NO_UPPER);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_truss_derivatives_fd),
        cmocka_unit_test(test_truss_bad_input),
        cmocka_unit_test(test_truss_statics_equilibrium),
        cmocka_unit_test(test_truss_branch_matches_cubic),
        cmocka_unit_test(test_truss_psi_sn_small_angle),
        cmocka_unit_test(test_truss_classification),
        cmocka_unit_test(test_truss_switch),
        cmocka_unit_test(test_truss_switch_limits),
        cmocka_unit_test(test_truss_printed_signs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
