/* sim_cmd_sweep.c: `ribbon-sim sweep`: the phase diagram of the regime over (phi, Gamma, Delta L).
 *
 * Design (DESIGN.md section 7: "a list of tasks, each writing one result row"; issue 16): a task
 * is one row of the diagram, every grid Gamma at one (phi, Delta L) (sim_sweep_task.h: the upper
 * states by continuation in Gamma from one route, the points classified by continuation in
 * Delta W, the boundaries bisected in Gamma). A task depends on nothing but the scene and the
 * grid, so its rows are the same bit for bit whoever runs it: threads of one process (--jobs,
 * default every online core), the ranks of `mpirun -np K` (sim_sweep_farm.h, a task farm with
 * rank 0 writing), or the shards of --shard i/N (task t belongs to shard t mod N), joined by
 * `ribbon-sim sweep-merge`. Rows are appended whole under a mutex and flushed, so an interrupted
 * sweep (Ctrl-C stops between classifications; a kill loses at most the rows being computed)
 * keeps every finished row; rerun the same command and classifications already in the file are
 * reused and finished rows of the diagram skipped.
 *
 * Angles: --phi takes the crease angle magnitude in degrees (the paper's phi); the sign is the
 * scene's (the paper scenes use -90, README "Crease orientation"). */
#include "cfg_number.h"
#include "sim_cmd.h"
#include "sim_opts.h"
#include "sim_plot_sweep.h"
#include "sim_sweep_farm.h"
#include "sim_sweep_origin.h"
#include "sim_sweep_row.h"
#include "sim_sweep_task.h"

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
    "usage: [mpirun -np K] ribbon-sim sweep --scene FILE --phi A:B:n --gamma C:D:m --out FILE.csv\n"
    "                        [--dl E:F:k] [--set k=v ...] [--plot FILE.png] [--jobs K] [--gamma-tol T]\n"
    "                        [--shard i/N] [--seed continue|route] [--heartbeat S] [--json]\n"
    "  Classifies every (phi, Gamma, Delta L) of the grid by continuation (pitchfork first:\n"
    "  asymmetric, saddle-node first: symmetric), then locates the boundary Gamma*(phi) by\n"
    "  bisection between neighbours of different regime, to T in Gamma (default 1e-3). phi is the\n"
    "  crease angle magnitude in degrees (the scene's sign is kept); --dl defaults to the scene's\n"
    "  Delta L. The upper state of each point is continued from its neighbour in Gamma\n"
    "  (--seed route: a fresh route per point). Rows go to FILE.csv as they finish (kind,phi_deg,\n"
    "  gamma,gamma_lo,gamma_hi,dl,regime,first_type,first_dw,first_dz,upper,wall_s,note); rerunning\n"
    "  an interrupted sweep reuses them. Under mpirun the ranks share the rows of the diagram\n"
    "  (rank 0 writes; --heartbeat: seconds of silence before a rank is taken for dead, default\n"
    "  30); --shard i/N (0 <= i < N) runs every N-th row into FILE.csv alone, for\n"
    "  `ribbon-sim sweep-merge`. Progress on stderr; --jobs defaults to every core. Prints Gamma*\n"
    "  per phi (--json: one object). Tip: --set mesh.nodes=61 for speed. docs/sweeps.md.\n";

static volatile sig_atomic_t interrupted;

static void on_sigint(int sig)
{
    (void)sig;
    interrupted = 1;
}

typedef struct task {
    int iphi, idl;
} task;

