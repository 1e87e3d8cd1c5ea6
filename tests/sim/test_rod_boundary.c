/* test_rod_boundary: the regime boundary traced directly (sim/rod_critical.h, rod_boundary.h) and
 * the truss's codimension-2 point (truss_codim2.c).
 *   - the mirror map commutes with the free Hessian on a sheared symmetric state;
 *   - the test function's gradient along q (directional difference of the Hessian) and its
 *     parameter derivatives against central differences of g itself;
 *   - at phi = 90 deg, Delta L = 0.5 (N = 61): the codim-2 point has both block eigenvalues zero
 *     to round-off with one even and one odd mode, and so do several points continued in phi;
 *   - the saddle-node and pitchfork curves pass through the events `continue` locates, at three
 *     Gamma on the same mesh, within 1e-4 in Delta W;
 *   - the direct codim-2 Newton gives the located points (1e-5) and solves most of them; the
 *     regime-boundary check on demand; a solve far from equilibrium stops at the phase-1 cap;
 *   - named stops: phi reaching 180 deg, the boundary leaving the Gamma range, no meeting point in
 *     the Gamma range from the start;
 *   - the truss: the codim-2 location equals truss_switch_find (the `truss --find-switch` value)
 *     within 1e-4, and tends to the paper's analytic L2* as alpha^2. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>
#include <gsl/gsl_errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rod_bifurcation.h"
#include "rod_boundary.h"
#include "rod_critical.h"
#include "rod_route.h"
#include "rod_snapshot.h"
#include "rod_solver.h"
#include "rod_stability.h"
#include "rod_symmetry.h"
#include "truss.h"

#define assert_close(a, b, tol)                                                                    \
    do {                                                                                           \
        double a_ = (a), b_ = (b), t_ = (tol);                                                     \
        if (!(fabs(a_ - b_) <= t_)) {                                                              \
            print_error("%s = %.12g, %s = %.12g, |diff| = %.3g > %.3g\n", #a, a_, #b, b_,          \
                        fabs(a_ - b_), t_);                                                        \
            fail();                                                                                \
        }                                                                                          \
    } while (0)

static rod_scene scene(int nodes, double gamma)
{
    rod_scene sc = rod_scene_default();
    sc.fold_angle_deg = -90.0;
    sc.fold_position = gamma;
    sc.fold_stiffness_factor = 1e4;
    sc.fold_angle_rel = 0.0;
    sc.nodes = nodes;
    sc.compression = 0.5;
    return sc;
}

/* A symmetric sheared equilibrium at dw on the upper branch. */
static rod *sheared(int nodes, double gamma, double dw)
{
    rod_scene sc = scene(nodes, gamma);
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&sc, &r, err, sizeof err), ROD_OK);
    rod_solver *s = rod_solver_alloc(r);
    rod_route_report rr = {0};
    assert_int_equal(rod_route_to_state(r, s, &sc, +1, &rr), ROD_OK);
    double reached;
    assert_int_equal(rod_follow_shear(r, s, &sc, sc.compression, 0.0, dw, 0.02, &reached, &rr), ROD_OK);
    rod_solver_free(s);
    return r;
}

static void test_mirror_commutes(void **state)
{
    (void)state;
    rod *r = sheared(41, 0.13, 0.2);
    int nf = rod_nfree(r);
    double *H = calloc((size_t)nf * (ROD_BAND + 1), sizeof(double)), *v = malloc(sizeof(double) * (size_t)nf),
           *Sv = malloc(sizeof(double) * (size_t)nf), *KSv = malloc(sizeof(double) * (size_t)nf),
           *Kv = malloc(sizeof(double) * (size_t)nf), *SKv = malloc(sizeof(double) * (size_t)nf);
    rod_frames_update(r);
    rod_hessian_add(r, 1.0, H);
    for (int k = 0; k < nf; k++) v[k] = sin(1.3 * k) + 0.1 * cos(7.1 * k);
    rod_mode_mirror(r, v, Sv);
    rod_band_symv(H, nf, Sv, KSv);
    rod_band_symv(H, nf, v, Kv);
    rod_mode_mirror(r, Kv, SKv);
    double d = 0.0, n = 0.0;
    for (int k = 0; k < nf; k++) {
        d = fmax(d, fabs(KSv[k] - SKv[k]));
        n = fmax(n, fabs(SKv[k]));
    }
    print_message("|K S v - S K v| = %.3g of %.3g\n", d, n);
    assert_true(d <= 1e-11 * n);
    /* S is an involution and the projections split v. */
    rod_mode_mirror(r, Sv, Kv);
    for (int k = 0; k < nf; k++) assert_close(Kv[k], v[k], 0.0);
    assert_true(rod_state_asymmetry(r) < 1e-10);
    free(H); free(v); free(Sv); free(KSv); free(Kv); free(SKv);
    rod_free(r);
}

