/* test_regime_rule: the regime read from a snap is the pathway the twin really took, for
 * specimens whose creases differ by up to 5%, both in the simulator's classification
 * (rod_predict) and in the trial's snap detector (snap_detect) on camera frames with the
 * tracker's noise (issue 31 B; the rule: sim/rod_regime.h).
 *
 * The truth uses no threshold on A: the same twin is run again with half the crease difference,
 * and the exponent of the peak |A| in the difference, log2(peak(rel) / peak(rel / 2)), is about 1
 * on the symmetric pathway (A is the linear response to the imperfection) and about 0 on the
 * asymmetric one (the antisymmetric mode grew by itself). Each case first checks that its truth
 * is clear (exponent >= 0.8 or <= 0.2), then the rule.
 *
 * The frames: the twin's A_cam (the side view the tracker measures) and Delta Z at the camera's
 * frame rate, each of NOISY runs with its own random frame phase and Gaussian noise of 0.015 rad
 * RMS on A (the tracker's error on A, docs/vision.md), through snap_detect with the scene's
 * snap.speed and asym_threshold. Every run must read the true pathway.
 *
 * `test_regime_rule table [fps]` prints the table of docs/simulator.md "The regime rule"
 * (3 scenes x 7 Gamma x 5 crease differences, a few minutes); it is not a ctest. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rod_protocol.h"
#include "rod_regime.h"
#include "scene_file.h"
#include "trial.h"

#define SIGMA_A 0.015 /* rad RMS, the tracker's error on A */
#define NOISY 50      /* noisy runs per case */

typedef struct twin_rec {
    double t, dw, dz, a_cam;
} twin_rec;

typedef struct twin_run {
    twin_rec *r;
    size_t n, cap;
    int failed; /* out of memory while recording */
} twin_run;

static int record(void *user, const rod_sample *s, const rod *r)
{
    (void)r;
    twin_run *b = user;
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 4096;
        twin_rec *p = realloc(b->r, cap * sizeof *p);
        if (!p) {
            b->failed = 1;
            return 1;
        }
        b->r = p;
        b->cap = cap;
    }
    b->r[b->n++] = (twin_rec){s->t, s->dw, s->dz, s->a_cam};
    return 0;
}

/* The twin: the fast prediction's stepping, followed for 1 s after the snap is detected (the
 * detector's window: the ribbon settles within it). Records every step when b is not NULL. */
static rod_prediction twin(const rod_scene *sc, twin_run *b)
{
    rod_predict_opts o = rod_predict_opts_fast(sc);
    o.end_after_swing = 0;
    o.post_snap_time = 1.0;
    o.post_snap_dt_max = 0.0;
    o.on_sample = b ? record : NULL;
    o.user = b;
    rod_prediction p;
    char why[256] = "";
    rod_status st = rod_predict(sc, &o, &p, why, sizeof why);
    if (st != ROD_OK || (b && b->failed)) print_error("prediction failed: %s\n", why);
    assert_int_equal(st, ROD_OK);
    assert_true(p.snapped);
    return p;
}

static rod_scene scene(const char *file, double gamma, double rel)
{
    char path[512], g[64], r[64];
    snprintf(path, sizeof path, "%s/config/scenes/%s", RIBBON_SOURCE_DIR, file);
    snprintf(g, sizeof g, "folds.position=%.17g", gamma);
    snprintf(r, sizeof r, "imperfection.fold_angle_rel=%.17g", rel);
    const char *ov[] = {"mesh.nodes=61", g, r};
    rod_scene sc;
    cfg_error err;
    if (cfg_scene_load(path, ov, 3, &sc, &err) != CFG_OK) print_error("%s: %s\n", path, err.message);
    assert_int_equal(cfg_scene_load(path, ov, 3, &sc, &err), CFG_OK);
    return sc;
}

/* A uniform deviate in (0, 1) and a Gaussian one (Box-Muller), from a 64-bit LCG. */
static double uniform(unsigned long long *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return ((double)(*s >> 11) + 0.5) / 9007199254740992.0;
}
static double gauss(unsigned long long *s)
{
    double u1 = uniform(s), u2 = uniform(s);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * 3.14159265358979323846 * u2);
}

