/* test_paper_regimes: the paper's two regimes through the full simulated protocol, their
 * robustness to the imperfection, exact symmetry without imperfection, and independence of the
 * route to the upper state.
 *
 * Runs on a coarsened paper scene (N = 61, dt = 10 ms, fast mode) so the whole file takes
 * seconds; the regimes are the paper's claim at N = 201 as well (README "Numbers"). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>

#include "rod_observe.h"
#include "rod_protocol.h"
#include "rod_route.h"
#include "rod_solver.h"

static rod_scene coarse_paper(double gamma, double rel)
{
    rod_scene s = rod_scene_default();
    s.fold_position = gamma;
    s.fold_angle_rel = rel;
    s.nodes = 61;
    s.dt = 0.01;
    s.shear_max = 0.6;
    return s;
}

static rod_prediction predict(const rod_scene *s, rod_predict_opts *o)
{
    rod_prediction p;
    char err[512] = "";
    rod_predict_opts def = rod_predict_opts_default();
    def.adaptive = 1;
    rod_status st = rod_predict(s, o ? o : &def, &p, err, sizeof err);
    if (st != ROD_OK) print_message("predict failed: %s\n", err);
    assert_int_equal(st, ROD_OK);
    return p;
}

static void test_regimes_over_imperfections(void **state)
{
    (void)state;
    const double rels[] = {1e-8, 1e-6, 1e-4};
    for (int k = 0; k < 3; k++) {
        rod_scene a = coarse_paper(0.13, rels[k]), b = coarse_paper(0.21, rels[k]);
        rod_prediction pa = predict(&a, NULL), pb = predict(&b, NULL);
        print_message("rel %.0e: Gamma 0.13 snap %.4f peak|A| %.3f (%s); Gamma 0.21 snap %.4f peak|A| %.2e (%s)\n",
                      rels[k], pa.snap_dw, pa.peak_abs_a, pa.asymmetric ? "asym" : "sym", pb.snap_dw,
                      pb.peak_abs_a, pb.asymmetric ? "asym" : "sym");
        assert_true(pa.snapped && pb.snapped);
        assert_true(pa.asymmetric);
        assert_false(pb.asymmetric);
        assert_true(pa.dz_final < 0.0 && pb.dz_final < 0.0);
    }
}

typedef struct amax {
    double max_abs_a;
    double speed_limit;
    double dz_prev, t_prev;
} amax;

static int track_a(void *user, const rod_sample *s, const rod *r)
{
    (void)r;
    amax *m = user;
    double speed = m->t_prev >= 0 ? fabs(s->dz - m->dz_prev) / (s->t - m->t_prev) : 0.0;
    m->dz_prev = s->dz;
    m->t_prev = s->t;
    if (speed > m->speed_limit) return 1; /* the snap has begun: stop */
    if (fabs(s->a) > m->max_abs_a) m->max_abs_a = fabs(s->a);
    return 0;
}

/* Without imperfection the scene and the loading are exactly C2-symmetric: A stays at round-off
 * up to the first instability. */
static void test_symmetry_without_imperfection(void **state)
{
    (void)state;
    rod_scene s = coarse_paper(0.13, 0.0);
    s.shear_max = 0.4; /* below the instability */
    amax m = {0, 0.1, 0, -1};
    rod_predict_opts o = rod_predict_opts_default();
    o.adaptive = 1;
    o.on_sample = track_a;
    o.user = &m;
    rod_prediction p = predict(&s, &o);
    print_message("max |A| up to Delta W = %.3f without imperfection: %.3e\n", s.shear_max, m.max_abs_a);
    assert_false(p.snapped);
    assert_true(m.max_abs_a < 1e-8);
    /* ...and the imperfection is what breaks it. */
    rod_scene t = coarse_paper(0.13, 1e-4);
    t.shear_max = 0.4;
    amax n = {0, 0.1, 0, -1};
    o.user = &n;
    predict(&t, &o);
    print_message("max |A| with imperfection 1e-4: %.3e\n", n.max_abs_a);
    assert_true(n.max_abs_a > 1e-7);
}

static void state_at(rod_route route, double *dz, double *energy, double *a)
{
    rod_scene s = coarse_paper(0.21, 1e-6);
    s.route = route;
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&s, &r, err, sizeof err), ROD_OK);
    rod_solver *sv = rod_solver_alloc(r);
    rod_route_report rep = {0};
    assert_int_equal(rod_route_to_state(r, sv, &s, +1, &rep), ROD_OK);
    double *k1 = malloc(sizeof(double) * (size_t)r->n);
    rod_obs ob;
    rod_observe(r, k1, &ob);
    *dz = ob.dz;
    *a = ob.a;
    *energy = rod_energy(r);
    free(k1);
    rod_solver_free(sv);
    rod_free(r);
}

static void test_route_independence(void **state)
{
    (void)state;
    double dz1, e1, a1, dz2, e2, a2;
    state_at(ROD_ROUTE_COMPRESS_THEN_FOLD, &dz1, &e1, &a1);
    state_at(ROD_ROUTE_TOGETHER, &dz2, &e2, &a2);
    print_message("compress-then-fold: dz %.9f E %.9f; together: dz %.9f E %.9f\n", dz1, e1, dz2, e2);
    assert_true(dz1 > 0.0);
    assert_true(fabs(dz1 - dz2) < 1e-6);
    assert_true(fabs(e1 - e2) < 1e-6 * fabs(e1));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_route_independence),
        cmocka_unit_test(test_symmetry_without_imperfection),
        cmocka_unit_test(test_regimes_over_imperfections),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