/* grad_q g . d and dg/dp against central differences of g with the borders held. */
static void test_test_function_derivatives(void **state)
{
    (void)state;
    rod *r = sheared(41, 0.13, 0.3);
    int nf = rod_nfree(r);
    rod_crit *c = rod_crit_alloc(r, NULL);
    assert_non_null(c);
    double p[ROD_NPAR] = {0.3, 0.13, -M_PI / 2, 0.5};
    p[ROD_PAR_GAMMA] = r->fold_position;
    rod_crit_report rep;
    assert_int_equal(rod_crit_modes(c, p, &rep, NULL, 0), ROD_OK);
    double *grad = malloc(sizeof(double) * (size_t)nf), *d = malloc(sizeof(double) * (size_t)nf),
           *q0 = malloc(sizeof(double) * (size_t)r->ndof);
    memcpy(q0, r->q, sizeof(double) * (size_t)r->ndof);
    rod_snapshot base;
    assert_true(rod_snapshot_alloc(r, &base));
    rod_state_symmetrize(r);
    rod_params_apply(r, p);
    memcpy(q0, r->q, sizeof(double) * (size_t)r->ndof);
    rod_snapshot_save(r, &base);
    for (int sign = 1; sign >= -1; sign -= 2) {
        const rod_par pars[3] = {ROD_PAR_DW, ROD_PAR_GAMMA, ROD_PAR_PHI};
        for (int pi = 0; pi < 3; pi++) {
            double gp;
            rod_snapshot_load(r, &base);
            assert_int_equal(rod_crit_gradient(c, p, sign, pars[pi], grad, &gp), ROD_OK);
            /* Along an even direction (q moves stay symmetric): a smooth bump in z. */
            double dd = 0.0;
            for (int k = 0; k < nf; k++) {
                int gk = k + ROD_FREE_BEGIN;
                d[k] = (gk % 4 == 2) ? sin(M_PI * r->s_node[gk / 4]) : 0.0;
                dd += d[k] * d[k];
            }
            for (int k = 0; k < nf; k++) d[k] /= sqrt(dd);
            double an = 0.0;
            for (int k = 0; k < nf; k++) an += grad[k] * d[k];
            double h = 1e-8 * r->length, gpl, gmi;
            rod_snapshot_load(r, &base);
            for (int k = 0; k < nf; k++) r->q[k + ROD_FREE_BEGIN] = q0[k + ROD_FREE_BEGIN] + h * d[k];
            rod_frames_update(r);
            assert_int_equal(rod_crit_testfn(c, p, sign, &gpl), ROD_OK);
            rod_snapshot_load(r, &base);
            for (int k = 0; k < nf; k++) r->q[k + ROD_FREE_BEGIN] = q0[k + ROD_FREE_BEGIN] - h * d[k];
            rod_frames_update(r);
            assert_int_equal(rod_crit_testfn(c, p, sign, &gmi), ROD_OK);
            double fd = (gpl - gmi) / (2.0 * h);
            if (pi == 0) {
                print_message("%s block: grad_q g . d = %.6g, difference %.6g\n", sign > 0 ? "even" : "odd", an, fd);
                assert_close(an, fd, 1e-3 * fabs(fd) + 1e-6);
            }
            /* Parameter derivative. */
            rod_snapshot_load(r, &base);
            double pp[ROD_NPAR], e = 1e-8; /* g is steep in p at fixed q (the clamps strain stiff edges) */
            memcpy(pp, p, sizeof pp);
            pp[pars[pi]] += e;
            assert_int_equal(rod_crit_testfn(c, pp, sign, &gpl), ROD_OK);
            rod_snapshot_load(r, &base);
            pp[pars[pi]] -= 2.0 * e;
            assert_int_equal(rod_crit_testfn(c, pp, sign, &gmi), ROD_OK);
            fd = (gpl - gmi) / (2.0 * e);
            print_message("%s block: dg/dp%d = %.6g, difference %.6g\n", sign > 0 ? "even" : "odd", pi, gp, fd);
            assert_close(gp, fd, 1e-3 * fabs(fd) + 1e-6);
        }
    }
    rod_snapshot_free(&base);
    free(grad); free(d); free(q0);
    rod_crit_free(c);
    rod_free(r);
}

