/* rigsim_camera.c: the twin filmed by a fake GigE Vision camera on 127.0.0.1 (see rigsim_camera.h). */
#define _GNU_SOURCE /* pthread_setaffinity_np */
#include "rigsim_camera.h"

#include <arv.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "rig_calib.h"
#include "rigsim_twin.h"

#define RIGSIM_IDLE_GAP_S 0.25 /* s without an image after which the twin's clock pauses */
#define RIGSIM_RENDER_MARGIN_S 2e-3 /* s: an image is ready this long before its send time */
#define RIGSIM_LEAD_RENDERS 32      /* renders whose slowest sets how early the next one starts */
#define RIGSIM_NOTE_EVERY_S 1.0     /* s at least between two "twin: behind" notes */
#define RIGSIM_FILL_WAIT 1.5        /* periods a send waits at most for an image newer than the last
                                       one sent (the render thread starved of a CPU) */
#define RIGSIM_SOLVER_SLACK 0.25    /* periods the solver may run ahead of a render's start */
#define RIGSIM_LAG_CATCHUP 0.25     /* periods a lagging exposure schedule gains back per frame */

/* The rendered images between the render thread and the sends: each slot free, being rendered,
 * ready (rendered for an exposure not sent yet) or the image sent last (a frozen camera sends it
 * again). A send takes the newest ready image whose exposure has come; the older ones are
 * skipped (never sent: a camera that missed them). */
enum { IMG_FREE, IMG_RENDERING, IMG_READY, IMG_LAST };
typedef struct image_slot {
    vis_frame *f;
    int state;
    double mono;                 /* the host instant its state stands for */
    double stamp_real;           /* its stamp on the real-time clock once sent (0: not yet): a
                                    repeat carries the very same stamp */
    double twin_t, dz, dl, dw;   /* the twin's time, Delta Z, Delta L, Delta W in it */
    int exact;                   /* 0: the solver was behind, the state is older than its exposure */
} image_slot;
#define RIGSIM_IMAGES 4          /* the last sent, two ready, one being rendered */

/* One line of the truth log, as the send made it. The sends only queue their lines (under the
 * camera's lock, no I/O); the main loop writes them (rigsim_camera_tick), so a slow disk never
 * delays an image. A 0.56 s gap in the sends was seen at load 7 with the write in the send. */
typedef struct truth_line {
    long image;
    double mono, real, pc, ps, dl, dw, dz, twin_t, age, sent, ahead;
    int frozen, exact;
} truth_line;
#define RIGSIM_TRUTH_RING 8192 /* lines: 55 s at 150 fps between two writes, which come every 10 ms */

struct rigsim_camera {
    ArvGvFakeCamera *gv;
    ArvFakeCamera *fc;          /* its camera (a reference of our own): the schedule, the fill */
    rigsim_rails *rails;
    rigsim_twin *twin;          /* the ribbon: its solver thread and logged states */
    vis_renderer *ren;          /* the synthetic side camera (the render thread's) */
    twin_shape rshape;          /* the state being rendered */
    image_slot img[RIGSIM_IMAGES];
    int last;                   /* the slot of the image sent last (IMG_LAST) */
    rig_calibration calib;
    double length_m;
    rigsim_camera_faults f;
    FILE *truth;
    truth_line ring[RIGSIM_TRUTH_RING];
    truth_line out[RIGSIM_TRUTH_RING]; /* the writer's copy, written outside the lock */
    long ring_head, ring_tail;  /* lines queued / taken for writing (index = count % RIGSIM_TRUTH_RING) */
    long truth_lost;            /* lines the ring had to overwrite before they were written */
    pthread_mutex_t lock;   /* the fill thread against stop and the counters */
    pthread_cond_t img_cond; /* a new image was swapped in (CLOCK_MONOTONIC) */
    long frames;
    double max_fill_s;
    int stopped;
    pthread_t twin_thread;      /* the render thread */
    int twin_started, twin_stop;
    int twin_realtime;          /* the render thread and the solver run SCHED_FIFO */
    double fps;                 /* the rig file's frame rate (the period until the sends show theirs) */
    double render_cpu_s;        /* the render thread's CPU time, s */
    long renders;               /* images rendered */
    double t_start;             /* host monotonic start, for the fault schedule */
    double last_fill_mono;      /* the last send's call (the camera's grid instant) */
    long repeats;               /* images sent that showed the same state as the one before */
    long inexact;               /* images sent whose state was not their exposure instant's */
    /* Images sent older than half a frame period (the instant they show is nearer the previous
     * send than their own): counted, the worst kept, noted by rigsim_camera_tick. */
    long behind, behind_noted;
    double behind_worst_s, behind_worst_real, behind_note_worst_s, last_note_mono;
    double age_max_s;           /* the oldest image sent, s */
    int8_t *noise;              /* the sensor's noise (NOISE_TABLE values, sigma = camera.noise_sigma) */
    uint64_t rng;               /* picks each exposure's offset into it */
};

