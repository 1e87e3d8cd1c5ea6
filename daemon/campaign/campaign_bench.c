/* campaign_bench.c: the simulated campaign (campaign_bench.h): truth and model traced at the
 * design phi, then specimen after specimen proposed by campaign_plan_run and measured on a twin. */
#include "campaign_bench.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "campaign_edge.h"
#include "campaign_plan.h"
#include "rod_bifurcation.h"
#include "rod_boundary.h"
#include "rod_protocol.h"

campaign_bench_opts campaign_bench_opts_default(void)
{
    campaign_bench_opts o = {.phi_deg = {60, 90, 120}, .nphi = 3, .relax_deg = 6, .twin_stiffness_factor = 3,
                             .spread = 0.01, .max_specimens = 15, .stop_width = 0.005, .seed = 1, .calibrate = 1};
    return o;
}

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* xorshift32 in [0, 1): the bench's own, so a seed means the same bench everywhere. */
static double uniform(unsigned *s)
{
    unsigned x = *s;
    x ^= x << 13;
    x ^= x >> 17;
    x ^= x << 5;
    *s = x;
    return (double)(x >> 8) / 16777216.0;
}

/* Gamma* of sc at each phi_deg[k] (ascending order not required), exactly: the codim-2 point
 * moved to each angle from the start. */
static int trace_at(const rod_scene *sc, const double *phi, size_t n, double *gamma, char *why, size_t why_len)
{
    rod_boundary_opts bo = rod_boundary_opts_default();
    rod_boundary *b = NULL;
    rod_codim2_point p;
    if (rod_boundary_start(sc, &bo, &b, &p, why, why_len) != ROD_OK) {
        rod_boundary_free(b);
        return -1;
    }
    rod_boundary_mark(b);
    for (size_t k = 0; k < n; k++) {
        rod_boundary_return(b);
        rod_boundary_curve part = {0};
        if (fabs(phi[k] - p.phi_deg) > 1e-12 && rod_boundary_move(b, ROD_PAR_PHI, phi[k], &part) != ROD_OK) {
            snprintf(why, why_len, "tracing the boundary to phi %g deg: %s", phi[k], part.end_reason);
            rod_boundary_curve_free(&part);
            rod_boundary_free(b);
            return -1;
        }
        rod_boundary_curve_free(&part);
        rod_codim2_point c;
        rod_boundary_current(b, &c);
        gamma[k] = c.gamma;
    }
    rod_boundary_free(b);
    return 0;
}

static double sign_of(double v)
{
    return v < 0 ? -1.0 : 1.0;
}

/* The simulated snap's regime of scene t (rod_predict, fast): 1 asymmetric, 0 symmetric, -1 no
 * snap or failed (why set). */
static int snap_regime(const rod_scene *t, char *why, size_t why_len)
{
    rod_predict_opts po = rod_predict_opts_fast(t);
    rod_prediction p;
    if (rod_predict(t, &po, &p, why, why_len) != ROD_OK) return -1;
    if (!p.snapped) {
        snprintf(why, why_len, "no snap up to Delta W %g at phi %g, Gamma %.4f", t->shear_max, fabs(t->fold_angle_deg),
                 t->fold_position);
        return -1;
    }
    return p.asymmetric ? 1 : 0;
}

/* Bracket and bisection tolerance of the dynamic truth (Gamma). */
#define DYN_TRUTH_BRACKET 0.04
#define DYN_TRUTH_TOL 5e-4

/* The dynamic switch of the twins' mean strip at crease angle phi (deg), bisected from
 * [g0 - DYN_TRUTH_BRACKET, g0 + DYN_TRUTH_BRACKET] (g0 its static Gamma*), into *g. */
