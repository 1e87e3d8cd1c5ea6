/* sim_bench_sweep.c: `ribbon-sim bench --sweep`: the sweep's scaling as one machine-readable line
 * (issue 16, part F). Slow (four sweeps of the 10 x 10 grid), so apart from the default bench.
 *   sweep_mpi_efficiency: a 10 x 10 sweep (phi 45..135 deg, Gamma 0.05..0.30, the README's
 *     diagram) in one process on one thread against `mpirun -np 2` with one compute thread per
 *     rank: T1 / (2 T2) (target >= 0.9);
 *   sweep_seed_route_wall_s / sweep_seed_continue_wall_s: the same one-process sweep with a fresh
 *     route per point (--seed route) and with the upper states continued in Gamma (the default),
 *     and sweep_seed_saving = 1 - continue / route;
 *   sweep_same_rows: 1 when the one-process and the mpirun files hold the same rows bit for bit
 *     (wall_s aside);
 *   sweep_mpi_cpu_efficiency, sweep_seed_cpu_saving: the same ratios in CPU time (user + system
 *     of the child and its descendants), which a machine shared with other work does not blur
 *     as it blurs wall time (load_avg: the 1-minute load average at the end; the wall-time
 *     figures mean something only when it is below the core count). mpirun runs with
 *     --bind-to none so a busy core does not hold a rank.
 * Each sweep runs as a child process (this binary, /proc/self/exe), the mpirun one under Open
 * MPI's mpirun (--allow-run-as-root when run as root), into a fresh temporary directory that is
 * removed afterwards. */
#include "sim_bench_sweep.h"
#include "sim_sweep_row.h"

#include <errno.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