/* Sensor noise is added per image sent, not per twin render: a real sensor never repeats a frame
 * bit for bit, even when the twin (slow at the snap) shows the same state twice; so only a
 * frozen-image fault repeats one (trial_runner.c's frozen check). A table of Gaussian values read
 * from a random offset per image: 0.3 ms per 640 x 480 image. */
#define NOISE_TABLE (1 << 20)

static uint64_t xorshift(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

static int8_t *noise_table(double sigma)
{
    int8_t *t = malloc(NOISE_TABLE);
    if (!t) return NULL;
    uint64_t s = 0x9e3779b97f4a7c15ull;
    for (int i = 0; i < NOISE_TABLE; i += 2) {
        double u1 = ((double)(xorshift(&s) >> 11) + 0.5) / 9007199254740992.0;
        double u2 = (double)(xorshift(&s) >> 11) / 9007199254740992.0;
        double r = sigma * sqrt(-2.0 * log(u1));
        double a = fmax(-127.0, fmin(127.0, round(r * cos(2.0 * M_PI * u2))));
        double b = fmax(-127.0, fmin(127.0, round(r * sin(2.0 * M_PI * u2))));
        t[i] = (int8_t)a;
        t[i + 1] = (int8_t)b;
    }
    return t;
}

static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The send time on both clocks as one instant: the real-time clock (the camera's stamp) read between
 * two monotonic reads (the truth: their midpoint), again if the pair was split by more than 20 us.
 * Read one after the other, a preemption between them (1.1 ms seen once in 1806 frames on a loaded
 * CI machine) put the stamp late against the truth by that much: an error of the simulator, not of
 * ribbond's clock map. */
static void paired_clocks(double *mono, double *real)
{
    for (int tries = 0;; tries++) {
        const double m1 = clock_s(CLOCK_MONOTONIC);
        *real = clock_s(CLOCK_REALTIME);
        const double m2 = clock_s(CLOCK_MONOTONIC);
        *mono = 0.5 * (m1 + m2);
        if (m2 - m1 <= 20e-6 || tries == 9) return;
    }
}

static double thread_cpu_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void sleep_until(double mono)
{
    struct timespec ts;
    ts.tv_sec = (time_t)mono;
    ts.tv_nsec = (long)((mono - (double)ts.tv_sec) * 1e9);
    if (ts.tv_nsec >= 1000000000L) ts.tv_nsec = 999999999L;
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, NULL) == EINTR) {
    }
}

/* The render thread: one image per camera frame, of the twin's state at that frame's exposure
 * instant (the send's schedule instant less the camera's delay). The schedule is the fake
 * camera's own (its frame period, as ribbond set it through GenICam, and the real-time clock: a
 * late send does not move the next one). The thread tells the twin's solver (rigsim_twin.h) the
 * exposure instants and how far ahead of real time it may step (a render's lead, 1.5 x the
 * slowest of the last renders + RIGSIM_RENDER_MARGIN_S, and RIGSIM_SOLVER_SLACK periods); takes
 * the logged state of the next send's exposure instant, waiting for the solver at most until the
 * render should start (behind real time, the latest state there is: the image is then stamped with
 * that state's own instant, rigsim_twin_state.exact = 0); renders it into a free image slot and
 * marks it ready for the send. (Before, one thread stepped the twin and rendered: at the snap a
 * step plus a render took up to 79 ms, and every second image repeated the previous one.) */
