/* sim_sweep_farm.c: the sweep's task farm on Open MPI (see sim_sweep_farm.h). */
#include "sim_sweep_farm.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef RIBBON_HAVE_MPI

void sweep_farm_start(int *argc, char ***argv, int *rank, int *size)
{
    (void)argc;
    (void)argv;
    *rank = 0;
    *size = 1;
}

void sweep_farm_stop(void) {}

void sweep_farm_barrier(void) {}

int sweep_farm_run(int rank, int size, int ntasks, sweep_task_fn run, void *run_ctx, sweep_emit_fn write,
                   void *write_ctx, const volatile sig_atomic_t *cancel, const sweep_farm_opts *o, char *why,
                   size_t why_len)
{
    (void)rank;
    (void)size;
    (void)o;
    int left = 0;
    for (int t = 0; t < ntasks; t++) {
        if (cancel && *cancel) {
            left++;
            continue;
        }
        run(run_ctx, t, write, write_ctx);
    }
    if (left) snprintf(why, why_len, "%d tasks not run (interrupted)", left);
    return left;
}

#else

#include <mpi.h>
#include <pthread.h>
#include <time.h>
#include <unistd.h>

enum { TAG_READY = 1, TAG_TASK, TAG_ROW, TAG_DONE, TAG_BEAT };
#define MAX_ATTEMPTS 3

static int mpi_started;
/* A rank was lost: MPI_Finalize's closing fence would wait for it for ever (seen with
 * --enable-recovery under load), so the survivors leave without it; mpirun --enable-recovery
 * accepts that (exit status 0). Set on rank 0 when it takes a worker for dead, and on workers by
 * the stop message STOP_LOST. */
static int rank_lost;
#define STOP_LOST (-2)

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void sweep_farm_start(int *argc, char ***argv, int *rank, int *size)
{
    *rank = 0;
    *size = 1;
    const char *ws = getenv("OMPI_COMM_WORLD_SIZE");
    if (!ws || atoi(ws) < 2) return;
    int provided = 0;
    if (MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) return;
    mpi_started = 1;
    MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, size);
}

void sweep_farm_stop(void)
{
    if (mpi_started && !rank_lost) MPI_Finalize();
    mpi_started = 0;
}

void sweep_farm_barrier(void)
{
    if (mpi_started) MPI_Barrier(MPI_COMM_WORLD);
}

typedef struct row_msg {
    int task, is_new;
    sweep_row row;
} row_msg;

/* ---- a compute thread and its outbox (workers) ---- */

typedef struct outbox {
    pthread_mutex_t mu;
    row_msg *q;
    size_t n, cap;
    int finished;
    int task;
    sweep_task_fn run;
    void *run_ctx;
} outbox;

static void outbox_emit(void *ctx, const sweep_row *row, int is_new)
{
    outbox *b = ctx;
    pthread_mutex_lock(&b->mu);
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 32;
        row_msg *nq = realloc(b->q, cap * sizeof *nq);
        if (nq) {
            b->q = nq;
            b->cap = cap;
        }
    }
    if (b->n < b->cap) {
        row_msg *m = &b->q[b->n++];
        memset(m, 0, sizeof *m);
        m->task = b->task;
        m->is_new = is_new;
        m->row = *row;
    }
    pthread_mutex_unlock(&b->mu);
}

static void *outbox_thread(void *arg)
{
    outbox *b = arg;
    b->run(b->run_ctx, b->task, outbox_emit, b);
    pthread_mutex_lock(&b->mu);
    b->finished = 1;
    pthread_mutex_unlock(&b->mu);
    return NULL;
}

/* Sends the queued rows; returns whether the thread had finished before (all rows are out). */
static int outbox_flush(outbox *b)
{
    pthread_mutex_lock(&b->mu);
    int fin = b->finished;
    size_t n = b->n;
    row_msg *q = b->q;
    b->q = NULL;
    b->n = b->cap = 0;
    pthread_mutex_unlock(&b->mu);
    for (size_t k = 0; k < n; k++) MPI_Send(&q[k], (int)sizeof q[k], MPI_BYTE, 0, TAG_ROW, MPI_COMM_WORLD);
    free(q);
    return fin;
}

