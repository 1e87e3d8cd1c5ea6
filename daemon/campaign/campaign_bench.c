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
#include "rod_fit.h"
#include "rod_boundary.h"
#include "rod_protocol.h"

campaign_bench_opts campaign_bench_opts_default(void)
{
    campaign_bench_opts o = {.phi_deg = {60, 90, 120}, .nphi = 3, .relax_deg = 6, .twin_stiffness_factor = 3,
                             .spread = 0.01, .max_specimens = 15, .stop_width = 0.005, .seed = 1, .calibrate = 1,
                             .lab_strip = 1, .fit_hinge_start = NAN, .fit_sigma_dz = 0.002, .fit_sigma_a = 0.015,
                             .fit_shear_frac = 0.8};
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
static int snap_regime(const rod_scene *t, double *snap_dw, char *why, size_t why_len)
{
    rod_predict_opts po = rod_predict_opts_fast(t);
    rod_prediction p;
    if (rod_predict(t, &po, &p, why, why_len) != ROD_OK) return -1;
    if (snap_dw) *snap_dw = p.snap_dw;
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
    int rl = snap_regime(&t, NULL, why, why_len);
    t.fold_position = hi;
    int rh = snap_regime(&t, NULL, why, why_len);
    if (rl != 1 || rh != 0) {
        snprintf(why, why_len, "the twins' dynamic switch at phi %g is not bracketed by Gamma %.4f (%s) .. %.4f (%s)", phi,
                 lo, rl == 1 ? "asymmetric" : rl == 0 ? "symmetric" : "failed", hi,
                 rh == 1 ? "asymmetric" : rh == 0 ? "symmetric" : "failed");
        return -1;
    }
    for (int k = 0; k < 20 && hi - lo > DYN_TRUTH_TOL; k++) {
        t.fold_position = 0.5 * (lo + hi);
        int r = snap_regime(&t, NULL, why, why_len);
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

/* The twin folded at (phi, gamma) into *t: the scene with its creases relaxed and off at random
 * (campaign_bench_draw, the camera campaign's draws too), softer; *angle its mean crease angle. */
static void fold_twin(const rod_scene *scene, const campaign_bench_opts *o, double phi, double gamma, unsigned *rng,
                      rod_scene *t, double *angle)
{
    *t = *scene;
    campaign_twin_draw d;
    campaign_bench_draw(rng, o->spread, phi - o->relax_deg, &d);
    *angle = d.mean_deg;
    t->fold_angle_deg = sign_of(scene->fold_angle_deg) * d.mean_deg;
    t->fold_angle_left_deg = t->fold_angle_right_deg = NAN;
    t->fold_position_left = t->fold_position_right = NAN;
    t->fold_position = gamma;
    t->fold_stiffness_factor = o->twin_stiffness_factor;
    if (o->twin_hinge > 0) t->fold_hinge_stiffness = o->twin_hinge;
    t->fold_angle_rel = d.rel;
}

/* Twin t's regime: 1 asymmetric, 0 symmetric, -1 failed or neither. *dw_crit: Delta W of its first
 * instability (static) or snap (dynamic), where its calibration's shear stops short of. */
static int measure(const rod_scene *t, const campaign_bench_opts *o, double phi, double gamma, double *dw_crit,
                   char *why, size_t why_len)
{
    *dw_crit = NAN;
    if (o->dynamic) return snap_regime(t, dw_crit, why, why_len);
    rod_analysis_opts ao = rod_analysis_opts_classify();
    rod_analysis a;
    if (rod_bifurcation_analyse(t, &ao, &a, why, why_len) != ROD_OK) return -1;
    int r = !strcmp(a.regime, "asymmetric") ? 1 : !strcmp(a.regime, "symmetric") ? 0 : -1;
    if (r < 0) snprintf(why, why_len, "the twin at phi %g, Gamma %.4f classified '%s'", phi, gamma, a.regime);
    else if (a.first >= 0) *dw_crit = a.events[a.first].at.dw;
    rod_analysis_free(&a);
    return r;
}

/* A standard normal from the bench's generator (Box-Muller). */
static double normal(unsigned *s)
{
    double u1 = 1.0 - uniform(s), u2 = uniform(s);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * M_PI * u2);
}

#define FIT_N_COMPRESS 5
#define FIT_N_HOLD 5
#define FIT_N_SHEAR 8
#define FIT_NOBS (FIT_N_COMPRESS + FIT_N_HOLD + FIT_N_SHEAR)
#define FIT_PRIOR_ANGLE_DEG 10.0 /* as trial_calibrate.h's TRIAL_CALIBRATE_PRIOR_ANGLE_DEG */
#define FIT_HINGE_DEFAULT 3e-3   /* N m/rad, the hinge a lab starts from (docs/calibration.md's) */

/* The hinge the fits start from on this bench (0: rigid creases, angles only). */
static double fit_hinge(const rod_scene *scene, const campaign_bench_opts *o)
{
    if (!rod_scene_hinge_rigid(scene)) return scene->fold_hinge_stiffness;
    if (isnan(o->fit_hinge_start)) return o->twin_hinge > 0 ? FIT_HINGE_DEFAULT : 0;
    return o->fit_hinge_start > 0 ? o->fit_hinge_start : 0;
}

/* Twin t's calibration as a trial would make it (campaign_bench.h): its observables before the
 * snap with noise, fitted from the design's scene. 1 with *f filled, 0 when there is no usable
 * calibration (why): the fit gave none, or the twin's own states could not be followed (a trial
 * whose fit fails goes on without one). */
static int calibrate_twin(const rod_scene *scene, const rod_scene *t, const campaign_bench_opts *o, double phi,
                          double gamma, double dw_crit, unsigned *nrng, campaign_strip_fit *f, char *why,
                          size_t why_len)
{
    rod_fit_obs obs[FIT_NOBS];
    double c = scene->compression;
    double dw_stop = isfinite(dw_crit) && dw_crit > 0 ? o->fit_shear_frac * dw_crit : 0;
    int n = 0;
    for (int k = 0; k < FIT_N_COMPRESS; k++)
        obs[n++] = (rod_fit_obs){.dl = c - 0.05 + 0.05 * k / (FIT_N_COMPRESS - 1), .dw = 0};
    for (int k = 0; k < FIT_N_HOLD; k++) obs[n++] = (rod_fit_obs){.dl = c, .dw = 0};
    for (int k = 0; dw_stop > 0 && k < FIT_N_SHEAR; k++)
        obs[n++] = (rod_fit_obs){.dl = c, .dw = dw_stop * (k + 1) / FIT_N_SHEAR};
    rod_fit_model *m = NULL;
    double y[2 * FIT_NOBS], u[ROD_FIT_NKEYS];
    char w[400];
    if (rod_fit_model_alloc(t, obs, n, 0, &m, w, sizeof w) != ROD_OK) {
        snprintf(why, why_len, "the twin's observables: %s", w);
        return 0;
    }
    rod_fit_scene_values(t, u);
    rod_status st = rod_fit_model_eval(m, u, NULL, y, NULL, w, sizeof w);
    rod_fit_model_free(m);
    if (st != ROD_OK) {
        snprintf(why, why_len, "the twin's observables: %s", w);
        return 0;
    }
    for (int k = 0; k < n; k++) {
        obs[k].dz = y[2 * k] + o->fit_sigma_dz * normal(nrng);
        obs[k].a = y[2 * k + 1] + o->fit_sigma_a * normal(nrng);
    }
    rod_scene start = *scene;
    start.fold_angle_deg = sign_of(scene->fold_angle_deg) * phi;
    start.fold_angle_left_deg = start.fold_angle_right_deg = NAN;
    start.fold_position_left = start.fold_position_right = NAN;
    start.fold_position = gamma;
    double k0 = fit_hinge(scene, o);
    if (k0 > 0) {
        start.fold_hinge_stiffness = k0;
        start.fold_hinge_stiffness_left = start.fold_hinge_stiffness_right = NAN;
    }
    rod_fit_opts fo = rod_fit_opts_default();
    for (int k = 0; k < ROD_FIT_NKEYS; k++) fo.fit[k] = 0;
    fo.fit[ROD_FIT_ANGLE_LEFT] = fo.fit[ROD_FIT_ANGLE_RIGHT] = 1;
    fo.fit[ROD_FIT_HINGE] = k0 > 0;
    fo.prior_sigma[ROD_FIT_ANGLE_LEFT] = fo.prior_sigma[ROD_FIT_ANGLE_RIGHT] = FIT_PRIOR_ANGLE_DEG;
    fo.sigma_dz = o->fit_sigma_dz;
    fo.sigma_a = o->fit_sigma_a;
    rod_fit_result res;
    if (rod_fit_run(&start, obs, n, &fo, &res, why, why_len) != ROD_OK) return 0;
    for (int k = 0; k < ROD_FIT_NKEYS; k++)
        if (res.fitted[k] && res.at_bound[k]) {
            snprintf(why, why_len, "the fit's %s ran to its bound", rod_fit_key_name(k));
            return 0;
        }
    if (res.misfit) {
        snprintf(why, why_len, "misfit (residual %.3g noise units)", res.rms);
        return 0;
    }
    if (!campaign_strip_fit_from_result(&res, phi, f)) {
        snprintf(why, why_len, "the fit determined no parameter");
        return 0;
    }
    return 1;
}

/* The planner's boundary from the lab strip pooled from fits[0..nfits): the scene's trace
 * (scene_curve) or the strip's (traced again when its hinge or E moved by more than a quarter of
 * their standard errors), read at phi - relaxation, into r->model. 0; 1 when the strip's trace
 * failed and r->model was kept (r->trace_failure says why); -1 with why. */
typedef struct strip_state {
    campaign_predicted scene_curve, strip_curve;
    int have_scene, have_strip;
    double traced_hinge, traced_youngs; /* the strip_curve's (NaN: the scene's) */
} strip_state;

static int moved(double traced, double now, double se_rel)
{
    if (isnan(traced) != isnan(now)) return 1;
    if (isnan(now)) return 0;
    return fabs(log(now / traced)) > fmax(0.25 * se_rel, 1e-3);
}

static int lab_model(const rod_scene *scene, const campaign_bench_opts *o, const campaign_strip_fit *fits,
                     size_t nfits, strip_state *ss, campaign_bench_result *r, char *why, size_t why_len)
{
    campaign_strip_pool(fits, nfits, &r->strip);
    const campaign_lab_strip *ls = &r->strip;
    double lo = 180, hi = 0;
    for (size_t j = 0; j < o->nphi; j++) lo = fmin(lo, o->phi_deg[j]), hi = fmax(hi, o->phi_deg[j]);
    lo -= 25, hi += 5; /* relaxations up to 25 deg (opened creases), 5 deg the other way */
    const campaign_predicted *curve;
    if (!campaign_strip_needs_trace(ls)) {
        if (!ss->have_scene) {
            double t0 = now_s();
            if (campaign_predicted_trace(scene, lo, hi, &ss->scene_curve, why, why_len)) {
                snprintf(r->trace_failure, sizeof r->trace_failure, "%.500s", why);
                r->trace_failures++;
                return 1;
            }
            r->trace_s += now_s() - t0;
            r->traces++;
            ss->have_scene = 1;
        }
        curve = &ss->scene_curve;
    } else {
        if (!ss->have_strip || moved(ss->traced_hinge, ls->hinge, ls->hinge_se_rel) ||
            moved(ss->traced_youngs, ls->youngs, ls->youngs_se_rel)) {
            rod_scene lab;
            campaign_strip_apply(scene, ls, &lab);
            /* Start at the design phi nearest the scene's angle, at the model's boundary there and
             * around it (campaign_strip_trace). */
            size_t near = 0;
            for (size_t j = 1; j < o->nphi; j++)
                if (fabs(o->phi_deg[j] - fabs(scene->fold_angle_deg)) < fabs(o->phi_deg[near] - fabs(scene->fold_angle_deg)))
                    near = j;
            double g0 = r->model[near] + r->offset_mean;
            double starts[] = {g0, g0 + 0.005, g0 - 0.005, g0 + 0.01};
            campaign_predicted next;
            double t0 = now_s();
            char w[1200];
            int rc = campaign_strip_trace(&lab, ls, o->phi_deg[near] - (ls->n_relax ? ls->relax_deg : 0), starts, 4, lo,
                                          hi, o->phi_deg, o->nphi, &next, w, sizeof w);
            r->trace_s += now_s() - t0;
            r->traces++;
            ss->traced_hinge = ls->hinge, ss->traced_youngs = ls->youngs; /* not tried again until it moves */
            if (rc) {
                /* The planner keeps the boundary it had (the scene's, or the last strip's). */
                r->trace_failures++;
                snprintf(r->trace_failure, sizeof r->trace_failure, "%.510s", w);
                return 1;
            }
            if (ss->have_strip) campaign_predicted_free(&ss->strip_curve);
            ss->strip_curve = next;
            ss->have_strip = 1;
        }
        if (!ss->have_strip) return 1;
        curve = &ss->strip_curve;
    }
    double m[CAMPAIGN_BENCH_MAX_PHI];
    for (size_t j = 0; j < o->nphi; j++)
        if (campaign_strip_at(curve, ls, o->phi_deg[j], &m[j], r->trace_failure, sizeof r->trace_failure)) {
            r->trace_failures++;
            return 1; /* the planner keeps its boundary at every phi */
        }
    memcpy(r->model, m, o->nphi * sizeof m[0]);
    return 0;
}

int campaign_bench_run(const rod_scene *scene, const campaign_bench_opts *o, campaign_bench_result *r,
                       void (*progress)(void *u, const char *line), void *u, char *why, size_t why_len)
{
    memset(r, 0, sizeof *r);
    double t0 = now_s();
    size_t n = o->nphi;
    if (n < 1 || n > CAMPAIGN_BENCH_MAX_PHI || o->max_specimens < 1 || o->truth < 0 || o->truth > 2) {
        snprintf(why, why_len, "bench: 1..%d phi values, at least one specimen, truth 0 (as measured), 1 (static) "
                 "or 2 (dynamic)", CAMPAIGN_BENCH_MAX_PHI);
        return -1;
    }
    rod_scene twin = *scene;
    twin.fold_stiffness_factor = o->twin_stiffness_factor;
    if (o->twin_hinge > 0) twin.fold_hinge_stiffness = o->twin_hinge;
    double relaxed[CAMPAIGN_BENCH_MAX_PHI];
    for (size_t j = 0; j < n; j++) relaxed[j] = o->phi_deg[j] - o->relax_deg;
    char w[600];
    if (trace_at(&twin, relaxed, n, r->truth_static, w, sizeof w)) {
        snprintf(why, why_len, "the twins' true boundary: %s", w);
        return -1;
    }
    int dyn_truth = o->truth == 2 || (o->truth == 0 && o->dynamic);
    for (size_t j = 0; j < n; j++) r->truth_dynamic[j] = NAN;
    for (size_t j = 0; dyn_truth && j < n; j++)
        if (dynamic_truth(&twin, relaxed[j], r->truth_static[j], &r->truth_dynamic[j], w, sizeof w)) {
            snprintf(why, why_len, "the twins' dynamic boundary: %s", w);
            return -1;
        }
    for (size_t j = 0; j < n; j++) r->truth[j] = dyn_truth ? r->truth_dynamic[j] : r->truth_static[j];
    if (trace_at(scene, o->phi_deg, n, r->predicted, w, sizeof w)) {
        snprintf(why, why_len, "the model's boundary: %s", w);
        return -1;
    }
    memcpy(r->model, r->predicted, sizeof r->model);
    r->strip = (campaign_lab_strip){.relax_se = NAN, .hinge = NAN, .hinge_se_rel = NAN, .youngs = NAN,
                                    .youngs_se_rel = NAN};
    campaign_obs *obs = r->obs;
    size_t nobs = 0;
    unsigned rng = o->seed ? o->seed : 1;
    /* The calibrations' noise on a stream of its own: the same seed folds the same twins whether
     * or not they are calibrated. */
    unsigned nrng = (o->seed ? o->seed : 1) * 2654435761u ^ 0x9e3779b9u;
    if (!nrng) nrng = 1;
    int use_strip = o->calibrate && o->lab_strip;
    campaign_strip_fit fits[64];
    size_t nfits = 0;
    strip_state ss = {.traced_hinge = NAN, .traced_youngs = NAN};
    campaign_plan_opts po = campaign_plan_opts_default();
    po.calibrate = o->calibrate;
    campaign_belief beliefs[CAMPAIGN_BENCH_MAX_PHI];
    campaign_proposal prop;
    campaign_plan_result res = {.beliefs = beliefs, .proposals = &prop};
    int rc = -1;
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
        if (campaign_plan_run(o->phi_deg, r->model, n, obs, nobs, &po, 1, &res, why, why_len)) goto out;
        r->offset_mean = res.offset_mean; /* the latest (the lab strip's trace starts near model + offset) */
        double t1 = now_s();
        double angle = NAN, dw_crit = NAN;
        rod_scene t;
        fold_twin(scene, o, prop.phi_deg, prop.gamma, &rng, &t, &angle);
        int reg = measure(&t, o, prop.phi_deg, prop.gamma, &dw_crit, w, sizeof w);
        r->classify_s += now_s() - t1;
        if (reg < 0) {
            snprintf(why, why_len, "measuring specimen %d: %s", r->specimens + 1, w);
            goto out;
        }
        char cal[200] = "";
        if (use_strip && nfits < sizeof fits / sizeof fits[0]) {
            double t2 = now_s();
            int c = calibrate_twin(scene, &t, o, prop.phi_deg, prop.gamma, dw_crit, &nrng, &fits[nfits], w, sizeof w);
            r->fit_s += now_s() - t2;
            if (c) {
                const campaign_strip_fit *f = &fits[nfits++];
                if (r->specimens < 64) r->fit[r->specimens] = *f, r->has_fit[r->specimens] = 1;
                r->calibrations++;
                snprintf(cal, sizeof cal, "; fit: creases %.2f +- %.2f deg%s", f->angle_mean_deg, f->angle_se_deg,
                         isfinite(f->ln_hinge) ? "" : ", hinge -");
                if (isfinite(f->ln_hinge)) {
                    size_t len = strlen(cal);
                    snprintf(cal + len, sizeof cal - len, ", hinge %.3g +- %.0f%%", exp(f->ln_hinge), 100 * f->ln_hinge_se);
                }
            } else {
                r->calibration_failures++;
                snprintf(cal, sizeof cal, "; no calibration: %.150s", w);
            }
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
        if (use_strip && nfits) {
            int traces = r->traces;
            int lm = lab_model(scene, o, fits, nfits, &ss, r, why, why_len);
            if (lm < 0) goto out;
            if (progress && (r->traces > traces || lm)) {
                char d[300], line[900];
                campaign_strip_describe(&r->strip, d, sizeof d);
                if (lm) snprintf(line, sizeof line, "lab strip %s: no boundary from it (%.500s); the planner keeps its boundary", d, r->trace_failure);
                else snprintf(line, sizeof line, "lab strip traced: %s", d);
                progress(u, line);
            }
        }
        if (progress) {
            char line[420];
            snprintf(line, sizeof line, "specimen %d: phi %g Gamma %.5f (twin's creases %.3f deg) -> %s (offset %+.4f)%s",
                     r->specimens, prop.phi_deg, prop.gamma, angle, reg ? "asymmetric" : "symmetric", res.offset_mean, cal);
            progress(u, line);
        }
    }
    /* the located boundary */
    if (campaign_plan_run(o->phi_deg, r->model, n, obs, nobs, &po, 0, &res, why, why_len)) goto out;
    r->offset_mean = res.offset_mean;
    for (size_t j = 0; j < n; j++) {
        campaign_edge e;
        campaign_edge_fit(obs, nobs, o->phi_deg[j], &e);
        r->located[j] = isfinite(e.gamma) ? e.gamma : beliefs[j].median;
        double err = fabs(r->located[j] - r->truth[j]);
        if (err > r->max_error) r->max_error = err;
    }
    r->wall_s = now_s() - t0;
    rc = 0;
out:
    if (ss.have_scene) campaign_predicted_free(&ss.scene_curve);
    if (ss.have_strip) campaign_predicted_free(&ss.strip_curve);
    return rc;
}
