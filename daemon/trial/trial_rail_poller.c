/* trial_rail_poller.c: the rails' own polling thread in a live trial (see trial_rail_poller.h). */
#include "trial_rail_poller.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rail_pair.h"

struct trial_rail_poller {
    rail *compress, *shear;
    rail_clock clock;
    double period_s;
    pthread_t thread;
    pthread_mutex_t rails;   /* held during every call on the rails */
    pthread_mutex_t lock;    /* guards what follows */
    pthread_cond_t first;    /* the first poll is in */
    int have, stop;
    rail_status sc, ss;
    double t_poll;
    rail_err err;
    char why[256];
    double max_poll_s;
    double max_gap_s;        /* longest time from the end of one poll to the start of the next */
    long polls;
    int polling;             /* a poll is in flight, since t_poll_start */
    double t_poll_start;
    double watch_until;      /* rail clock: until then the shear is read fresh every TRIAL_STOP_WATCH_PERIOD_S
                                (trial_rail_poller_watch_stop); NaN = not watching */
    double watch_stand_t;    /* rail clock of the fresh reading that ended the watch standing (NaN: none) */
};

/* A frozen daemon: both rails emergency-stopped first, then the fault published (every later read
 * returns it). gap: s the clock ran (bound: s it may); what: where it was seen. Call with the
 * rails' lock held (so nothing can be sent between the check and the stops) and without p->lock.
 * Returns 1 when this call stopped them (0: a fault was already out). */
static int clock_jumped_locked(trial_rail_poller *p, double gap, double bound, const char *what)
{
    pthread_mutex_lock(&p->lock);
    int first = p->err == RAIL_OK;
    pthread_mutex_unlock(&p->lock);
    if (!first) return 0;
    rail_pair_estop(p->compress, p->shear);
    pthread_mutex_lock(&p->lock);
    p->err = RAIL_E_STATE;
    snprintf(p->why, sizeof p->why,
             "the monotonic clock jumped %.2f s %s (at most %.2f s expected): the daemon was frozen (SIGSTOP, a "
             "suspended machine or a stalled scheduler); both rails stopped before anything resumed",
             gap, what, bound);
    p->have = 1;
    pthread_cond_broadcast(&p->first);
    pthread_mutex_unlock(&p->lock);
    return 1;
}

/* The same, taking the rails' lock itself (call with neither lock held). */
static int clock_jumped(trial_rail_poller *p, double gap, double bound, const char *what)
{
    pthread_mutex_lock(&p->rails);
    int r = clock_jumped_locked(p, gap, bound, what);
    pthread_mutex_unlock(&p->rails);
    return r;
}

