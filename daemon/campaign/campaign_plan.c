/* campaign_plan.c: beliefs about the boundary at each planned phi and the next specimens
 * (campaign_plan.h). Everything on grids: Gamma*_j on [gamma_min, gamma_max], delta on
 * [-4 offset_sd, 4 offset_sd], both in steps of grid_step (2.5e-4: 1721 and 961 points at the
 * defaults); the work is about 3 nphi * (Gamma grid) * (delta grid) Gaussian evaluations, 15 M for
 * three phi: the whole `ribbonctl plan` for three phi took 0.16 s CPU (measured, cache warm).
 *
 *   L_j(g)       likelihood of phi j's trials given Gamma*_j = g (the probit of campaign_plan.h)
 *   c_j(d)       = sum_g N(g; P_j + d, tau) L_j(g): what phi j's trials say about delta
 *   p(d | -j)    proportional to N(d; 0, offset_sd) prod_{k != j} c_k(d)
 *   p_j(g)       proportional to L_j(g) sum_d p(d | -j) N(g; P_j + d, tau)
 *   p(d)         proportional to N(d; 0, offset_sd) prod_k c_k(d)  (the fitted offset)
 * Products are kept as logs, shifted by their maximum before exponentiating. */
#include "campaign_plan.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define SAME_PHI 1e-6
#define PLAN_TIE 1e-3 /* relative: belief widths closer than this are a tie (see the allocation) */

campaign_plan_opts campaign_plan_opts_default(void)
{
    campaign_plan_opts o = {.tau = 0.003, .offset_sd = 0.03, .noise = 0.002, .gamma_min = 0.02,
                            .gamma_max = 0.45, .grid_step = 2.5e-4, .calibrate = 1};
    return o;
}

static double log_phi_cdf(double x)
{
    if (x > -30) return log(0.5 * erfc(-x / M_SQRT2));
    return -0.5 * x * x - log(-x) - 0.5 * log(2 * M_PI);
}

/* log L_j on the Gamma grid. */
static void log_lik(const campaign_obs *obs, size_t nobs, double phi, const campaign_plan_opts *o, size_t ng,
                    double *ll)
{
    for (size_t i = 0; i < ng; i++) {
        double g = o->gamma_min + (double)i * o->grid_step, s = 0;
        for (size_t k = 0; k < nobs; k++) {
            if (fabs(obs[k].phi_deg - phi) > SAME_PHI) continue;
            double z = (g - obs[k].gamma) / o->noise;
            if (obs[k].n_asym) s += obs[k].n_asym * log_phi_cdf(z);
            if (obs[k].n_sym) s += obs[k].n_sym * log_phi_cdf(-z);
        }
        ll[i] = s;
    }
}

static void exp_shift(double *v, size_t n)
{
    double m = -INFINITY;
    for (size_t i = 0; i < n; i++)
        if (v[i] > m) m = v[i];
    for (size_t i = 0; i < n; i++) v[i] = exp(v[i] - m);
}

/* Mean, sd, quantiles of a density w on the Gamma grid. */
static void summarise(const double *w, size_t ng, const campaign_plan_opts *o, campaign_belief *b)
{
    double s = 0, m = 0, v = 0;
    for (size_t i = 0; i < ng; i++) s += w[i];
    for (size_t i = 0; i < ng; i++) m += w[i] * (o->gamma_min + (double)i * o->grid_step);
    m /= s;
    for (size_t i = 0; i < ng; i++) {
        double d = o->gamma_min + (double)i * o->grid_step - m;
        v += w[i] * d * d;
    }
    b->mean = m;
    b->sd = sqrt(v / s);
    double c = 0;
    b->lo = b->hi = b->median = NAN;
    for (size_t i = 0; i < ng; i++) {
        double g = o->gamma_min + (double)i * o->grid_step;
        double before = c;
        c += w[i] / s;
        if (isnan(b->lo) && c >= 0.025) b->lo = g;
        if (isnan(b->median) && c >= 0.5) {
            /* linear within the cell, so the median moves smoothly with the data */
            double f = w[i] > 0 ? (0.5 - before) / (w[i] / s) : 0;
            b->median = g - o->grid_step * (1 - f);
            if (b->median < o->gamma_min) b->median = o->gamma_min;
        }
        if (isnan(b->hi) && c >= 0.975) b->hi = g;
    }
}