static void check_critical(const rod_codim2_point *pt)
{
    /* Round-off floor of an eigenvalue is ~1e-16 max |K_ii|; the soft eigenvalues are ~1e-2. */
    assert_true(fabs(pt->eig_even) <= 1e-14 * pt->eig_scale);
    assert_true(fabs(pt->eig_odd) <= 1e-14 * pt->eig_scale);
    assert_true(pt->parity_even > 0.99);
    assert_true(pt->parity_odd < -0.99);
    assert_true(pt->residual_rel <= 1e-3);
}

/* Start on the mesh the sweep uses at Gamma* (N = 61: 10 outer edges for Gamma 0.164-0.181). */
#define NODES 61
#define GAMMA0 0.172

/* A boundary session started at the scene's codim-2 point (its start asserted). */
static rod_boundary *started(const rod_scene *sc, const rod_boundary_opts *o, rod_codim2_point *pt)
{
    rod_boundary *b = NULL;
    char why[512] = "";
    rod_status st = rod_boundary_start(sc, o, &b, pt, why, sizeof why);
    if (st != ROD_OK) print_error("%s\n", why);
    assert_int_equal(st, ROD_OK);
    return b;
}

static void test_codim2_and_phi(void **state)
{
    (void)state;
    rod_scene sc = scene(NODES, GAMMA0);
    rod_boundary_opts o = rod_boundary_opts_default();
    rod_boundary *b = NULL;
    rod_codim2_point pt;
    char why[512] = "";
    rod_status st = rod_boundary_start(&sc, &o, &b, &pt, why, sizeof why);
    if (st != ROD_OK) print_error("%s\n", why);
    assert_int_equal(st, ROD_OK);
    print_message("Gamma* = %.6f, Delta W = %.6f, eigenvalues %.3g %.3g (max K_ii %.3g)\n", pt.gamma, pt.dw, pt.eig_even,
                  pt.eig_odd, pt.eig_scale);
    assert_true(pt.gamma > 0.17 && pt.gamma < 0.18);
    assert_int_equal(pt.outer_edges, 10);
    check_critical(&pt);
    rod_boundary_curve c = {0};
    assert_int_equal(rod_boundary_move(b, ROD_PAR_PHI, 100.0, &c), ROD_OK);
    assert_true(c.n >= 3);
    for (size_t k = 0; k < c.n; k++) check_critical(&c.pts[k]);
    assert_close(c.pts[c.n - 1].phi_deg, 100.0, 1e-9);
    /* Gamma*(phi) rises with phi here (README: 0.136 at 45 deg to 0.189 at 135 deg). */
    assert_true(c.pts[c.n - 1].gamma > pt.gamma);
    rod_boundary_curve_free(&c);
    /* Delta L continuation. */
    assert_int_equal(rod_boundary_move(b, ROD_PAR_DL, 0.45, &c), ROD_OK);
    for (size_t k = 0; k < c.n; k++) check_critical(&c.pts[k]);
    rod_boundary_curve_free(&c);
    /* A target at 180 deg is refused by name, nothing changes. */
    rod_codim2_point before, after;
    rod_boundary_current(b, &before);
    assert_int_not_equal(rod_boundary_move(b, ROD_PAR_PHI, 180.0, &c), ROD_OK);
    assert_non_null(strstr(c.end_reason, "180"));
    rod_boundary_current(b, &after);
    assert_close(after.gamma, before.gamma, 0.0);
    rod_boundary_curve_free(&c);
    rod_boundary_free(b);

    /* The boundary leaving the Gamma range: a named stop, the good points kept. */
    o.gamma_max = pt.gamma + 0.002;
    assert_int_equal(rod_boundary_start(&sc, &o, &b, &pt, why, sizeof why), ROD_OK);
    st = rod_boundary_move(b, ROD_PAR_PHI, 120.0, &c);
    print_message("stop: %s (%zu points kept)\n", c.end_reason, c.n);
    assert_int_equal(st, ROD_ERR_BRANCH_LOST);
    assert_non_null(strstr(c.end_reason, "left the Gamma range"));
    assert_true(c.n >= 1);
    for (size_t k = 0; k < c.n; k++) {
        assert_true(c.pts[k].gamma <= o.gamma_max);
        check_critical(&c.pts[k]);
    }
    rod_boundary_curve_free(&c);
    rod_boundary_free(b);

    /* No meeting point reachable from the start inside the Gamma range. */
    o = rod_boundary_opts_default();
    o.gamma_min = GAMMA0 - 0.01;
    o.gamma_max = GAMMA0 + 0.002;
    st = rod_boundary_start(&sc, &o, &b, &pt, why, sizeof why);
    print_message("no meeting: %s\n", why);
    assert_int_not_equal(st, ROD_OK);
    assert_non_null(strstr(why, "codim-2 point not found"));
    assert_true(isfinite(pt.gamma) && pt.gamma == 0.0);
    rod_boundary_free(b);
}

