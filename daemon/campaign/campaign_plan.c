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
#define PLAN_Z 9.0    /* Gaussian kernels are cut at 9 sd (exp(-40.5): nothing a sum of them sees) */

campaign_plan_opts campaign_plan_opts_default(void)
{
    campaign_plan_opts o = {.tau = 0.003, .offset_sd = 0.03, .spread_max = 0.02, .noise = 0.002, .undecided = 0.002,
                            .gamma_min = 0.02, .gamma_max = 0.45, .grid_step = 2.5e-4, .calibrate = 1};
    return o;
}

static double log_phi_cdf(double x)
{
    if (x > -30) return log(0.5 * erfc(-x / M_SQRT2));
    return -0.5 * x * x - log(-x) - 0.5 * log(2 * M_PI);
}

/* log (Phi(b) - Phi(a)) for a < b, without cancelling in either tail. */
static double log_phi_between(double a, double b)
{
    double v;
    if (a > 0) v = 0.5 * (erfc(a / M_SQRT2) - erfc(b / M_SQRT2));
    else if (b < 0) v = 0.5 * (erfc(-b / M_SQRT2) - erfc(-a / M_SQRT2));
    else v = 1.0 - 0.5 * erfc(-a / M_SQRT2) - 0.5 * erfc(b / M_SQRT2);
    return v > 1e-300 ? log(v) : log(1e-300);
}

/* The log probabilities of one trial's three outcomes at Gamma with the boundary at g
 * (campaign_plan.h: the ordered probit; h = 0: two outcomes, undecided impossible); lu may be
 * NULL when no undecided trial needs it. */
static void outcome_logp(double g, double gamma, const campaign_plan_opts *o, double *la, double *ls, double *lu)
{
    double h = o->undecided > 0 ? o->undecided : 0, z = (g - gamma) / o->noise, hz = h / o->noise;
    *la = log_phi_cdf(z - hz);
    *ls = log_phi_cdf(-z - hz);
    if (lu) *lu = h > 0 ? log_phi_between(z - hz, z + hz) : -INFINITY;
}

