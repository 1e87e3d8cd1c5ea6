/* campaign_edge.c: the experimental regime boundary at one phi from measured counts: the
 * bracket where the regimes separate, a probit fit where they overlap (campaign_edge.h).
 *
 * The probit fit is a grid search, not Newton: with a handful of points the likelihood is flat
 * in places and Newton wanders, and a grid is deterministic and has an obvious cap. Gamma* runs
 * over the span of the data widened by 0.02 on each side in steps of 1e-4; the width w over 49
 * log-spaced values from 1e-4 to 0.1. The profile log-likelihood of Gamma* (the best w for each
 * Gamma*) gives the 95% interval: the Gammas whose profile lies within 1.92 (chi^2_1 / 2) of the
 * maximum. */
#include "campaign_edge.h"

#include <math.h>

#define SAME_PHI 1e-6
#define PAD 0.02
#define STEP 1e-4
#define NW 49
#define W_MIN 1e-4
#define W_MAX 0.1
#define DROP95 1.920729

const char *campaign_edge_method_name(campaign_edge_method m)
{
    switch (m) {
    case CAMPAIGN_EDGE_BELOW: return "below";
    case CAMPAIGN_EDGE_ABOVE: return "above";
    case CAMPAIGN_EDGE_BRACKET: return "bracket";
    case CAMPAIGN_EDGE_PROBIT: return "probit";
    default: return "none";
    }
}

/* log Phi(x) without underflow for very negative x (the asymptotic tail). */
static double log_phi_cdf(double x)
{
    if (x > -30) return log(0.5 * erfc(-x / M_SQRT2));
    return -0.5 * x * x - log(-x) - 0.5 * log(2 * M_PI);
}

static double loglik(const campaign_obs *obs, size_t n, double phi, double g, double w)
{
    double ll = 0;
    for (size_t k = 0; k < n; k++) {
        if (fabs(obs[k].phi_deg - phi) > SAME_PHI) continue;
        double z = (g - obs[k].gamma) / w; /* P(asym) = Phi(z) */
        if (obs[k].n_asym) ll += obs[k].n_asym * log_phi_cdf(z);
        if (obs[k].n_sym) ll += obs[k].n_sym * log_phi_cdf(-z);
    }
    return ll;
}

static void probit(const campaign_obs *obs, size_t n, double phi, double gmin, double gmax, campaign_edge *e)
{
    double g0 = gmin - PAD, g1 = gmax + PAD;
    long ng = (long)ceil((g1 - g0) / STEP) + 1;
    double best = -INFINITY, best_g = g0, best_w = W_MAX;
    /* First pass: the maximum. Second pass: the profile's interval. */
    for (int pass = 0; pass < 2; pass++) {
        double lo = NAN, hi = NAN;
        for (long i = 0; i < ng; i++) {
            double g = g0 + (double)i * STEP;
            double prof = -INFINITY, pw = W_MAX;
            for (int j = 0; j < NW; j++) {
                double w = W_MIN * pow(W_MAX / W_MIN, (double)j / (NW - 1));
                double ll = loglik(obs, n, phi, g, w);
                if (ll > prof) prof = ll, pw = w;
            }
            if (pass == 0 && prof > best) best = prof, best_g = g, best_w = pw;
            if (pass == 1 && prof >= best - DROP95) {
                if (isnan(lo)) lo = g;
                hi = g;
            }
        }
        if (pass == 1) {
            e->lo = lo;
            e->hi = hi;
        }
    }
    e->gamma = best_g;
    e->width = best_w;
}

void campaign_edge_fit(const campaign_obs *obs, size_t n, double phi_deg, campaign_edge *e)
{
    e->phi_deg = phi_deg;
    e->method = CAMPAIGN_EDGE_NONE;
    e->gamma = e->lo = e->hi = e->width = NAN;
    e->n_asym = e->n_sym = e->n_points = 0;
    double max_asym = -INFINITY, min_sym = INFINITY, gmin = INFINITY, gmax = -INFINITY;
    for (size_t k = 0; k < n; k++) {
        if (fabs(obs[k].phi_deg - phi_deg) > SAME_PHI || obs[k].n_asym + obs[k].n_sym == 0) continue;
        e->n_points++;
        e->n_asym += obs[k].n_asym;
        e->n_sym += obs[k].n_sym;
        if (obs[k].n_asym && obs[k].gamma > max_asym) max_asym = obs[k].gamma;
        if (obs[k].n_sym && obs[k].gamma < min_sym) min_sym = obs[k].gamma;
        if (obs[k].gamma < gmin) gmin = obs[k].gamma;
        if (obs[k].gamma > gmax) gmax = obs[k].gamma;
    }
    if (!e->n_points) return;
    if (!e->n_asym) {
        e->method = CAMPAIGN_EDGE_BELOW;
        e->hi = min_sym;
    } else if (!e->n_sym) {
        e->method = CAMPAIGN_EDGE_ABOVE;
        e->lo = max_asym;
    } else if (max_asym < min_sym) {
        e->method = CAMPAIGN_EDGE_BRACKET;
        e->lo = max_asym;
        e->hi = min_sym;
        e->gamma = 0.5 * (max_asym + min_sym);
        e->width = 0;
    } else {
        e->method = CAMPAIGN_EDGE_PROBIT;
        probit(obs, n, phi_deg, gmin, gmax, e);
    }
}

size_t campaign_edge_phis(const campaign_obs *obs, size_t n, double *phis, size_t max)
{
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        int seen = 0;
        for (size_t j = 0; j < m; j++)
            if (fabs(phis[j] - obs[k].phi_deg) <= SAME_PHI) seen = 1;
        if (seen || m >= max) continue;
        size_t j = m++;
        while (j > 0 && phis[j - 1] > obs[k].phi_deg) { phis[j] = phis[j - 1]; j--; }
        phis[j] = obs[k].phi_deg;
    }
    return m;
}
