/* test_truss_dynamics.c: the truss under slow release (sim/truss_dynamics.c). With a small
 * imperfection (support rest angles split by 1e-3), psi_A grows through the snap when the
 * pitchfork comes first (L2 = 0.8) and stays at the imperfection's level when the saddle-node
 * comes first (L2 = 0.4); at the paper's rate 0.001 and, more clearly, ten times slower. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <gsl/gsl_errno.h>
#include <math.h>

#include "truss.h"

typedef struct dyn_case {
    double psi_a0;      /* |psi_A| at T = 0 (the static imperfect upper state) */
    double mu_snap;
    double psi_a_before;
    double psi_a_max;
    double mu_sn, mu_pf; /* static events of the perfect model */
} dyn_case;

static dyn_case run_case(double l2, double rate)
{
    dyn_case r = {0};
    truss_params p = truss_params_default();
    p.l2 = l2;
    truss_cont_opts co = truss_cont_opts_default();
    truss_branch b;
    assert_int_equal(truss_continue(&p, &co, 0, &b), TRUSS_OK);
    assert_true(b.pitchfork.found);
    r.mu_sn = b.saddle_node.at.mu;
    r.mu_pf = b.pitchfork.at.mu;
    truss_branch_free(&b);

    p.imperfection = 1e-3;
    truss_dyn_opts o = truss_dyn_opts_default();
    o.mu_rate = rate;
    o.sample_dt = 0.01 / rate;
    truss_dyn_result d;
    assert_int_equal(truss_dynamics_run(&p, &o, 1, &d), TRUSS_OK);
    assert_true(d.n > 10);
    assert_true(d.samples[0].t == 0.0 && d.samples[0].mu == o.mu_start);
    for (size_t i = 0; i < d.n; i++)
        assert_true(isfinite(d.samples[i].psi_s) && isfinite(d.samples[i].psi_a));
    assert_true(d.snapped);
    r.psi_a0 = fabs(d.samples[0].psi_a);
    r.mu_snap = d.mu_snap;
    r.psi_a_before = d.psi_a_max_before;
    r.psi_a_max = d.psi_a_max;
    assert_true(r.psi_a_max >= r.psi_a_before && r.psi_a_before >= r.psi_a0);
    print_message("L2 %.1f rate %g: |psi_A(0)| %.2e, snap at mu %.4f (static SN %.4f, PF %.4f), "
                  "max |psi_A| before snap %.3e, over run %.3e\n", l2, rate, r.psi_a0, r.mu_snap,
                  r.mu_sn, r.mu_pf, r.psi_a_before, r.psi_a_max);
    truss_dyn_result_free(&d);
    return r;
}

static void test_truss_dynamics_paper_rate(void **state)
{
    (void)state;
    dyn_case sym = run_case(0.4, 1e-3);
    dyn_case asym = run_case(0.8, 1e-3);
    /* a slow release snaps after the first static instability, never before it */
    assert_true(sym.mu_snap < sym.mu_sn);
    assert_true(asym.mu_snap < asym.mu_pf);
    /* L2 = 0.4: psi_A stays at the imperfection's level (below 1e-3, theta_A < 1e-4 rad; it
     * rises from 2e-5 as the antisymmetric stiffness softens near the fold) */
    assert_true(sym.psi_a_max < 1e-3);
    /* L2 = 0.8: psi_A grows past the pitchfork and through the snap */
    assert_true(asym.psi_a_max > 4.0 * asym.psi_a0);
    assert_true(asym.psi_a_max > 10.0 * sym.psi_a_max);
}

static void test_truss_dynamics_quasi_static(void **state)
{
    (void)state;
    dyn_case sym = run_case(0.4, 1e-4);
    dyn_case asym = run_case(0.8, 1e-4);
    assert_true(sym.mu_snap < sym.mu_sn && sym.mu_snap > 0.9 * sym.mu_sn);
    assert_true(asym.mu_snap < asym.mu_pf);
    assert_true(sym.psi_a_max < 1e-3);
    /* the asymmetry is O(1) before psi_S changes sign */
    assert_true(asym.psi_a_before > 0.1);
}

static void test_truss_dynamics_bad_input(void **state)
{
    (void)state;
    truss_params p = truss_params_default();
    truss_dyn_opts o = truss_dyn_opts_default();
    truss_dyn_result d;
    o.mu_rate = 0.0;
    assert_int_equal(truss_dynamics_run(&p, &o, 0, &d), TRUSS_ERR_PARAM);
    o = truss_dyn_opts_default();
    o.damping = NAN;
    assert_int_equal(truss_dynamics_run(&p, &o, 0, &d), TRUSS_ERR_PARAM);
    /* the step cap ends the run with a reason */
    o = truss_dyn_opts_default();
    o.max_steps = 10;
    assert_int_equal(truss_dynamics_run(&p, &o, 1, &d), TRUSS_ERR_MAX_ITER);
    assert_null(d.samples);
    /* below the saddle-node there is no upper state to start from */
    o = truss_dyn_opts_default();
    o.mu_start = 0.1;
    o.mu_end = 0.0;
    assert_int_equal(truss_dynamics_run(&p, &o, 0, &d), TRUSS_ERR_NO_UPPER);
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_truss_dynamics_paper_rate),
        cmocka_unit_test(test_truss_dynamics_quasi_static),
        cmocka_unit_test(test_truss_dynamics_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