/* The direct codim-2 Newton (opts.direct): from phi 90 to 100 deg most points are solved by it,
 * each a verified codim-2 point, and the end point agrees with the located one (direct off). */
static void test_direct_codim2(void **state)
{
    (void)state;
    rod_scene sc = scene(NODES, GAMMA0);
    double end[2] = {0, 0};
    size_t ndirect = 0, n = 0;
    for (int d = 0; d <= 1; d++) {
        rod_boundary_opts o = rod_boundary_opts_default();
        o.direct = d;
        o.verify_ends = 0;
        rod_codim2_point pt;
        rod_boundary *b = started(&sc, &o, &pt);
        rod_boundary_curve c = {0};
        assert_int_equal(rod_boundary_move(b, ROD_PAR_PHI, 100.0, &c), ROD_OK);
        for (size_t k = 0; k < c.n; k++) {
            check_critical(&c.pts[k]);
            if (d) ndirect += (size_t)c.pts[k].direct;
            else assert_int_equal(c.pts[k].direct, 0);
        }
        if (d) n = c.n;
        end[d] = c.pts[c.n - 1].gamma;
        rod_boundary_curve_free(&c);
        /* The end of a move without its own check: rod_boundary_check on the current point. */
        double fdw = -1.0;
        assert_int_equal(rod_boundary_check(b, &fdw), 1);
        rod_boundary_current(b, &pt);
        assert_close(fdw, pt.dw, 0.02);
        rod_boundary_free(b);
    }
    print_message("phi 100 deg: Gamma* %.8f located, %.8f with the direct Newton (%zu of %zu points direct)\n", end[0],
                  end[1], ndirect, n);
    assert_true(2 * ndirect >= n);
    assert_close(end[1], end[0], 1e-5);
}

/* Delta L 0.3: the codim-2 point's Delta W runs to 0 near phi 129.24 deg (N = 61); the move stops
 * there by that name, the points before kept, their Delta W falling toward 0. Delta W^2 is linear
 * in phi there (a square-root end), so the named end, extrapolated by that law, does not depend on
 * where the steps fell: the secant's and the quadratic predictor's steps give the same end within
 * 0.02 deg. */
static double dw_zero_end(int predictor)
{
    rod_scene sc = scene(NODES, GAMMA0);
    rod_boundary_opts o = rod_boundary_opts_default();
    o.verify_every = 0.0;
    o.predictor = predictor;
    rod_codim2_point pt;
    rod_boundary *b = started(&sc, &o, &pt);
    rod_boundary_curve c = {0};
    assert_int_equal(rod_boundary_move(b, ROD_PAR_DL, 0.3, &c), ROD_OK);
    rod_boundary_curve_free(&c);
    rod_status st = rod_boundary_move(b, ROD_PAR_PHI, 135.0, &c);
    print_message("%s (%zu points)\n", c.end_reason, c.n);
    assert_int_equal(st, ROD_ERR_BRANCH_LOST);
    assert_non_null(strstr(c.end_reason, "Delta W runs to 0"));
    assert_true(c.n >= 3);
    assert_true(c.pts[c.n - 1].dw < 0.05 && c.pts[c.n - 1].dw > 0.0);
    assert_true(c.pts[c.n - 1].phi_deg > 120.0 && c.pts[c.n - 1].phi_deg < 135.0);
    for (size_t k = 0; k < c.n; k++) check_critical(&c.pts[k]);
    const char *at = strstr(c.end_reason, "runs to 0 at phi = ");
    assert_non_null(at);
    double end = atof(at + strlen("runs to 0 at phi = "));
    assert_true(end > c.pts[c.n - 1].phi_deg && end < 135.0);
    rod_boundary_curve_free(&c);
    rod_boundary_free(b);
    return end;
}