extern char **environ;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double children_cpu_s(void)
{
    struct rusage ru;
    getrusage(RUSAGE_CHILDREN, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
           1e-6 * (double)ru.ru_stime.tv_usec;
}

/* Runs argv (stdout to /dev/null), returns its wall time or -1 on failure; *cpu: the CPU time of
 * it and its descendants (mpirun waits for its ranks, so theirs is counted). */
static double run_timed(char *const argv[], double *cpu)
{
    double c0 = children_cpu_s();
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", 0x1 /* O_WRONLY */, 0);
    pid_t pid;
    double t0 = now();
    int rc = posix_spawnp(&pid, argv[0], &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) {
        fprintf(stderr, "ribbon-sim bench: cannot start %s: %s\n", argv[0], strerror(rc));
        return -1.0;
    }
    int st;
    if (waitpid(pid, &st, 0) < 0 || !WIFEXITED(st) || WEXITSTATUS(st) != 0) {
        fprintf(stderr, "ribbon-sim bench: %s failed\n", argv[0]);
        return -1.0;
    }
    double wall = now() - t0;
    *cpu = children_cpu_s() - c0;
    return wall;
}

/* The rows of a sweep file in canonical order without wall_s, or -1. */
static int same_rows(const char *a, const char *b)
{
    sweep_table ta, tb;
    char err[256];
    if (sweep_table_load(a, &ta, err, sizeof err) != 0) return -1;
    if (sweep_table_load(b, &tb, err, sizeof err) != 0) {
        sweep_table_free(&ta);
        return -1;
    }
    int same = ta.n == tb.n;
    qsort(ta.rows, ta.n, sizeof *ta.rows, sweep_row_compare);
    qsort(tb.rows, tb.n, sizeof *tb.rows, sweep_row_compare);
    for (size_t k = 0; same && k < ta.n; k++) {
        sweep_row x = ta.rows[k], y = tb.rows[k];
        x.wall_s = y.wall_s = 0.0;
        same = x.kind == y.kind && x.phi == y.phi && x.gamma == y.gamma && x.gamma_lo == y.gamma_lo &&
               x.gamma_hi == y.gamma_hi && x.dl == y.dl && !strcmp(x.regime, y.regime) &&
               !strcmp(x.first_type, y.first_type) && x.first_dw == y.first_dw && x.first_dz == y.first_dz &&
               !strcmp(x.upper, y.upper) && !strcmp(x.note, y.note);
    }
    sweep_table_free(&ta);
    sweep_table_free(&tb);
    return same;
}

int sim_bench_sweep(const char *scene, const char *const *sets, int nsets, int json)
{
    char dir[] = "/tmp/ribbon-bench-sweep-XXXXXX";
    if (!mkdtemp(dir)) {
        fprintf(stderr, "ribbon-sim bench: cannot make a temporary directory: %s\n", strerror(errno));
        return 1;
    }
    char self[4096];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0) {
        fprintf(stderr, "ribbon-sim bench: cannot find this program (/proc/self/exe)\n");
        rmdir(dir);
        return 1;
    }
    self[n] = '\0';
    char out[4][4200];
    static const char *const names[4] = {"one.csv", "np2.csv", "route.csv", "unused.csv"};
    for (int k = 0; k < 4; k++) snprintf(out[k], sizeof out[k], "%s/%s", dir, names[k]);
    /* argv: [mpirun opts] self sweep --scene F [--set ...] --phi --gamma --out X --jobs 1 [--seed route] */
    char *argv[64];
    double t[3] = {-1, -1, -1}, cpu[3] = {0, 0, 0};
    for (int run = 0; run < 3; run++) {
        int a = 0;
        if (run == 1) {
            argv[a++] = "mpirun";
            if (geteuid() == 0) argv[a++] = "--allow-run-as-root";
            argv[a++] = "--oversubscribe";
            argv[a++] = "--bind-to";
            argv[a++] = "none"; /* a shared machine: let the kernel move the ranks */
            argv[a++] = "-np";
            argv[a++] = "2";
        }
        argv[a++] = self;
        argv[a++] = "sweep";
        argv[a++] = "--scene";
        argv[a++] = (char *)scene;
        for (int s = 0; s < nsets && a < 48; s++) {
            argv[a++] = "--set";
            argv[a++] = (char *)sets[s];
        }
        argv[a++] = "--phi";
        argv[a++] = "45:135:10";
        argv[a++] = "--gamma";
        argv[a++] = "0.05:0.30:10";
        argv[a++] = "--out";
        argv[a++] = out[run];
        argv[a++] = "--jobs";
        argv[a++] = "1";
        if (run == 2) {
            argv[a++] = "--seed";
            argv[a++] = "route";
        }
        argv[a] = NULL;
        t[run] = run_timed(argv, &cpu[run]);
        if (t[run] < 0) break;
    }
    int same = t[1] > 0 ? same_rows(out[0], out[1]) : -1;
    for (int k = 0; k < 4; k++) unlink(out[k]);
    rmdir(dir);
    if (t[0] < 0 || t[1] < 0 || t[2] < 0) return 1;
    double eff = t[0] / (2.0 * t[1]), saving = 1.0 - t[0] / t[2], cpu_eff = cpu[0] / cpu[1];
    double cpu_saving = 1.0 - cpu[0] / cpu[2];
    double load[1] = {0.0};
    if (getloadavg(load, 1) < 1) load[0] = -1.0;
    if (json)
        printf("{\"sweep_mpi_efficiency\":%.3f,\"sweep_1proc_wall_s\":%.2f,\"sweep_np2_wall_s\":%.2f,"
               "\"sweep_mpi_cpu_efficiency\":%.3f,\"sweep_1proc_cpu_s\":%.2f,\"sweep_np2_cpu_s\":%.2f,"
               "\"sweep_seed_route_wall_s\":%.2f,\"sweep_seed_continue_wall_s\":%.2f,\"sweep_seed_saving\":%.3f,"
               "\"sweep_seed_cpu_saving\":%.3f,\"sweep_same_rows\":%d,\"points\":100,\"load_avg\":%.2f}\n",
               eff, t[0], t[1], cpu_eff, cpu[0], cpu[1], t[2], t[0], saving, cpu_saving, same, load[0]);
    else
        printf("bench-sweep sweep_mpi_efficiency=%.3f sweep_1proc_wall_s=%.2f sweep_np2_wall_s=%.2f "
               "sweep_mpi_cpu_efficiency=%.3f sweep_1proc_cpu_s=%.2f sweep_np2_cpu_s=%.2f "
               "sweep_seed_route_wall_s=%.2f sweep_seed_continue_wall_s=%.2f sweep_seed_saving=%.3f "
               "sweep_seed_cpu_saving=%.3f sweep_same_rows=%d points=100 load_avg=%.2f\n",
               eff, t[0], t[1], cpu_eff, cpu[0], cpu[1], t[2], t[0], saving, cpu_saving, same, load[0]);
    return 0;
}