typedef struct sweep {
    sweep_spec spec;
    double *phi, *gamma, *dl;
    int nphi, ngamma, ndl;
    sweep_table known;       /* the rows read at the start (read-only while tasks run) */
    sweep_table table;       /* every row known: read from the file, then appended */
    FILE *out;
    pthread_mutex_t mu;
    task *tasks;             /* the row tasks this process (or this farm) runs */
    int ntasks, next;
    int points_total, points_done;
    int tty;
    double t0;
} sweep;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int parse_range(const char *flag, const char *v, double *a, double *b, int *n)
{
    int rc = cfg_number_range(v, a, b, n, 1000);
    if (rc == -2) {
        fprintf(stderr, "ribbon-sim sweep: %s '%s' runs from high to low; write it low to high (A <= B)\n", flag, v);
        return 0;
    }
    if (rc != 0) {
        fprintf(stderr, "ribbon-sim sweep: %s needs A:B:n with finite A <= B and 1 <= n <= 1000, got '%s'\n", flag,
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

static void progress(sweep *sw)
{
    if (!sw->tty) return;
    /* A task retried after a lost worker passes its points again: never past the total. */
    int done = sw->points_done < sw->points_total ? sw->points_done : sw->points_total;
    int width = 40, filled = sw->points_total ? width * done / sw->points_total : width;
    char bar[64];
    for (int i = 0; i < width; i++) bar[i] = i < filled ? '#' : '.';
    bar[width] = '\0';
    fprintf(stderr, "\r  points [%s] %d/%d  %.0f s ", bar, done, sw->points_total, now() - sw->t0);
}

/* Every row of every task comes here (any thread): a new one is appended to the table and the
 * file unless the table has it already (a task retried after a lost worker), whole and flushed. */
static void write_row(void *ctx, const sweep_row *row, int is_new)
{
    sweep *sw = ctx;
    pthread_mutex_lock(&sw->mu);
    if (is_new && !sweep_table_find_same(&sw->table, row) && sweep_table_add(&sw->table, row)) {
        sweep_row_write(sw->out, row);
        fflush(sw->out);
    }
    if (row->kind == 'p') {
        sw->points_done++;
        progress(sw);
    }
    pthread_mutex_unlock(&sw->mu);
}

static void run_task(void *ctx, int t, sweep_emit_fn emit, void *emit_ctx)
{
    sweep *sw = ctx;
    sweep_run_row(&sw->spec, sw->phi[sw->tasks[t].iphi], sw->dl[sw->tasks[t].idl], &sw->known, emit, emit_ctx,
                  &interrupted);
}

static void *thread_main(void *arg)
{
    sweep *sw = arg;
    for (;;) {
        pthread_mutex_lock(&sw->mu);
        int t = (interrupted || sw->next >= sw->ntasks) ? -1 : sw->next++;
        pthread_mutex_unlock(&sw->mu);
        if (t < 0) return NULL;
        run_task(sw, t, write_row, sw);
    }
}

/* One process: the tasks on `jobs` threads. */
static void run_threads(sweep *sw, int jobs)
{
    pthread_t th[64];
    int started = 0;
    sw->next = 0;
    for (int k = 0; k < jobs && k < 64 && k < sw->ntasks; k++)
        if (pthread_create(&th[started], NULL, thread_main, sw) == 0) started++;
    if (started == 0) thread_main(sw); /* no threads available: run in this one */
    for (int k = 0; k < started; k++) pthread_join(th[k], NULL);
}

/* This command's own options, pulled out of argv before the shared ones. */
typedef struct extra {
    const char *phi, *gamma, *dl, *plot, *jobs, *tol, *shard, *seed, *heartbeat;
} extra;

/* Pulls this command's own options out of argv; returns the new argc or -1. */
static int take_extra(int argc, char **argv, extra *x)
{
    int out = 1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char **dst = !strcmp(a, "--phi")         ? &x->phi
                           : !strcmp(a, "--gamma")     ? &x->gamma
                           : !strcmp(a, "--dl")        ? &x->dl
                           : !strcmp(a, "--plot")      ? &x->plot
                           : !strcmp(a, "--jobs")      ? &x->jobs
                           : !strcmp(a, "--gamma-tol") ? &x->tol
                           : !strcmp(a, "--shard")     ? &x->shard
                           : !strcmp(a, "--seed")      ? &x->seed
                           : !strcmp(a, "--heartbeat") ? &x->heartbeat
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
    if (x->dl != y->dl) return x->dl < y->dl ? -1 : 1;
    if (x->phi != y->phi) return x->phi < y->phi ? -1 : 1;
    return x->gamma < y->gamma ? -1 : x->gamma > y->gamma;
}

static int on_grid(const double *g, int n, double v)
{
    for (int i = 0; i < n; i++)
        if (fabs(v - g[i]) <= 1e-9 * fmax(1.0, fabs(v))) return 1;
    return 0;
}

/* The summary on stdout: the boundaries by Delta L and phi. */
static void print_summary(const sweep *sw, const char *out, int json, int jobs, int ranks, double ga, double gb)
{
    const sweep_row **bs = malloc(sizeof(*bs) * (sw->table.n ? sw->table.n : 1));
    int nbs = 0, nopoint = 0;
    for (size_t k = 0; bs && k < sw->table.n; k++) {
        const sweep_row *r = &sw->table.rows[k];
        if (r->kind == 'p' && on_grid(sw->phi, sw->nphi, r->phi) && on_grid(sw->dl, sw->ndl, r->dl) &&
            !strcmp(r->regime, "no-upper"))
            nopoint++;
        if (r->kind != 'b' || !on_grid(sw->phi, sw->nphi, r->phi) || !on_grid(sw->dl, sw->ndl, r->dl) ||
            r->gamma < fmin(ga, gb) || r->gamma > fmax(ga, gb))
            continue;
        bs[nbs++] = r;
    }
    if (bs) qsort(bs, (size_t)nbs, sizeof *bs, compare_boundary);
    int npoints = sw->nphi * sw->ngamma * sw->ndl;
    if (json) {
        printf("{\"out\":\"%s\",\"points\":%d,\"jobs\":%d,\"ranks\":%d,\"no_upper\":%d,\"wall_s\":%.3f,\"boundaries\":[",
               out, npoints, jobs, ranks, nopoint, now() - sw->t0);
        for (int k = 0; k < nbs; k++)
            printf("%s{\"phi_deg\":%.10g,\"dl\":%.10g,\"gamma\":%.10g,\"gamma_lo\":%.10g,\"gamma_hi\":%.10g,"
                   "\"note\":\"%s\"}",
                   k ? "," : "", bs[k]->phi, bs[k]->dl, bs[k]->gamma, bs[k]->gamma_lo, bs[k]->gamma_hi, bs[k]->note);
        printf("]}\n");
    } else {
        printf("sweep        %s: %d x %d x %d grid, %d jobs x %d ranks, %.1f s wall\n", out, sw->nphi, sw->ngamma,
               sw->ndl, jobs, ranks, now() - sw->t0);
        if (nopoint) printf("no upper     %d grid points (no stable upper state reached; evidence in the notes)\n", nopoint);
        if (nbs == 0) printf("boundary     none in the grid (one regime throughout, or failures)\n");
        for (int k = 0; k < nbs; k++)
            printf("boundary     phi %6.2f deg, Delta L %.3g: Gamma* = %.4f (bracket %.4f .. %.4f; %s)\n", bs[k]->phi,
                   bs[k]->dl, bs[k]->gamma, bs[k]->gamma_lo, bs[k]->gamma_hi, bs[k]->note);
    }
    free(bs);
}

/* --jobs (default every online core, at most 64). 0, or 2 (usage) after saying why. */
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

/* "--shard i/N": 0 <= i < N. */
static int parse_shard(const char *v, int *i, int *n)
{
    char extra;
    if (!v) {
        *i = 0;
        *n = 1;
        return 1;
    }
    if (sscanf(v, "%d/%d%c", i, n, &extra) != 2 || *n < 1 || *n > 100000 || *i < 0 || *i >= *n) {
        fprintf(stderr, "ribbon-sim sweep: --shard needs i/N with 0 <= i < N, got '%s'\n", v);
        return 0;
    }
    return 1;
}

/* RIBBON_SWEEP_TEST_DIE=rank:n (tests only, sim_sweep_farm.h). */
static void test_hook(sweep_farm_opts *fo)
{
    fo->die_rank = fo->die_task = -1;
    const char *v = getenv("RIBBON_SWEEP_TEST_DIE");
    if (v && sscanf(v, "%d:%d", &fo->die_rank, &fo->die_task) != 2) fo->die_rank = fo->die_task = -1;
}

int sim_cmd_sweep(int argc, char **argv)
{
    extra x;
    memset(&x, 0, sizeof x);
    argc = take_extra(argc, argv, &x);
    if (argc < 0) return 2;
    sim_opts o;
    int rc = sim_opts_parse(argc, argv, "json out", usage, &o);
    if (rc) return rc == 1 ? 0 : 2;
    double pa, pb, ga, gb, da = 0.0, db = 0.0;
    int np, ng, nd = 1, shard_i, shard_n;
    if (!parse_range("--phi", x.phi, &pa, &pb, &np) || !parse_range("--gamma", x.gamma, &ga, &gb, &ng)) return 2;
    if (x.dl && !parse_range("--dl", x.dl, &da, &db, &nd)) return 2;
    if (!parse_shard(x.shard, &shard_i, &shard_n)) return 2;
    if (!o.out) {
        fprintf(stderr, "ribbon-sim sweep: --out FILE.csv is required\n");
        return 2;
    }
    if (x.seed && strcmp(x.seed, "continue") && strcmp(x.seed, "route")) {
        fprintf(stderr, "ribbon-sim sweep: --seed is continue or route, got '%s'\n", x.seed);
        return 2;
    }
    if (pa <= 0.0 || pb <= 0.0 || pa >= 180.0 || pb >= 180.0) {
        fprintf(stderr, "ribbon-sim sweep: --phi needs crease angles in (0, 180) deg\n");
        return 2;
    }
    if (fmin(ga, gb) <= 0.0 || fmax(ga, gb) >= 0.5) {
        fprintf(stderr, "ribbon-sim sweep: --gamma needs crease positions in (0, 0.5)\n");
        return 2;
    }
    if (x.dl && (fmin(da, db) <= 0.0 || fmax(da, db) >= 1.0)) {
        fprintf(stderr, "ribbon-sim sweep: --dl needs compressions in (0, 1)\n");
        return 2;
    }
    long jobs;
    if (parse_jobs(x.jobs, &jobs)) return 2;
    sweep_farm_opts fo;
    memset(&fo, 0, sizeof fo);
    fo.heartbeat_timeout_s = 30.0;
    if (x.heartbeat) {
        char *end;
        fo.heartbeat_timeout_s = cfg_number_strtod(x.heartbeat, &end);
        if (*end || !(fo.heartbeat_timeout_s >= 2.0) || !isfinite(fo.heartbeat_timeout_s)) {
            fprintf(stderr, "ribbon-sim sweep: --heartbeat needs seconds >= 2, got '%s'\n", x.heartbeat);
            return 2;
        }
    }
    test_hook(&fo);
    sweep sw;
    memset(&sw, 0, sizeof sw);
    char err0[512];
    interrupted = 0;
    sw.spec.seed_route = x.seed && !strcmp(x.seed, "route");
    if (parse_gamma_tol(x.tol, &sw.spec.gamma_tol)) return 2;
    if (!sim_opts_load_scene(&o, &sw.spec.base)) return 2;
    {
        /* The sweep moves the symmetric pair (phi, Gamma): its base must be that pair. */
        char msg[256], key[64];
        if (rod_scene_require_symmetric(&sw.spec.base, msg, sizeof msg, key, sizeof key)) {
            fprintf(stderr, "ribbon-sim sweep: %s: %s: %s\n", o.scene, key, msg);
            return 2;
        }
    }
    if (!x.dl) da = db = sw.spec.base.compression;
    sw.spec.sign = sw.spec.base.fold_angle_deg < 0.0 ? -1.0 : 1.0;
    sw.phi = grid(pa, pb, np);
    sw.gamma = grid(ga, gb, ng);
    sw.dl = grid(da, db, nd);
    sw.nphi = np;
    sw.ngamma = ng;
    sw.ndl = nd;
    sw.spec.gamma = sw.gamma;
    sw.spec.ngamma = ng;
    char origin[SWEEP_ORIGIN_MAX];
    sweep_origin_format(&sw.spec, pa, pb, np, ga, gb, ng, da, db, nd, origin, sizeof origin);
    if (sw.phi && sw.gamma && sw.dl && sweep_grid_check(&sw.spec, sw.phi, np, sw.dl, nd, err0, sizeof err0) != 0) {
        /* A point the mesh cannot hold, refused before anything runs (issue 33, item 10). */
        fprintf(stderr, "ribbon-sim sweep: the grid has a point the scene cannot take: %s\n", err0);
        free(sw.phi);
        free(sw.gamma);
        free(sw.dl);
        return 2;
    }
    int status = 1, rank = 0, ranks = 1, mu_init = 0, sig_set = 0;
    char err[256] = "";
    struct sigaction sa, old;
    sweep_farm_start(&argc, &argv, &rank, &ranks);
    if (!sw.phi || !sw.gamma || !sw.dl) goto done;
    /* Every rank reads the file, and sees whether it exists, before rank 0 creates or appends to
     * it: a rank that looked after rank 0 had written the header would take the file for another
     * sweep's, leave, and the others wait for it forever. */
    int fresh = access(o.out, F_OK) != 0;
    int loaded = sweep_table_load(o.out, &sw.table, err, sizeof err);
    sweep_farm_barrier();
    if (loaded != 0) {
        if (rank == 0) fprintf(stderr, "ribbon-sim sweep: %s\n", err);
        goto done;
    }
    /* A file to resume must come from this sweep (sim_sweep_origin.h): the same program, scene,
     * N, tolerance and seed, the same Gamma grid, and phi and Delta L on its grid. */
    if (!fresh) {
        char what[400];
        if (!sw.table.origin[0]) {
            if (rank == 0)
                fprintf(stderr,
                        "ribbon-sim sweep: %s does not say what made it (no '# made by:' line: an earlier ribbon-sim "
                        "wrote it); start a new file\n",
                        o.out);
            goto done;
        }
        if (sweep_origin_resumable(sw.table.origin, origin, what, sizeof what) != 0) {
            if (rank == 0)
                fprintf(stderr, "ribbon-sim sweep: %s was made by another sweep (%s); name another file\n", o.out,
                        what);
            goto done;
        }
    }
    for (size_t k = 0; k < sw.table.n; k++)
        if (!sweep_table_add(&sw.known, &sw.table.rows[k])) goto done;
    /* The row tasks: every (phi, Delta L) of this shard not finished in the file. */
    sw.tasks = malloc(sizeof(task) * (size_t)(np * nd));
    if (!sw.tasks) goto done;
    for (int k = 0; k < nd; k++)
        for (int i = 0; i < np; i++) {
            int t = k * np + i;
            if (t % shard_n != shard_i) continue;
            sw.points_total += ng;
            if (sweep_row_complete(&sw.spec, sw.phi[i], sw.dl[k], &sw.table)) {
                sw.points_done += ng;
                continue;
            }
            sw.tasks[sw.ntasks].iphi = i;
            sw.tasks[sw.ntasks].idl = k;
            sw.ntasks++;
        }
    pthread_mutex_init(&sw.mu, NULL);
    mu_init = 1;
    if (rank == 0) {
        /* A row cut by a kill is cut off, so the file holds whole rows only. */
        if (!fresh && sweep_table_fix_tail(o.out) != 0) {
            fprintf(stderr, "ribbon-sim sweep: cannot cut the unfinished last row off %s: %s\n", o.out, strerror(errno));
            goto done;
        }
        sw.out = fopen(o.out, "a");
        if (!sw.out) {
            fprintf(stderr, "ribbon-sim sweep: cannot open %s: %s\n", o.out, strerror(errno));
            goto done;
        }
        if (fresh) sweep_row_write_header(sw.out, origin);
        fflush(sw.out); /* a job killed before its first row still leaves a sweep file to resume */
        sw.tty = isatty(2);
        if (sw.table.n) fprintf(stderr, "ribbon-sim sweep: resuming %s (%zu rows kept)\n", o.out, sw.table.n);
    }
    sw.t0 = now();
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_sigint;
    sigaction(SIGINT, &sa, &old);
    sig_set = 1;
    progress(&sw);

    int left = 0;
    if (ranks > 1) {
        left = sweep_farm_run(rank, ranks, sw.ntasks, run_task, &sw, write_row, &sw, &interrupted, &fo, err,
                              sizeof err);
        if (rank != 0) {
            status = 0;
            goto done;
        }
    } else {
        run_threads(&sw, (int)jobs);
    }
    if (sw.tty) fputs("\n", stderr);
    if (interrupted) {
        fprintf(stderr, "ribbon-sim sweep: interrupted; finished rows are in %s, rerun to resume\n", o.out);
        status = 130;
        goto done;
    }
    if (left) {
        fprintf(stderr, "ribbon-sim sweep: %s; finished rows are in %s, rerun to resume\n", err, o.out);
        goto done;
    }
    print_summary(&sw, o.out, o.json, ranks > 1 ? 1 : (int)jobs, ranks, ga, gb);
    status = 0;
    if (x.plot) {
        char perr[256];
        if (sim_plot_sweep(x.plot, &sw.table, pa, pb, ga, gb, sw.dl[0], perr, sizeof perr) != 0) {
            fprintf(stderr, "ribbon-sim sweep: %s\n", perr);
            status = 1;
        }
    }

done:
    if (sig_set) sigaction(SIGINT, &old, NULL);
    if (mu_init) pthread_mutex_destroy(&sw.mu);
    if (sw.out && fclose(sw.out) != 0) {
        fprintf(stderr, "ribbon-sim sweep: error writing %s\n", o.out);
        status = 1;
    }
    sweep_farm_stop();
    free(sw.tasks);
    sweep_table_free(&sw.table);
    sweep_table_free(&sw.known);
    free(sw.phi);
    free(sw.gamma);
    free(sw.dl);
    return status;
}
