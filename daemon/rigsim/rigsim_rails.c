/* rigsim_rails.c: the rig simulator's GRBL controller or Modbus TCP drives on their own thread (see
 * rigsim_rails.h). */
#include "rigsim_rails.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "grbl_sim.h"
#include "mb_sim.h"

#define RIGSIM_AXES_LOG_S 0.005   /* s between lines of the axes log */
#define RIGSIM_DRIVE_ALARM 0x30   /* the Modbus drive alarm raised on command (mb_sim's own default) */
#define RIGSIM_RING 8192          /* axes-log lines buffered for the writer (41 s at 5 ms) */

/* The rails' thread runs at a real-time priority and never writes a file itself (a write may
 * block for tenths of a second when the kernel throttles dirty pages, as the recorder's video
 * makes it do): its log lines and fault notes wait here for rigsim_rails_flush. */
typedef struct axes_line {
    double mono, real, pc, ps;
} axes_line;

struct rigsim_rails {
    grbl_sim *sim;              /* GRBL: the controller, or NULL */
    mb_sim *mb[2];              /* Modbus: the compression and the shear drive, or NULL */
    char port[RIG_PATH_MAX];    /* GRBL: the linked port */
    char label[2 * RIG_PATH_MAX];
    int ic, is;                 /* GRBL: axis index of the compression and the shear rail */
    pthread_t thread;
    pthread_mutex_t lock;       /* held during each step and each read of the positions */
    int stop;
    double t0, link_lost_after_s;
    int lost_noted;             /* the link-lost time has been printed */
    int alarm_now;              /* an alarm on command, for the thread to raise */
    int realtime;               /* the thread runs SCHED_FIFO */
    FILE *axes;                 /* the axes log, or NULL */
    double axes_next;           /* mono time of its next line */
    axes_line ring[RIGSIM_RING];
    axes_line out[RIGSIM_RING]; /* the flush's copy, written outside the lock */
    long ring_head, ring_tail;  /* lines written / flushed (ring index = count % RIGSIM_RING) */
    char notes[4][48];          /* fault notes to print: what */
    double note_t[4];           /* and when (unix time) */
    int n_notes;
};

static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
static double mono_s(void) { return clock_s(CLOCK_MONOTONIC); }

/* Positions under the lock. */
static void positions_locked(rigsim_rails *r, double *pc, double *ps, double *t)
{
    if (r->sim) {
        double mm[GRBL_SIM_AXES];
        grbl_sim_positions(r->sim, mm, t);
        *pc = mm[r->ic];
        *ps = mm[r->is];
    } else {
        mb_sim_position(r->mb[0], pc, t);
        mb_sim_position(r->mb[1], ps, NULL);
    }
}

/* A fault note for the flush to print, with the time it happened (lock held). */
static void note_fault(rigsim_rails *r, const char *what)
{
    if (r->n_notes == 4) return;
    snprintf(r->notes[r->n_notes], sizeof r->notes[0], "%s", what);
    r->note_t[r->n_notes++] = clock_s(CLOCK_REALTIME);
}

static void *rails_main(void *arg)
{
    rigsim_rails *r = arg;
    for (;;) {
        pthread_mutex_lock(&r->lock);
        int stop = r->stop;
        double now = mono_s();
        int lost = r->link_lost_after_s >= 0.0 && now - r->t0 >= r->link_lost_after_s;
        if (lost && !r->lost_noted) {
            r->lost_noted = 1;
            if (r->mb[0])
                for (int k = 0; k < 2; k++) mb_sim_set_deaf(r->mb[k], true);
            note_fault(r, "link lost");
        }
        if (r->alarm_now) {
            r->alarm_now = 0;
            if (r->sim)
                grbl_sim_raise_alarm(r->sim, 1);
            else
                mb_sim_raise_alarm(r->mb[1], RIGSIM_DRIVE_ALARM);
            note_fault(r, r->sim ? "controller alarm" : "drive alarm");
        }
        if (!stop) {
            if (r->sim && !lost) grbl_sim_step(r->sim, 0.0);
            /* A deaf drive still moves (its watchdog halts it): Modbus drives step on. */
            for (int k = 0; k < 2; k++)
                if (r->mb[k]) mb_sim_step(r->mb[k], 0.0);
        }
        if (r->axes && now >= r->axes_next) {
            double pc, ps;
            positions_locked(r, &pc, &ps, NULL);
            axes_line *a = &r->ring[r->ring_head % RIGSIM_RING];
            *a = (axes_line){now, clock_s(CLOCK_REALTIME), pc, ps};
            r->ring_head++;
            if (r->ring_head - r->ring_tail > RIGSIM_RING) r->ring_tail = r->ring_head - RIGSIM_RING; /* oldest lost */
            r->axes_next = now + RIGSIM_AXES_LOG_S;
        }
        pthread_mutex_unlock(&r->lock);
        if (stop) break;
        struct timespec ts = {0, 1000000}; /* 1 ms: the controller's step, and the link's latency */
        nanosleep(&ts, NULL);
    }
    return NULL;
}