static void *render_main(void *arg)
{
    rigsim_camera *c = arg;
    ArvFakeCamera *fc = c->fc;
    double done_target = -1.0, last_t = 0.0;
    /* s the exposures lag their schedule: the solver was behind real time. The images keep the
     * camera's rate (one exposure a period, RIGSIM_LAG_CATCHUP shorter while the lag shrinks)
     * instead of jumping through the states the solver catches up with: a snap filmed behind
     * real time is filmed late, never in fewer images. */
    double lag = 0.0;
    long n_renders = 0;
    double recent[RIGSIM_LEAD_RENDERS] = {0}; /* the last renders' times, s */
    for (;;) {
        pthread_mutex_lock(&c->lock);
        int stop = c->twin_stop;
        double last = c->last_fill_mono;
        pthread_mutex_unlock(&c->lock);
        if (stop) break;
        double t, t_real;
        paired_clocks(&t, &t_real);
        /* Nobody streams: the twin's clock pauses (RIGSIM_IDLE_GAP_S). */
        if (t - last > RIGSIM_IDLE_GAP_S) {
            rigsim_twin_hold(c->twin, t);
            lag = 0.0; /* the held twin's latest state stands for now */
            struct timespec ts = {0, 5000000};
            nanosleep(&ts, NULL);
            continue;
        }
        /* The camera's schedule, exactly: Aravis's fake camera sends when the real-time clock
         * reaches a whole multiple of its frame period (AcquisitionFramePeriod, us, as ribbond
         * set the frame rate), whenever its thread gets the CPU after that. */
        guint32 period_us = 0;
        guint64 next_us = 0;
        arv_fake_camera_read_register(fc, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US, &period_us);
        arv_fake_camera_get_sleep_time_for_next_frame(fc, &next_us);
        const double period = period_us > 0 ? 1e-6 * (double)period_us : 1.0 / c->fps;
        const double next_send = t + (1e-6 * (double)next_us - t_real);
        double slowest = 0.0;
        for (int k = 0; k < RIGSIM_LEAD_RENDERS; k++) slowest = fmax(slowest, recent[k]);
        const double lead = fmin(1.5 * slowest + RIGSIM_RENDER_MARGIN_S, 2.0 * period);
        double target = next_send;
        /* (A render that cannot start `lead` before its send still goes: its image may leave a
         * little late, the send waiting for it, RIGSIM_FILL_WAIT, rather than repeat the last.) */
        while (target < t || target <= done_target + 0.5 * period) target += period;
        /* The solver lands on every exposure instant and may run a render's lead and a period
         * ahead of real time, less the camera's delay (an exposure precedes its send by it): the
         * axes are extrapolated that far at their velocity. */
        rigsim_twin_set_grid(c->twin, target - c->f.delay_s, period,
                             fmax(0.0, lead + RIGSIM_SOLVER_SLACK * period - c->f.delay_s));
        pthread_mutex_lock(&c->lock);
        const int frozen = c->f.freeze_after_s >= 0.0 && t - c->t_start >= c->f.freeze_after_s;
        pthread_mutex_unlock(&c->lock);
        rigsim_twin_state st;
        const double want = target - c->f.delay_s - lag;
        const int got = !frozen && rigsim_twin_state_at(c->twin, want, target - lead, last_t, &c->rshape, &st);
        if (got) {
            /* behind the instant asked for: the lag is what the solver lacks; there: it shrinks */
            if (!st.exact)
                lag = fmax(0.0, target - c->f.delay_s - st.mono);
            else
                lag = fmax(0.0, lag - RIGSIM_LAG_CATCHUP * period);
            st.exact = st.exact && fabs(st.mono - (target - c->f.delay_s)) < 1e-6;
        }
        pthread_mutex_lock(&c->lock);
        stop = c->twin_stop;
        pthread_mutex_unlock(&c->lock);
        if (stop) break;
        done_target = target;
        if (!got) {
            if (frozen) sleep_until(target);
            continue; /* no state newer than the last image's yet: the next frame's turn */
        }
        const double t_render = clock_s(CLOCK_MONOTONIC), cpu0 = thread_cpu_s();
        /* A free slot (none: the oldest ready image, which no send took) */
        pthread_mutex_lock(&c->lock);
        int slot = -1;
        for (int k = 0; k < RIGSIM_IMAGES && slot < 0; k++)
            if (c->img[k].state == IMG_FREE) slot = k;
        for (int k = 0; k < RIGSIM_IMAGES && slot < 0; k++)
            if (c->img[k].state == IMG_READY) slot = k;
        for (int k = 0; k < RIGSIM_IMAGES; k++)
            if (c->img[k].state == IMG_READY && slot >= 0 && c->img[slot].state == IMG_READY &&
                c->img[k].mono < c->img[slot].mono)
                slot = k;
        if (slot >= 0) c->img[slot].state = IMG_RENDERING;
        pthread_mutex_unlock(&c->lock);
        if (slot < 0) continue;
        vis_error ve = {0};
        const int drawn = vis_renderer_draw(c->ren, &c->rshape.view, c->img[slot].f, NULL, &ve) == VIS_OK;
        const double t_drawn = clock_s(CLOCK_MONOTONIC);
        pthread_mutex_lock(&c->lock);
        image_slot *im = &c->img[slot];
        im->state = drawn ? IMG_READY : IMG_FREE;
        if (drawn) {
            last_t = st.t;
            im->mono = st.mono;
            im->stamp_real = 0.0;
            im->twin_t = st.t;
            im->exact = st.exact;
            im->dz = st.dz;
            im->dl = st.dl;
            im->dw = st.dw;
            pthread_cond_broadcast(&c->img_cond);
        }
        pthread_mutex_unlock(&c->lock);
        const double took = t_drawn - t_render;
        recent[n_renders++ % RIGSIM_LEAD_RENDERS] = took;
        pthread_mutex_lock(&c->lock);
        c->renders++;
        c->render_cpu_s += thread_cpu_s() - cpu0;
        if (took > c->max_fill_s) c->max_fill_s = took;
        pthread_mutex_unlock(&c->lock);
    }
    return NULL;
}

