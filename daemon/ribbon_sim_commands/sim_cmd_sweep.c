/* sim_cmd_sweep.c: `ribbon-sim sweep`: the phase diagram of the regime over (phi, Gamma).
 *
 * Design (DESIGN.md section 7: "a list of tasks, each writing one result row"):
 *   phase 1  every grid point (phi_i, Gamma_j) is an independent task: the scene with the fold
 *            angle and position replaced is classified by continuation
 *            (rod_analysis_opts_classify: the primary branch up to its first instability) and
 *            one `point` row is appended to the CSV;
 *   phase 2  for each phi, every pair of neighbouring Gammas with different regimes (asymmetric,
 *            symmetric, or none: no instability on the traced branch) is a task:
 *            bisection in Gamma (each probe a classification, appended as a `probe` row) until
 *            the bracket is narrower than --gamma-tol, then one `boundary` row (the mesh puts
 *            nodes on each Gamma, rod.c, so the boundary is not tied to the grid spacing).
 * Tasks run on --jobs threads (default: every online core); the simulator has no global state.
 * Rows are appended whole under a mutex and flushed, so an interrupted sweep (Ctrl-C stops
 * taking tasks; a kill loses at most the rows being computed) keeps every finished row; rerun
 * the same command and classifications already in the file (points and probes) are reused and
 * finished boundaries skipped. A later MPI launcher can split the same task list.
 *
 * Angles: --phi takes the crease angle magnitude in degrees (the paper's phi); the sign is the
 * scene's (the paper scenes use -90, README "Crease orientation"). */
#include "rod_bifurcation.h"
#include "cfg_number.h"
#include "sim_cmd.h"
#include "sim_opts.h"
#include "sim_plot_sweep.h"
#include "sim_sweep_row.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static const char usage[] =
    "usage: ribbon-sim sweep --scene FILE --phi A:B:n --gamma C:D:m --out FILE.csv [--set k=v ...]\n"
    "                        [--plot FILE.png] [--jobs K] [--gamma-tol T] [--json]\n"
    "  Classifies every (phi, Gamma) of the grid by continuation (pitchfork first: asymmetric,\n"
    "  saddle-node first: symmetric), then locates the boundary Gamma*(phi) by bisection between\n"
    "  neighbours of different regime, to T in Gamma (default 1e-3). phi is the crease angle\n"
    "  magnitude in degrees (the scene's sign is kept). Rows go to FILE.csv as they finish\n"
    "  (kind,phi_deg,gamma,gamma_lo,gamma_hi,regime,first_type,first_dw,first_dz,wall_s,note);\n"
    "  rerunning an interrupted sweep reuses them. Progress on stderr; --jobs defaults to every\n"
    "  core. Prints Gamma* per phi (--json: one object). Tip: --set mesh.nodes=61 for speed.\n";

static volatile sig_atomic_t interrupted;

static void on_sigint(int sig)
{
    (void)sig;
    interrupted = 1;
}

typedef struct sweep {
    rod_scene base;
    double sign;             /* sign of the scene's crease angle */
    double *phi, *gamma;
    int nphi, ngamma;
    double gamma_tol;
    sweep_table table;       /* every row known: read from the file, then appended */
    FILE *out;
    pthread_mutex_t mu;
    int next, ntasks, done;  /* task counter of the running phase */
    int tty;
    double t0;
    /* phase 2 tasks */
    int *btask_phi;
    double *btask_lo, *btask_hi;
} sweep;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int parse_range(const char *flag, const char *v, double *a, double *b, int *n)
{
    if (cfg_number_range(v, a, b, n, 1000) != 0) {
        fprintf(stderr, "ribbon-sim sweep: %s needs A:B:n with finite A, B and 1 <= n <= 1000, got '%s'\n", flag,
                v ? v : "");
        return 0;
    }
    return 1;
}

static double *grid(double a, double b, int n)
{
    double *g = malloc(sizeof(double) * (size_t)n);
    if (!g) return NULL;
    for (int i = 0; i < n; i++) g[i] = n == 1 ? a : a + (b - a) * i / (n - 1);
    return g;
}

