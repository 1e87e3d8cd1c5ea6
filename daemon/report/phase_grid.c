/* phase_grid.c: the predicted phase diagram point by point (see phase_grid.h). */
#include "phase_grid.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "plot.h"
#include "rod_protocol.h"
#include "rod_seed_fold.h"

/* rod_predict's per-step hook: non-zero stops the run once the grid is cancelled. */
static int stop_when_cancelled(void *user, const rod_sample *s, const rod *r)
{
    (void)s;
    (void)r;
    const atomic_int *cancel = user;
    return cancel && atomic_load(cancel);
}

int phase_grid_compute(const rod_scene *base, double phi0, double phi1, size_t n_phi, double g0, double g1,
                       size_t n_gamma, phase_grid *out, void (*progress)(void *u, size_t done, size_t total),
                       void *u, const atomic_int *cancel, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    if (n_phi < 1 || n_gamma < 1 || n_phi > 64 || n_gamma > 64) {
        snprintf(why, why_len, "phase grid: 1 to 64 values of each parameter");
        return -1;
    }
    out->n_phi = n_phi;
    out->n_gamma = n_gamma;
    out->phi_deg = calloc(n_phi, sizeof(double));
    out->gamma = calloc(n_gamma, sizeof(double));
    out->regime = calloc(n_phi * n_gamma, sizeof(int));
    if (!out->phi_deg || !out->gamma || !out->regime) {
        phase_grid_free(out);
        snprintf(why, why_len, "phase grid: out of memory");
        return -1;
    }
    for (size_t i = 0; i < n_phi; i++) out->phi_deg[i] = n_phi > 1 ? phi0 + (phi1 - phi0) * i / (n_phi - 1) : phi0;
    for (size_t j = 0; j < n_gamma; j++) out->gamma[j] = n_gamma > 1 ? g0 + (g1 - g0) * j / (n_gamma - 1) : g0;
    double sign = base->fold_angle_deg < 0 ? -1.0 : 1.0;
    for (size_t i = 0; i < n_phi; i++)
        for (size_t j = 0; j < n_gamma; j++) {
            if (cancel && atomic_load(cancel)) {
                phase_grid_free(out);
                snprintf(why, why_len, "phase grid: cancelled");
                return -1;
            }
            rod_scene s = *base;
            s.fold_angle_deg = sign * fabs(out->phi_deg[i]);
            s.fold_position = out->gamma[j];
            /* The grid is over the symmetric pair (phi, Gamma): a specimen's own crease values
             * would pin every cell to them. */
            s.fold_angle_left_deg = s.fold_angle_right_deg = NAN;
            s.fold_position_left = s.fold_position_right = NAN;
            rod_predict_opts o = rod_predict_opts_default();
            o.adaptive = 1;
            o.on_sample = stop_when_cancelled;
            o.user = (void *)cancel;
            rod_prediction p;
            char err[256];
            int code = PLOT_REGIME_UNKNOWN;
            if (rod_scene_check(&s, NULL, 0, NULL, 0) == 0 && rod_predict(&s, &o, &p, err, sizeof err) == ROD_OK)
                code = !p.snapped ? PLOT_REGIME_NO_SNAP : p.asymmetric ? PLOT_REGIME_ASYMMETRIC : PLOT_REGIME_SYMMETRIC;
            out->regime[i * n_gamma + j] = code;
            if (progress) progress(u, i * n_gamma + j + 1, n_phi * n_gamma);
        }
    /* A failed cell whose upper state, followed from the nearest classified cell of its row or
     * column, ends at a located fold or pitchfork before it has no stable upper state to snap
     * from (rod_seed_fold.h; docs/sweeps.md part B): the cell says so instead of "failed". */
    for (size_t i = 0; i < n_phi; i++)
        for (size_t j = 0; j < n_gamma; j++) {
            if (out->regime[i * n_gamma + j] != PLOT_REGIME_UNKNOWN) continue;
            for (int d = 0; d < 4 && !(cancel && atomic_load(cancel)); d++) {
                long di = d == 2 ? -1 : d == 3 ? 1 : 0, dj = d == 0 ? -1 : d == 1 ? 1 : 0;
                long ii = (long)i + di, jj = (long)j + dj;
                while (ii >= 0 && jj >= 0 && ii < (long)n_phi && jj < (long)n_gamma &&
                       (out->regime[ii * n_gamma + jj] == PLOT_REGIME_UNKNOWN ||
                        out->regime[ii * n_gamma + jj] == PLOT_REGIME_NO_UPPER)) {
                    ii += di;
                    jj += dj;
                }
                if (ii < 0 || jj < 0 || ii >= (long)n_phi || jj >= (long)n_gamma) continue;
                rod_scene from = *base, to = *base;
                from.fold_angle_deg = sign * fabs(out->phi_deg[ii]);
                from.fold_position = out->gamma[jj];
                to.fold_angle_deg = sign * fabs(out->phi_deg[i]);
                to.fold_position = out->gamma[j];
                rod_seed_fold_report fr;
                if (rod_seed_end_between(&from, &to, &fr) == 1) {
                    out->regime[i * n_gamma + j] = PLOT_REGIME_NO_UPPER;
                    break;
                }
            }
        }
    if (cancel && atomic_load(cancel)) { /* the last point may have been cut short */
        phase_grid_free(out);
        snprintf(why, why_len, "phase grid: cancelled");
        return -1;
    }
    return 0;
}

void phase_grid_free(phase_grid *g)
{
    free(g->phi_deg);
    free(g->gamma);
    free(g->regime);
    memset(g, 0, sizeof *g);
}
