/* sim_bench_fit.c: `ribbon-sim bench --fit` (sim_bench_fit.h). */
#include "sim_bench_fit.h"

#include "rod_fit.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define N_COMPRESS 20
#define N_HOLD 20

static double clock_s(clockid_t id)
{
    struct timespec t;
    clock_gettime(id, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static uint64_t rng_state = 0x2545F4914F6CDD1Dull;
static double gauss(void)
{
    double u[2];
    for (int k = 0; k < 2; k++) {
        rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
        u[k] = ((double)(rng_state >> 11) + 0.5) / 9007199254740992.0;
    }
    return sqrt(-2.0 * log(u[0])) * cos(2.0 * M_PI * u[1]);
}

int sim_bench_fit(const rod_scene *sc, sim_bench_fit_result *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    if (!rod_scene_has_creases(sc)) {
        snprintf(why, why_len, "the scene has no creases to fit");
        return -1;
    }
    rod_scene truth = *sc;
    truth.fold_angle_left_deg = 0.96 * rod_scene_crease_angle_deg(sc, 0);
    truth.fold_angle_right_deg = 0.99 * rod_scene_crease_angle_deg(sc, 1);
    if (!rod_scene_hinge_rigid(sc)) truth.fold_hinge_stiffness = 0.7 * sc->fold_hinge_stiffness;
    int n = N_COMPRESS + N_HOLD;
    rod_fit_obs obs[N_COMPRESS + N_HOLD];
    double dl = sc->compression, dl0 = fmax(0.5 * dl, dl - 0.05);
    for (int k = 0; k < N_COMPRESS; k++) obs[k] = (rod_fit_obs){dl0 + (dl - dl0) * k / (N_COMPRESS - 1), 0, 0, 0};
    for (int k = 0; k < N_HOLD; k++) obs[N_COMPRESS + k] = (rod_fit_obs){dl, 0, 0, 0};
    rod_fit_opts o = rod_fit_opts_default();
    o.fit[ROD_FIT_ANGLE_LEFT] = o.fit[ROD_FIT_ANGLE_RIGHT] = 1;
    o.fit[ROD_FIT_HINGE] = !rod_scene_hinge_rigid(sc);
    int use[ROD_FIT_NKEYS];
    memcpy(use, o.fit, sizeof use);
    int p = 0;
    for (int k = 0; k < ROD_FIT_NKEYS; k++) p += use[k];

    rod_fit_model *m = NULL;
    double *y = malloc(sizeof(double) * 2 * (size_t)n), *jac = malloc(sizeof(double) * 2 * (size_t)n * ROD_FIT_NKEYS);
    int rc = -1;
    if (!y || !jac) {
        snprintf(why, why_len, "out of memory");
        goto done;
    }
    if (rod_fit_model_alloc(&truth, obs, n, 0, &m, why, why_len) != ROD_OK) goto done;
    double u[ROD_FIT_NKEYS];
    rod_fit_scene_values(&truth, u);
    if (rod_fit_model_eval(m, u, NULL, y, NULL, why, why_len) != ROD_OK) goto done;
    for (int k = 0; k < n; k++) {
        obs[k].dz = y[2 * k] + o.sigma_dz * gauss();
        obs[k].a = y[2 * k + 1] + o.sigma_a * gauss();
    }
    rod_fit_model_free(m);
    m = NULL;

    /* The Jacobian at the scene's values, from the route: by sensitivities, then by central
       differences of whole paths (each one followed again from the route). */
    if (rod_fit_model_alloc(sc, obs, n, 0, &m, why, why_len) != ROD_OK) goto done;
    rod_fit_scene_values(sc, u);
    double t0 = clock_s(CLOCK_MONOTONIC);
    if (rod_fit_model_eval(m, u, use, y, jac, why, why_len) != ROD_OK) goto done;
    out->sens_jacobian_s = clock_s(CLOCK_MONOTONIC) - t0;
    t0 = clock_s(CLOCK_MONOTONIC);
    rod_fit_model_reset(m);
    if (rod_fit_model_eval(m, u, NULL, y, NULL, why, why_len) != ROD_OK) goto done;
    for (int k = 0; k < ROD_FIT_NKEYS; k++) {
        if (!use[k]) continue;
        for (int s = -1; s <= 1; s += 2) {
            double up[ROD_FIT_NKEYS];
            memcpy(up, u, sizeof up);
            up[k] += s * 1e-4;
            rod_fit_model_reset(m);
            if (rod_fit_model_eval(m, up, NULL, y, NULL, why, why_len) != ROD_OK) goto done;
        }
    }
    out->fd_jacobian_s = clock_s(CLOCK_MONOTONIC) - t0;
    out->sens_speedup = out->fd_jacobian_s / out->sens_jacobian_s;

    rod_fit_result r;
    double w0 = clock_s(CLOCK_MONOTONIC), c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
    if (rod_fit_run(sc, obs, n, &o, &r, why, why_len) != ROD_OK) goto done;
    out->fit_wall_s = clock_s(CLOCK_MONOTONIC) - w0;
    out->fit_cpu_s = clock_s(CLOCK_PROCESS_CPUTIME_ID) - c0;
    out->nodes = sc->nodes;
    out->samples = n;
    out->parameters = p;
    out->iterations = r.iterations;
    out->evaluations = r.evaluations;
    out->rms = r.rms;
    rc = 0;
done:
    rod_fit_model_free(m);
    free(y);
    free(jac);
    return rc;
}