/* Classifies (phi, gamma) into row (kind set by the caller). */
static void classify(const sweep *sw, double phi, double gamma, sweep_row *row)
{
    double t0 = now();
    memset(row, 0, sizeof *row);
    row->phi = phi;
    row->gamma = row->gamma_lo = row->gamma_hi = gamma;
    rod_scene sc = sw->base;
    sc.fold_angle_deg = sw->sign * phi;
    sc.fold_position = gamma;
    rod_analysis_opts o = rod_analysis_opts_classify();
    rod_analysis a;
    char err[256] = "";
    rod_status st = rod_bifurcation_analyse(&sc, &o, &a, err, sizeof err);
    if (st != ROD_OK) {
        snprintf(row->regime, sizeof row->regime, "failed");
        snprintf(row->first_type, sizeof row->first_type, "none");
        snprintf(row->note, sizeof row->note, "%.150s", err[0] ? err : rod_status_message(st));
    } else {
        snprintf(row->regime, sizeof row->regime, "%s", a.regime);
        if (a.first >= 0) {
            const rod_event *e = &a.events[a.first];
            snprintf(row->first_type, sizeof row->first_type, "%s", rod_event_name(e->kind));
            row->first_dw = e->at.dw;
            row->first_dz = e->at.dz;
        } else {
            snprintf(row->first_type, sizeof row->first_type, "none");
            snprintf(row->note, sizeof row->note, "%.150s", a.branches[0].end_reason);
        }
        rod_analysis_free(&a);
    }
    row->wall_s = now() - t0;
}

static void progress(sweep *sw, const char *phase)
{
    if (!sw->tty) return;
    int width = 40, filled = sw->ntasks ? width * sw->done / sw->ntasks : width;
    char bar[64];
    for (int i = 0; i < width; i++) bar[i] = i < filled ? '#' : '.';
    bar[width] = '\0';
    fprintf(stderr, "\r  %s [%s] %d/%d  %.0f s ", phase, bar, sw->done, sw->ntasks, now() - sw->t0);
}

/* Appends a row to the table and the file (caller holds the mutex). */
static int record(sweep *sw, const sweep_row *row)
{
    if (!sweep_table_add(&sw->table, row)) return 0;
    sweep_row_write(sw->out, row);
    fflush(sw->out);
    return 1;
}

/* A classification through the cache: the table first, else computed and recorded as a probe. */
static void lookup_or_classify(sweep *sw, double phi, double gamma, sweep_row *row)
{
    pthread_mutex_lock(&sw->mu);
    const sweep_row *hit = sweep_table_find(&sw->table, phi, gamma);
    if (hit) *row = *hit;
    pthread_mutex_unlock(&sw->mu);
    if (hit) return;
    classify(sw, phi, gamma, row);
    row->kind = 'q';
    pthread_mutex_lock(&sw->mu);
    record(sw, row);
    pthread_mutex_unlock(&sw->mu);
}

static int take_task(sweep *sw)
{
    pthread_mutex_lock(&sw->mu);
    int i = (interrupted || sw->next >= sw->ntasks) ? -1 : sw->next++;
    pthread_mutex_unlock(&sw->mu);
    return i;
}

static void *points_worker(void *arg)
{
    sweep *sw = arg;
    int i;
    while ((i = take_task(sw)) >= 0) {
        double phi = sw->phi[i / sw->ngamma], gamma = sw->gamma[i % sw->ngamma];
        pthread_mutex_lock(&sw->mu);
        int known = sweep_table_find(&sw->table, phi, gamma) != NULL;
        pthread_mutex_unlock(&sw->mu);
        if (!known) {
            sweep_row row;
            classify(sw, phi, gamma, &row);
            row.kind = 'p';
            pthread_mutex_lock(&sw->mu);
            record(sw, &row);
            pthread_mutex_unlock(&sw->mu);
        }
        pthread_mutex_lock(&sw->mu);
        sw->done++;
        progress(sw, "points    ");
        pthread_mutex_unlock(&sw->mu);
    }
    return NULL;
}

/* Regimes a boundary may separate: the two snaps and "none" (the upper branch reaches the end of
 * the load range without an instability: no snap). Failed points separate nothing. */
static int is_regime(const sweep_row *r)
{
    return !strcmp(r->regime, "asymmetric") || !strcmp(r->regime, "symmetric") || !strcmp(r->regime, "none");
}

/* Bisects one grid cell of one phi. A midpoint of a third regime (a narrow band inside the
 * cell, such as "none" between the two snaps) splits the cell: the upper part is pushed and
 * bisected after the lower one, so each boundary gets its own row (at most 8 parts per cell). */