static void *poll_main(void *arg)
{
    trial_rail_poller *p = arg;
    double prev_end = NAN;
    for (;;) {
        pthread_mutex_lock(&p->lock);
        int stop = p->stop || p->err != RAIL_OK;
        pthread_mutex_unlock(&p->lock);
        if (stop) break;
        /* Woken more than the bound after the last poll: frozen; nothing is sent but the stops. */
        double t_wake = rail_clock_now(p->clock);
        if (t_wake - prev_end > p->period_s + TRIAL_CLOCK_JUMP_S) {
            clock_jumped(p, t_wake - prev_end, p->period_s + TRIAL_CLOCK_JUMP_S, "between two rail polls");
            break;
        }
        rail_status sc, ss;
        char why[256] = "";
        /* The rails one at a time (rail_pair_judge), so a fault is published after its own round
         * trip, before the other rail is read over what may be the same dead link; the other is
         * then stopped at once (rail_pair_poll's rule). */
        pthread_mutex_lock(&p->rails);
        double t0 = rail_clock_now(p->clock);
        /* Checked again with the rails' lock held, before anything is sent: a freeze between the
         * check above and here (waiting for the lock behind the trial's thread included) would
         * otherwise poll, and so top up a G-code jog, as if nothing had happened. */
        if (t0 - prev_end > p->period_s + TRIAL_CLOCK_JUMP_S) {
            clock_jumped_locked(p, t0 - prev_end, p->period_s + TRIAL_CLOCK_JUMP_S,
                                "before a rail poll (it waited for the rails)");
            pthread_mutex_unlock(&p->rails);
            break;
        }
        pthread_mutex_lock(&p->lock);
        p->polling = 1;
        p->t_poll_start = t0;
        pthread_mutex_unlock(&p->lock);
        memset(&sc, 0, sizeof sc);
        memset(&ss, 0, sizeof ss);
        rail *other = NULL;
        rail_err e = rail_pair_judge(p->compress, rail_status_get(p->compress, &sc), &sc, why, sizeof why);
        if (e != RAIL_OK) {
            other = p->shear;
            ss = p->ss;
        } else {
            pthread_mutex_lock(&p->lock);
            int watching = t0 < p->watch_until;
            pthread_mutex_unlock(&p->lock);
            /* Watching a stop: a fresh reading on every pass, not the poll_hz rate limit's
             * extrapolation, so the rail's first standing report is seen within one short pass. */
            e = rail_pair_judge(p->shear, watching ? rail_status_poll(p->shear, &ss) : rail_status_get(p->shear, &ss),
                                &ss, why, sizeof why);
            if (e != RAIL_OK) other = p->compress;
        }
        double t1 = rail_clock_now(p->clock);
        pthread_mutex_lock(&p->lock);
        p->polling = 0;
        pthread_mutex_unlock(&p->lock);
        pthread_mutex_unlock(&p->rails);
        if (e == RAIL_OK && t1 - t0 > 2.0 * TRIAL_CLOCK_JUMP_S) {
            /* A poll answers within its drivers' reply timeouts or fails: frozen inside it. */
            clock_jumped(p, t1 - t0, 2.0 * TRIAL_CLOCK_JUMP_S, "inside a rail poll");
            break;
        }
        int published = 0;
        if (e != RAIL_OK) {
            pthread_mutex_lock(&p->lock);
            if (p->err != RAIL_OK) { /* a freeze was seen first: that is the fault */
                pthread_mutex_unlock(&p->lock);
                break;
            }
            published = 1;
            p->sc = sc;
            p->ss = ss;
            p->t_poll = t1;
            p->err = e;
            snprintf(p->why, sizeof p->why, "%s", why);
            p->have = 1;
            pthread_cond_broadcast(&p->first);
            pthread_mutex_unlock(&p->lock);
            pthread_mutex_lock(&p->rails);
            rail_estop(other);
            pthread_mutex_unlock(&p->rails);
        }
        pthread_mutex_lock(&p->lock);
        if (p->err != RAIL_OK && !published) { /* the reader saw a freeze meanwhile (clock_jumped) */
            pthread_mutex_unlock(&p->lock);
            break;
        }
        p->sc = sc;
        p->ss = ss;
        p->t_poll = t1;
        p->err = e;
        if (e != RAIL_OK) snprintf(p->why, sizeof p->why, "%s", why);
        if (t1 - t0 > p->max_poll_s) p->max_poll_s = t1 - t0;
        if (t0 - prev_end > p->max_gap_s) p->max_gap_s = t0 - prev_end;
        prev_end = t1;
        p->polls++;
        p->have = 1;
        pthread_cond_broadcast(&p->first);
        pthread_mutex_unlock(&p->lock);
        if (e != RAIL_OK) break;
        /* While a stop is watched, until the shear reads standing (or the window ends). */
        pthread_mutex_lock(&p->lock);
        int watch = t1 < p->watch_until;
        if (watch && ss.state != RAIL_STATE_MOVING && ss.state != RAIL_STATE_HOMING && !ss.extrapolated) {
            p->watch_stand_t = ss.t_s;
            p->watch_until = NAN;
            watch = 0;
        }
        pthread_mutex_unlock(&p->lock);
        rail_clock_sleep(p->clock, watch ? fmin(p->period_s, TRIAL_STOP_WATCH_PERIOD_S) : p->period_s);
    }
    pthread_mutex_lock(&p->lock);
    p->have = 1;
    pthread_cond_broadcast(&p->first);
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

trial_rail_poller *trial_rail_poller_start(rail *compress, rail *shear, double period_s, char *why, size_t why_len)
{
    if (!compress || !shear || !(period_s > 0.0)) {
        snprintf(why, why_len, "rail poller: need two rails and a positive period");
        return NULL;
    }
    trial_rail_poller *p = calloc(1, sizeof *p);
    if (!p) {
        snprintf(why, why_len, "rail poller: out of memory");
        return NULL;
    }
    p->compress = compress;
    p->shear = shear;
    p->clock = rail_get_clock(compress);
    p->period_s = period_s;
    p->watch_until = p->watch_stand_t = NAN;
    pthread_mutex_init(&p->rails, NULL);
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->first, NULL);
    if (pthread_create(&p->thread, NULL, poll_main, p) != 0) {
        snprintf(why, why_len, "rail poller: the thread could not start");
        pthread_cond_destroy(&p->first);
        pthread_mutex_destroy(&p->lock);
        pthread_mutex_destroy(&p->rails);
        free(p);
        return NULL;
    }
    return p;
}

