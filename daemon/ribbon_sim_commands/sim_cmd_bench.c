/* sim_cmd_bench.c: `ribbon-sim bench`: the simulator's speed and memory on the paper scene, as
 * one machine-readable line (a benchmark, never a timed test).
 *   newton_iter_banded_s / newton_iter_dense_s: one Newton iteration's linear algebra on the
 *     N = 201 upper state: assembly of gradient and Hessian (one pass, as rod_solver.c does) plus
 *     factorisation and solve of the same system c1 M + H, banded (rod_band.c, the production
 *     LDL^T) and dense (GSL LU with GSL's own CBLAS), in the same run; newton_iter_dense_ldlt_s
 *     is the dense side with GSL's dense LDL^T instead, the like-for-like factorisation (about
 *     half the flops of LU), reported so the ratio's fairness can be judged;
 *   paper_predict_wall_s, realtime_factor: the full Gamma = 0.13 prediction at the paper's
 *     fixed dt = 1 ms, N = 201, and its simulated time over wall time;
 *   fast_predict_wall_s, fast_predict_rel_diff: the same prediction in fast mode and its relative
 *     difference in snap Delta W from the fixed-step run;
 *   continue_wall_s: the full bifurcation analysis of the scene (`ribbon-sim continue`: route to
 *     the upper state, primary branch, the branch switched at the first pitchfork, all events
 *     located), with continue_route_wall_s, the route's share, and continue_first_dw;
 *   sweep_point_wall_s: one `ribbon-sim sweep` task (route and primary branch to its first
 *     instability), the mean of the scene's Gamma and Gamma 0.21, at the scene's mesh;
 *   peak_rss_mb: the process's peak resident memory. */
#include "rod_band.h"
#include "rod_bifurcation.h"
#include "rod_protocol.h"
#include "rod_route.h"
#include "rod_solver.h"
#include "sim_bench_sweep.h"
#include "sim_cmd.h"
#include "sim_opts.h"
#include "sim_bench_boundary.h"
#include "sim_bench_fit.h"

#include <gsl/gsl_linalg.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

