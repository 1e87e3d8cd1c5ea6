/* rigsim_twin.c: the twin stepped on its own thread, its trajectory logged for the camera (see
 * rigsim_twin.h). */
#define _GNU_SOURCE /* pthread_setaffinity_np */
#include "rigsim_twin.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "rig_calib.h"
#include "rod_observe.h"
#include "rod_twin.h"

/* States logged: the solver runs at most a frame period or two ahead of the renders, in chunks of
 * at least a fraction of dt, and a render takes the state of an instant at most a period or so
 * old; 256 chunks hold 0.38 s at the rehearsal twin's dt of 1.5 ms, more at any coarser one. */
#define RING 256
#define IDLE_POLL_S 2e-3 /* s: the solver's nap while it is ahead of its lead or held */

typedef struct slot {
    rigsim_twin_state st;
    double *pos, *normal; /* 3 n values each: the shape's arrays */
} slot;

struct rigsim_twin {
    rod_twin *rod;
    twin_shape work;  /* the solver's shape, filled after each chunk */
    size_t n;         /* the shape's points */
    rigsim_rails *rails;
    rig_calibration calib;
    double length_m, dt;
    pthread_t thread;
    int started;
    pthread_mutex_t lock;
    pthread_cond_t cond; /* a state was logged (CLOCK_MONOTONIC) */
    int stop;
    double t0;            /* host monotonic instant of the twin's time 0 */
    int active;           /* a grid is set and not held */
    double grid, period, lead;
    slot ring[RING];
    long head;            /* states logged; the latest at (head - 1) % RING */
    rod_snap_report snap;
    double dw_now;
    rigsim_twin_stats stats;
    char err[256];
};

static double mono_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double thread_cpu_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static struct timespec abs_ts(double mono)
{
    struct timespec ts;
    ts.tv_sec = (time_t)mono;
    ts.tv_nsec = (long)((mono - (double)ts.tv_sec) * 1e9);
    if (ts.tv_nsec >= 1000000000L) ts.tv_nsec = 999999999L;
    return ts;
}

static void nap(double s)
{
    struct timespec ts = {0, (long)(s * 1e9)};
    while (nanosleep(&ts, &ts) == EINTR) {
    }
}

/* Logs the solver's current state (lock held). */
static void publish(rigsim_twin *tw, double t, double dl, double dw, double dz)
{
    slot *s = &tw->ring[tw->head % RING];
    memcpy(s->pos, tw->work.pos, 3 * tw->n * sizeof *s->pos);
    memcpy(s->normal, tw->work.normal, 3 * tw->n * sizeof *s->normal);
    s->st = (rigsim_twin_state){t, tw->t0 + t, dl, dw, dz, 1};
    tw->head++;
    pthread_cond_broadcast(&tw->cond);
}

/* The solver's thread: the next chunk ends at the next exposure instant of the grid or one dt on,
 * whichever is first, once real time is within `lead` of it; the axes' positions there (history,
 * or extrapolated up to lead ahead) are the clamps' at its end. */
static void *solver_main(void *arg)
{
    rigsim_twin *tw = arg;
    double cpu0 = thread_cpu_s();
    for (;;) {
        pthread_mutex_lock(&tw->lock);
        const int stop = tw->stop, active = tw->active;
        const double t0 = tw->t0, grid = tw->grid, period = tw->period, lead = tw->lead;
        pthread_mutex_unlock(&tw->lock);
        if (stop) break;
        if (!active || !(period > 0.0)) {
            nap(IDLE_POLL_S);
            continue;
        }
        const double t_cur = rod_twin_time(tw->rod), m_cur = t0 + t_cur;
        double k = floor((m_cur - grid) / period) + 1.0;
        double e = grid + k * period; /* the next exposure instant after the current state */
        if (e - m_cur < 1e-7) e += period;
        const double m_end = fmin(e, m_cur + tw->dt);
        const double now = mono_now();
        if (m_end > now + lead) {
            nap(fmin(IDLE_POLL_S, m_end - lead - now));
            continue;
        }
        double pc, ps;
        rigsim_rails_positions_at(tw->rails, m_end, &pc, &ps);
        const double dl = rig_calib_dl(&tw->calib, tw->length_m, pc), dw = rig_calib_dw(&tw->calib, tw->length_m, ps);
        char msg[256] = "";
        const double w0 = mono_now();
        const int ok = rod_twin_advance(tw->rod, m_end - t0, dl, dw, msg, sizeof msg) == ROD_OK &&
                       twin_shape_from_rod(&tw->work, rod_twin_rod(tw->rod), msg, sizeof msg) == TWIN_OK;
        const double w1 = mono_now();
        rod_obs o;
        double dz = NAN;
        rod_snap_report snap = tw->snap;
        if (ok) {
            rod_twin_observe(tw->rod, &o);
            dz = o.dz_cam;
            rod_twin_snap(tw->rod, &snap);
        }
        const double cpu = thread_cpu_s();
        pthread_mutex_lock(&tw->lock);
        tw->stats.chunks++;
        tw->stats.cpu_s += cpu - cpu0;
        if (w1 - w0 > tw->stats.worst_chunk_s) tw->stats.worst_chunk_s = w1 - w0;
        if (ok) {
            /* The clock may have paused meanwhile (a hold): the state stands for its twin time. */
            publish(tw, rod_twin_time(tw->rod), dl, dw, dz);
            tw->snap = snap;
            tw->dw_now = rod_twin_dw(tw->rod);
            const double behind = w1 - (tw->t0 + rod_twin_time(tw->rod));
            tw->stats.behind_s = behind;
            if (behind > tw->stats.behind_max_s) tw->stats.behind_max_s = behind;
        } else {
            tw->stats.failures++;
            snprintf(tw->err, sizeof tw->err, "%s", msg);
        }
        pthread_mutex_unlock(&tw->lock);
        cpu0 = cpu;
        if (!ok) nap(IDLE_POLL_S); /* a failed advance: the next chunk tries again, not at once */
    }
    return NULL;
}