/* How old the image sent at send_mono is (lock held): counted when older than half a period; a
 * frozen image (the fault) is old on purpose and not counted. */
static void note_age(rigsim_camera *c, double send_mono, double send_real, int frozen)
{
    if (frozen) return;
    const double age = send_mono - c->f.delay_s - c->img[c->last].mono;
    if (age > c->age_max_s) c->age_max_s = age;
    if (age > 0.5 / c->fps) {
        c->behind++;
        if (age > c->behind_note_worst_s) c->behind_note_worst_s = age;
        if (age > c->behind_worst_s) {
            c->behind_worst_s = age;
            c->behind_worst_real = send_real;
        }
    }
}

/* The camera's fill: the latest twin image, stamped as it leaves (never waits for the twin). */
static void fill(ArvBuffer *b, void *user, guint32 exposure_us, guint32 gain, ArvPixelFormat pf)
{
    (void)exposure_us;
    (void)gain;
    rigsim_camera *c = user;
    size_t n = 0;
    uint8_t *dst = (uint8_t *)arv_buffer_get_data(b, &n);
    const int w = arv_buffer_get_image_width(b), h = arv_buffer_get_image_height(b);
    pthread_mutex_lock(&c->lock);
    /* The image of this send: the newest rendered one whose exposure has come (a camera sends
     * an image after it was exposed), waiting at most RIGSIM_FILL_WAIT periods for one (its
     * exposure instant to come, or the render thread starved of a CPU); none: the last image
     * again, counted and stamped as it was (a repeated stamp: the same exposure), not as new.
     * The first send, or the first after a pause (the twin's clock stood still meanwhile), does
     * not wait: it shows the state the twin paused in, as of now. */
    const double fill_mono = clock_s(CLOCK_MONOTONIC);
    const int frozen_at_fill = c->f.freeze_after_s >= 0.0 && fill_mono - c->t_start >= c->f.freeze_after_s;
    const int resumed = c->frames == 0 || fill_mono - c->last_fill_mono > RIGSIM_IDLE_GAP_S;
    int pick = -1;
    if (resumed)
        for (int k = 0; k < RIGSIM_IMAGES; k++)
            if (c->img[k].state == IMG_READY) c->img[k].state = IMG_FREE; /* rendered before the pause */
    if (!frozen_at_fill) {
        const double deadline = fill_mono + RIGSIM_FILL_WAIT / c->fps;
        for (;;) {
            const double now = clock_s(CLOCK_MONOTONIC);
            double wake = deadline;
            for (int k = 0; k < RIGSIM_IMAGES; k++) {
                const image_slot *im = &c->img[k];
                if (im->state != IMG_READY || !(im->mono > c->img[c->last].mono)) continue;
                if (im->mono + c->f.delay_s <= now) {
                    if (pick < 0 || im->mono > c->img[pick].mono) pick = k;
                } else
                    wake = fmin(wake, im->mono + c->f.delay_s);
            }
            if (pick >= 0 || resumed || c->twin_stop || now >= deadline) break;
            struct timespec until;
            until.tv_sec = (time_t)wake;
            until.tv_nsec = (long)((wake - (double)until.tv_sec) * 1e9);
            if (until.tv_nsec >= 1000000000L) until.tv_nsec = 999999999L;
            pthread_cond_timedwait(&c->img_cond, &c->lock, &until);
        }
    }
    if (pick >= 0) {
        /* the ready images older than this one were never sent: skipped */
        for (int k = 0; k < RIGSIM_IMAGES; k++)
            if (k != pick && (c->img[k].state == IMG_LAST ||
                              (c->img[k].state == IMG_READY && c->img[k].mono < c->img[pick].mono)))
                c->img[k].state = IMG_FREE;
        c->img[pick].state = IMG_LAST;
        c->last = pick;
    }
    image_slot *im = &c->img[c->last];
    vis_frame *frame = im->f;
    const int fw = vis_frame_width(frame), fh = vis_frame_height(frame);
    const size_t stride = vis_frame_stride(frame);
    const uint8_t *src = vis_frame_data(frame);
    if (pf == ARV_PIXEL_FORMAT_MONO_8 && dst) {
        for (int y = 0; y < h; y++) {
            if (y < fh && w <= fw)
                memcpy(dst + (size_t)y * w, src + (size_t)y * stride, (size_t)w);
            else
                for (int x = 0; x < w; x++) dst[(size_t)y * w + x] = (x < fw && y < fh) ? src[(size_t)y * stride + x] : 128;
        }
        const int frozen_now = c->f.freeze_after_s >= 0.0 && clock_s(CLOCK_MONOTONIC) - c->t_start >= c->f.freeze_after_s;
        if (c->noise && !frozen_now) {
            const size_t n = (size_t)w * (size_t)h;
            size_t off = (size_t)(xorshift(&c->rng) % NOISE_TABLE);
            for (size_t i = 0; i < n; i++) {
                int v = dst[i] + c->noise[off];
                dst[i] = (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v);
                if (++off == NOISE_TABLE) off = 0;
            }
        }
    }
    double send_mono, send_real;
    paired_clocks(&send_mono, &send_real);
    int frozen = c->f.freeze_after_s >= 0.0 && send_mono - c->t_start >= c->f.freeze_after_s;
    /* The stamp: the instant the image's state stands for, plus the camera's delay (a real
     * camera's exposure precedes its stamp by it). On time that is the send's own grid instant;
     * with the solver behind real time it is earlier than the send, and says so. A frozen image
     * (the fault) is stamped as it leaves: the camera's clock goes on, its image does not. */
    if (resumed && !frozen && pick < 0) im->mono = send_mono - c->f.delay_s;
    const double stamp_mono = frozen ? send_mono : fmin(send_mono, im->mono + c->f.delay_s);
    double stamp_real = send_real - (send_mono - stamp_mono);
    if (!frozen) {
        if (im->stamp_real > 0.0 && !resumed)
            stamp_real = im->stamp_real;
        else
            im->stamp_real = stamp_real;
    }
    arv_buffer_set_timestamp(b, (guint64)llround(stamp_real * 1e9));
    const int repeat = !frozen && !resumed && pick < 0;
    if (repeat) c->repeats++;
    if (!frozen && !im->exact) c->inexact++;
    /* the axes at the stamp's instant (the truth log's positions, Delta L and Delta W) */
    double pc, ps;
    rigsim_rails_positions_at(c->rails, stamp_mono, &pc, &ps);
    if (c->truth) {
        rigsim_twin_stats ts;
        rigsim_twin_stats_get(c->twin, &ts);
        c->ring[c->ring_head % RIGSIM_TRUTH_RING] = (truth_line){
            c->frames, stamp_mono, stamp_real, pc, ps, rig_calib_dl(&c->calib, c->length_m, pc),
            rig_calib_dw(&c->calib, c->length_m, ps), im->dz, im->twin_t,
            stamp_mono - c->f.delay_s - im->mono, send_mono, ts.latest_mono - send_mono, frozen, !frozen && im->exact};
        c->ring_head++;
        if (c->ring_head - c->ring_tail > RIGSIM_TRUTH_RING) {
            c->truth_lost += c->ring_head - c->ring_tail - RIGSIM_TRUTH_RING;
            c->ring_tail = c->ring_head - RIGSIM_TRUTH_RING;
        }
    }
    note_age(c, send_mono, send_real, frozen);
    c->frames++;
    c->last_fill_mono = fill_mono; /* the camera's grid instant, not the send after a wait */
    pthread_mutex_unlock(&c->lock);
}