static const char usage[] =
    "usage: ribbon-sim bench --scene FILE [--set section.key=value ...] [--sweep | --boundary | --fit] [--json]\n"
    "  Measures the scene (the paper's Gamma = 0.13 scene is the reference:\n"
    "  config/scenes/paper-gamma013.ini): banded vs dense Newton iteration, the fixed-step and\n"
    "  fast predictions, the continuation (continue_wall_s), peak memory. Prints one line (one JSON object with --json). Takes about\n"
    "  a minute. --sweep instead: the 10 x 10 sweep in one process against `mpirun -np 2`\n"
    "  (sweep_mpi_efficiency) and with a route per point against continued upper states\n"
    "  (sweep_seed_saving); several minutes (--set mesh.nodes=61 for the README's mesh).\n"
    "  --boundary instead: only boundary_vs_sweep and its parts (traced boundary at 20 phi\n"
    "  against the sweep's bisection), one line.\n"
    "  --fit instead: the fit from a compression and hold (sim_bench_fit.h; fit_wall_s, fit_cpu_s)\n"
    "  and the sensitivities' Jacobian against central differences of whole paths\n"
    "  (sens_speedup), one line; seconds (--set mesh.nodes=61 on config/scenes/pet-200x5.ini).\n";

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Times one banded and one dense Newton iteration's linear algebra at the upper state. */
static int time_newton(const rod_scene *sc, double *banded, double *dense, double *dense_ldlt)
{
    rod *r = NULL;
    char err[256];
    if (rod_alloc(sc, &r, err, sizeof err) != ROD_OK) {
        fprintf(stderr, "ribbon-sim bench: %s\n", err);
        return 0;
    }
    rod_solver *s = rod_solver_alloc(r);
    int nf = rod_nfree(r), w = ROD_BAND + 1, ok = 0;
    double *g = malloc(sizeof(double) * (size_t)r->ndof);
    double *H = malloc(sizeof(double) * (size_t)nf * (size_t)w);
    double *x = malloc(sizeof(double) * (size_t)nf);
    gsl_matrix *D = gsl_matrix_alloc((size_t)nf, (size_t)nf);
    gsl_permutation *p = gsl_permutation_alloc((size_t)nf);
    if (!s || !g || !H || !x || !D || !p || rod_route_to_state(r, s, sc, +1, NULL) != ROD_OK) goto out;
    const int nb = 400, nd = 3;
    double t0 = now();
    for (int it = 0; it < nb; it++) {
        memset(H, 0, sizeof(double) * (size_t)nf * (size_t)w);
        rod_gradient_hessian(r, g, 1.0, H);
        for (int a = 0; a < nf; a++) H[a * w] += 1e3 * r->mass[a + ROD_FREE_BEGIN];
        for (int a = 0; a < nf; a++) x[a] = -g[a + ROD_FREE_BEGIN];
        if (rod_band_ldlt_decomp(H, nf)) goto out;
        rod_band_ldlt_solve(H, nf, x);
    }
    *banded = (now() - t0) / nb;
    for (int kind = 0; kind < 2; kind++) {
    t0 = now();
    for (int it = 0; it < nd; it++) {
        memset(H, 0, sizeof(double) * (size_t)nf * (size_t)w);
        rod_gradient_hessian(r, g, 1.0, H);
        gsl_matrix_set_zero(D);
        for (int a = 0; a < nf; a++)
            for (int k = 0; k < w && a + k < nf; k++) {
                double v = H[a * w + k] + (k == 0 ? 1e3 * r->mass[a + ROD_FREE_BEGIN] : 0.0);
                gsl_matrix_set(D, (size_t)a, (size_t)(a + k), v);
                gsl_matrix_set(D, (size_t)(a + k), (size_t)a, v);
            }
        int sign;
        for (int a = 0; a < nf; a++) x[a] = -g[a + ROD_FREE_BEGIN];
        gsl_vector_view xv = gsl_vector_view_array(x, (size_t)nf);
        if (kind == 0 && (gsl_linalg_LU_decomp(D, p, &sign) || gsl_linalg_LU_svx(D, p, &xv.vector))) goto out;
        if (kind == 1 && (gsl_linalg_ldlt_decomp(D) || gsl_linalg_ldlt_svx(D, &xv.vector))) goto out;
    }
    if (kind == 0) *dense = (now() - t0) / nd;
    else *dense_ldlt = (now() - t0) / nd;
    }
    ok = 1;
out:
    if (!ok) fprintf(stderr, "ribbon-sim bench: the Newton timing failed\n");
    free(g); free(H); free(x);
    if (D) gsl_matrix_free(D);
    if (p) gsl_permutation_free(p);
    rod_solver_free(s);
    rod_free(r);
    return ok;
}

static int predict(const rod_scene *sc, int fast, rod_prediction *p)
{
    rod_predict_opts o = fast ? rod_predict_opts_fast(sc) : rod_predict_opts_default();
    char err[512] = "";
    rod_status st = rod_predict(sc, &o, p, err, sizeof err);
    if (st != ROD_OK || !p->snapped) {
        fprintf(stderr, "ribbon-sim bench: %s prediction: %s\n", fast ? "fast" : "fixed-step",
                st != ROD_OK ? err : "no snap");
        return 0;
    }
    return 1;
}