static int worker(int rank, sweep_task_fn run, void *run_ctx, const sweep_farm_opts *o)
{
    if (o && o->die_rank == rank && o->die_task == 0) { /* test hook: gone before its first READY */
        fprintf(stderr, "\nribbon-sim sweep: test hook: rank %d exits before asking for a task\n", rank);
        _exit(7);
    }
    for (int given = 1;; given++) {
        int dummy = 0, task = -1;
        MPI_Send(&dummy, 1, MPI_INT, 0, TAG_READY, MPI_COMM_WORLD);
        /* Wait by polling, not in a blocking MPI_Recv: Open MPI's blocking calls spin on a core,
         * which an idle worker would take from the ranks still computing (oversubscribed runs). */
        for (int flag = 0; !flag;) {
            if (MPI_Iprobe(0, TAG_TASK, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE) != MPI_SUCCESS) return 1;
            if (!flag) usleep(2000);
        }
        if (MPI_Recv(&task, 1, MPI_INT, 0, TAG_TASK, MPI_COMM_WORLD, MPI_STATUS_IGNORE) != MPI_SUCCESS) return 1;
        if (task == STOP_LOST) rank_lost = 1;
        if (task < 0) return 0;
        if (o && o->die_rank == rank && o->die_task == given) { /* test hook (sim_sweep_farm.h) */
            fprintf(stderr, "\nribbon-sim sweep: test hook: rank %d exits on task %d\n", rank, task);
            _exit(7);
        }
        outbox b;
        memset(&b, 0, sizeof b);
        pthread_mutex_init(&b.mu, NULL);
        b.task = task;
        b.run = run;
        b.run_ctx = run_ctx;
        pthread_t th;
        if (pthread_create(&th, NULL, outbox_thread, &b) != 0) {
            outbox_thread(&b); /* no thread: compute here, send afterwards */
            outbox_flush(&b);
        } else {
            double beat = now();
            while (!outbox_flush(&b)) {
                if (now() - beat >= 1.0) {
                    MPI_Send(&task, 1, MPI_INT, 0, TAG_BEAT, MPI_COMM_WORLD);
                    beat = now();
                }
                usleep(2000);
            }
            pthread_join(th, NULL);
        }
        pthread_mutex_destroy(&b.mu);
        MPI_Send(&task, 1, MPI_INT, 0, TAG_DONE, MPI_COMM_WORLD);
    }
}

/* ---- rank 0 ---- */

enum { T_PENDING, T_RUNNING, T_DONE, T_GIVEN_UP };

typedef struct farm {
    pthread_mutex_t mu;
    int ntasks;
    int *state, *owner, *attempts;
    int local_busy, local_quit;
    sweep_task_fn run;
    void *run_ctx;
    sweep_emit_fn write;
    void *write_ctx;
    const volatile sig_atomic_t *cancel;
} farm;

/* Next pending task (marked running by `owner`), or -1. Caller holds the mutex. */
static int take_pending(farm *f, int owner)
{
    if (f->cancel && *f->cancel) return -1;
    for (int t = 0; t < f->ntasks; t++)
        if (f->state[t] == T_PENDING) {
            f->state[t] = T_RUNNING;
            f->owner[t] = owner;
            f->attempts[t]++;
            return t;
        }
    return -1;
}

static void *local_thread(void *arg)
{
    farm *f = arg;
    for (;;) {
        pthread_mutex_lock(&f->mu);
        int quit = f->local_quit;
        int t = quit ? -1 : take_pending(f, 0);
        f->local_busy = t >= 0;
        pthread_mutex_unlock(&f->mu);
        if (quit) return NULL;
        if (t < 0) {
            usleep(5000);
            continue;
        }
        f->run(f->run_ctx, t, f->write, f->write_ctx);
        pthread_mutex_lock(&f->mu);
        f->state[t] = T_DONE;
        f->local_busy = 0;
        pthread_mutex_unlock(&f->mu);
    }
}

