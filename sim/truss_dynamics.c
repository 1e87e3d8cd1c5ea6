/* truss_dynamics.c: the truss under a slowly released load, as in the paper's "dynamic
 * validation": 1 - mu = mu_rate T (shifted to start at mu_start), unit masses, the paper's
 * m q'' + dU/dq = 0 plus optional viscous damping -c q'.
 *
 * Design. State y = [x1, y1, x2, y2, vx1, vy1, vx2, vy2]; the right-hand side is the analytic
 * energy gradient of truss.c (the paper's nonlinear "K q"). GSL's explicit RK8PD with adaptive
 * error control: the system is only mildly stiff (stretching frequency ~ 1.7, bending ~ 0.02 in
 * units of sqrt(k_s / m)), so an explicit high-order method is cheap. The caller-owned loop walks
 * the evolve API one accepted step at a time, with a total step cap, so that the snap (the first
 * sign change of psi_S, from the inverted to the natural state) and the peaks of |psi_A| are
 * taken at every step, not only at output samples.
 *
 * The run starts at rest in the static upper state of the given (possibly imperfect) truss: a
 * symmetry-breaking seed is the `imperfection` of truss_params (unequal support rest angles);
 * without one a pitchfork is crossed only at round-off level. */
#include "truss.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

truss_dyn_opts truss_dyn_opts_default(void)
{
    truss_dyn_opts o;
    o.mu_start = 1.0;
    o.mu_rate = 1e-3;
    o.mu_end = 0.0;
    o.damping = 0.0;
    o.sample_dt = 1.0;
    o.rtol = 1e-10;
    o.atol = 1e-12;
    o.max_steps = 2000000;
    return o;
}

typedef struct dyn_ctx {
    const truss_params *p;
    const truss_dyn_opts *o;
    truss_error err; /* why the right-hand side failed, if it did */
} dyn_ctx;

static double dyn_mu(const truss_dyn_opts *o, double t)
{
    return o->mu_start - o->mu_rate * t;
}

static int dyn_rhs(double t, const double y[], double dydt[], void *params)
{
    dyn_ctx *c = params;
    double g[4];
    truss_error e = truss_energy_eval(c->p, dyn_mu(c->o, t), y, NULL, g, NULL, NULL);
    if (e != TRUSS_OK) {
        c->err = e;
        return GSL_EBADFUNC;
    }
    for (int i = 0; i < 4; i++) {
        dydt[i] = y[4 + i];
        dydt[4 + i] = -g[i] - c->o->damping * y[4 + i];
    }
    return GSL_SUCCESS;
}

void truss_dyn_result_free(truss_dyn_result *r)
{
    if (r == NULL)
        return;
    free(r->samples);
    r->samples = NULL;
    r->n = 0;
}

static truss_error dyn_opts_check(const truss_dyn_opts *o)
{
    if (!isfinite(o->mu_start) || !isfinite(o->mu_end) || !(o->mu_end < o->mu_start))
        return TRUSS_ERR_PARAM;
    if (!(o->mu_rate > 0.0) || !isfinite(o->mu_rate))
        return TRUSS_ERR_PARAM;
    if (!(o->damping >= 0.0) || !isfinite(o->damping))
        return TRUSS_ERR_PARAM;
    if (!(o->sample_dt > 0.0) || !isfinite(o->sample_dt))
        return TRUSS_ERR_PARAM;
    if (!(o->rtol > 0.0) || !(o->atol > 0.0) || o->max_steps == 0)
        return TRUSS_ERR_PARAM;
    /* the sample count must stay bounded */
    if ((o->mu_start - o->mu_end) / o->mu_rate / o->sample_dt > 1e7)
        return TRUSS_ERR_PARAM;
    return TRUSS_OK;
}