int rigsim_camera_start(const rig_config *cfg, const rod_scene *sc, double dl_start, rigsim_rails *rails,
                        const char *serial, const char *calib_path, const char *truth_path,
                        const rigsim_camera_faults *f, rigsim_camera **out, char *why, size_t why_len)
{
    *out = NULL;
    rigsim_camera *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(why, why_len, "out of memory");
        return -1;
    }
    c->rails = rails;
    c->calib = cfg->calib;
    c->length_m = sc->length;
    c->f = f ? *f : (rigsim_camera_faults){-1.0, -1.0, 0.0, 0.0, 0.0};
    pthread_mutex_init(&c->lock, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&c->img_cond, &ca);
    pthread_condattr_destroy(&ca);
    twin_camera_params cp = twin_camera_params_default();
    cp.width_px = cfg->camera.width_px > 0 ? cfg->camera.width_px : 640;
    cp.height_px = cfg->camera.height_px > 0 ? cfg->camera.height_px : 480;
    cp.tilt_rad = c->f.tilt_rad;
    vis_error ve = {0};
    for (int k = 0; k < RIGSIM_IMAGES; k++)
        if (!(c->img[k].f = vis_frame_alloc(cp.width_px, cp.height_px, 1, &ve))) {
            snprintf(why, why_len, "out of memory");
            goto fail;
        }
    c->fps = cfg->camera.fps > 0 ? cfg->camera.fps : 30.0;
    c->rng = 0x2545f4914f6cdd1dull;
    if (cfg->camera.noise_sigma > 0.0 && !(c->noise = noise_table(cfg->camera.noise_sigma))) {
        snprintf(why, why_len, "out of memory");
        goto fail;
    }
    /* The twin's mounted state (a static solve, seconds): done here, at the twin's time 0, before
     * any image is due. */
    if (rigsim_twin_open(sc, dl_start, &c->calib, rails, &c->twin, why, why_len)) goto fail;
    /* the side camera renders without noise: the camera adds it per image (noise_table) */
    vis_render_params rp;
    char err[256] = "";
    if (twin_render_params_for_scene(sc, &cp, &rp, err, sizeof err) != TWIN_OK ||
        twin_shape_init(&c->rshape, sc, TWIN_Y_RIG, err, sizeof err) != TWIN_OK) {
        snprintf(why, why_len, "twin camera: %s", err);
        goto fail;
    }
    rp.noise_sigma = 0.0;
    rp.blur_sigma_px = cfg->camera.blur_sigma_px;
    rp.seed = 1u;
    if (!(c->ren = vis_renderer_create(&rp, &ve))) {
        snprintf(why, why_len, "twin camera: %s", ve.message);
        goto fail;
    }
    if (calib_path) {
        vis_calib cal;
        if (twin_calib_for_scene(sc, &rp.camera, &cal, err, sizeof err) != TWIN_OK) {
            snprintf(why, why_len, "camera calibration: %s", err);
            goto fail;
        }
        if (vis_calib_save(&cal, calib_path, &ve) != VIS_OK) {
            snprintf(why, why_len, "camera calibration %s: %s", calib_path, ve.message);
            goto fail;
        }
    }
    if (truth_path) {
        c->truth = fopen(truth_path, "w");
        if (!c->truth) {
            snprintf(why, why_len, "truth log %s cannot be written", truth_path);
            goto fail;
        }
        fprintf(c->truth, "image,mono_s,real_s,compress_mm,shear_mm,dl,dw,dz,frozen,twin_t_s,image_age_s,camera_delay_s,"
                          "sent_mono_s,state_exact,solver_ahead_s\n");
    }
    /* The first image: the mounted state, at the twin's time 0. */
    {
        rigsim_twin_state st;
        if (!rigsim_twin_state_at(c->twin, 0.0, 0.0, -1.0, &c->rshape, &st) ||
            vis_renderer_draw(c->ren, &c->rshape.view, c->img[0].f, NULL, &ve) != VIS_OK) {
            snprintf(why, why_len, "twin camera: the mounted state: %s", ve.message);
            goto fail;
        }
        c->img[0] = (image_slot){c->img[0].f, IMG_LAST, 0.0, 0.0, 0.0, st.dz, st.dl, st.dw, 1};
        c->last = 0;
    }
    c->t_start = c->last_fill_mono = c->img[0].mono = clock_s(CLOCK_MONOTONIC);
    /* The twin stands for the ribbon and the camera, which never wait for a CPU: like the rails'
     * controller (rigsim_rails.c, priority 10) the solver and the render thread run at a
     * real-time priority (5) when the process may, below the controller's; refused, at the
     * process's priority (rigsim_camera_twin_realtime says which). Measured at load 26-29 on 2
     * cores: at the process's priority (nice -10) the solver fell 17 s behind real time; held to
     * one core beside the render, 0.3 of a core and up to 108 ms behind at the snap, 73-97
     * images of an older state; free, 0.15 of a core, up to 56 ms behind, 8. */
    const int cpu = -1;
    c->gv = arv_gv_fake_camera_new("127.0.0.1", serial);
    if (!c->gv || !arv_gv_fake_camera_is_running(c->gv)) {
        snprintf(why, why_len, "the GigE Vision camera could not be served on 127.0.0.1 (GVCP port 3956 taken?)");
        goto fail;
    }
    if (c->f.lost_packets > 0.0) g_object_set(c->gv, "gvsp-lost-ratio", c->f.lost_packets, NULL);
    /* the render thread's own reference: it reads the camera's schedule after a stop fault too */
    c->fc = g_object_ref(arv_gv_fake_camera_get_fake_camera(c->gv));
    arv_fake_camera_set_fill_pattern(c->fc, fill, c);
    int solver_rt = 0;
    if (rigsim_twin_run(c->twin, c->t_start, 5, cpu, &solver_rt, why, why_len)) goto fail;
    if (pthread_create(&c->twin_thread, NULL, render_main, c) != 0) {
        snprintf(why, why_len, "the twin camera's render thread could not start");
        goto fail;
    }
    c->twin_started = 1;
    struct sched_param sp = {.sched_priority = 5};
    c->twin_realtime = solver_rt && pthread_setschedparam(c->twin_thread, SCHED_FIFO, &sp) == 0;
    *out = c;
    return 0;
