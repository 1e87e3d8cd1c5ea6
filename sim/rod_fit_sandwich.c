/* rod_fit_sandwich.c: the fit's covariance with a per-phase common-mode error (rod_fit_sandwich.h,
 * issue 32 D): the phases, the common mode's size from the residuals, the sandwich's extra terms. */
#include "rod_fit_sandwich.h"

#include <math.h>
#include <stdlib.h>

void rod_fit_phases(const rod_fit_obs *obs, int nobs, int *phase)
{
    for (int k = 0; k < nobs; k++) {
        if (obs[k].dw != 0.0) {
            phase[k] = ROD_FIT_PHASE_SHEAR;
            continue;
        }
        phase[k] = ROD_FIT_PHASE_COMPRESSION;
        for (int j = 0; j < nobs; j++)
            if (j != k && obs[j].dl == obs[k].dl && obs[j].dw == obs[k].dw) {
                phase[k] = ROD_FIT_PHASE_HOLD;
                break;
            }
    }
}

void rod_fit_common_mode_estimate(const double *f, int nobs, const int *phase, double rho[2])
{
    for (int a = 0; a < 2; a++) {
        double s = 0.0;
        int used = 0;
        for (int ph = 0; ph < ROD_FIT_NPHASES; ph++) {
            double sum = 0.0;
            int m = 0;
            for (int k = 0; k < nobs; k++)
                if (phase[k] == ph) {
                    sum += f[2 * k + a];
                    m++;
                }
            if (m < 2) continue;
            double mean = sum / m;
            s += mean * mean - 1.0 / m;
            used++;
        }
        rho[a] = used > 0 && s > 0.0 ? s / used : 0.0;
    }
}

int rod_fit_sandwich_add(const double *Jw, int nobs, int p, const int *phase, const double rho[2], const double *hinv, double *cov)
{
    double *g = malloc(sizeof(double) * 2 * (size_t)(p > 0 ? p : 1)), *h = g + (p > 0 ? p : 1);
    if (!g) return -1;
    for (int ph = 0; ph < ROD_FIT_NPHASES; ph++)
        for (int a = 0; a < 2; a++) {
            if (!(rho[a] > 0.0)) continue;
            int m = 0;
            for (int j = 0; j < p; j++) g[j] = 0.0;
            for (int k = 0; k < nobs; k++)
                if (phase[k] == ph) {
                    for (int j = 0; j < p; j++) g[j] += Jw[(size_t)(2 * k + a) * p + j];
                    m++;
                }
            if (m == 0) continue;
            for (int i = 0; i < p; i++) {
                h[i] = 0.0;
                for (int j = 0; j < p; j++) h[i] += hinv[(size_t)i * p + j] * g[j];
            }
            for (int i = 0; i < p; i++)
                for (int j = 0; j < p; j++) cov[(size_t)i * p + j] += rho[a] * h[i] * h[j];
        }
    free(g);
    return 0;
}

int rod_fit_sandwich_add_shapes(const double *Jw, const double *f, int p, int row0, const int *rows, int nshapes,
                                const double *hinv, double *cov)
{
    double *g = malloc(sizeof(double) * 2 * (size_t)(p > 0 ? p : 1)), *h = g + (p > 0 ? p : 1);
    if (!g) return -1;
    for (int s = 0, r0 = row0; s < nshapes; r0 += rows[s], s++) {
        for (int j = 0; j < p; j++) g[j] = 0.0;
        for (int r = r0; r < r0 + rows[s]; r++)
            for (int j = 0; j < p; j++) g[j] += Jw[(size_t)r * p + j] * f[r];
        for (int i = 0; i < p; i++) {
            h[i] = 0.0;
            for (int j = 0; j < p; j++) h[i] += hinv[(size_t)i * p + j] * g[j];
        }
        for (int i = 0; i < p; i++)
            for (int j = 0; j < p; j++) cov[(size_t)i * p + j] += h[i] * h[j];
    }
    free(g);
    return 0;
}
