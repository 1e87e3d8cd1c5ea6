/* test_rod_derivatives: the analytic gradient and Hessian of every energy term against central
 * finite differences, on random configurations, with and without folds and gravity, and with
 * compliant hinges (rod_hinge.c) of unequal angles at unequal positions, the hinge term alone
 * and with the others.
 *
 * Frames at a perturbed state are parallel-transported from the base state, exactly as inside a
 * Newton iteration; the Hessian is compared with the symmetric part of the finite-difference
 * Jacobian of the gradient (see rod_bend.c for why the symmetric part). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rod.h"

typedef struct saved {
    double *q, (*d1)[3], (*d2)[3], (*tref)[3], *mref;
} saved;

static void save(const rod *r, saved *s)
{
    int n = r->n;
    s->q = malloc(sizeof(double) * (size_t)r->ndof);
    s->d1 = malloc(sizeof(double[3]) * (size_t)n);
    s->d2 = malloc(sizeof(double[3]) * (size_t)n);
    s->tref = malloc(sizeof(double[3]) * (size_t)n);
    s->mref = malloc(sizeof(double) * (size_t)n);
    memcpy(s->q, r->q, sizeof(double) * (size_t)r->ndof);
    memcpy(s->d1, r->d1, sizeof(double[3]) * (size_t)n);
    memcpy(s->d2, r->d2, sizeof(double[3]) * (size_t)n);
    memcpy(s->tref, r->tref, sizeof(double[3]) * (size_t)n);
    memcpy(s->mref, r->mref, sizeof(double) * (size_t)n);
}

static void restore(rod *r, const saved *s)
{
    int n = r->n;
    memcpy(r->q, s->q, sizeof(double) * (size_t)r->ndof);
    memcpy(r->d1, s->d1, sizeof(double[3]) * (size_t)n);
    memcpy(r->d2, s->d2, sizeof(double[3]) * (size_t)n);
    memcpy(r->tref, s->tref, sizeof(double[3]) * (size_t)n);
    memcpy(r->mref, s->mref, sizeof(double) * (size_t)n);
}

static void release(saved *s)
{
    free(s->q); free(s->d1); free(s->d2); free(s->tref); free(s->mref);
}

/* Deterministic PRNG (xorshift) so failures reproduce. */
static double urand(unsigned long long *st)
{
    *st ^= *st << 13; *st ^= *st >> 7; *st ^= *st << 17;
    return (double)(*st >> 11) / 9007199254740992.0;
}

static rod *random_rod_scene(rod_scene s, unsigned long long seed);

static rod *random_rod(double fold_deg, int gravity, unsigned long long seed)
{
    rod_scene s = rod_scene_default();
    s.nodes = 11;
    s.fold_angle_deg = fold_deg;
    s.fold_position = 0.25;
    s.fold_stiffness_factor = 10.0;
    s.compression = 0.3;
    if (gravity) s.gravity[2] = -9.81;
    return random_rod_scene(s, seed);
}

static rod *random_rod_scene(rod_scene s, unsigned long long seed)
{
    rod *r = NULL;
    char err[256];
    assert_int_equal(rod_alloc(&s, &r, err, sizeof err), ROD_OK);
    rod_set_clamps(r, 0.2, 0.05);
    /* Large random displacements of the free nodes and angles, moved in a few transported
     * steps so the frames and reference twist are generic. */
    double h = r->length / (r->n - 3);
    unsigned long long st = seed;
    double *target = malloc(sizeof(double) * (size_t)r->ndof);
    memcpy(target, r->q, sizeof(double) * (size_t)r->ndof);
    for (int k = ROD_FREE_BEGIN; k < r->free_end; k++) {
        if (k % 4 == 3) target[k] += 1.0 * (urand(&st) - 0.5);
        else target[k] += 0.6 * h * (urand(&st) - 0.5) + (k % 4 == 2 ? 0.3 * h : 0.0);
    }
    for (int step = 1; step <= 5; step++) {
        for (int k = ROD_FREE_BEGIN; k < r->free_end; k++)
            r->q[k] = r->q[k] + (target[k] - r->q[k]) / (6 - step);
        rod_frames_update(r);
    }
    free(target);
    return r;
}

static void check_gradient(rod *r)
{
    int nd = r->ndof;
    saved base;
    save(r, &base);
    double *g = malloc(sizeof(double) * (size_t)nd);
    rod_gradient(r, g);
    double gmax = 0.0;
    for (int k = 0; k < nd; k++) gmax = fmax(gmax, fabs(g[k]));
    double worst = 0.0;
    for (int k = 0; k < nd; k++) {
        double hk = (k % 4 == 3) ? 1e-6 : 1e-6 * r->length;
        restore(r, &base);
        r->q[k] += hk;
        rod_frames_update(r);
        double ep = rod_energy(r);
        restore(r, &base);
        r->q[k] -= hk;
        rod_frames_update(r);
        double em = rod_energy(r);
        double fd = (ep - em) / (2 * hk);
        double err = fabs(fd - g[k]) / gmax;
        if (err > worst) worst = err;
    }
    restore(r, &base);
    print_message("gradient: worst relative error %.3e (max |g| %.3e)\n", worst, gmax);
    assert_true(worst < 1e-6);
    free(g);
    release(&base);
}