/* The q-quantile of w (linear within a cell). */
static double quantile(const double *w, size_t ng, const campaign_plan_opts *o, double q)
{
    double s = 0, c = 0;
    for (size_t i = 0; i < ng; i++) s += w[i];
    for (size_t i = 0; i < ng; i++) {
        double before = c;
        c += w[i] / s;
        if (c >= q) {
            double f = w[i] > 0 ? (q - before) / (w[i] / s) : 0;
            double g = o->gamma_min + ((double)i - 1 + f) * o->grid_step;
            return g < o->gamma_min ? o->gamma_min : g;
        }
    }
    return o->gamma_max;
}

/* Phi j's belief on the Gamma grid into w (relative density): its own trials (ll_j) times the
 * offset as the other phi's trials tell it (lc, k != j) under its prior. wd: nd scratch. */
static void belief_density(size_t j, size_t nphi, const double *predicted, const double *ll, const double *lc,
                           size_t ng, size_t nd, double d0, double tau, const campaign_plan_opts *o, double *wd,
                           double *w)
{
    for (size_t a = 0; a < nd; a++) {
        double d = d0 + (double)a * o->grid_step;
        wd[a] = o->calibrate ? -0.5 * (d / o->offset_sd) * (d / o->offset_sd) : 0;
        for (size_t q = 0; q < nphi; q++)
            if (q != j) wd[a] += lc[q * nd + a];
    }
    exp_shift(wd, nd);
    for (size_t i = 0; i < ng; i++) {
        double g = o->gamma_min + (double)i * o->grid_step, s = 0;
        for (size_t a = 0; a < nd; a++) {
            double z = (g - predicted[j] - d0 - (double)a * o->grid_step) / tau;
            if (fabs(z) < 9) s += wd[a] * exp(-0.5 * z * z);
        }
        w[i] = s > 0 ? log(s) + ll[j * ng + i] : -INFINITY;
    }
    exp_shift(w, ng);
}