static void bisect_cell(sweep *sw, double phi, double lo0, double hi0)
{
    struct part {
        double lo, hi;
        char rlo[16], rhi[16];
    } stack[8];
    int top = 0;
    sweep_row rlo, rhi;
    lookup_or_classify(sw, phi, lo0, &rlo);
    lookup_or_classify(sw, phi, hi0, &rhi);
    if (!is_regime(&rlo) || !is_regime(&rhi) || !strcmp(rlo.regime, rhi.regime)) return;
    stack[top].lo = lo0;
    stack[top].hi = hi0;
    snprintf(stack[top].rlo, sizeof stack[top].rlo, "%s", rlo.regime);
    snprintf(stack[top].rhi, sizeof stack[top].rhi, "%s", rhi.regime);
    top++;
    while (top > 0 && !interrupted) {
        struct part p = stack[--top];
        char note[160] = "";
        for (int it = 0; p.hi - p.lo > sw->gamma_tol && it < 60 && !interrupted; it++) {
            double mid = 0.5 * (p.lo + p.hi);
            sweep_row rm;
            lookup_or_classify(sw, phi, mid, &rm);
            if (!strcmp(rm.regime, p.rlo)) {
                p.lo = mid;
            } else if (!strcmp(rm.regime, p.rhi)) {
                p.hi = mid;
            } else if (is_regime(&rm) && top < 8) {
                stack[top].lo = mid;
                stack[top].hi = p.hi;
                snprintf(stack[top].rlo, sizeof stack[top].rlo, "%s", rm.regime);
                snprintf(stack[top].rhi, sizeof stack[top].rhi, "%s", p.rhi);
                top++;
                p.hi = mid;
                snprintf(p.rhi, sizeof p.rhi, "%s", rm.regime);
            } else {
                snprintf(note, sizeof note, "bisection stopped: Gamma %.6g is %s", mid, rm.regime);
                break;
            }
        }
        if (interrupted) break;
        sweep_row b;
        memset(&b, 0, sizeof b);
        b.kind = 'b';
        b.phi = phi;
        b.gamma = 0.5 * (p.lo + p.hi);
        b.gamma_lo = p.lo;
        b.gamma_hi = p.hi;
        snprintf(b.regime, sizeof b.regime, "boundary");
        snprintf(b.first_type, sizeof b.first_type, "none");
        if (!note[0]) snprintf(note, sizeof note, "%s below; %s above", p.rlo, p.rhi);
        snprintf(b.note, sizeof b.note, "%s", note);
        pthread_mutex_lock(&sw->mu);
        record(sw, &b);
        pthread_mutex_unlock(&sw->mu);
    }
}

static void *boundary_worker(void *arg)
{
    sweep *sw = arg;
    int i;
    while ((i = take_task(sw)) >= 0) {
        bisect_cell(sw, sw->phi[sw->btask_phi[i]], sw->btask_lo[i], sw->btask_hi[i]);
        pthread_mutex_lock(&sw->mu);
        sw->done++;
        progress(sw, "boundaries");
        pthread_mutex_unlock(&sw->mu);
    }
    return NULL;
}

static void run_phase(sweep *sw, int jobs, void *(*fn)(void *), int ntasks)
{
    sw->next = 0;
    sw->done = 0;
    sw->ntasks = ntasks;
    pthread_t th[64];
    int started = 0;
    for (int k = 0; k < jobs && k < 64; k++)
        if (pthread_create(&th[started], NULL, fn, sw) == 0) started++;
    if (started == 0) fn(sw); /* no threads available: run in this one */
    for (int k = 0; k < started; k++) pthread_join(th[k], NULL);
    if (sw->tty) fputs("\n", stderr);
}

/* Pulls this command's own options out of argv; returns the new argc or -1. */
static int take_extra(int argc, char **argv, const char **phi, const char **gamma, const char **plot,
                      const char **jobs, const char **tol)
{
    int out = 1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char **dst = !strcmp(a, "--phi")         ? phi
                           : !strcmp(a, "--gamma")     ? gamma
                           : !strcmp(a, "--plot")      ? plot
                           : !strcmp(a, "--jobs")      ? jobs
                           : !strcmp(a, "--gamma-tol") ? tol
                                                       : NULL;
        if (!dst) {
            argv[out++] = argv[i];
            continue;
        }
        if (i + 1 >= argc) {
            fprintf(stderr, "ribbon-sim sweep: %s needs a value\n", a);
            return -1;
        }
        *dst = argv[++i];
    }
    return out;
}

static int compare_boundary(const void *a, const void *b)
{
    const sweep_row *x = *(const sweep_row *const *)a, *y = *(const sweep_row *const *)b;
    if (x->phi != y->phi) return x->phi < y->phi ? -1 : 1;
    return x->gamma < y->gamma ? -1 : x->gamma > y->gamma;
}