static void test_dw_runs_to_zero(void **state)
{
    (void)state;
    double e1 = dw_zero_end(1), e2 = dw_zero_end(2);
    print_message("Delta W runs to 0 at phi %.4f (secant's steps) / %.4f (quadratic's)\n", e1, e2);
    assert_close(e1, e2, 0.02);
    assert_true(e2 > 128.5 && e2 < 130.0);
}

/* The quadratic predictor (default) against the secant on the same move: the same Gamma*, in fewer
 * points (its first guess is O(h^3) off, the secant's O(h^2), so fewer steps fail and halve;
 * NODES = 61: 16 points against 22 from phi 90 to 130). */
static void test_quadratic_predictor(void **state)
{
    (void)state;
    rod_scene sc = scene(NODES, GAMMA0);
    double end_gamma[2];
    int points[2];
    for (int order = 1; order <= 2; order++) {
        rod_boundary_opts o = rod_boundary_opts_default();
        o.predictor = order;
        o.verify_every = 0.0;
        rod_codim2_point pt;
        rod_boundary *b = started(&sc, &o, &pt);
        rod_boundary_curve c = {0};
        assert_int_equal(rod_boundary_move(b, ROD_PAR_PHI, 130.0, &c), ROD_OK);
        for (size_t k = 0; k < c.n; k++) check_critical(&c.pts[k]);
        end_gamma[order - 1] = c.pts[c.n - 1].gamma;
        points[order - 1] = (int)c.n;
        rod_boundary_curve_free(&c);
        rod_boundary_free(b);
    }
    print_message("phi 90 -> 130: secant %d points, quadratic %d points; Gamma* %.8f / %.8f\n", points[0],
                  points[1], end_gamma[0], end_gamma[1]);
    assert_close(end_gamma[1], end_gamma[0], 1e-5);
    assert_true(points[1] < points[0]);
}

/* rod_crit_set_phase1_cap: a solve from a badly strained state (the crease angle moved by 5 deg
 * at fixed q) fails after the cap, with its reason, instead of running to the Newton cap. */
static void test_phase1_cap(void **state)
{
    (void)state;
    rod *r = sheared(41, 0.13, 0.3);
    rod_crit *c = rod_crit_alloc(r, NULL);
    assert_non_null(c);
    double p[ROD_NPAR] = {0.3, 0.13, -M_PI / 2, 0.5};
    p[ROD_PAR_GAMMA] = r->fold_position;
    assert_int_equal(rod_crit_modes(c, p, NULL, NULL, 0), ROD_OK);
    p[ROD_PAR_PHI] += 5.0 * M_PI / 180.0;
    rod_params_apply(r, p);
    assert_int_equal(rod_crit_set_phase1_cap(c, 3), 40);
    const rod_par dw_only[1] = {ROD_PAR_DW};
    rod_crit_report rep;
    char why[200] = "";
    assert_int_equal(rod_crit_solve(c, ROD_CRIT_FOLD, dw_only, p, &rep, why, sizeof why), ROD_ERR_MAXITER);
    print_message("%s\n", why);
    assert_non_null(strstr(why, "equilibrium not restored within 3 iterations"));
    rod_crit_free(c);
    rod_free(r);
}