int campaign_plan_run(const double *phi_deg, const double *predicted, size_t nphi, const campaign_obs *obs,
                      size_t nobs, const campaign_plan_opts *o, size_t k, campaign_plan_result *res, char *why,
                      size_t why_len)
{
    if (!(o->tau > 0) || !(o->noise > 0) || !(o->offset_sd > 0) || !(o->grid_step > 0) ||
        !(o->gamma_min < o->gamma_max) || nphi == 0) {
        snprintf(why, why_len, "planner: tau, noise, offset_sd and the grid step must be > 0, gamma_min < gamma_max, "
                               "and at least one phi planned");
        return -1;
    }
    for (size_t j = 0; j < nphi; j++)
        if (!(predicted[j] >= o->gamma_min && predicted[j] <= o->gamma_max)) {
            snprintf(why, why_len, "planner: the predicted boundary at phi %g deg (%g) is outside Gamma [%g, %g]",
                     phi_deg[j], predicted[j], o->gamma_min, o->gamma_max);
            return -1;
        }
    size_t ng = (size_t)floor((o->gamma_max - o->gamma_min) / o->grid_step + 1e-9) + 1;
    size_t nd = o->calibrate ? 2 * (size_t)ceil(4 * o->offset_sd / o->grid_step) + 1 : 1;
    double d0 = o->calibrate ? -(double)(nd / 2) * o->grid_step : 0;
    double *ll = malloc(nphi * ng * sizeof *ll), *lc = malloc(nphi * nd * sizeof *lc);
    double *pd = malloc(nd * sizeof *pd), *w = malloc(ng * sizeof *w), *wd = malloc(nd * sizeof *wd);
    int *alloc = calloc(nphi, sizeof *alloc);
    if (!ll || !lc || !pd || !w || !wd || !alloc) {
        free(ll), free(lc), free(pd), free(w), free(wd), free(alloc);
        snprintf(why, why_len, "planner: out of memory");
        return -1;
    }
    /* Without calibration delta is 0 and each phi's prior carries the offset's width. */
    double tau = o->calibrate ? o->tau : sqrt(o->tau * o->tau + o->offset_sd * o->offset_sd);
    for (size_t j = 0; j < nphi; j++) {
        log_lik(obs, nobs, phi_deg[j], o, ng, ll + j * ng);
        /* log c_j(d) */
        for (size_t a = 0; a < nd; a++) {
            double d = d0 + (double)a * o->grid_step, m = -INFINITY;
            for (size_t i = 0; i < ng; i++) {
                double z = (o->gamma_min + (double)i * o->grid_step - predicted[j] - d) / tau;
                w[i] = ll[j * ng + i] - 0.5 * z * z;
                if (w[i] > m) m = w[i];
            }
            double s = 0;
            for (size_t i = 0; i < ng; i++) s += exp(w[i] - m);
            lc[j * nd + a] = m + log(s);
        }
    }
    /* The offset's posterior. */
    for (size_t a = 0; a < nd; a++) {
        double d = d0 + (double)a * o->grid_step;
        pd[a] = -0.5 * (d / o->offset_sd) * (d / o->offset_sd);
        for (size_t j = 0; j < nphi; j++) pd[a] += lc[j * nd + a];
    }
    exp_shift(pd, nd);
    {
        double s = 0, m = 0, v = 0;
        for (size_t a = 0; a < nd; a++) s += pd[a], m += pd[a] * (d0 + (double)a * o->grid_step);
        m /= s;
        for (size_t a = 0; a < nd; a++) {
            double e = d0 + (double)a * o->grid_step - m;
            v += pd[a] * e * e;
        }
        res->offset_mean = o->calibrate ? m : 0;
        res->offset_sd = o->calibrate ? sqrt(v / s) : 0;
    }
    /* Each phi's belief: its own trials times the offset told by the others. */
    for (size_t j = 0; j < nphi; j++) {
        belief_density(j, nphi, predicted, ll, lc, ng, nd, d0, tau, o, wd, w);
        campaign_belief *b = &res->beliefs[j];
        b->phi_deg = phi_deg[j];
        b->predicted = predicted[j];
        summarise(w, ng, o, b);
    }
    /* Allocate the k specimens: widest effective belief first. Widths within PLAN_TIE of each
     * other are a tie, given to the phi listed first: beliefs equal in exact arithmetic (the prior
     * at every phi; two phi the trials have not touched) differ by the grid's aliasing and by
     * round-off, and round-off differs between builds (ribbonctl resolves cblas_* to libblas, the
     * tests to GSL's own cblas: the codim-2 traces then differ by 1e-6), which used to decide
     * where the next specimen went and so the whole campaign (docs/campaign.md). */
    for (size_t n = 0; n < k; n++) {
        size_t best = 0;
        double bw = -1;
        for (size_t j = 0; j < nphi; j++) {
            double e = res->beliefs[j].sd / (alloc[j] + 1);
            if (e > bw * (1 + PLAN_TIE)) bw = e, best = j;
        }
        alloc[best]++;
    }
    size_t n = 0;
    for (size_t j = 0; j < nphi && n < k; j++) {
        if (!alloc[j]) continue;
        belief_density(j, nphi, predicted, ll, lc, ng, nd, d0, tau, o, wd, w);
        for (int m = 1; m <= alloc[j] && n < k; m++, n++) {
            res->proposals[n].phi_deg = phi_deg[j];
            res->proposals[n].gamma = quantile(w, ng, o, (double)m / (alloc[j] + 1));
            res->proposals[n].sd_before = res->beliefs[j].sd;
        }
    }
    res->k = n;
    free(ll), free(lc), free(pd), free(w), free(wd), free(alloc);
    return 0;
}