int rigsim_twin_open(const rod_scene *sc, double dl_start, const rig_calibration *calib, rigsim_rails *rails,
                     rigsim_twin **out, char *why, size_t why_len)
{
    *out = NULL;
    rigsim_twin *tw = calloc(1, sizeof *tw);
    if (!tw) {
        snprintf(why, why_len, "twin: out of memory");
        return -1;
    }
    tw->rails = rails;
    tw->calib = *calib;
    tw->length_m = sc->length;
    tw->dt = sc->dt > 0.0 ? sc->dt : 1e-3;
    pthread_mutex_init(&tw->lock, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&tw->cond, &ca);
    pthread_condattr_destroy(&ca);
    char err[256] = "";
    if (twin_shape_init(&tw->work, sc, TWIN_Y_RIG, err, sizeof err) != TWIN_OK) {
        snprintf(why, why_len, "twin: %s", err);
        goto fail;
    }
    tw->n = tw->work.n;
    for (int k = 0; k < RING; k++) {
        tw->ring[k].pos = malloc(3 * tw->n * sizeof(double));
        tw->ring[k].normal = malloc(3 * tw->n * sizeof(double));
        if (!tw->ring[k].pos || !tw->ring[k].normal) {
            snprintf(why, why_len, "twin: out of memory");
            goto fail;
        }
    }
    if (rod_twin_open(sc, dl_start, &tw->rod, err, sizeof err) != ROD_OK) {
        snprintf(why, why_len, "twin: %s", err);
        goto fail;
    }
    if (twin_shape_from_rod(&tw->work, rod_twin_rod(tw->rod), err, sizeof err) != TWIN_OK) {
        snprintf(why, why_len, "twin: %s", err);
        goto fail;
    }
    rod_obs o;
    rod_twin_observe(tw->rod, &o);
    rod_twin_snap(tw->rod, &tw->snap);
    tw->dw_now = rod_twin_dw(tw->rod);
    /* the mounted state, at the twin's time 0, with the clamps where it was mounted */
    publish(tw, 0.0, dl_start, tw->dw_now, o.dz_cam);
    *out = tw;
    return 0;
fail:
    rigsim_twin_close(tw);
    return -1;
}

int rigsim_twin_run(rigsim_twin *tw, double t0_mono, int priority, int cpu, int *realtime, char *why,
                    size_t why_len)
{
    pthread_mutex_lock(&tw->lock);
    tw->t0 = t0_mono;
    for (long k = 0; k < tw->head && k < RING; k++) tw->ring[k].st.mono = t0_mono + tw->ring[k].st.t;
    pthread_mutex_unlock(&tw->lock);
    if (pthread_create(&tw->thread, NULL, solver_main, tw) != 0) {
        snprintf(why, why_len, "the twin's thread could not start");
        return -1;
    }
    tw->started = 1;
    if (realtime) *realtime = 0;
    if (cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(cpu, &set);
        pthread_setaffinity_np(tw->thread, sizeof set, &set); /* refused: any core */
    }
    if (priority > 0) {
        struct sched_param sp = {.sched_priority = priority};
        const int got = pthread_setschedparam(tw->thread, SCHED_FIFO, &sp) == 0;
        if (realtime) *realtime = got;
    }
    return 0;
}

void rigsim_twin_close(rigsim_twin *tw)
{
    if (!tw) return;
    if (tw->started) {
        pthread_mutex_lock(&tw->lock);
        tw->stop = 1;
        pthread_mutex_unlock(&tw->lock);
        pthread_join(tw->thread, NULL);
    }
    rod_twin_close(tw->rod);
    twin_shape_release(&tw->work);
    for (int k = 0; k < RING; k++) {
        free(tw->ring[k].pos);
        free(tw->ring[k].normal);
    }
    pthread_cond_destroy(&tw->cond);
    pthread_mutex_destroy(&tw->lock);
    free(tw);
}