typedef struct wstate {
    int waiting, stopped, dead, task;
    double last_seen;
} wstate;

static int master(int size, farm *f, const sweep_farm_opts *o, char *why, size_t why_len)
{
    double timeout = o && o->heartbeat_timeout_s > 0 ? o->heartbeat_timeout_s : 30.0;
    wstate *w = calloc((size_t)size, sizeof *w);
    if (!w) {
        snprintf(why, why_len, "out of memory");
        return f->ntasks;
    }
    for (int k = 0; k < size; k++) {
        w[k].task = -1;
        w[k].last_seen = now();
    }
    pthread_t th;
    int have_local = pthread_create(&th, NULL, local_thread, f) == 0;
    int lost = 0, lost_idle = 0;
    for (;;) {
        int flag = 0;
        MPI_Status st;
        MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
        if (flag) {
            int src = st.MPI_SOURCE;
            if (st.MPI_TAG == TAG_ROW) {
                row_msg m;
                MPI_Recv(&m, (int)sizeof m, MPI_BYTE, src, TAG_ROW, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
                f->write(f->write_ctx, &m.row, m.is_new);
            } else {
                int v = 0;
                MPI_Recv(&v, 1, MPI_INT, src, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
                if (st.MPI_TAG == TAG_READY) w[src].waiting = 1;
                if (st.MPI_TAG == TAG_DONE) {
                    pthread_mutex_lock(&f->mu);
                    if (v >= 0 && v < f->ntasks && f->state[v] != T_GIVEN_UP) f->state[v] = T_DONE;
                    pthread_mutex_unlock(&f->mu);
                    w[src].task = -1;
                }
            }
            w[src].last_seen = now();
            if (w[src].dead) {
                /* Taken for dead but alive: it may go on (its rows are kept), as a fresh worker. */
                w[src].dead = 0;
            }
        }
        pthread_mutex_lock(&f->mu);
        /* Silent workers: their task goes back to the queue. */
        for (int k = 1; k < size; k++)
            if (!w[k].dead && !w[k].stopped && w[k].task >= 0 && now() - w[k].last_seen > timeout) {
                int t = w[k].task;
                w[k].dead = 1;
                rank_lost = 1;
                w[k].task = -1;
                w[k].waiting = 0;
                if (f->state[t] == T_RUNNING && f->owner[t] == k) {
                    f->state[t] = f->attempts[t] >= MAX_ATTEMPTS ? T_GIVEN_UP : T_PENDING;
                    fprintf(stderr, "\nribbon-sim sweep: rank %d silent for %.0f s, taken for dead; task %d %s\n", k,
                            timeout, t, f->state[t] == T_PENDING ? "queued again" : "given up (3 ranks lost on it)");
                }
            }
        /* Workers that hold no task and have not asked for one (they left before READY, or between
         * a DONE and their next READY, which follow each other at once): the same bound, or rank 0
         * would wait for them for ever (they count as alive until they stop). */
        for (int k = 1; k < size; k++)
            if (!w[k].dead && !w[k].stopped && !w[k].waiting && w[k].task < 0 && now() - w[k].last_seen > timeout) {
                w[k].dead = 1;
                rank_lost = 1;
                lost_idle++;
                fprintf(stderr, "\nribbon-sim sweep: rank %d never asked for a task (no READY for %.0f s): taken for "
                        "dead, the farm goes on without it\n", k, timeout);
            }
        int open = 0;
        for (int t = 0; t < f->ntasks; t++) open += f->state[t] == T_PENDING || f->state[t] == T_RUNNING;
        int cancelled = f->cancel && *f->cancel;
        /* Workers not yet heard from (alive, no task, not waiting): until each asks for a task or is
         * taken for dead, no one is told to stop, because a worker stopped normally enters
         * MPI_Finalize, whose closing fence waits for ever for a rank that left without READY (seen
         * as a 300 s hang in one clean run of test_sweep_mpi: rank 2 stopped before rank 1 was
         * taken for dead); after that the stop says STOP_LOST and the survivors leave without it. */
        int unsettled = 0;
        for (int k = 1; k < size; k++) unsettled += !w[k].dead && !w[k].stopped && !w[k].waiting && w[k].task < 0;
        for (int k = 1; k < size; k++) {
            if (!w[k].waiting || w[k].dead || w[k].stopped) continue;
            int t = take_pending(f, k);
            if (t >= 0) {
                w[k].waiting = 0;
                w[k].task = t;
                w[k].last_seen = now();
                MPI_Send(&t, 1, MPI_INT, k, TAG_TASK, MPI_COMM_WORLD);
            } else if ((open == 0 && unsettled == 0) || cancelled) {
                int stop = rank_lost ? STOP_LOST : -1;
                w[k].waiting = 0;
                w[k].stopped = 1;
                MPI_Send(&stop, 1, MPI_INT, k, TAG_TASK, MPI_COMM_WORLD);
            }
        }
        int running_remote = 0, alive = 0;
        for (int k = 1; k < size; k++) {
            running_remote += w[k].task >= 0 && !w[k].dead;
            alive += !w[k].stopped && !w[k].dead;
        }
        int local_busy = f->local_busy;
        int pending = 0;
        for (int t = 0; t < f->ntasks; t++) pending += f->state[t] == T_PENDING;
        pthread_mutex_unlock(&f->mu);
        int finished = running_remote == 0 && !local_busy && (pending == 0 || cancelled) && alive == 0;
        if (pending > 0 && !have_local && alive == 0) finished = 1; /* nobody left to compute */
        if (finished) break;
        if (!flag) usleep(1000);
    }
    pthread_mutex_lock(&f->mu);
    f->local_quit = 1;
    pthread_mutex_unlock(&f->mu);
    if (have_local) pthread_join(th, NULL);
    int left = 0;
    for (int t = 0; t < f->ntasks; t++) left += f->state[t] != T_DONE;
    for (int t = 0; t < f->ntasks; t++) lost += f->state[t] == T_GIVEN_UP;
    if (left) snprintf(why, why_len, "%d tasks not done (%d given up after %d lost ranks each, the others interrupted%s)",
                       left, lost, MAX_ATTEMPTS, lost_idle ? "; a rank never asked for a task" : "");
    free(w);
    return left;
}

int sweep_farm_run(int rank, int size, int ntasks, sweep_task_fn run, void *run_ctx, sweep_emit_fn write,
                   void *write_ctx, const volatile sig_atomic_t *cancel, const sweep_farm_opts *o, char *why,
                   size_t why_len)
{
    if (!mpi_started || size < 2) {
        int left = 0;
        for (int t = 0; t < ntasks; t++) {
            if (cancel && *cancel) {
                left++;
                continue;
            }
            run(run_ctx, t, write, write_ctx);
        }
        if (left) snprintf(why, why_len, "%d tasks not run (interrupted)", left);
        return left;
    }
    if (rank != 0) return worker(rank, run, run_ctx, o);
    farm f;
    memset(&f, 0, sizeof f);
    pthread_mutex_init(&f.mu, NULL);
    f.ntasks = ntasks;
    f.state = calloc((size_t)ntasks + 1, sizeof(int));
    f.owner = calloc((size_t)ntasks + 1, sizeof(int));
    f.attempts = calloc((size_t)ntasks + 1, sizeof(int));
    f.run = run;
    f.run_ctx = run_ctx;
    f.write = write;
    f.write_ctx = write_ctx;
    f.cancel = cancel;
    int left = ntasks;
    if (f.state && f.owner && f.attempts) left = master(size, &f, o, why, why_len);
    else snprintf(why, why_len, "out of memory");
    free(f.state);
    free(f.owner);
    free(f.attempts);
    pthread_mutex_destroy(&f.mu);
    return left;
}

#endif