/* --jobs (default: the cores online, kept to 1..64). 0, or 2 (usage) after saying why. */
static int parse_jobs(const char *jobs_s, long *out)
{
    long jobs = sysconf(_SC_NPROCESSORS_ONLN);
    if (jobs_s) {
        char *end;
        jobs = strtol(jobs_s, &end, 10);
        if (*end || jobs < 1 || jobs > 64) {
            fprintf(stderr, "ribbon-sim sweep: --jobs needs 1..64, got '%s'\n", jobs_s);
            return 2;
        }
    }
    if (jobs < 1) jobs = 1;
    if (jobs > 64) jobs = 64;
    *out = jobs;
    return 0;
}

/* --gamma-tol (default 1e-3). 0, or 2 (usage) after saying why. */
static int parse_gamma_tol(const char *tol_s, double *out)
{
    *out = 1e-3;
    if (tol_s) {
        char *end;
        *out = cfg_number_strtod(tol_s, &end);
        if (*end || !(*out > 0.0) || !isfinite(*out)) {
            fprintf(stderr, "ribbon-sim sweep: --gamma-tol needs a positive number, got '%s'\n", tol_s);
            return 2;
        }
    }
    return 0;
}

/* Phase 2 tasks from the grid's regimes: every pair of neighbouring Gammas of one phi whose
 * regimes differ and whose boundary is not in the table yet. The number of tasks, or -1 when
 * memory runs out. */
static int boundary_tasks(sweep *sw)
{
    int np = sw->nphi, ng = sw->ngamma;
    int cap = np * (ng > 1 ? ng - 1 : 1), nb = 0;
    sw->btask_phi = malloc(sizeof(int) * (size_t)cap);
    sw->btask_lo = malloc(sizeof(double) * (size_t)cap);
    sw->btask_hi = malloc(sizeof(double) * (size_t)cap);
    if (!sw->btask_phi || !sw->btask_lo || !sw->btask_hi) return -1;
    for (int i = 0; i < np && !interrupted; i++)
        for (int j = 0; j + 1 < ng; j++) {
            const sweep_row *a = sweep_table_find(&sw->table, sw->phi[i], sw->gamma[j]);
            const sweep_row *b = sweep_table_find(&sw->table, sw->phi[i], sw->gamma[j + 1]);
            if (!a || !b || !is_regime(a) || !is_regime(b) || !strcmp(a->regime, b->regime)) continue;
            if (sweep_table_find_boundary(&sw->table, sw->phi[i], sw->gamma[j], sw->gamma[j + 1])) continue;
            sw->btask_phi[nb] = i;
            sw->btask_lo[nb] = sw->gamma[j];
            sw->btask_hi[nb] = sw->gamma[j + 1];
            nb++;
        }
    return nb;
}

/* Summary: the boundaries inside the grid, by phi (text, or one JSON line). */
static void print_summary(const sweep *sw, const sim_opts *o, long jobs, double ga, double gb)
{
    int np = sw->nphi, ng = sw->ngamma;
    const sweep_row **bs = malloc(sizeof(*bs) * (sw->table.n ? sw->table.n : 1));
    int nbs = 0;
    for (size_t k = 0; bs && k < sw->table.n; k++) {
        const sweep_row *r = &sw->table.rows[k];
        if (r->kind != 'b') continue;
        for (int i = 0; i < np; i++)
            if (fabs(r->phi - sw->phi[i]) <= 1e-9 * fmax(1.0, fabs(r->phi)) && r->gamma >= fmin(ga, gb) &&
                r->gamma <= fmax(ga, gb)) {
                bs[nbs++] = r;
                break;
            }
    }
    if (bs) qsort(bs, (size_t)nbs, sizeof *bs, compare_boundary);
    if (o->json) {
        printf("{\"out\":\"%s\",\"points\":%d,\"jobs\":%ld,\"wall_s\":%.3f,\"boundaries\":[", o->out, np * ng, jobs,
               now() - sw->t0);
        for (int k = 0; k < nbs; k++)
            printf("%s{\"phi_deg\":%.10g,\"gamma\":%.10g,\"gamma_lo\":%.10g,\"gamma_hi\":%.10g,\"note\":\"%s\"}",
                   k ? "," : "", bs[k]->phi, bs[k]->gamma, bs[k]->gamma_lo, bs[k]->gamma_hi, bs[k]->note);
        printf("]}\n");
    } else {
        printf("sweep        %s: %d x %d grid, %d jobs, %.1f s wall\n", o->out, np, ng, (int)jobs, now() - sw->t0);
        if (nbs == 0) printf("boundary     none in the grid (one regime throughout, or failures)\n");
        for (int k = 0; k < nbs; k++)
            printf("boundary     phi %6.2f deg: Gamma* = %.4f (bracket %.4f .. %.4f; %s)\n", bs[k]->phi, bs[k]->gamma,
                   bs[k]->gamma_lo, bs[k]->gamma_hi, bs[k]->note);
    }
    free(bs);
}