/* --boundary: only the boundary part (boundary_wall_s, boundary_vs_sweep and their parts). */
static int bench_boundary_only(const rod_scene *sc, int json)
{
    sim_bench_boundary_result bb;
    char cerr[512] = "";
    if (sim_bench_boundary(sc, &bb, cerr, sizeof cerr) != 0) {
        fprintf(stderr, "ribbon-sim bench: boundary: %s\n", cerr);
        return 1;
    }
    if (json)
        printf("{\"nodes\":%d,\"boundary_wall_s\":%.6g,\"boundary_vs_sweep\":%.6g,\"boundary_sweep_wall_s\":%.6g,"
               "\"boundary_cpu_s\":%.6g,\"boundary_sweep_cpu_s\":%.6g,\"traced_phi90_gamma\":%.8g,"
               "\"sweep_phi90_gamma\":%.8g,\"sweep_classifications\":%d}\n",
               sc->nodes, bb.boundary_wall_s, bb.boundary_vs_sweep, bb.sweep_wall_s, bb.boundary_cpu_s, bb.sweep_cpu_s,
               bb.traced_phi90_gamma, bb.sweep_phi90_gamma, bb.sweep_classifications);
    else
        printf("bench-boundary nodes=%d boundary_vs_sweep=%.2f boundary_cpu_s=%.2f boundary_sweep_cpu_s=%.2f "
               "boundary_wall_s=%.2f boundary_sweep_wall_s=%.2f traced_phi90_gamma=%.6f sweep_phi90_gamma=%.6f "
               "sweep_classifications=%d\n",
               sc->nodes, bb.boundary_vs_sweep, bb.boundary_cpu_s, bb.sweep_cpu_s, bb.boundary_wall_s, bb.sweep_wall_s,
               bb.traced_phi90_gamma, bb.sweep_phi90_gamma, bb.sweep_classifications);
    return 0;
}

/* --fit: only the fit part. */
static int bench_fit_only(const rod_scene *sc, int json)
{
    sim_bench_fit_result b;
    char cerr[512] = "";
    if (sim_bench_fit(sc, &b, cerr, sizeof cerr) != 0) {
        fprintf(stderr, "ribbon-sim bench: fit: %s\n", cerr);
        return 1;
    }
    if (json)
        printf("{\"nodes\":%d,\"fit_samples\":%d,\"fit_parameters\":%d,\"fit_wall_s\":%.6g,\"fit_cpu_s\":%.6g,"
               "\"fit_iterations\":%d,\"fit_evaluations\":%d,\"fit_rms\":%.6g,\"sens_jacobian_s\":%.6g,"
               "\"fd_jacobian_s\":%.6g,\"sens_speedup\":%.6g}\n",
               b.nodes, b.samples, b.parameters, b.fit_wall_s, b.fit_cpu_s, b.iterations, b.evaluations, b.rms,
               b.sens_jacobian_s, b.fd_jacobian_s, b.sens_speedup);
    else
        printf("bench-fit nodes=%d samples=%d parameters=%d fit_wall_s=%.3f fit_cpu_s=%.3f iterations=%d "
               "evaluations=%d rms=%.3f sens_jacobian_s=%.4f fd_jacobian_s=%.4f sens_speedup=%.1f\n",
               b.nodes, b.samples, b.parameters, b.fit_wall_s, b.fit_cpu_s, b.iterations, b.evaluations, b.rms,
               b.sens_jacobian_s, b.fd_jacobian_s, b.sens_speedup);
    return 0;
}