truss_error truss_dynamics_run(const truss_params *p, const truss_dyn_opts *opts, int keep_samples,
                               truss_dyn_result *out)
{
    memset(out, 0, sizeof *out);
    if (truss_params_check(p, NULL, 0) != TRUSS_OK)
        return TRUSS_ERR_PARAM;
    truss_error e = dyn_opts_check(opts);
    if (e != TRUSS_OK)
        return e;
    if (!(opts->mu_start * p->alpha * p->alpha < TRUSS_COMPRESSION_MAX))
        return TRUSS_ERR_PARAM;

    /* static upper state at mu_start */
    double roots[3];
    int nr = truss_analytic_psi_roots(p->lambda, p->l2, opts->mu_start, roots);
    double psi_guess = roots[nr == 3 ? 2 : 0];
    if (!(psi_guess > 0.0))
        return TRUSS_ERR_NO_UPPER;
    double y[8] = {0};
    truss_config_guess(p, opts->mu_start, psi_guess, y);
    truss_newton_opts nopt = truss_newton_opts_default();
    e = truss_statics_solve(p, opts->mu_start, y, &nopt, NULL);
    if (e != TRUSS_OK)
        return e;
    truss_stability st;
    e = truss_stability_eval(p, opts->mu_start, y, &st);
    if (e != TRUSS_OK)
        return e;
    double psi_s0, psi_a0;
    truss_coords_psi(p, opts->mu_start, y, &psi_s0, &psi_a0);
    if (!st.stable || !(psi_s0 > 0.0))
        return TRUSS_ERR_NO_UPPER;

    const double t_end = (opts->mu_start - opts->mu_end) / opts->mu_rate;
    size_t n_samples = (size_t)floor(t_end / opts->sample_dt) + 1;
    if (keep_samples) {
        out->samples = calloc(n_samples + 1, sizeof *out->samples);
        if (out->samples == NULL)
            return TRUSS_ERR_NOMEM;
    }

    dyn_ctx ctx = {p, opts, TRUSS_OK};
    gsl_odeiv2_system sys = {dyn_rhs, NULL, 8, &ctx};
    gsl_odeiv2_step *step = gsl_odeiv2_step_alloc(gsl_odeiv2_step_rk8pd, 8);
    gsl_odeiv2_control *ctrl = gsl_odeiv2_control_y_new(opts->atol, opts->rtol);
    gsl_odeiv2_evolve *ev = gsl_odeiv2_evolve_alloc(8);
    if (step == NULL || ctrl == NULL || ev == NULL) {
        e = TRUSS_ERR_NOMEM;
        goto done;
    }

    double t = 0.0, h = 1e-3;
    size_t steps = 0;
    size_t k = 0; /* next sample index */
    e = TRUSS_OK;
    for (;;) {
        double psi_s, psi_a;
        truss_coords_psi(p, dyn_mu(opts, t), y, &psi_s, &psi_a);
        if (!isfinite(psi_s) || !isfinite(psi_a)) {
            e = TRUSS_ERR_NAN;
            break;
        }
        double apsi = fabs(psi_a);
        out->psi_a_max = fmax(out->psi_a_max, apsi);
        if (!out->snapped) {
            out->psi_a_max_before = fmax(out->psi_a_max_before, apsi);
            if (psi_s < 0.0) {
                out->snapped = 1;
                out->t_snap = t;
                out->mu_snap = dyn_mu(opts, t);
            }
        }
        if (k < n_samples && t >= k * opts->sample_dt) {
            if (keep_samples) {
                truss_dyn_sample *sm = &out->samples[out->n];
                sm->t = t;
                sm->mu = dyn_mu(opts, t);
                sm->psi_s = psi_s;
                sm->psi_a = psi_a;
                out->n++;
            }
            k++;
        }
        if (t >= t_end)
            break;
        if (steps >= opts->max_steps) {
            e = TRUSS_ERR_MAX_ITER;
            break;
        }
        /* step toward the next sample time (or the end) so samples land exactly */
        double t1 = k < n_samples ? fmin(k * opts->sample_dt, t_end) : t_end;
        if (!(t1 > t))
            t1 = t_end;
        int rc = gsl_odeiv2_evolve_apply(ev, ctrl, step, &sys, &t, t1, &h, y);
        steps++;
        if (rc != GSL_SUCCESS) {
            e = ctx.err != TRUSS_OK ? ctx.err : TRUSS_ERR_GSL;
            break;
        }
        for (int i = 0; i < 8; i++) {
            if (!isfinite(y[i])) {
                e = TRUSS_ERR_NAN;
                break;
            }
        }
        if (e != TRUSS_OK)
            break;
    }

done:
    if (ev != NULL)
        gsl_odeiv2_evolve_free(ev);
    if (ctrl != NULL)
        gsl_odeiv2_control_free(ctrl);
    if (step != NULL)
        gsl_odeiv2_step_free(step);
    if (e != TRUSS_OK)
        truss_dyn_result_free(out);
    return e;
}
