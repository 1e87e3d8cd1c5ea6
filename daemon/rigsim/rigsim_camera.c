/* rigsim_camera.c: the twin filmed by a fake GigE Vision camera on 127.0.0.1 (see rigsim_camera.h). */
#include "rigsim_camera.h"

#include <arv.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "twin.h"

#define RIGSIM_IDLE_GAP_S 0.25 /* s without an image after which the twin's clock pauses */
#define RIGSIM_RENDER_MARGIN_S 2e-3 /* s: an image is ready this long before its send time */
#define RIGSIM_LEAD_RENDERS 32      /* renders whose slowest sets how early the next one starts */
#define RIGSIM_GRID_SENDS 8         /* sends whose earliest gives the camera's schedule */
#define RIGSIM_NOTE_EVERY_S 1.0     /* s at least between two "twin: behind" notes */

/* One line of the truth log, as the send made it. The sends only queue their lines (under the
 * camera's lock, no I/O); the main loop writes them (rigsim_camera_tick), so a slow disk never
 * delays an image. A 0.56 s gap in the sends was seen at load 7 with the write in the send. */
typedef struct truth_line {
    long image;
    double mono, real, pc, ps, dl, dw, dz, twin_t, age;
    int frozen;
} truth_line;
#define RIGSIM_TRUTH_RING 8192 /* lines: 55 s at 150 fps between two writes, which come every 10 ms */