static void test_curves_through_continue_events(void **state)
{
    (void)state;
    rod_scene sc = scene(NODES, GAMMA0);
    rod_boundary_opts o = rod_boundary_opts_default();
    rod_boundary *b = NULL;
    rod_codim2_point pt;
    char why[512] = "";
    assert_int_equal(rod_boundary_start(&sc, &o, &b, &pt, why, sizeof why), ROD_OK);
    rod_crit_curve fold, pf;
    const double g3[3] = {0.168, 0.1735, 0.179};
    rod_status s1 = rod_boundary_crit_curve(b, ROD_CRIT_FOLD, g3[0], g3[2], 0.0055, &fold);
    if (s1 != ROD_OK) print_error("saddle-node curve: %s\n", fold.end_reason);
    rod_status s2 = rod_boundary_crit_curve(b, ROD_CRIT_PITCHFORK, g3[0], g3[2], 0.0055, &pf);
    if (s2 != ROD_OK) print_error("pitchfork curve: %s\n", pf.end_reason);
    assert_int_equal(s1, ROD_OK);
    assert_int_equal(s2, ROD_OK);
    for (int k = 0; k < 3; k++) {
        assert_int_equal(rod_mesh_outer_edges(NODES, g3[k]), 10);
        rod_scene s2 = scene(NODES, g3[k]);
        rod_analysis_opts ao = rod_analysis_opts_default();
        ao.switch_branches = 0;
        rod_analysis a;
        assert_int_equal(rod_bifurcation_analyse(&s2, &ao, &a, why, sizeof why), ROD_OK);
        double dw_sn = NAN, dw_pf = NAN;
        for (int e = 0; e < a.nevents; e++) {
            if (a.events[e].branch != 0) continue;
            if (a.events[e].kind == ROD_EVENT_SADDLE_NODE && isnan(dw_sn)) dw_sn = a.events[e].at.dw;
            if (a.events[e].kind == ROD_EVENT_PITCHFORK && isnan(dw_pf)) dw_pf = a.events[e].at.dw;
        }
        rod_analysis_free(&a);
        double cf = NAN, cp = NAN;
        for (size_t i = 0; i < fold.n; i++)
            if (fabs(fold.pts[i].gamma - g3[k]) < 1e-9) cf = fold.pts[i].dw;
        for (size_t i = 0; i < pf.n; i++)
            if (fabs(pf.pts[i].gamma - g3[k]) < 1e-9) cp = pf.pts[i].dw;
        print_message("Gamma %.4f: saddle-node %.6f (continue %.6f), pitchfork %.6f (continue %.6f)\n", g3[k], cf, dw_sn,
                      cp, dw_pf);
        assert_close(cf, dw_sn, 1e-4);
        assert_close(cp, dw_pf, 1e-4);
    }
    /* Both curves pass through the codim-2 point. */
    int seen = 0;
    for (size_t i = 0; i < fold.n; i++)
        if (fabs(fold.pts[i].gamma - pt.gamma) < 1e-12) {
            assert_close(fold.pts[i].dw, pt.dw, 1e-9);
            seen++;
        }
    for (size_t i = 0; i < pf.n; i++)
        if (fabs(pf.pts[i].gamma - pt.gamma) < 1e-12) {
            assert_close(pf.pts[i].dw, pt.dw, 1e-9);
            seen++;
        }
    assert_int_equal(seen, 2);
    rod_crit_curve_free(&fold);
    rod_crit_curve_free(&pf);
    rod_boundary_free(b);
}

static void test_truss_codim2(void **state)
{
    (void)state;
    truss_cont_opts o = truss_cont_opts_default();
    const double alphas[3] = {0.1, 0.03, 0.01};
    double prev_err = INFINITY;
    for (int a = 0; a < 3; a++) {
        truss_params p = truss_params_default();
        p.alpha = alphas[a];
        double star = truss_analytic_l2_star(p.lambda);
        /* Closed form: at L2* the small-angle pitchfork and saddle-node coincide. */
        assert_close(truss_analytic_psi_pf(star), truss_analytic_psi_sn(p.lambda), 1e-12);
        p.l2 = star;
        truss_codim2 c;
        assert_int_equal(truss_codim2_find(&p, &o, &c), TRUSS_OK);
        double sw;
        assert_int_equal(truss_switch_find(&p, &o, 0.3, 0.9, 1e-9, &sw), TRUSS_OK);
        double err = fabs(c.l2 - star);
        print_message("alpha %g: codim-2 L2 %.8f, switch %.8f, analytic L2* %.8f (|diff| %.2e, / alpha^2 %.3f)\n",
                      p.alpha, c.l2, sw, star, err, err / (p.alpha * p.alpha));
        assert_close(c.l2, sw, 1e-4);
        assert_true(fabs(c.eig_sym) < 1e-10 && fabs(c.eig_anti) < 1e-10);
        /* The full model tends to the small-angle L2* as alpha^2. */
        assert_true(err < 0.3 * p.alpha * p.alpha);
        assert_true(err < prev_err);
        prev_err = err;
    }
}

int main(void)
{
    gsl_set_error_handler_off();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mirror_commutes),
        cmocka_unit_test(test_test_function_derivatives),
        cmocka_unit_test(test_codim2_and_phi),
        cmocka_unit_test(test_direct_codim2),
        cmocka_unit_test(test_phase1_cap),
        cmocka_unit_test(test_quadratic_predictor),
        cmocka_unit_test(test_dw_runs_to_zero),
        cmocka_unit_test(test_curves_through_continue_events),
        cmocka_unit_test(test_truss_codim2),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