rail_err trial_rail_poller_latest(trial_rail_poller *p, rail_status *sc, rail_status *ss, double *t_poll, char *why,
                                  size_t why_len)
{
    pthread_mutex_lock(&p->lock);
    while (!p->have) pthread_cond_wait(&p->first, &p->lock);
    /* The poller's last poll ended longer ago than it may have: this thread woke first from a
     * freeze, and stops the rails itself before the poller can send anything. */
    double now = rail_clock_now(p->clock);
    double gap = p->polling ? now - p->t_poll_start : now - p->t_poll;
    double bound = p->polling ? 2.0 * TRIAL_CLOCK_JUMP_S : p->period_s + TRIAL_CLOCK_JUMP_S;
    if (p->err == RAIL_OK && p->polls > 0 && gap > bound) {
        int in_poll = p->polling;
        pthread_mutex_unlock(&p->lock);
        clock_jumped(p, gap, bound, in_poll ? "inside a rail poll" : "since the last rail poll");
        pthread_mutex_lock(&p->lock);
    }
    *sc = p->sc;
    *ss = p->ss;
    *t_poll = p->t_poll;
    rail_err e = p->err;
    if (e != RAIL_OK) snprintf(why, why_len, "%s", p->why);
    pthread_mutex_unlock(&p->lock);
    return e;
}

rail_err trial_rail_poller_lock_for_move(trial_rail_poller *p, char *why, size_t why_len)
{
    rail_status sc, ss;
    double t;
    rail_err e = trial_rail_poller_latest(p, &sc, &ss, &t, why, why_len);
    if (e != RAIL_OK) return e;
    pthread_mutex_lock(&p->rails);
    /* With the rails' lock held the poller is between polls: its last one ended at t_poll. */
    pthread_mutex_lock(&p->lock);
    e = p->err;
    double gap = rail_clock_now(p->clock) - p->t_poll, bound = p->period_s + TRIAL_CLOCK_JUMP_S;
    int jumped = e == RAIL_OK && p->polls > 0 && gap > bound;
    if (e != RAIL_OK) snprintf(why, why_len, "%s", p->why);
    pthread_mutex_unlock(&p->lock);
    if (e == RAIL_OK && !jumped) return RAIL_OK; /* the lock stays held for the move */
    if (jumped) {
        clock_jumped_locked(p, gap, bound, "before a move");
        pthread_mutex_lock(&p->lock);
        e = p->err;
        snprintf(why, why_len, "%s", p->why);
        pthread_mutex_unlock(&p->lock);
    }
    pthread_mutex_unlock(&p->rails);
    return e;
}

void trial_rail_poller_watch_stop(trial_rail_poller *p, double window_s)
{
    /* Test hook: the stop unwatched, as before issue 34 F (bench_snap_stop.sh compares both). */
    const char *off = getenv("RIBBON_TEST_NO_STOP_WATCH");
    if (off && *off && strcmp(off, "0") != 0) return;
    pthread_mutex_lock(&p->lock);
    p->watch_until = rail_clock_now(p->clock) + fmax(0.0, window_s);
    p->watch_stand_t = NAN;
    pthread_mutex_unlock(&p->lock);
}

double trial_rail_poller_stop_seen(trial_rail_poller *p)
{
    pthread_mutex_lock(&p->lock);
    double t = p->watch_stand_t;
    pthread_mutex_unlock(&p->lock);
    return t;
}

void trial_rail_poller_lock(trial_rail_poller *p) { pthread_mutex_lock(&p->rails); }
void trial_rail_poller_unlock(trial_rail_poller *p) { pthread_mutex_unlock(&p->rails); }

void trial_rail_poller_stats(trial_rail_poller *p, double *max_poll_s, double *max_gap_s, long *polls)
{
    pthread_mutex_lock(&p->lock);
    *max_poll_s = p->max_poll_s;
    *max_gap_s = p->max_gap_s;
    *polls = p->polls;
    pthread_mutex_unlock(&p->lock);
}

void trial_rail_poller_stop(trial_rail_poller *p)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    p->stop = 1;
    pthread_mutex_unlock(&p->lock);
    pthread_join(p->thread, NULL);
    pthread_cond_destroy(&p->first);
    pthread_mutex_destroy(&p->lock);
    pthread_mutex_destroy(&p->rails);
    free(p);
}