/* One camera's view of the twin: frames at fps from a phase in [0, 1/fps), A with noise sigma,
 * through the trial's detector with the scene's parameters. */
static snap_detect watch(const rod_scene *sc, const twin_run *b, double fps, double sigma, unsigned long long seed)
{
    snap_params sp = snap_params_default();
    sp.snap_speed = sc->snap_speed;
    sp.asym_threshold = sc->asym_threshold;
    snap_detect d;
    snap_detect_init(&d, &sp);
    unsigned long long rs = seed * 2654435761ULL + 12345ULL;
    double t0 = b->r[0].t + (seed ? uniform(&rs) / fps : 0.0);
    size_t j = 0;
    for (long k = 0;; k++) {
        double t = t0 + (double)k / fps;
        while (j + 1 < b->n && b->r[j + 1].t < t) j++;
        if (j + 1 >= b->n) break;
        const twin_rec *p = &b->r[j], *q = &b->r[j + 1];
        double w = (t - p->t) / (q->t - p->t);
        double dz = p->dz + w * (q->dz - p->dz), dw = p->dw + w * (q->dw - p->dw);
        double a = p->a_cam + w * (q->a_cam - p->a_cam) + (seed ? sigma * gauss(&rs) : 0.0);
        if (snap_detect_add(&d, k, t, dw, dz, a, 1) == SNAP_DONE) break;
    }
    return d;
}

typedef struct case_result {
    double exponent;         /* of the peak |A| in the crease difference */
    double peak;             /* the simulator's peak |A| */
    int sim_asym;            /* the simulator's regime */
    double frames_min, frames_max; /* measured peak |A| over the noisy runs */
    int frames_asym, frames_sym, frames_none;
} case_result;

static case_result run_case(const char *file, double gamma, double rel, double fps)
{
    case_result c;
    memset(&c, 0, sizeof c);
    rod_scene sc = scene(file, gamma, rel), half = scene(file, gamma, 0.5 * rel);
    twin_run b = {0};
    rod_prediction p = twin(&sc, &b), ph = twin(&half, NULL);
    c.exponent = log2(p.peak_abs_a / ph.peak_abs_a);
    c.peak = p.peak_abs_a;
    c.sim_asym = p.asymmetric;
    c.frames_min = INFINITY;
    for (unsigned long long s = 1; s <= NOISY; s++) {
        snap_detect d = watch(&sc, &b, fps, SIGMA_A, s);
        if (!snap_detect_snapped(&d)) {
            c.frames_none++;
            continue;
        }
        c.frames_min = fmin(c.frames_min, d.peak_abs_a);
        c.frames_max = fmax(c.frames_max, d.peak_abs_a);
        if (snap_detect_asymmetric(&d)) c.frames_asym++;
        else c.frames_sym++;
    }
    free(b.r);
    return c;
}

typedef struct regime_case {
    const char *scene;
    double gamma, rel, fps;
    int asymmetric; /* the true pathway */
} regime_case;

/* The rig's cameras run at 60 fps (config/rig-*.ini). */
static const regime_case cases[] = {
    {"mock-gamma013.ini", 0.21, 0.03, 60, 0}, {"mock-gamma013.ini", 0.21, 0.05, 60, 0},
    {"mock-gamma013.ini", 0.13, 0.03, 60, 1}, {"mock-gamma013.ini", 0.13, 0.05, 60, 1},
    /* next to the boundary (Gamma* = 0.1755 at N = 61): a 1% difference snaps asymmetrically;
     * with 1e-6 the pitchfork comes first but its mode has no time to grow before the
     * saddle-node, so the snap is symmetric */
    {"mock-gamma013.ini", 0.175, 0.01, 60, 1}, {"mock-gamma013.ini", 0.175, 1e-6, 60, 0},
    {"pet-200x5.ini", 0.21, 0.05, 60, 0},      {"pet-200x5.ini", 0.13, 0.05, 60, 1},
};

