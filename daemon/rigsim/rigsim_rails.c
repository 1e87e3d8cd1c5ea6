/* rigsim_rails.c: the rig simulator's GRBL controller on its own thread (see rigsim_rails.h). */
#include "rigsim_rails.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

struct rigsim_rails {
    grbl_sim *sim;
    char port[RIG_PATH_MAX];
    int ic, is;                 /* axis index of the compression and the shear rail */
    pthread_t thread;
    pthread_mutex_t lock;       /* held during each step and each read of the positions */
    int stop;
    double t0, link_lost_after_s;
    int lost_noted;             /* the link-lost time has been printed */
};

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void *rails_main(void *arg)
{
    rigsim_rails *r = arg;
    for (;;) {
        pthread_mutex_lock(&r->lock);
        int stop = r->stop;
        int lost = r->link_lost_after_s >= 0.0 && mono_s() - r->t0 >= r->link_lost_after_s;
        if (lost && !r->lost_noted) {
            r->lost_noted = 1;
            struct timespec rt;
            clock_gettime(CLOCK_REALTIME, &rt);
            printf("fault: link lost at %.3f (unix time)\n", (double)rt.tv_sec + 1e-9 * (double)rt.tv_nsec);
            fflush(stdout);
        }
        if (!stop && !lost) grbl_sim_step(r->sim, 0.0);
        pthread_mutex_unlock(&r->lock);
        if (stop) break;
        struct timespec ts = {0, 1000000}; /* 1 ms: the controller's step, and the pty's latency */
        nanosleep(&ts, NULL);
    }
    return NULL;
}

static int axis_index(char a) { return a >= 'X' && a <= 'Z' ? a - 'X' : -1; }

int rigsim_rails_start(const rig_config *cfg, double compress_start_mm, const rigsim_rail_faults *f,
                       rigsim_rails **out, char *why, size_t why_len)
{
    *out = NULL;
    const rail_config *c = &cfg->compress, *s = &cfg->shear;
    if (strcmp(c->driver, "gcode") || strcmp(s->driver, "gcode") || strcmp(c->gcode.port, s->gcode.port)) {
        snprintf(why, why_len,
                 "the rig simulator serves one GRBL controller: both rails need driver = gcode on the same port");
        return -1;
    }
    rigsim_rails *r = calloc(1, sizeof *r);
    if (!r) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    r->ic = axis_index(c->gcode.axis);
    r->is = axis_index(s->gcode.axis);
    if (r->ic < 0 || r->is < 0 || r->ic == r->is) {
        snprintf(why, why_len, "rails need two different axes X, Y or Z (got %c and %c)", c->gcode.axis, s->gcode.axis);
        free(r);
        return -1;
    }
    grbl_sim_params p = grbl_sim_params_default();
    p.n_axes = (r->ic > r->is ? r->ic : r->is) + 1;
    p.travel_mm[r->ic] = c->params.soft_max_mm + 10.0;
    p.travel_mm[r->is] = s->params.soft_max_mm + 10.0;
    p.start_mm[r->ic] = compress_start_mm;
    p.start_mm[r->is] = cfg->calib.shear_zero_mm;
    p.accel_mm_s2 = fmin(c->params.accel_mm_s2, s->params.accel_mm_s2);
    p.alarm_after_s = f ? f->alarm_after_s : -1.0;
    if (f && f->stall_axis) {
        int k = axis_index(f->stall_axis);
        if (k >= 0) p.stall_at_mm[k] = f->stall_at_mm;
    }
    if (grbl_sim_open(&r->sim, &p, why, why_len) != RAIL_OK) {
        free(r);
        return -1;
    }
    snprintf(r->port, sizeof r->port, "%s", c->gcode.port);
    unlink(r->port);
    if (symlink(grbl_sim_path(r->sim), r->port) != 0) {
        snprintf(why, why_len, "cannot link %s to the controller's pty %s: %s", r->port, grbl_sim_path(r->sim),
                 strerror(errno));
        grbl_sim_close(r->sim);
        free(r);
        return -1;
    }
    r->t0 = mono_s();
    r->link_lost_after_s = f ? f->link_lost_after_s : -1.0;
    pthread_mutex_init(&r->lock, NULL);
    if (pthread_create(&r->thread, NULL, rails_main, r) != 0) {
        snprintf(why, why_len, "the controller's thread could not start");
        unlink(r->port);
        grbl_sim_close(r->sim);
        pthread_mutex_destroy(&r->lock);
        free(r);
        return -1;
    }
    *out = r;
    return 0;
}

void rigsim_rails_positions(rigsim_rails *r, double *compress_mm, double *shear_mm, double *t_s)
{
    double mm[GRBL_SIM_AXES], t;
    pthread_mutex_lock(&r->lock);
    grbl_sim_positions(r->sim, mm, &t);
    pthread_mutex_unlock(&r->lock);
    *compress_mm = mm[r->ic];
    *shear_mm = mm[r->is];
    if (t_s) *t_s = t;
}

const char *rigsim_rails_port(const rigsim_rails *r) { return r->port; }

void rigsim_rails_cut_link(rigsim_rails *r)
{
    pthread_mutex_lock(&r->lock);
    r->link_lost_after_s = mono_s() - r->t0;
    pthread_mutex_unlock(&r->lock);
}

void rigsim_rails_stop(rigsim_rails *r)
{
    if (!r) return;
    pthread_mutex_lock(&r->lock);
    r->stop = 1;
    pthread_mutex_unlock(&r->lock);
    pthread_join(r->thread, NULL);
    unlink(r->port);
    grbl_sim_close(r->sim);
    pthread_mutex_destroy(&r->lock);
    free(r);
}