void rigsim_twin_set_grid(rigsim_twin *tw, double grid_mono, double period_s, double lead_s)
{
    pthread_mutex_lock(&tw->lock);
    tw->grid = grid_mono;
    tw->period = period_s;
    tw->lead = lead_s;
    tw->active = 1;
    pthread_mutex_unlock(&tw->lock);
}

void rigsim_twin_hold(rigsim_twin *tw, double now_mono)
{
    pthread_mutex_lock(&tw->lock);
    tw->active = 0;
    /* The solver stands (it steps only while active): its latest state stands for now, and goes on
     * standing for now while the hold lasts. */
    const double latest = tw->ring[(tw->head - 1) % RING].st.t;
    if (now_mono - latest > tw->t0) tw->t0 = now_mono - latest;
    pthread_mutex_unlock(&tw->lock);
}

double rigsim_twin_t0(rigsim_twin *tw)
{
    pthread_mutex_lock(&tw->lock);
    const double t0 = tw->t0;
    pthread_mutex_unlock(&tw->lock);
    return t0;
}

int rigsim_twin_state_at(rigsim_twin *tw, double at_mono, double deadline_mono, double after_t, twin_shape *shape,
                         rigsim_twin_state *st)
{
    const double eps = 1e-7;
    pthread_mutex_lock(&tw->lock);
    for (;;) {
        const double latest = tw->ring[(tw->head - 1) % RING].st.t;
        if (latest >= at_mono - tw->t0 - eps || tw->stop) break;
        if (mono_now() >= deadline_mono) break;
        struct timespec ts = abs_ts(deadline_mono);
        pthread_cond_timedwait(&tw->cond, &tw->lock, &ts);
    }
    /* The latest logged state at or before the instant (newest first), and the one after it when
     * the solver has passed the instant: the shape between the two (twin_shape_lerp), which is
     * the state itself when the solver landed on the instant. */
    const double want = at_mono - tw->t0;
    const long oldest = tw->head > RING ? tw->head - RING : 0;
    long pick = -1;
    for (long k = tw->head - 1; k >= oldest; k--)
        if (tw->ring[k % RING].st.t <= want + eps) {
            pick = k;
            break;
        }
    int got = 0;
    if (pick >= 0 && tw->ring[pick % RING].st.t > after_t + eps) {
        const slot *a = &tw->ring[pick % RING];
        *st = a->st;
        st->exact = fabs(a->st.t - want) <= eps;
        int lerped = 0;
        if (!st->exact && pick + 1 < tw->head) {
            const slot *b = &tw->ring[(pick + 1) % RING];
            const double w = (want - a->st.t) / (b->st.t - a->st.t);
            twin_shape sa = {.n = tw->n, .pos = a->pos, .normal = a->normal};
            twin_shape sb = {.n = tw->n, .pos = b->pos, .normal = b->normal};
            char why[160];
            if (w >= 0.0 && w <= 1.0 && twin_shape_lerp(shape, &sa, &sb, w, why, sizeof why) == TWIN_OK) {
                st->t = want;
                st->dl = a->st.dl + w * (b->st.dl - a->st.dl);
                st->dw = a->st.dw + w * (b->st.dw - a->st.dw);
                st->dz = a->st.dz + w * (b->st.dz - a->st.dz);
                st->exact = lerped = 1;
            }
        }
        if (!lerped) {
            memcpy(shape->pos, a->pos, 3 * tw->n * sizeof *a->pos);
            memcpy(shape->normal, a->normal, 3 * tw->n * sizeof *a->normal);
        }
        st->mono = tw->t0 + st->t;
        got = 1;
    }
    pthread_mutex_unlock(&tw->lock);
    return got;
}

void rigsim_twin_truth(rigsim_twin *tw, rod_snap_report *snap, double *dw_now)
{
    pthread_mutex_lock(&tw->lock);
    if (snap) *snap = tw->snap;
    if (dw_now) *dw_now = tw->dw_now;
    pthread_mutex_unlock(&tw->lock);
}

void rigsim_twin_stats_get(rigsim_twin *tw, rigsim_twin_stats *out)
{
    pthread_mutex_lock(&tw->lock);
    *out = tw->stats;
    out->latest_mono = tw->t0 + tw->ring[(tw->head - 1) % RING].st.t;
    pthread_mutex_unlock(&tw->lock);
}

void rigsim_twin_last_error(rigsim_twin *tw, char *out, size_t n)
{
    pthread_mutex_lock(&tw->lock);
    snprintf(out, n, "%s", tw->err);
    pthread_mutex_unlock(&tw->lock);
}