static void check_hessian(rod *r)
{
    int nd = r->ndof, nf = rod_nfree(r), w = ROD_BAND + 1;
    saved base;
    save(r, &base);
    double *H = calloc((size_t)nf * (size_t)w, sizeof(double));
    rod_hessian_add(r, 1.0, H);
    double *J = calloc((size_t)nf * (size_t)nf, sizeof(double));
    double *gp = malloc(sizeof(double) * (size_t)nd), *gm = malloc(sizeof(double) * (size_t)nd);
    for (int a = 0; a < nf; a++) {
        int k = a + ROD_FREE_BEGIN;
        double hk = (k % 4 == 3) ? 1e-6 : 1e-6 * r->length;
        restore(r, &base);
        r->q[k] += hk;
        rod_frames_update(r);
        rod_gradient(r, gp);
        restore(r, &base);
        r->q[k] -= hk;
        rod_frames_update(r);
        rod_gradient(r, gm);
        for (int b = 0; b < nf; b++)
            J[b * nf + a] = (gp[b + ROD_FREE_BEGIN] - gm[b + ROD_FREE_BEGIN]) / (2 * hk);
    }
    restore(r, &base);
    double hmax = 0.0;
    for (int i = 0; i < nf * w; i++) hmax = fmax(hmax, fabs(H[i]));
    double worst = 0.0, outside = 0.0;
    int wa = -1, wb = -1;
    for (int a = 0; a < nf; a++)
        for (int b = a; b < nf; b++) {
            double fd = 0.5 * (J[a * nf + b] + J[b * nf + a]);
            double an = (b - a <= ROD_BAND) ? H[a * w + (b - a)] : 0.0;
            /* Scale each entry by its row and column magnitudes (stretch dwarfs the rest). */
            double sc = sqrt(fabs(H[a * w]) * fabs(H[b * w])) + 1e-12 * hmax;
            double err = fabs(fd - an) / sc;
            if (b - a > ROD_BAND) outside = fmax(outside, fabs(fd) / sc);
            if (err > worst) { worst = err; wa = a; wb = b; }
        }
    print_message("hessian: worst scaled error %.3e at (%d, %d); outside band %.3e\n", worst, wa + ROD_FREE_BEGIN,
                  wb + ROD_FREE_BEGIN, outside);
    assert_true(worst < 1e-5);
    assert_true(outside < 1e-7);
    free(H); free(J); free(gp); free(gm);
    release(&base);
}

/* Each term alone, so a small term's error is not hidden under the stiff stretching term. */
static void check_each_term(rod *r)
{
    rod_terms all = r->terms;
    const char *names[3] = {"stretch", "bend", "twist"};
    for (int t = 0; t < 3; t++) {
        r->terms.stretch = t == 0;
        r->terms.bend = t == 1;
        r->terms.twist = t == 2;
        r->terms.gravity = 0;
        print_message("-- %s alone\n", names[t]);
        check_gradient(r);
        check_hessian(r);
    }
    r->terms = all;
    print_message("-- all terms\n");
    check_gradient(r);
    check_hessian(r);
}

static void test_no_folds(void **state)
{
    (void)state;
    rod *r = random_rod(0.0, 0, 88172645463325252ULL);
    check_each_term(r);
    rod_free(r);
}

static void test_with_folds(void **state)
{
    (void)state;
    rod *r = random_rod(90.0, 0, 1234567ULL);
    assert_true(r->terms.fold);
    check_each_term(r);
    rod_free(r);
}

static void test_with_folds_and_gravity(void **state)
{
    (void)state;
    rod *r = random_rod(-60.0, 1, 987654321ULL);
    assert_true(r->terms.gravity);
    check_gradient(r);
    check_hessian(r);
    rod_free(r);
}

/* Compliant hinges: k = 0.05 N m/rad against the strip's E I1 / v = 0.13 N m/rad at N = 11, so
 * both parts of k_eff matter; unequal angles (60 and 75 deg) at unequal positions (0.2, 0.7);
 * the random state turns each crease node far from its rest angle. The hinge term alone (every
 * other term off: the kappa1 part of the crease nodes only), then with everything. */
static void test_with_hinges(void **state)
{
    (void)state;
    rod_scene s = rod_scene_default();
    s.nodes = 11;
    s.fold_angle_deg = 60.0;
    s.fold_angle_right_deg = 75.0;
    s.fold_position_left = 0.2;
    s.fold_position_right = 0.7;
    s.fold_hinge_stiffness = 0.05;
    s.compression = 0.3;
    s.gravity[2] = -9.81;
    rod *r = random_rod_scene(s, 42424242ULL);
    assert_true(r->terms.hinge && !r->terms.fold);
    assert_true(r->fold_node[0] > 1 && r->fold_node[1] > r->fold_node[0] && r->fold_node[1] < r->n - 2);
    rod_terms all = r->terms;
    r->terms = (rod_terms){0};
    r->terms.hinge = 1;
    print_message("-- hinge alone\n");
    double e = rod_energy(r);
    print_message("hinge energy %.6e J\n", e);
    assert_true(e > 0.0);
    check_gradient(r);
    check_hessian(r);
    r->terms = all;
    print_message("-- all terms\n");
    check_gradient(r);
    check_hessian(r);
    rod_free(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_with_hinges),
        cmocka_unit_test(test_no_folds),
        cmocka_unit_test(test_with_folds),
        cmocka_unit_test(test_with_folds_and_gravity),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
