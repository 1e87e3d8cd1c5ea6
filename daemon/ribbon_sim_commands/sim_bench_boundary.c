/* sim_bench_boundary.c: boundary_wall_s and boundary_vs_sweep of `ribbon-sim bench`.
 *
 * Traced: rod_boundary_start at the scene, then the codim-2 point moved to each of the 20 phi
 * 60 + 70 k / 19 deg in turn (each move ends on its phi exactly; its checks that the point is
 * still the regime boundary included), all timed. (Below about 50 deg at N = 61 another
 * pitchfork decides the snap, rod_boundary.h, so the range starts at 60.)
 * Sweep: what `ribbon-sim sweep --phi 45:135:20 --gamma 0.05:0.30:10 --gamma-tol 1e-5` does for
 * the lower boundary: per phi, 10 grid classifications and the bisection of the cell that
 * brackets Gamma* to 1e-5 (about the traced boundary's own accuracy; 12 probes from the
 * 0.028-wide cell). It is measured in full at phi = 90 deg (one thread, the classifications of
 * rod_analysis_opts_classify, as the sweep's tasks) and multiplied by 20: the cost of a
 * classification hardly depends on phi (the README's sweep: 0.4-0.5 s per task at N = 61
 * throughout the grid). Both sides run on one thread. */
#include "sim_bench_boundary.h"
#include "rod_bifurcation.h"
#include "rod_boundary.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#define NPHI 20
#define NGRID 10
#define GAMMA_TOL 1e-5

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* CPU time of the process: both sides run on one thread, so the ratio is taken in CPU time,
 * which other jobs on a shared machine do not inflate (wall time there was 9x the CPU time). */
static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* +1 asymmetric, -1 symmetric, 0 none or failed. */
static int classify(const rod_scene *base, double phi, double gamma, int *count)
{
    rod_scene sc = *base;
    sc.fold_angle_deg = (base->fold_angle_deg < 0 ? -1.0 : 1.0) * phi;
    sc.fold_position = gamma;
    rod_analysis_opts o = rod_analysis_opts_classify();
    rod_analysis a;
    char err[256];
    (*count)++;
    if (rod_bifurcation_analyse(&sc, &o, &a, err, sizeof err) != ROD_OK) return 0;
    int r = !strcmp(a.regime, "asymmetric") ? 1 : !strcmp(a.regime, "symmetric") ? -1 : 0;
    rod_analysis_free(&a);
    return r;
}

int sim_bench_boundary(const rod_scene *sc, sim_bench_boundary_result *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    double t0 = now(), c0 = cpu_now();
    rod_boundary_opts bo = rod_boundary_opts_default();
    bo.verify_ends = 0; /* the 20 moves are one range: checked every 10 deg along it, and at its end */
    rod_boundary *b = NULL;
    rod_codim2_point pt;
    if (rod_boundary_start(sc, &bo, &b, &pt, why, why_len) != ROD_OK) {
        rod_boundary_free(b);
        return -1;
    }
    for (int k = 0; k < NPHI; k++) {
        double phi = 60.0 + 70.0 * k / (NPHI - 1);
        rod_boundary_curve c = {0};
        rod_status st = rod_boundary_move(b, ROD_PAR_PHI, phi, &c);
        if (st != ROD_OK) {
            snprintf(why, why_len, "traced boundary at phi %g: %.200s", phi, c.end_reason);
            rod_boundary_curve_free(&c);
            rod_boundary_free(b);
            return -1;
        }
        rod_boundary_curve_free(&c);
    }
    double first_dw;
    if (!rod_boundary_check(b, &first_dw)) {
        snprintf(why, why_len, "traced boundary: at phi 130 the codim-2 point is no longer the regime boundary "
                 "(first instability at Delta W %.4f)", first_dw);
        rod_boundary_free(b);
        return -1;
    }
    out->boundary_wall_s = now() - t0;
    out->boundary_cpu_s = cpu_now() - c0;
    rod_boundary_move(b, ROD_PAR_PHI, 90.0, NULL);
    rod_boundary_current(b, &pt);
    out->traced_phi90_gamma = pt.gamma;
    rod_boundary_free(b);

    double t1 = now(), c1 = cpu_now();
    int count = 0, reg[NGRID];
    double g[NGRID];
    for (int j = 0; j < NGRID; j++) {
        g[j] = 0.05 + 0.25 * j / (NGRID - 1);
        reg[j] = classify(sc, 90.0, g[j], &count);
    }
    int cell = -1;
    for (int j = 0; j + 1 < NGRID; j++)
        if (reg[j] == 1 && reg[j + 1] == -1) {
            cell = j;
            break;
        }
    if (cell < 0) {
        snprintf(why, why_len, "the sweep's grid at phi 90 has no asymmetric/symmetric cell");
        return -1;
    }
    double lo = g[cell], hi = g[cell + 1];
    while (hi - lo > GAMMA_TOL) {
        double mid = 0.5 * (lo + hi);
        int r = classify(sc, 90.0, mid, &count);
        if (r == 1) lo = mid;
        else hi = mid;
    }
    double t_phi = now() - t1, c_phi = cpu_now() - c1;
    out->sweep_phi90_gamma = 0.5 * (lo + hi);
    out->sweep_classifications = count;
    out->sweep_wall_s = NPHI * t_phi;
    out->sweep_cpu_s = NPHI * c_phi;
    out->boundary_vs_sweep = out->sweep_cpu_s / out->boundary_cpu_s;
    return 0;
}