int sim_cmd_sweep(int argc, char **argv)
{
    const char *phi_s = NULL, *gamma_s = NULL, *plot = NULL, *jobs_s = NULL, *tol_s = NULL;
    argc = take_extra(argc, argv, &phi_s, &gamma_s, &plot, &jobs_s, &tol_s);
    if (argc < 0) return 2;
    sim_opts o;
    int rc = sim_opts_parse(argc, argv, "json out", usage, &o);
    if (rc) return rc == 1 ? 0 : 2;
    double pa, pb, ga, gb;
    int np, ng;
    if (!parse_range("--phi", phi_s, &pa, &pb, &np) || !parse_range("--gamma", gamma_s, &ga, &gb, &ng)) return 2;
    if (!o.out) {
        fprintf(stderr, "ribbon-sim sweep: --out FILE.csv is required\n");
        return 2;
    }
    long jobs;
    if (parse_jobs(jobs_s, &jobs)) return 2;
    sweep sw;
    memset(&sw, 0, sizeof sw);
    interrupted = 0;
    if (parse_gamma_tol(tol_s, &sw.gamma_tol)) return 2;
    if (!sim_opts_load_scene(&o, &sw.base)) return 2;
    sw.sign = sw.base.fold_angle_deg < 0.0 ? -1.0 : 1.0;
    sw.phi = grid(pa, pb, np);
    sw.gamma = grid(ga, gb, ng);
    sw.nphi = np;
    sw.ngamma = ng;
    int status = 1;
    char err[256] = "";
    if (!sw.phi || !sw.gamma) goto done;
    if (sweep_table_load(o.out, &sw.table, err, sizeof err) != 0) {
        fprintf(stderr, "ribbon-sim sweep: %s\n", err);
        goto done;
    }
    size_t resumed = sw.table.n;
    int fresh = access(o.out, F_OK) != 0;
    sw.out = fopen(o.out, "a");
    if (!sw.out) {
        fprintf(stderr, "ribbon-sim sweep: cannot open %s: %s\n", o.out, strerror(errno));
        goto done;
    }
    if (fresh) sweep_row_write_header(sw.out);
    else sweep_table_fix_tail(o.out, sw.out);
    pthread_mutex_init(&sw.mu, NULL);
    sw.tty = isatty(2);
    sw.t0 = now();
    struct sigaction sa, old;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigaction(SIGINT, &sa, &old);
    if (resumed) fprintf(stderr, "ribbon-sim sweep: resuming %s (%zu rows kept)\n", o.out, resumed);

    run_phase(&sw, (int)jobs, points_worker, np * ng);

    int nb = boundary_tasks(&sw);
    if (nb < 0) goto done_sig;
    if (!interrupted) run_phase(&sw, (int)jobs, boundary_worker, nb);
    if (interrupted) {
        fprintf(stderr, "ribbon-sim sweep: interrupted; finished rows are in %s, rerun to resume\n", o.out);
        status = 130;
        goto done_sig;
    }

    print_summary(&sw, &o, jobs, ga, gb);
    status = 0;
    if (plot) {
        char perr[256];
        if (sim_plot_sweep(plot, &sw.table, pa, pb, ga, gb, perr, sizeof perr) != 0) {
            fprintf(stderr, "ribbon-sim sweep: %s\n", perr);
            status = 1;
        }
    }

done_sig:
    sigaction(SIGINT, &old, NULL);
    pthread_mutex_destroy(&sw.mu);
done:
    if (sw.out && fclose(sw.out) != 0) {
        fprintf(stderr, "ribbon-sim sweep: error writing %s\n", o.out);
        status = 1;
    }
    free(sw.btask_phi);
    free(sw.btask_lo);
    free(sw.btask_hi);
    sweep_table_free(&sw.table);
    free(sw.phi);
    free(sw.gamma);
    return status;
}