/* log L_j on the Gamma grid. */
static void log_lik(const campaign_obs *obs, size_t nobs, double phi, const campaign_plan_opts *o, size_t ng,
                    double *ll)
{
    for (size_t i = 0; i < ng; i++) {
        double g = o->gamma_min + (double)i * o->grid_step, s = 0;
        for (size_t k = 0; k < nobs; k++) {
            if (fabs(obs[k].phi_deg - phi) > SAME_PHI) continue;
            int und = obs[k].n_unknown && o->undecided > 0;
            double la, ls, lu = 0;
            outcome_logp(g, obs[k].gamma, o, &la, &ls, und ? &lu : NULL);
            if (obs[k].n_asym) s += obs[k].n_asym * la;
            if (obs[k].n_sym) s += obs[k].n_sym * ls;
            if (und) s += obs[k].n_unknown * lu;
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

/* The planner's grids and the per-phi likelihoods, shared by the offset's posterior, the beliefs
 * and the proposals. */
typedef struct plan_grid {
    size_t ng, nd, ns;
    double d0;
    double spread[PLAN_MAX_SPREAD]; /* s_m, Gamma: the per-phi deviations' sd */
    double log_prior_s[PLAN_MAX_SPREAD];
    const double *predicted;
    size_t nphi;
    double *ll;                     /* nphi x ng: log L_j(g) */
    double *lc;                     /* nphi x ns x nd: log c_j(d; s) */
} plan_grid;

/* The kernel's index window: i - a in [*t0, *t1] where |z| < PLAN_Z, z = ((i - a) step + c) / s. */
static void kernel_window(double c, double sd, double step, long *t0, long *t1)
{
    *t0 = (long)ceil((-PLAN_Z * sd - c) / step);
    *t1 = (long)floor((PLAN_Z * sd - c) / step);
}

/* log c_j(d_a; s) for every a: sum_g N(g; P_j + d_a, s) L_j(g), the Gaussian normalised, so that
 * different s compare. Fast as a correlation of exp(ll - max) with the kernel; where that
 * underflows, by log-sum-exp. */
static void log_c(const plan_grid *G, size_t j, size_t m, const campaign_plan_opts *o, double *kern, double *lx,
                  double *out)
{
    const double *ll = G->ll + j * G->ng;
    double sd = G->spread[m], c = o->gamma_min - G->predicted[j] - G->d0, lmax = -INFINITY;
    double lnorm = log(o->grid_step / (sd * sqrt(2 * M_PI)));
    for (size_t i = 0; i < G->ng; i++)
        if (ll[i] > lmax) lmax = ll[i];
    for (size_t i = 0; i < G->ng; i++) lx[i] = exp(ll[i] - lmax);
    long t0, t1;
    kernel_window(c, sd, o->grid_step, &t0, &t1);
    for (long t = t0; t <= t1; t++) {
        double z = ((double)t * o->grid_step + c) / sd;
        kern[t - t0] = exp(-0.5 * z * z);
    }
    for (size_t a = 0; a < G->nd; a++) {
        long i0 = (long)a + t0, i1 = (long)a + t1;
        if (i0 < 0) i0 = 0;
        if (i1 > (long)G->ng - 1) i1 = (long)G->ng - 1;
        double sum = 0;
        for (long i = i0; i <= i1; i++) sum += lx[i] * kern[i - (long)a - t0];
        if (sum > 1e-250) {
            out[a] = lmax + log(sum) + lnorm;
            continue;
        }
        double mx = -INFINITY;
        for (long i = i0; i <= i1; i++) {
            double z = ((double)(i - (long)a) * o->grid_step + c) / sd;
            double v = ll[i] - 0.5 * z * z;
            if (v > mx) mx = v;
        }
        sum = 0;
        for (long i = i0; i <= i1 && isfinite(mx); i++) {
            double z = ((double)(i - (long)a) * o->grid_step + c) / sd;
            sum += exp(ll[i] - 0.5 * z * z - mx);
        }
        out[a] = isfinite(mx) && sum > 0 ? mx + log(sum) + lnorm : -INFINITY;
    }
}

/* The log joint of (delta_a, s_m) given every phi's trials but phi skip's (skip = nphi: all), into
 * wd (ns x nd), exponentiated and shifted to its maximum. */
static void joint(const plan_grid *G, size_t skip, const campaign_plan_opts *o, double *wd)
{
    for (size_t m = 0; m < G->ns; m++)
        for (size_t a = 0; a < G->nd; a++) {
            double d = G->d0 + (double)a * o->grid_step;
            double v = (o->calibrate ? -0.5 * (d / o->offset_sd) * (d / o->offset_sd) : 0) + G->log_prior_s[m];
            for (size_t q = 0; q < G->nphi; q++)
                if (q != skip) v += G->lc[(q * G->ns + m) * G->nd + a];
            wd[m * G->nd + a] = v;
        }
    exp_shift(wd, G->ns * G->nd);
}

/* Phi j's belief on the Gamma grid into w (relative density): its own trials (ll_j) times its
 * Gamma*_j = P_j + delta + e_j, e_j ~ N(0, s^2), with (delta, s) as the other phi's trials tell
 * them under their priors. wd: ns x nd scratch. */
static void belief_density(const plan_grid *G, size_t j, const campaign_plan_opts *o, double *wd, double *w)
{
    joint(G, j, o, wd);
    for (size_t i = 0; i < G->ng; i++) w[i] = 0;
    double c = o->gamma_min - G->predicted[j] - G->d0;
    for (size_t m = 0; m < G->ns; m++) {
        double sd = G->spread[m], norm = 1 / sd;
        long t0, t1;
        kernel_window(c, sd, o->grid_step, &t0, &t1);
        const double *wm = wd + m * G->nd;
        for (size_t i = 0; i < G->ng; i++) {
            /* a = i - t for t in [t0, t1] */
            long a0 = (long)i - t1, a1 = (long)i - t0;
            if (a0 < 0) a0 = 0;
            if (a1 > (long)G->nd - 1) a1 = (long)G->nd - 1;
            double s = 0;
            for (long a = a0; a <= a1; a++) {
                if (wm[a] == 0) continue;
                double z = ((double)((long)i - a) * o->grid_step + c) / sd;
                s += wm[a] * exp(-0.5 * z * z);
            }
            w[i] += norm * s;
        }
    }
    for (size_t i = 0; i < G->ng; i++) w[i] = w[i] > 0 ? log(w[i]) + G->ll[j * G->ng + i] : -INFINITY;
    exp_shift(w, G->ng);
}

int campaign_plan_run(const double *phi_deg, const double *predicted, size_t nphi, const campaign_obs *obs,
                      size_t nobs, const campaign_plan_opts *o, size_t k, campaign_plan_result *res, char *why,
                      size_t why_len)
{
    if (!(o->tau > 0) || !(o->noise > 0) || !(o->offset_sd > 0) || !(o->grid_step > 0) || !(o->undecided >= 0) ||
        !(o->gamma_min < o->gamma_max) || nphi == 0 || !(o->spread_max >= o->tau) || !isfinite(o->spread_max)) {
        snprintf(why, why_len, "planner: tau, noise, offset_sd and the grid step must be > 0, undecided >= 0, "
                               "gamma_min < gamma_max, spread_max >= tau (finite), and at least one phi planned");
        return -1;
    }
    for (size_t j = 0; j < nphi; j++)
        if (!(predicted[j] >= o->gamma_min && predicted[j] <= o->gamma_max)) {
            snprintf(why, why_len, "planner: the predicted boundary at phi %g deg (%g) is outside Gamma [%g, %g]",
                     phi_deg[j], predicted[j], o->gamma_min, o->gamma_max);
            return -1;
        }
    plan_grid G = {.predicted = predicted, .nphi = nphi};
    G.ng = (size_t)floor((o->gamma_max - o->gamma_min) / o->grid_step + 1e-9) + 1;
    G.nd = o->calibrate ? 2 * (size_t)ceil(4 * o->offset_sd / o->grid_step) + 1 : 1;
    G.d0 = o->calibrate ? -(double)(G.nd / 2) * o->grid_step : 0;
    /* The per-phi deviations' sd s: log-uniform on [tau, spread_max] (one value, tau, when they
     * are equal: one offset for every phi, the planner before); without calibration delta is 0
     * and each phi's prior carries the offset's width. */
    if (!o->calibrate) {
        G.ns = 1;
        G.spread[0] = sqrt(o->tau * o->tau + o->offset_sd * o->offset_sd);
    } else if (o->spread_max <= o->tau * (1 + 1e-9)) {
        G.ns = 1;
        G.spread[0] = o->tau;
    } else {
        G.ns = PLAN_MAX_SPREAD;
        for (size_t m = 0; m < G.ns; m++)
            G.spread[m] = o->tau * pow(o->spread_max / o->tau, (double)m / (double)(G.ns - 1));
    }
    for (size_t m = 0; m < G.ns; m++) G.log_prior_s[m] = -log((double)G.ns);
    size_t nk = 2 * (size_t)ceil(PLAN_Z * G.spread[G.ns - 1] / o->grid_step) + 3;
    size_t njoint = G.ns * G.nd;
    G.ll = malloc(nphi * G.ng * sizeof *G.ll);
    G.lc = malloc(nphi * njoint * sizeof *G.lc);
    double *w = malloc(G.ng * sizeof *w), *wd = malloc(njoint * sizeof *wd), *kern = malloc(nk * sizeof *kern);
    double *lx = malloc(G.ng * sizeof *lx);
    int *alloc = calloc(nphi, sizeof *alloc);
    if (!G.ll || !G.lc || !w || !wd || !kern || !lx || !alloc) {
        free(G.ll), free(G.lc), free(w), free(wd), free(kern), free(lx), free(alloc);
        snprintf(why, why_len, "planner: out of memory");
        return -1;
    }
    for (size_t j = 0; j < nphi; j++) {
        log_lik(obs, nobs, phi_deg[j], o, G.ng, G.ll + j * G.ng);
        for (size_t m = 0; m < G.ns; m++) log_c(&G, j, m, o, kern, lx, G.lc + (j * G.ns + m) * G.nd);
    }
    /* The offset's and the spread's posteriors: the joint given every phi's trials. */
    joint(&G, nphi, o, wd);
    {
        double s = 0, m = 0, v = 0, sm = 0;
        for (size_t q = 0; q < G.ns; q++)
            for (size_t a = 0; a < G.nd; a++) {
                double p = wd[q * G.nd + a];
                s += p, m += p * (G.d0 + (double)a * o->grid_step), sm += p * G.spread[q];
            }
        m /= s;
        for (size_t q = 0; q < G.ns; q++)
            for (size_t a = 0; a < G.nd; a++) {
                double e = G.d0 + (double)a * o->grid_step - m;
                v += wd[q * G.nd + a] * e * e;
            }
        res->offset_mean = o->calibrate ? m : 0;
        res->offset_sd = o->calibrate ? sqrt(v / s) : 0;
        res->spread_mean = o->calibrate ? sm / s : 0;
    }
    /* Each phi's belief: its own trials times the offset and the spread told by the others. */
    for (size_t j = 0; j < nphi; j++) {
        belief_density(&G, j, o, wd, w);
        campaign_belief *b = &res->beliefs[j];
        b->phi_deg = phi_deg[j];
        b->predicted = predicted[j];
        summarise(w, G.ng, o, b);
        b->offset_mean = b->mean - predicted[j];
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
        belief_density(&G, j, o, wd, w);
        for (int m = 1; m <= alloc[j] && n < k; m++, n++) {
            res->proposals[n].phi_deg = phi_deg[j];
            res->proposals[n].gamma = quantile(w, G.ng, o, (double)m / (alloc[j] + 1));
            res->proposals[n].sd_before = res->beliefs[j].sd;
        }
    }
    res->k = n;
    free(G.ll), free(G.lc), free(w), free(wd), free(kern), free(lx), free(alloc);
    return 0;
}