struct rigsim_camera {
    ArvGvFakeCamera *gv;
    rigsim_rails *rails;
    mock_camera *twin;
    vis_frame *frame;
    rig_calibration calib;
    double length_m;
    double t0;
    rigsim_camera_faults f;
    FILE *truth;
    truth_line ring[RIGSIM_TRUTH_RING];
    truth_line out[RIGSIM_TRUTH_RING]; /* the writer's copy, written outside the lock */
    long ring_head, ring_tail;  /* lines queued / taken for writing (index = count % RIGSIM_TRUTH_RING) */
    long truth_lost;            /* lines the ring had to overwrite before they were written */
    pthread_mutex_t lock;   /* the fill thread against stop and the counters */
    long frames;
    double max_fill_s;
    int stopped;
    vis_frame *back;            /* the twin thread renders here, then swaps it with `frame` */
    pthread_t twin_thread;
    int twin_started, twin_stop;
    int twin_realtime;          /* the twin's thread runs SCHED_FIFO */
    double fps;                 /* the rig file's frame rate (the period until the sends show theirs) */
    double render_cpu_s;        /* the twin thread's CPU time, s */
    long renders;               /* images rendered */
    double t_start;             /* host monotonic start, for the fault schedule */
    double t_paused;            /* the last time the twin's clock was paused */
    double last_fill_mono;      /* the last image's send time */
    double img_twin_t, img_dz, img_dl, img_dw; /* what the latest image shows */
    rod_snap_report snap;       /* the twin's own snap so far (mock_camera_truth), under the lock */
    double snap_dw_now;         /* the twin's Delta W at the last render */
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

/* The twin's own thread: one image per camera frame, rendered for that frame's send time. The
 * camera sends at its own period (measured from the sends: ribbond sets the frame rate through
 * GenICam); the thread picks the next send it can still make (now + the running mean of a step
 * and render + RIGSIM_RENDER_MARGIN_S), sleeps until it is that far away, reads the axes' actual
 * positions, extrapolates them to the send time at the axes' velocity, steps the twin to it,
 * renders and swaps the image in. So an image shows the ribbon at the instant it is sent, not at
 * the instant the render began (it used to render twice per frame period as fast as it could and
 * the fill took the latest: images 4 ms old on average, and two renders per frame).
 * (Measured, docs/rig-realtime.md: the render is 5 ms of the 5.7 ms a frame costs; the twin's
 * steps through the snap 20 ms at most in a frame period.) */
static void *twin_main(void *arg)
{
    rigsim_camera *c = arg;
    const double nominal = 1.0 / c->fps;
    double period = nominal, prev_last = NAN, prev_ts = NAN, prev_c = 0.0, prev_s = 0.0, done_target = -1.0;
    long prev_frames = -1, n_renders = 0, n_grid = 0, grid_n[RIGSIM_GRID_SENDS];
    double grid_t[RIGSIM_GRID_SENDS];
    double recent[RIGSIM_LEAD_RENDERS] = {0}; /* the last renders' times, s */
    for (;;) {
        pthread_mutex_lock(&c->lock);
        int stop = c->twin_stop;
        double last = c->last_fill_mono;
        long frames = c->frames;
        pthread_mutex_unlock(&c->lock);
        if (stop) break;
        double t = clock_s(CLOCK_MONOTONIC);
        /* Nobody streams: the twin's clock pauses (RIGSIM_IDLE_GAP_S). */
        if (t - last > RIGSIM_IDLE_GAP_S) {
            pthread_mutex_lock(&c->lock);
            c->t0 += t - fmax(last, c->t_paused);
            c->t_paused = t;
            pthread_mutex_unlock(&c->lock);
            prev_frames = -1;
            n_grid = 0;
            struct timespec ts = {0, 5000000};
            nanosleep(&ts, NULL);
            continue;
        }
        /* The camera's period, from consecutive sends (a mean over the frames between two looks),
         * and its schedule: Aravis's fake camera sends on a fixed grid, so a late send does not
         * move the next one; the grid is the earliest of the last RIGSIM_GRID_SENDS sends carried
         * forward by whole periods. */
        if (prev_frames >= 0 && frames > prev_frames && last > prev_last) {
            double d = (last - prev_last) / (double)(frames - prev_frames);
            if (d > 0.25 * nominal && d < 4.0 * nominal) period = 0.9 * period + 0.1 * d;
        }
        if (frames != prev_frames) {
            grid_t[n_grid % RIGSIM_GRID_SENDS] = last;
            grid_n[n_grid % RIGSIM_GRID_SENDS] = frames - 1;
            n_grid++;
        }
        prev_frames = frames;
        prev_last = last;
        double next_send = last + period; /* the send of image `frames` */
        for (long k = 0; k < n_grid && k < RIGSIM_GRID_SENDS; k++)
            next_send = fmin(next_send, grid_t[k] + (double)(frames - grid_n[k]) * period);
        if (next_send < last + 0.5 * period) next_send = last + period;
        /* The next send this render can make (and not one already rendered for): it starts 1.5 x
         * the slowest of the last RIGSIM_LEAD_RENDERS renders (+ a margin) before the send, at
         * most two periods (the renders grow frame by frame towards the snap; starting early
         * costs only the extrapolation's length). */
        double slowest = 0.0;
        for (int k = 0; k < RIGSIM_LEAD_RENDERS; k++) slowest = fmax(slowest, recent[k]);
        double lead = fmin(1.5 * slowest + RIGSIM_RENDER_MARGIN_S, 2.0 * period);
        double target = next_send;
        while (target - lead < t || target <= done_target + 0.5 * period) target += period;
        sleep_until(target - lead);
        pthread_mutex_lock(&c->lock);
        stop = c->twin_stop;
        pthread_mutex_unlock(&c->lock);
        if (stop) break;
        double t_render = clock_s(CLOCK_MONOTONIC), cpu0 = thread_cpu_s();
        double pc, ps, tp;
        rigsim_rails_positions(c->rails, &pc, &ps, &tp);
        double vc = 0.0, vs = 0.0;
        if (isfinite(prev_ts) && tp > prev_ts && tp - prev_ts < 0.5) {
            vc = (pc - prev_c) / (tp - prev_ts);
            vs = (ps - prev_s) / (tp - prev_ts);
        }
        prev_ts = tp;
        prev_c = pc;
        prev_s = ps;
        /* The instant the image shows: its send time less the camera's delay (the exposure comes
         * before the stamp), never before the instant the last image showed. */
        const double shown = target - c->f.delay_s;
        double ec = pc + vc * (shown - tp), es = ps + vs * (shown - tp);
        double dl = rig_calib_dl(&c->calib, c->length_m, ec), dw = rig_calib_dw(&c->calib, c->length_m, es);
        pthread_mutex_lock(&c->lock);
        double t_twin = fmax(shown - c->t0, c->img_twin_t);
        int frozen = c->f.freeze_after_s >= 0.0 && t_render - c->t_start >= c->f.freeze_after_s;
        pthread_mutex_unlock(&c->lock);
        double t_drawn = t_render;
        if (!frozen) {
            vis_error ve = {0};
            double tf;
            const int drawn = mock_camera_grab(c->twin, t_twin, dl, dw, c->back, &tf, &ve) == VIS_OK;
            t_drawn = clock_s(CLOCK_MONOTONIC);
            if (drawn) {
                double dz = mock_camera_true_dz(c->twin), dw_now;
                rod_snap_report snap;
                mock_camera_truth(c->twin, &snap, &dw_now);
                pthread_mutex_lock(&c->lock);
                c->snap = snap;
                c->snap_dw_now = dw_now;
                pthread_mutex_unlock(&c->lock);
                /* Swapped in once the send before its own has gone (that one shows its own image),
                 * or when that send is a period late. */
                for (;;) {
                    pthread_mutex_lock(&c->lock);
                    const int gone = c->last_fill_mono >= target - 1.5 * period || c->twin_stop;
                    pthread_mutex_unlock(&c->lock);
                    if (gone || clock_s(CLOCK_MONOTONIC) > target) break;
                    struct timespec ts = {0, 200000};
                    nanosleep(&ts, NULL);
                }
                pthread_mutex_lock(&c->lock);
                vis_frame *x = c->frame;
                c->frame = c->back;
                c->back = x;
                c->img_twin_t = t_twin;
                c->img_dz = dz;
                c->img_dl = dl;
                c->img_dw = dw;
                pthread_mutex_unlock(&c->lock);
            }
        }
        done_target = target;
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
    const double age = send_mono - c->f.delay_s - (c->img_twin_t + c->t0);
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
    const int fw = vis_frame_width(c->frame), fh = vis_frame_height(c->frame);
    const size_t stride = vis_frame_stride(c->frame);
    const uint8_t *src = vis_frame_data(c->frame);
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
    arv_buffer_set_timestamp(b, (guint64)llround(send_real * 1e9));
    double pc, ps;
    rigsim_rails_positions(c->rails, &pc, &ps, NULL);
    int frozen = c->f.freeze_after_s >= 0.0 && send_mono - c->t_start >= c->f.freeze_after_s;
    if (c->truth) {
        c->ring[c->ring_head % RIGSIM_TRUTH_RING] = (truth_line){
            c->frames, send_mono, send_real, pc, ps, rig_calib_dl(&c->calib, c->length_m, pc),
            rig_calib_dw(&c->calib, c->length_m, ps), c->img_dz, c->img_twin_t,
            send_mono - c->f.delay_s - (c->img_twin_t + c->t0), frozen};
        c->ring_head++;
        if (c->ring_head - c->ring_tail > RIGSIM_TRUTH_RING) {
            c->truth_lost += c->ring_head - c->ring_tail - RIGSIM_TRUTH_RING;
            c->ring_tail = c->ring_head - RIGSIM_TRUTH_RING;
        }
    }
    note_age(c, send_mono, send_real, frozen);
    c->frames++;
    c->last_fill_mono = send_mono;
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
    twin_camera_params cp = twin_camera_params_default();
    cp.width_px = cfg->camera.width_px > 0 ? cfg->camera.width_px : 640;
    cp.height_px = cfg->camera.height_px > 0 ? cfg->camera.height_px : 480;
    cp.tilt_rad = c->f.tilt_rad;
    vis_error ve = {0};
    c->frame = vis_frame_alloc(cp.width_px, cp.height_px, 1, &ve);
    c->back = vis_frame_alloc(cp.width_px, cp.height_px, 1, &ve);
    c->fps = cfg->camera.fps > 0 ? cfg->camera.fps : 30.0;
    c->rng = 0x2545f4914f6cdd1dull;
    if (cfg->camera.noise_sigma > 0.0 && !(c->noise = noise_table(cfg->camera.noise_sigma))) {
        snprintf(why, why_len, "out of memory");
        goto fail;
    }
    /* the twin renders without noise: the camera adds it per image (noise_table) */
    if (!c->frame || !c->back || mock_camera_open(sc, dl_start, &cp, 0.0, cfg->camera.blur_sigma_px, 1u,
                                      &c->twin, why, why_len))
        goto fail;
    mock_camera_truth(c->twin, &c->snap, &c->snap_dw_now);
    if (calib_path) {
        vis_render_params rp;
        vis_calib cal;
        char err[256] = "";
        if (twin_render_params_for_scene(sc, &cp, &rp, err, sizeof err) != TWIN_OK ||
            twin_calib_for_scene(sc, &rp.camera, &cal, err, sizeof err) != TWIN_OK) {
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
        fprintf(c->truth, "image,mono_s,real_s,compress_mm,shear_mm,dl,dw,dz,frozen,twin_t_s,image_age_s,camera_delay_s\n");
    }
    /* The twin's first grab finds its mounted state (a static solve, seconds): done here, at the
     * twin's time 0, before any image is due. */
    {
        double pc, ps, tf;
        rigsim_rails_positions(rails, &pc, &ps, NULL);
        if (mock_camera_grab(c->twin, 0.0, rig_calib_dl(&c->calib, c->length_m, pc),
                             rig_calib_dw(&c->calib, c->length_m, ps), c->frame, &tf, &ve) != VIS_OK) {
            snprintf(why, why_len, "twin: %s", ve.message);
            goto fail;
        }
        c->img_dz = mock_camera_true_dz(c->twin);
    }
    c->t0 = c->t_start = c->t_paused = c->last_fill_mono = clock_s(CLOCK_MONOTONIC);
    if (pthread_create(&c->twin_thread, NULL, twin_main, c) != 0) {
        snprintf(why, why_len, "the twin's thread could not start");
        goto fail;
    }
    c->twin_started = 1;
    /* The twin stands for the ribbon, which never waits for a CPU: like the rails' controller
     * (rigsim_rails.c, priority 10) its thread runs at a real-time priority when the process may,
     * below the controller's. It sleeps between images (0.35 of a core at 640 x 480, 60 fps);
     * refused, it runs at the process's priority (rigsim_camera_twin_realtime says which). */
    struct sched_param sp = {.sched_priority = 5};
    c->twin_realtime = pthread_setschedparam(c->twin_thread, SCHED_FIFO, &sp) == 0;
    c->gv = arv_gv_fake_camera_new("127.0.0.1", serial);
    if (!c->gv || !arv_gv_fake_camera_is_running(c->gv)) {
        snprintf(why, why_len, "the GigE Vision camera could not be served on 127.0.0.1 (GVCP port 3956 taken?)");
        goto fail;
    }
    if (c->f.lost_packets > 0.0) g_object_set(c->gv, "gvsp-lost-ratio", c->f.lost_packets, NULL);
    arv_fake_camera_set_fill_pattern(arv_gv_fake_camera_get_fake_camera(c->gv), fill, c);
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
    vis_frame_free(c->back);
    if (c->truth) fclose(c->truth);
    mock_camera_close(c->twin);
    vis_frame_free(c->frame);
    free(c->noise);
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
        fprintf(c->truth, "%ld,%.9f,%.9f,%.6f,%.6f,%.6f,%.6f,%.6f,%d,%.9f,%.6f,%.6f\n", l->image, l->mono, l->real,
                l->pc, l->ps, l->dl, l->dw, l->dz, l->frozen, l->twin_t, l->age, c->f.delay_s);
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
    pthread_mutex_lock(&c->lock);
    const double up = clock_s(CLOCK_MONOTONIC) - c->t_start;
    snprintf(out, n,
             "images sent: %ld, rendered: %ld (twin thread %.2f of a core), slowest twin step + render %.1f ms; "
             "images older than half a frame period when sent: %ld (the oldest %.1f ms)%s",
             c->frames, c->renders, up > 0.0 ? c->render_cpu_s / up : 0.0, 1e3 * c->max_fill_s, c->behind,
             1e3 * c->age_max_s, c->truth_lost ? "; TRUTH LOG INCOMPLETE: lines overwritten before written" : "");
    pthread_mutex_unlock(&c->lock);
}

void rigsim_camera_stop(rigsim_camera *c)
{
    if (!c) return;
    if (c->gv) g_object_unref(c->gv);
    pthread_mutex_lock(&c->lock);
    c->twin_stop = 1;
    pthread_mutex_unlock(&c->lock);
    if (c->twin_started) pthread_join(c->twin_thread, NULL);
    truth_write(c); /* no send after the camera's unref: the last lines */
    if (c->truth_lost) fprintf(stderr, "ribbon-rigsim: truth log incomplete: %ld lines overwritten before written\n", c->truth_lost);
    vis_frame_free(c->back);
    if (c->truth) fclose(c->truth);
    mock_camera_close(c->twin);
    vis_frame_free(c->frame);
    free(c->noise);
    pthread_mutex_destroy(&c->lock);
    free(c);
}

void rigsim_camera_twin_truth(rigsim_camera *c, rod_snap_report *snap, double *dw_now)
{
    pthread_mutex_lock(&c->lock);
    if (snap) *snap = c->snap;
    if (dw_now) *dw_now = c->snap_dw_now;
    pthread_mutex_unlock(&c->lock);
}