static void case_reads_its_pathway(void **state)
{
    const regime_case *k = *state;
    case_result c = run_case(k->scene, k->gamma, k->rel, k->fps);
    printf("%-18s Gamma %.3f rel %-6g: exponent %5.2f (truth %s), simulator peak |A| %.4f -> %s; "
           "frames at %g fps: peak |A| %.4f .. %.4f, %d asymmetric, %d symmetric, %d no snap\n",
           k->scene, k->gamma, k->rel, c.exponent, k->asymmetric ? "asymmetric" : "symmetric", c.peak,
           c.sim_asym ? "asymmetric" : "symmetric", k->fps, c.frames_min, c.frames_max, c.frames_asym, c.frames_sym,
           c.frames_none);
    /* The truth is clear, and the one the table says. */
    assert_true(k->asymmetric ? c.exponent <= 0.2 : c.exponent >= 0.8);
    assert_int_equal(c.sim_asym, k->asymmetric);
    assert_int_equal(c.frames_none, 0);
    assert_int_equal(k->asymmetric ? c.frames_asym : c.frames_sym, NOISY);
}

/* The rule itself: a threshold on the peak, never a pathway from a non-finite value. */
static void rule_edges(void **state)
{
    (void)state;
    assert_true(ROD_REGIME_ASYM_THRESHOLD == 0.5);
    assert_true(rod_regime_asymmetric(0.51, 0.5));
    assert_false(rod_regime_asymmetric(0.5, 0.5));
    assert_false(rod_regime_asymmetric(NAN, 0.5));
    assert_false(rod_regime_asymmetric(INFINITY, 0.5));
    snap_params p = snap_params_default();
    assert_true(p.asym_threshold == ROD_REGIME_ASYM_THRESHOLD);
    assert_true(rod_scene_default().asym_threshold == ROD_REGIME_ASYM_THRESHOLD);
}

/* The docs' table: every scene, Gamma and crease difference. */
static int table(double fps)
{
    static const char *files[] = {"paper-gamma021.ini", "mock-gamma013.ini", "pet-200x5.ini"};
    static const double gammas[][7] = {{0.13, 0.16, 0.17, 0.175, 0.18, 0.19, 0.21},
                                       {0.13, 0.16, 0.17, 0.175, 0.18, 0.19, 0.21},
                                       {0.13, 0.15, 0.17, 0.18, 0.19, 0.21, 0.23}};
    static const double rels[] = {1e-6, 0.01, 0.02, 0.03, 0.05};
    printf("scene,gamma,rel,exponent,peak_abs_a,sim_regime,fps,frames_peak_min,frames_peak_max,frames_asym,"
           "frames_sym,frames_none\n");
    for (int f = 0; f < 3; f++)
        for (int g = 0; g < 7; g++)
            for (int r = 0; r < 5; r++) {
                case_result c = run_case(files[f], gammas[f][g], rels[r], fps);
                printf("%s,%g,%g,%.2f,%.4f,%s,%g,%.4f,%.4f,%d,%d,%d\n", files[f], gammas[f][g], rels[r], c.exponent,
                       c.peak, c.sim_asym ? "asymmetric" : "symmetric", fps, c.frames_min, c.frames_max,
                       c.frames_asym, c.frames_sym, c.frames_none);
                fflush(stdout);
            }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "table")) return table(argc >= 3 ? atof(argv[2]) : 60.0);
    enum { NC = sizeof cases / sizeof cases[0] };
    struct CMUnitTest tests[NC + 1];
    tests[0] = (struct CMUnitTest)cmocka_unit_test(rule_edges);
    for (int i = 0; i < NC; i++) {
        tests[i + 1] = (struct CMUnitTest)cmocka_unit_test_prestate(case_reads_its_pathway, (void *)&cases[i]);
        static char names[NC][96];
        snprintf(names[i], sizeof names[i], "%s Gamma %g rel %g", cases[i].scene, cases[i].gamma, cases[i].rel);
        tests[i + 1].name = names[i];
    }
    return cmocka_run_group_tests(tests, NULL, NULL);
}
