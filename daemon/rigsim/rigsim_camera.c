/* rigsim_camera.c: the twin filmed by a fake GigE Vision camera on 127.0.0.1 (see rigsim_camera.h). */
#include "rigsim_camera.h"

#include <arv.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mock_camera.h"
#include "twin_camera.h"

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
    int have_image;
    double fill_ema_s;          /* running mean of the fill time (twin step + render), s */
    double prev_t, prev_c, prev_s; /* the previous fill's time and axis positions */
};

static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void fill(ArvBuffer *b, void *user, guint32 exposure_us, guint32 gain, ArvPixelFormat pf)
{
    (void)exposure_us;
    (void)gain;
    rigsim_camera *c = user;
    size_t n = 0;
    uint8_t *dst = (uint8_t *)arv_buffer_get_data(b, &n);
    const int w = arv_buffer_get_image_width(b), h = arv_buffer_get_image_height(b);
    const double mono = clock_s(CLOCK_MONOTONIC);
    pthread_mutex_lock(&c->lock);
    /* While nobody streams the twin's clock pauses: a gap of more than RIGSIM_IDLE_GAP_S since the
     * last image (before the first one, between ribbond's sessions) is skipped, not simulated, so
     * the next image does not wait for seconds of dynamics at rest. ribbond streams whenever it
     * moves the rails, so no motion falls in a gap. */
    double last = c->frames > 0 ? c->prev_t : c->t0;
    if (mono - last > RIGSIM_IDLE_GAP_S) c->t0 += mono - last - 1.0 / 60.0;
    double pc, ps, tr;
    rigsim_rails_positions(c->rails, &pc, &ps, &tr);
    /* The image is sent when this callback returns, about one fill time from now: the twin is
     * stepped to that instant with the axes' positions extrapolated at their current velocity. */
    double ahead = c->fill_ema_s;
    double vc = 0.0, vs = 0.0;
    if (c->frames > 0 && mono > c->prev_t) {
        vc = (pc - c->prev_c) / (mono - c->prev_t);
        vs = (ps - c->prev_s) / (mono - c->prev_t);
    }
    c->prev_t = mono;
    c->prev_c = pc;
    c->prev_s = ps;
    double ec = pc + vc * ahead, es = ps + vs * ahead;
    double dl = rig_calib_dl(&c->calib, c->length_m, ec), dw = rig_calib_dw(&c->calib, c->length_m, es);
    int frozen = c->f.freeze_after_s >= 0.0 && mono - c->t0 >= c->f.freeze_after_s && c->have_image;
    if (!frozen) {
        vis_error ve = {0};
        double tf;
        if (mock_camera_grab(c->twin, mono + ahead - c->t0, dl, dw, c->frame, &tf, &ve) == VIS_OK) c->have_image = 1;
    }
    const int fw = vis_frame_width(c->frame), fh = vis_frame_height(c->frame);
    const size_t stride = vis_frame_stride(c->frame);
    const uint8_t *src = vis_frame_data(c->frame);
    if (pf == ARV_PIXEL_FORMAT_MONO_8 && dst && c->have_image) {
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) dst[(size_t)y * w + x] = (x < fw && y < fh) ? src[(size_t)y * stride + x] : 128;
    }
    double dz = mock_camera_true_dz(c->twin);
    /* The camera's timestamp is the moment the image leaves (Aravis stamped the start of the fill). */
    const double send_mono = clock_s(CLOCK_MONOTONIC), send_real = clock_s(CLOCK_REALTIME);
    arv_buffer_set_timestamp(b, (guint64)llround(send_real * 1e9));
    double sc_, ss_;
    rigsim_rails_positions(c->rails, &sc_, &ss_, NULL);
    if (c->truth)
        fprintf(c->truth, "%ld,%.9f,%.9f,%.6f,%.6f,%.6f,%.6f,%.6f,%d,%.9f,%.6f\n", c->frames, send_mono, send_real, sc_,
                ss_, rig_calib_dl(&c->calib, c->length_m, sc_), rig_calib_dw(&c->calib, c->length_m, ss_), dz, frozen,
                mono + ahead - c->t0, send_mono - mono);
    c->frames++;
    double took = send_mono - mono;
    if (took > c->max_fill_s) c->max_fill_s = took;
    c->fill_ema_s = c->frames == 1 ? took : 0.8 * c->fill_ema_s + 0.2 * took;
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
    c->f = f ? *f : (rigsim_camera_faults){-1.0, -1.0};
    pthread_mutex_init(&c->lock, NULL);
    twin_camera_params cp = twin_camera_params_default();
    cp.width_px = cfg->camera.width_px > 0 ? cfg->camera.width_px : 640;
    cp.height_px = cfg->camera.height_px > 0 ? cfg->camera.height_px : 480;
    vis_error ve = {0};
    c->frame = vis_frame_alloc(cp.width_px, cp.height_px, 1, &ve);
    if (!c->frame || mock_camera_open(sc, dl_start, &cp, cfg->camera.noise_sigma, cfg->camera.blur_sigma_px, 1u,
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
        fprintf(c->truth, "image,mono_s,real_s,compress_mm,shear_mm,dl,dw,dz,frozen,twin_t_s,fill_s\n");
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
        c->have_image = 1;
    }
    c->t0 = clock_s(CLOCK_MONOTONIC);
    c->gv = arv_gv_fake_camera_new("127.0.0.1", serial);
    if (!c->gv || !arv_gv_fake_camera_is_running(c->gv)) {
        snprintf(why, why_len, "the GigE Vision camera could not be served on 127.0.0.1 (GVCP port 3956 taken?)");
        goto fail;
    }
    arv_fake_camera_set_fill_pattern(arv_gv_fake_camera_get_fake_camera(c->gv), fill, c);
    *out = c;
    return 0;
fail:
    if (c->gv) g_object_unref(c->gv);
    if (c->truth) fclose(c->truth);
    mock_camera_close(c->twin);
    vis_frame_free(c->frame);
    pthread_mutex_destroy(&c->lock);
    free(c);
    return -1;
}

int rigsim_camera_tick(rigsim_camera *c)
{
    if (c->stopped) return 1;
    if (c->f.stop_after_s >= 0.0 && clock_s(CLOCK_MONOTONIC) - c->t0 >= c->f.stop_after_s) {
        g_object_unref(c->gv); /* joins its threads: no fill runs after this */
        c->gv = NULL;
        c->stopped = 1;
        printf("fault: camera stopped at %.3f (unix time)\n", clock_s(CLOCK_REALTIME));
        fflush(stdout);
        if (c->truth) fflush(c->truth);
    }
    return c->stopped;
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
    if (c->truth) fclose(c->truth);
    mock_camera_close(c->twin);
    vis_frame_free(c->frame);
    pthread_mutex_destroy(&c->lock);
    free(c);
}
