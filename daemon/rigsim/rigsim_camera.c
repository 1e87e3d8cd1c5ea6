/* rigsim_camera.c: the twin filmed by a fake GigE Vision camera on 127.0.0.1 (see rigsim_camera.h). */
#include "rigsim_camera.h"

#include <arv.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "twin.h"

#define RIGSIM_IDLE_GAP_S 0.25 /* s without an image after which the twin's clock pauses */

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
    pthread_mutex_t lock;   /* the fill thread against stop and the counters */
    long frames;
    double max_fill_s;
    int stopped;
    vis_frame *back;            /* the twin thread renders here, then swaps it with `frame` */
    pthread_t twin_thread;
    int twin_started, twin_stop;
    double fps;                 /* the rig file's frame rate (paces the twin thread) */
    double render_ema_s;        /* running mean of a twin step + render, s (twin thread only) */
    double t_start;             /* host monotonic start, for the fault schedule */
    double t_paused;            /* the last time the twin's clock was paused */
    double last_fill_mono;      /* the last image's send time */
    double img_twin_t, img_dz, img_dl, img_dw; /* what the latest image shows */
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

/* The twin's own thread: step the twin to the expected time of the next image (now + the running
 * mean of a step and render, positions extrapolated at the axes' velocity), render it into the back
 * frame, swap it in as the latest image. Paced at twice the camera's rate at most. */
static void *twin_main(void *arg)
{
    rigsim_camera *c = arg;
    double prev_t = NAN, prev_c = 0.0, prev_s = 0.0;
    for (;;) {
        pthread_mutex_lock(&c->lock);
        int stop = c->twin_stop;
        pthread_mutex_unlock(&c->lock);
        if (stop) break;
        double t = clock_s(CLOCK_MONOTONIC);
        pthread_mutex_lock(&c->lock);
        double last = c->last_fill_mono;
        pthread_mutex_unlock(&c->lock);
        /* Nobody streams: the twin's clock pauses (RIGSIM_IDLE_GAP_S). */
        if (t - last > RIGSIM_IDLE_GAP_S) {
            pthread_mutex_lock(&c->lock);
            c->t0 += t - fmax(last, c->t_paused);
            c->t_paused = t;
            pthread_mutex_unlock(&c->lock);
            struct timespec ts = {0, 5000000};
            nanosleep(&ts, NULL);
            continue;
        }
        double pc, ps;
        rigsim_rails_positions(c->rails, &pc, &ps, NULL);
        double vc = 0.0, vs = 0.0;
        if (isfinite(prev_t) && t > prev_t) {
            vc = (pc - prev_c) / (t - prev_t);
            vs = (ps - prev_s) / (t - prev_t);
        }
        prev_t = t;
        prev_c = pc;
        prev_s = ps;
        double ahead = c->render_ema_s;
        double ec = pc + vc * ahead, es = ps + vs * ahead;
        double dl = rig_calib_dl(&c->calib, c->length_m, ec), dw = rig_calib_dw(&c->calib, c->length_m, es);
        pthread_mutex_lock(&c->lock);
        double t_twin = t + ahead - c->t0;
        int frozen = c->f.freeze_after_s >= 0.0 && t - c->t_start >= c->f.freeze_after_s;
        pthread_mutex_unlock(&c->lock);
        if (!frozen) {
            vis_error ve = {0};
            double tf;
            if (mock_camera_grab(c->twin, t_twin, dl, dw, c->back, &tf, &ve) == VIS_OK) {
                double dz = mock_camera_true_dz(c->twin);
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
        double took = clock_s(CLOCK_MONOTONIC) - t;
        c->render_ema_s = c->render_ema_s == 0.0 ? took : 0.8 * c->render_ema_s + 0.2 * took;
        pthread_mutex_lock(&c->lock);
        if (took > c->max_fill_s) c->max_fill_s = took;
        pthread_mutex_unlock(&c->lock);
        double rest = 0.5 / c->fps - took;
        if (rest > 0) {
            struct timespec ts = {0, (long)(rest * 1e9)};
            nanosleep(&ts, NULL);
        }
    }
    return NULL;
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
    if (c->truth)
        fprintf(c->truth, "%ld,%.9f,%.9f,%.6f,%.6f,%.6f,%.6f,%.6f,%d,%.9f,%.6f\n", c->frames, send_mono, send_real, pc,
                ps, rig_calib_dl(&c->calib, c->length_m, pc), rig_calib_dw(&c->calib, c->length_m, ps), c->img_dz,
                frozen, c->img_twin_t, send_mono - (c->img_twin_t + c->t0));
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
    c->f = f ? *f : (rigsim_camera_faults){-1.0, -1.0, 0.0};
    pthread_mutex_init(&c->lock, NULL);
    twin_camera_params cp = twin_camera_params_default();
    cp.width_px = cfg->camera.width_px > 0 ? cfg->camera.width_px : 640;
    cp.height_px = cfg->camera.height_px > 0 ? cfg->camera.height_px : 480;
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
        fprintf(c->truth, "image,mono_s,real_s,compress_mm,shear_mm,dl,dw,dz,frozen,twin_t_s,image_age_s\n");
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

int rigsim_camera_tick(rigsim_camera *c)
{
    if (c->stopped) return 1;
    if (c->f.stop_after_s >= 0.0 && clock_s(CLOCK_MONOTONIC) - c->t_start >= c->f.stop_after_s) {
        g_object_unref(c->gv); /* joins its threads: no fill runs after this */
        c->gv = NULL;
        c->stopped = 1;
        printf("fault: camera stopped at %.3f (unix time)\n", clock_s(CLOCK_REALTIME));
        fflush(stdout);
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

double rigsim_camera_max_fill_s(rigsim_camera *c)
{
    pthread_mutex_lock(&c->lock);
    double m = c->max_fill_s;
    pthread_mutex_unlock(&c->lock);
    return m;
}

void rigsim_camera_stop(rigsim_camera *c)
{
    if (!c) return;
    if (c->gv) g_object_unref(c->gv);
    pthread_mutex_lock(&c->lock);
    c->twin_stop = 1;
    pthread_mutex_unlock(&c->lock);
    if (c->twin_started) pthread_join(c->twin_thread, NULL);
    vis_frame_free(c->back);
    if (c->truth) fclose(c->truth);
    mock_camera_close(c->twin);
    vis_frame_free(c->frame);
    free(c->noise);
    pthread_mutex_destroy(&c->lock);
    free(c);
}