static int dynamic_truth(const rod_scene *twin, double phi, double g0, double *g, char *why, size_t why_len)
{
    rod_scene t = *twin;
    t.fold_angle_deg = (twin->fold_angle_deg < 0 ? -1.0 : 1.0) * phi;
    double lo = g0 - DYN_TRUTH_BRACKET, hi = g0 + DYN_TRUTH_BRACKET;
    t.fold_position = lo;
    int rl = snap_regime(&t, why, why_len);
    t.fold_position = hi;
    int rh = snap_regime(&t, why, why_len);
    if (rl != 1 || rh != 0) {
        snprintf(why, why_len, "the twins' dynamic switch at phi %g is not bracketed by Gamma %.4f (%s) .. %.4f (%s)", phi,
                 lo, rl == 1 ? "asymmetric" : rl == 0 ? "symmetric" : "failed", hi,
                 rh == 1 ? "asymmetric" : rh == 0 ? "symmetric" : "failed");
        return -1;
    }
    for (int k = 0; k < 20 && hi - lo > DYN_TRUTH_TOL; k++) {
        t.fold_position = 0.5 * (lo + hi);
        int r = snap_regime(&t, why, why_len);
        if (r < 0) return -1;
        if (r) lo = t.fold_position;
        else hi = t.fold_position;
    }
    *g = 0.5 * (lo + hi);
    return 0;
}

void campaign_bench_draw(unsigned *rng, double spread, double base_deg, campaign_twin_draw *d)
{
    d->ul = (2 * uniform(rng) - 1) * spread;
    d->ur = (2 * uniform(rng) - 1) * spread;
    d->mean_deg = base_deg * (1 + 0.5 * (d->ul + d->ur));
    d->rel = (d->ul - d->ur) / (1 + 0.5 * (d->ul + d->ur));
}

int campaign_bench_trace(const rod_scene *sc, const double *phi, size_t n, double *gamma, char *why, size_t why_len)
{
    return trace_at(sc, phi, n, gamma, why, why_len);
}

int campaign_bench_dynamic_switch(const rod_scene *mean, double phi, double g0, double *g, char *why, size_t why_len)
{
    return dynamic_truth(mean, phi, g0, g, why, why_len);
}

/* The twin folded at (phi, gamma): 1 asymmetric, 0 symmetric, -1 failed or neither. */
static int measure(const rod_scene *scene, const campaign_bench_opts *o, double phi, double gamma, unsigned *rng,
                   double *angle, char *why, size_t why_len)
{
    rod_scene t = *scene;
    campaign_twin_draw d;
    campaign_bench_draw(rng, o->spread, phi - o->relax_deg, &d);
    double mean = d.mean_deg;
    *angle = mean;
    t.fold_angle_deg = sign_of(scene->fold_angle_deg) * mean;
    t.fold_angle_left_deg = t.fold_angle_right_deg = NAN;
    t.fold_position_left = t.fold_position_right = NAN;
    t.fold_position = gamma;
    t.fold_stiffness_factor = o->twin_stiffness_factor;
    if (o->twin_hinge > 0) t.fold_hinge_stiffness = o->twin_hinge;
    t.fold_angle_rel = d.rel;
    if (o->dynamic) return snap_regime(&t, why, why_len);
    rod_analysis_opts ao = rod_analysis_opts_classify();
    rod_analysis a;
    if (rod_bifurcation_analyse(&t, &ao, &a, why, why_len) != ROD_OK) return -1;
    int r = !strcmp(a.regime, "asymmetric") ? 1 : !strcmp(a.regime, "symmetric") ? 0 : -1;
    if (r < 0) snprintf(why, why_len, "the twin at phi %g, Gamma %.4f classified '%s'", phi, gamma, a.regime);
    rod_analysis_free(&a);
    return r;
}