fail:
    if (c->gv) g_object_unref(c->gv);
    if (c->twin_started) {
        pthread_mutex_lock(&c->lock);
        c->twin_stop = 1;
        pthread_mutex_unlock(&c->lock);
        pthread_join(c->twin_thread, NULL);
    }
    if (c->fc) g_object_unref(c->fc);
    rigsim_twin_close(c->twin);
    vis_renderer_free(c->ren);
    twin_shape_release(&c->rshape);
    if (c->truth) fclose(c->truth);
    for (int k = 0; k < RIGSIM_IMAGES; k++) vis_frame_free(c->img[k].f);
    free(c->noise);
    pthread_cond_destroy(&c->img_cond);
    pthread_mutex_destroy(&c->lock);
    free(c);
    return -1;
}

/* Writes the queued truth lines (the main loop's thread; the sends only queue them). */
static void truth_write(rigsim_camera *c)
{
    if (!c->truth) return;
    pthread_mutex_lock(&c->lock);
    const long n = c->ring_head - c->ring_tail;
    for (long k = 0; k < n; k++) c->out[k] = c->ring[(c->ring_tail + k) % RIGSIM_TRUTH_RING];
    c->ring_tail = c->ring_head;
    pthread_mutex_unlock(&c->lock);
    for (long k = 0; k < n; k++) {
        const truth_line *l = &c->out[k];
        fprintf(c->truth, "%ld,%.9f,%.9f,%.6f,%.6f,%.6f,%.6f,%.6f,%d,%.9f,%.6f,%.6f,%.9f,%d,%.6f\n", l->image, l->mono,
                l->real, l->pc, l->ps, l->dl, l->dw, l->dz, l->frozen, l->twin_t, l->age, c->f.delay_s, l->sent,
                l->exact, l->ahead);
    }
}