static int axis_index(char a) { return a >= 'X' && a <= 'Z' ? a - 'X' : -1; }

/* The GRBL controller for two gcode rails on one port. */
static int open_grbl(rigsim_rails *r, const rig_config *cfg, double compress_start_mm, const rigsim_rail_faults *f,
                     char *why, size_t why_len)
{
    const rail_config *c = &cfg->compress, *s = &cfg->shear;
    if (strcmp(c->gcode.port, s->gcode.port)) {
        snprintf(why, why_len, "the rig simulator serves one GRBL controller: both gcode rails need the same port");
        return -1;
    }
    r->ic = axis_index(c->gcode.axis);
    r->is = axis_index(s->gcode.axis);
    if (r->ic < 0 || r->is < 0 || r->ic == r->is) {
        snprintf(why, why_len, "rails need two different axes X, Y or Z (got %c and %c)", c->gcode.axis, s->gcode.axis);
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
    if (grbl_sim_open(&r->sim, &p, why, why_len) != RAIL_OK) return -1;
    snprintf(r->port, sizeof r->port, "%s", c->gcode.port);
    unlink(r->port);
    if (symlink(grbl_sim_path(r->sim), r->port) != 0) {
        snprintf(why, why_len, "cannot link %s to the controller's pty %s: %s", r->port, grbl_sim_path(r->sim),
                 strerror(errno));
        grbl_sim_close(r->sim);
        r->sim = NULL;
        return -1;
    }
    snprintf(r->label, sizeof r->label, "%s", r->port);
    return 0;
}

/* "127.0.0.1:PORT" or "localhost:PORT" -> port; -1 when the address is not on loopback. */
static int loopback_port(const char *address)
{
    const char *colon = strrchr(address, ':');
    if (!colon) return -1;
    size_t h = (size_t)(colon - address);
    if (!((h == 9 && !strncmp(address, "127.0.0.1", 9)) || (h == 9 && !strncmp(address, "localhost", 9)))) return -1;
    char *end = NULL;
    long p = strtol(colon + 1, &end, 10);
    return end && !*end && p > 0 && p < 65536 ? (int)p : -1;
}

/* Two Modbus TCP drives, one per rail. */
static int open_modbus(rigsim_rails *r, const rig_config *cfg, double compress_start_mm, const rigsim_rail_faults *f,
                       char *why, size_t why_len)
{
    const rail_config *rc[2] = {&cfg->compress, &cfg->shear};
    const char *name[2] = {"compress", "shear"};
    double start[2] = {compress_start_mm, cfg->calib.shear_zero_mm};
    for (int k = 0; k < 2; k++) {
        const rail_modbus_params *m = &rc[k]->modbus;
        if (m->rtu || strcmp(m->map.name, "ribbon-sim")) {
            snprintf(why, why_len, "rail.%s: the rig simulator serves Modbus TCP drives with map = ribbon-sim", name[k]);
            return -1;
        }
        int port = loopback_port(m->address);
        if (port < 0) {
            snprintf(why, why_len, "rail.%s: address %s is not 127.0.0.1:PORT (the rig simulator serves loopback only)",
                     name[k], m->address);
            return -1;
        }
        mb_sim_params p = mb_sim_params_default();
        p.port = port;
        p.slave = m->slave;
        p.counts_per_mm = m->map.counts_per_mm > 0.0 ? m->map.counts_per_mm : 1000.0;
        p.travel_mm = rc[k]->params.soft_max_mm + 10.0;
        p.start_mm = start[k];
        p.alarm_after_s = k == 1 && f ? f->alarm_after_s : -1.0;
        if (f && f->stall_axis == (k ? 'Y' : 'X')) p.stall_at_mm = f->stall_at_mm;
        if (mb_sim_open(&r->mb[k], &p, why, why_len) != RAIL_OK) {
            char sub[256];
            snprintf(sub, sizeof sub, "%s", why);
            snprintf(why, why_len, "rail.%s: %s", name[k], sub);
            return -1;
        }
    }
    snprintf(r->label, sizeof r->label, "modbus %s (compress), %s (shear)", cfg->compress.modbus.address,
             cfg->shear.modbus.address);
    return 0;
}

static void close_all(rigsim_rails *r)
{
    if (r->sim) {
        unlink(r->port);
        grbl_sim_close(r->sim);
    }
    for (int k = 0; k < 2; k++) mb_sim_close(r->mb[k]);
    if (r->axes) fclose(r->axes);
}

int rigsim_rails_start(const rig_config *cfg, double compress_start_mm, const rigsim_rail_faults *f,
                       const char *axes_log, rigsim_rails **out, char *why, size_t why_len)
{
    *out = NULL;
    const rail_config *c = &cfg->compress, *s = &cfg->shear;
    int grbl = !strcmp(c->driver, "gcode") && !strcmp(s->driver, "gcode");
    int modbus = !strcmp(c->driver, "modbus") && !strcmp(s->driver, "modbus");
    if (!grbl && !modbus) {
        snprintf(why, why_len,
                 "the rig simulator serves one GRBL controller (both rails driver = gcode on one port) or two Modbus "
                 "TCP drives (both driver = modbus); got %s and %s",
                 c->driver, s->driver);
        return -1;
    }
    rigsim_rails *r = calloc(1, sizeof *r);
    if (!r) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    if ((grbl ? open_grbl : open_modbus)(r, cfg, compress_start_mm, f, why, why_len)) {
        close_all(r);
        free(r);
        return -1;
    }
    if (axes_log) {
        r->axes = fopen(axes_log, "w");
        if (!r->axes) {
            snprintf(why, why_len, "axes log %s cannot be written: %s", axes_log, strerror(errno));
            close_all(r);
            free(r);
            return -1;
        }
        fprintf(r->axes, "mono_s,real_s,compress_mm,shear_mm\n");
    }
    r->t0 = mono_s();
    r->link_lost_after_s = f ? f->link_lost_after_s : -1.0;
    pthread_mutex_init(&r->lock, NULL);
    if (pthread_create(&r->thread, NULL, rails_main, r) != 0) {
        snprintf(why, why_len, "the rails' thread could not start");
        close_all(r);
        pthread_mutex_destroy(&r->lock);
        free(r);
        return -1;
    }
    /* The controller stands for a microcontroller that never shares its CPU: its thread runs at
       a real-time priority when the process may (root, CAP_SYS_NICE), so a loaded machine does not
       make the simulated board late to answer. It sleeps 1 ms per step, so it cannot starve the
       machine. Refused: it runs at the process's priority (rigsim_rails_realtime says which). */
    struct sched_param sp = {.sched_priority = 10};
    r->realtime = pthread_setschedparam(r->thread, SCHED_FIFO, &sp) == 0;
    *out = r;
    return 0;
}

int rigsim_rails_realtime(const rigsim_rails *r) { return r->realtime; }

void rigsim_rails_flush(rigsim_rails *r)
{
    axes_line *out = r->out;
    char notes[4][48];
    double note_t[4];
    pthread_mutex_lock(&r->lock);
    long n = r->ring_head - r->ring_tail;
    for (long k = 0; k < n; k++) out[k] = r->ring[(r->ring_tail + k) % RIGSIM_RING];
    r->ring_tail = r->ring_head;
    int nn = r->n_notes;
    memcpy(notes, r->notes, sizeof notes);
    memcpy(note_t, r->note_t, sizeof note_t);
    r->n_notes = 0;
    pthread_mutex_unlock(&r->lock);
    for (int k = 0; k < nn; k++) printf("fault: %s at %.3f (unix time)\n", notes[k], note_t[k]);
    if (nn) fflush(stdout);
    if (!r->axes) return;
    for (long k = 0; k < n; k++) fprintf(r->axes, "%.6f,%.6f,%.6f,%.6f\n", out[k].mono, out[k].real, out[k].pc, out[k].ps);
    if (n) fflush(r->axes);
}

void rigsim_rails_positions(rigsim_rails *r, double *compress_mm, double *shear_mm, double *t_s)
{
    double t;
    pthread_mutex_lock(&r->lock);
    positions_locked(r, compress_mm, shear_mm, &t);
    pthread_mutex_unlock(&r->lock);
    if (t_s) *t_s = t;
}

const char *rigsim_rails_port(const rigsim_rails *r) { return r->label; }

void rigsim_rails_cut_link(rigsim_rails *r)
{
    pthread_mutex_lock(&r->lock);
    r->link_lost_after_s = mono_s() - r->t0;
    pthread_mutex_unlock(&r->lock);
}

void rigsim_rails_alarm(rigsim_rails *r)
{
    pthread_mutex_lock(&r->lock);
    r->alarm_now = 1;
    pthread_mutex_unlock(&r->lock);
}

void rigsim_rails_stop(rigsim_rails *r)
{
    if (!r) return;
    pthread_mutex_lock(&r->lock);
    r->stop = 1;
    pthread_mutex_unlock(&r->lock);
    pthread_join(r->thread, NULL);
    rigsim_rails_flush(r);
    close_all(r);
    pthread_mutex_destroy(&r->lock);
    free(r);
}