int campaign_bench_run(const rod_scene *scene, const campaign_bench_opts *o, campaign_bench_result *r,
                       void (*progress)(void *u, const char *line), void *u, char *why, size_t why_len)
{
    memset(r, 0, sizeof *r);
    double t0 = now_s();
    size_t n = o->nphi;
    if (n < 1 || n > CAMPAIGN_BENCH_MAX_PHI || o->max_specimens < 1) {
        snprintf(why, why_len, "bench: 1..%d phi values and at least one specimen", CAMPAIGN_BENCH_MAX_PHI);
        return -1;
    }
    rod_scene twin = *scene;
    twin.fold_stiffness_factor = o->twin_stiffness_factor;
    if (o->twin_hinge > 0) twin.fold_hinge_stiffness = o->twin_hinge;
    double relaxed[CAMPAIGN_BENCH_MAX_PHI];
    for (size_t j = 0; j < n; j++) relaxed[j] = o->phi_deg[j] - o->relax_deg;
    char w[600];
    if (trace_at(&twin, relaxed, n, r->truth, w, sizeof w)) {
        snprintf(why, why_len, "the twins' true boundary: %s", w);
        return -1;
    }
    for (size_t j = 0; o->dynamic && j < n; j++)
        if (dynamic_truth(&twin, relaxed[j], r->truth[j], &r->truth[j], w, sizeof w)) {
            snprintf(why, why_len, "the twins' dynamic boundary: %s", w);
            return -1;
        }
    if (trace_at(scene, o->phi_deg, n, r->predicted, w, sizeof w)) {
        snprintf(why, why_len, "the model's boundary: %s", w);
        return -1;
    }
    campaign_obs *obs = r->obs;
    size_t nobs = 0;
    unsigned rng = o->seed ? o->seed : 1;
    campaign_plan_opts po = campaign_plan_opts_default();
    po.calibrate = o->calibrate;
    campaign_belief beliefs[CAMPAIGN_BENCH_MAX_PHI];
    campaign_proposal prop;
    campaign_plan_result res = {.beliefs = beliefs, .proposals = &prop};
    for (;;) {
        /* done? every phi's experimental interval closed and narrow */
        int done = 1;
        for (size_t j = 0; j < n; j++) {
            campaign_edge e;
            campaign_edge_fit(obs, nobs, o->phi_deg[j], &e);
            if (!(e.method == CAMPAIGN_EDGE_BRACKET || e.method == CAMPAIGN_EDGE_PROBIT) || !(e.hi - e.lo <= o->stop_width))
                done = 0;
        }
        if (done) {
            r->converged = 1;
            break;
        }
        if (r->specimens >= o->max_specimens) break;
        if (campaign_plan_run(o->phi_deg, r->predicted, n, obs, nobs, &po, 1, &res, why, why_len)) return -1;
        double t1 = now_s();
        double angle = NAN;
        int reg = measure(scene, o, prop.phi_deg, prop.gamma, &rng, &angle, w, sizeof w);
        r->classify_s += now_s() - t1;
        if (reg < 0) {
            snprintf(why, why_len, "measuring specimen %d: %s", r->specimens + 1, w);
            return -1;
        }
        size_t k = 0;
        while (k < nobs && !(obs[k].phi_deg == prop.phi_deg && obs[k].gamma == prop.gamma)) k++;
        if (k == nobs) {
            if (nobs == sizeof r->obs / sizeof r->obs[0]) break;
            obs[nobs++] = (campaign_obs){.phi_deg = prop.phi_deg, .gamma = prop.gamma};
        }
        if (reg) obs[k].n_asym++;
        else obs[k].n_sym++;
        obs[k].n_specimens++;
        if (r->specimens < 64) r->order[r->specimens] = (int)k;
        r->nobs = nobs;
        r->specimens++;
        for (size_t j = 0; j < n; j++)
            if (o->phi_deg[j] == prop.phi_deg) r->per_phi[j]++;
        if (progress) {
            char line[200];
            snprintf(line, sizeof line, "specimen %d: phi %g Gamma %.5f (twin's creases %.3f deg) -> %s (offset %+.4f)",
                     r->specimens, prop.phi_deg, prop.gamma, angle, reg ? "asymmetric" : "symmetric", res.offset_mean);
            progress(u, line);
        }
    }
    /* the located boundary */
    if (campaign_plan_run(o->phi_deg, r->predicted, n, obs, nobs, &po, 0, &res, why, why_len)) return -1;
    r->offset_mean = res.offset_mean;
    for (size_t j = 0; j < n; j++) {
        campaign_edge e;
        campaign_edge_fit(obs, nobs, o->phi_deg[j], &e);
        r->located[j] = isfinite(e.gamma) ? e.gamma : beliefs[j].median;
        double err = fabs(r->located[j] - r->truth[j]);
        if (err > r->max_error) r->max_error = err;
    }
    r->wall_s = now_s() - t0;
    return 0;
}