int rigsim_camera_tick(rigsim_camera *c)
{
    truth_write(c);
    pthread_mutex_lock(&c->lock);
    const double now = clock_s(CLOCK_MONOTONIC);
    const long nb = c->behind - c->behind_noted;
    const double worst = c->behind_note_worst_s;
    const int note = nb > 0 && now - c->last_note_mono >= RIGSIM_NOTE_EVERY_S;
    if (note) {
        c->behind_noted = c->behind;
        c->behind_note_worst_s = 0.0;
        c->last_note_mono = now;
    }
    pthread_mutex_unlock(&c->lock);
    if (note) {
        printf("twin: behind real time: %ld images sent older than half a frame period since the last note (the "
               "oldest %.1f ms) at %.3f (unix time)\n",
               nb, 1e3 * worst, clock_s(CLOCK_REALTIME));
        fflush(stdout);
    }
    if (c->stopped) return 1;
    if (c->f.stop_after_s >= 0.0 && clock_s(CLOCK_MONOTONIC) - c->t_start >= c->f.stop_after_s) {
        g_object_unref(c->gv); /* joins its threads: no fill runs after this */
        c->gv = NULL;
        c->stopped = 1;
        printf("fault: camera stopped at %.3f (unix time)\n", clock_s(CLOCK_REALTIME));
        fflush(stdout);
        truth_write(c);
        if (c->truth) fflush(c->truth);
    }
    return c->stopped;
}