int sim_cmd_bench(int argc, char **argv)
{
    int sweep = 0, boundary_only = 0, fit_only = 0, out = 1;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--sweep")) sweep = 1;
        else if (!strcmp(argv[i], "--boundary")) boundary_only = 1;
        else if (!strcmp(argv[i], "--fit")) fit_only = 1;
        else argv[out++] = argv[i];
    }
    argc = out;
    sim_opts o;
    int rc = sim_opts_parse(argc, argv, "json", usage, &o);
    if (rc) return rc == 1 ? 0 : 2;
    rod_scene sc;
    if (!sim_opts_load_scene(&o, &sc)) return 2;
    if (sweep) return sim_bench_sweep(o.scene, o.sets, o.nsets, o.json);
    if (boundary_only) return bench_boundary_only(&sc, o.json);
    if (fit_only) return bench_fit_only(&sc, o.json);
    double banded = 0, dense = 0, dense_ldlt = 0;
    rod_prediction fixed, fast;
    if (!time_newton(&sc, &banded, &dense, &dense_ldlt)) return 1;
    if (!predict(&sc, 0, &fixed) || !predict(&sc, 1, &fast)) return 1;
    rod_analysis an;
    char cerr[512] = "";
    rod_status cst = rod_bifurcation_analyse(&sc, NULL, &an, cerr, sizeof cerr);
    if (cst != ROD_OK) {
        fprintf(stderr, "ribbon-sim bench: continuation: %s\n", cerr[0] ? cerr : rod_status_message(cst));
        return 1;
    }
    double cont_wall = an.wall_s, cont_route = an.route_wall_s;
    double cont_first = an.first >= 0 ? an.events[an.first].at.dw : 0.0;
    rod_analysis_free(&an);
    /* sweep_point_wall_s: one sweep task (classification only) at the scene's mesh, averaged
     * over the scene's Gamma and a symmetric-snap Gamma 0.21. */
    double sweep_pt = 0.0;
    const double sweep_gammas[2] = {sc.fold_position, 0.21};
    rod_analysis_opts so = rod_analysis_opts_classify();
    for (int k = 0; k < 2; k++) {
        rod_scene ss = sc;
        ss.fold_position = sweep_gammas[k];
        if (rod_bifurcation_analyse(&ss, &so, &an, cerr, sizeof cerr) != ROD_OK) {
            fprintf(stderr, "ribbon-sim bench: sweep point: %s\n", cerr);
            return 1;
        }
        sweep_pt += 0.5 * an.wall_s;
        rod_analysis_free(&an);
    }
    sim_bench_boundary_result bb;
    if (sim_bench_boundary(&sc, &bb, cerr, sizeof cerr) != 0) {
        fprintf(stderr, "ribbon-sim bench: boundary: %s\n", cerr);
        return 1;
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    double rss_mb = (double)ru.ru_maxrss / 1024.0;
    double rel = fabs(fast.snap_dw - fixed.snap_dw) / fabs(fixed.snap_dw);
    json_t *j = json_pack("{s:i,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f,s:f}", "nodes",
                          sc.nodes, "newton_iter_banded_s", banded, "newton_iter_dense_s", dense, "banded_vs_dense",
                          dense / banded, "newton_iter_dense_ldlt_s", dense_ldlt, "banded_vs_dense_ldlt",
                          dense_ldlt / banded, "fast_switch_dw", fast.dw_switch, "paper_predict_wall_s", fixed.wall_s, "realtime_factor",
                          fixed.sim_time / fixed.wall_s, "fast_predict_wall_s", fast.wall_s,
                          "fast_predict_rel_diff", rel, "peak_rss_mb", rss_mb, "snap_dw_fixed", fixed.snap_dw,
                          "snap_dw_fast", fast.snap_dw, "continue_wall_s", cont_wall, "continue_route_wall_s",
                          cont_route, "continue_first_dw", cont_first, "sweep_point_wall_s", sweep_pt);
    json_object_set_new(j, "boundary_wall_s", json_real(bb.boundary_wall_s));
    json_object_set_new(j, "boundary_vs_sweep", json_real(bb.boundary_vs_sweep));
    json_object_set_new(j, "boundary_sweep_wall_s", json_real(bb.sweep_wall_s));
    json_object_set_new(j, "boundary_cpu_s", json_real(bb.boundary_cpu_s));
    json_object_set_new(j, "boundary_sweep_cpu_s", json_real(bb.sweep_cpu_s));
    char *txt = json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(6));
    if (o.json) puts(txt);
    else
        printf("bench nodes=%d banded=%.3gs dense=%.3gs ratio=%.0f paper_wall=%.2fs realtime=%.2f fast_wall=%.2fs "
               "fast_rel_diff=%.2e continue_wall=%.2fs boundary_wall=%.2fs boundary_vs_sweep=%.1f rss=%.1fMB\n",
               sc.nodes, banded, dense, dense / banded, fixed.wall_s, fixed.sim_time / fixed.wall_s, fast.wall_s, rel,
               cont_wall, bb.boundary_wall_s, bb.boundary_vs_sweep, rss_mb);
    free(txt);
    json_decref(j);
    return 0;
}