void rigsim_camera_stop_sending(rigsim_camera *c) { c->f.stop_after_s = 0.0; }

void rigsim_camera_freeze(rigsim_camera *c)
{
    pthread_mutex_lock(&c->lock);
    double now = clock_s(CLOCK_MONOTONIC);
    c->f.freeze_after_s = now - c->t_start;
    pthread_mutex_unlock(&c->lock);
    printf("fault: image frozen at %.3f (unix time)\n", clock_s(CLOCK_REALTIME));
    fflush(stdout);
}

long rigsim_camera_frames(rigsim_camera *c)
{
    pthread_mutex_lock(&c->lock);
    long n = c->frames;
    pthread_mutex_unlock(&c->lock);
    return n;
}

int rigsim_camera_twin_realtime(const rigsim_camera *c) { return c->twin_realtime; }

void rigsim_camera_report(rigsim_camera *c, char *out, size_t n)
{
    rigsim_twin_stats ts;
    rigsim_twin_stats_get(c->twin, &ts);
    char err[256] = "", failed[320] = "";
    if (ts.failures > 0) {
        rigsim_twin_last_error(c->twin, err, sizeof err);
        snprintf(failed, sizeof failed, "; TWIN SOLVER FAILED %ld times (the last: %s)", ts.failures, err);
    }
    pthread_mutex_lock(&c->lock);
    const double up = clock_s(CLOCK_MONOTONIC) - c->t_start;
    snprintf(out, n,
             "images sent: %ld, rendered: %ld (render thread %.2f of a core, slowest render %.1f ms); twin solver "
             "%.2f of a core, %ld steps (the slowest %.1f ms), at most %.1f ms behind real time; images whose state "
             "was older than their exposure (solver behind, stamped with the state's instant): %ld; images repeating "
             "the previous state: %ld; images older than half a frame period when sent: %ld (the oldest %.1f ms)%s%s",
             c->frames, c->renders, up > 0.0 ? c->render_cpu_s / up : 0.0, 1e3 * c->max_fill_s,
             up > 0.0 ? ts.cpu_s / up : 0.0, ts.chunks, 1e3 * ts.worst_chunk_s, 1e3 * fmax(0.0, ts.behind_max_s),
             c->inexact, c->repeats, c->behind, 1e3 * c->age_max_s,
             failed, c->truth_lost ? "; TRUTH LOG INCOMPLETE: lines overwritten before written" : "");
    pthread_mutex_unlock(&c->lock);
}

void rigsim_camera_stop(rigsim_camera *c)
{
    if (!c) return;
    if (c->gv) g_object_unref(c->gv);
    pthread_mutex_lock(&c->lock);
    c->twin_stop = 1;
    pthread_cond_broadcast(&c->img_cond);
    pthread_mutex_unlock(&c->lock);
    if (c->twin_started) pthread_join(c->twin_thread, NULL);
    truth_write(c); /* no send after the camera's unref: the last lines */
    if (c->truth_lost) fprintf(stderr, "ribbon-rigsim: truth log incomplete: %ld lines overwritten before written\n", c->truth_lost);
    if (c->fc) g_object_unref(c->fc);
    rigsim_twin_close(c->twin);
    vis_renderer_free(c->ren);
    twin_shape_release(&c->rshape);
    if (c->truth) fclose(c->truth);
    for (int k = 0; k < RIGSIM_IMAGES; k++) vis_frame_free(c->img[k].f);
    free(c->noise);
    pthread_cond_destroy(&c->img_cond);
    pthread_mutex_destroy(&c->lock);
    free(c);
}

void rigsim_camera_twin_truth(rigsim_camera *c, rod_snap_report *snap, double *dw_now)
{
    rigsim_twin_truth(c->twin, snap, dw_now);
}
