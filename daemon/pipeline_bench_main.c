/* pipeline_bench_main.c: `ribbon-pipeline-bench`, the live pipeline's speed (issue 13 F).
 *
 * Aravis's fake GigE Vision camera on 127.0.0.1 in this process streams a rendered twin image
 * (the rehearsal scene at the requested size; the fill copies it, so the camera itself costs only
 * the copy and the loopback transport) at the requested rate; the pipeline runs as in a rig trial:
 * capture thread, ring, recorder (raw Y800 AVI, every frame), and on this thread each frame tracked
 * (the real tracker and calibration) and stored (SQLite samples, batched, as a trial stores them).
 * Prints one JSON line per region: full frame, then the trial's automatic ROI crop:
 *   {"bench":"live_pipeline","roi":"full","width":..,"height":..,"fps_asked":..,"seconds":..,
 *    "fps_sustained":..,"captured":..,"lost":..,"incomplete":..,"dropped":..,"skipped":..,
 *    "recorded":..,"p99_capture_to_stored_ms":..,"max_capture_to_stored_ms":..,"load1":..}
 * fps_sustained counts frames captured per second; "zero drops" means lost + incomplete + dropped
 * = 0 (skipped frames are stored untracked and counted, not dropped); tracked / measured: frames
 * the tracker ran on / found the ribbon in. Options: --seconds (60) --fps (120) --width (1280)
 * --height (720) --rig (config/rig-rehearsal.ini: the scene and its twin camera). */
#include <arv.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "rig_config.h"
#include "store.h"
#include "trial.h"
#include "twin.h"

static double mono(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct image {
    const uint8_t *px;
    int w, h;
    size_t stride;
} image;

static void fill(ArvBuffer *b, void *user, guint32 e, guint32 g, ArvPixelFormat pf)
{
    (void)e;
    (void)g;
    (void)pf;
    image *im = user;
    size_t n = 0;
    uint8_t *dst = (uint8_t *)arv_buffer_get_data(b, &n);
    int w = arv_buffer_get_image_width(b), h = arv_buffer_get_image_height(b);
    for (int y = 0; y < h && y < im->h; y++) memcpy(dst + (size_t)y * w, im->px + (size_t)y * im->stride, (size_t)(w < im->w ? w : im->w));
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static int run(const rig_config *cfg, const vis_calib *cal, int w, int h, double fps, double seconds, int crop,
               const char *dir)
{
    char why[512] = "";
    vis_error ve = {0};
    vis_camera_settings cs = vis_camera_settings_default();
    cs.aravis = 1;
    cs.path = "127.0.0.1";
    cs.width_px = w;
    cs.height_px = h;
    cs.fps = fps;
    cs.n_buffers = 64;
    vis_source *src = vis_source_open_camera(&cs, &ve);
    if (!src) {
        fprintf(stderr, "ribbon-pipeline-bench: %s\n", ve.message);
        return 1;
    }
    trial_capture_params p = trial_capture_params_default();
    char video[512];
    snprintf(video, sizeof video, "%s/bench-%s.avi", dir, crop ? "roi" : "full");
    p.video_path = video;
    p.fps = fps;
    p.roi = crop ? trial_roi_auto(cal, w, h, cfg->scene.length * 1000.0, cfg->scene.compression, 20)
                 : (trial_roi){0, 0, w & ~1, h & ~1};
    trial_capture *c = trial_capture_start(src, &p, why, sizeof why);
    if (!c) {
        fprintf(stderr, "ribbon-pipeline-bench: %s\n", why);
        return 1;
    }
    char dbp[512];
    snprintf(dbp, sizeof dbp, "%s/bench.db", dir);
    store *st = NULL;
    int64_t id = 0;
    store_samples *sw = NULL;
    store_trial_def def = store_trial_def_default();
    def.config_text = "bench";
    def.calibration_json = "{}";
    def.created_wall_s = store_wall_now();
    if (store_open(dbp, &st, why, sizeof why) != STORE_OK || store_trial_create(st, &def, &id, why, sizeof why) ||
        store_samples_begin(st, id, NULL, &sw, why, sizeof why) != STORE_OK) {
        fprintf(stderr, "ribbon-pipeline-bench: store: %s\n", why);
        return 1;
    }
    vis_track_params tp = vis_track_params_default();
    tp.length_mm = cfg->scene.length * 1000.0;
    vis_tracker *trk = vis_tracker_create(&tp, cal, &ve);
    vis_frame *fr = vis_frame_alloc(16, 16, 1, &ve);
    size_t cap = (size_t)(fps * seconds * 1.5) + 1000, n = 0;
    double *lat = malloc(cap * sizeof *lat);
    if (!trk || !fr || !lat) {
        fprintf(stderr, "ribbon-pipeline-bench: tracker: %s\n", ve.message);
        return 1;
    }
    double t0 = mono(), t_end = t0 + seconds, max_track = 0.0, max_store = 0.0, sum_track = 0.0;
    long n_tracked = 0, n_measured = 0;
    int rc = 0;
    while (mono() < t_end) {
        trial_frame_info fi;
        if (trial_capture_next(c, fr, &fi, why, sizeof why)) {
            fprintf(stderr, "ribbon-pipeline-bench: %s\n", why);
            rc = 1;
            break;
        }
        store_sample x = store_sample_default();
        x.t_s = fi.t_s - t0;
        x.kind = STORE_SAMPLE_FRAME;
        x.frame = fi.index;
        if (!fi.skip && !fi.dropped) {
            vis_measure m;
            double ta = mono();
            vis_tracker_process(trk, fr, 0.0, &m, &ve);
            double tk = mono() - ta;
            if (tk > max_track) max_track = tk;
            n_tracked++;
            sum_track += tk;
            if (m.reason == VIS_REASON_NONE) {
                n_measured++;
                x.dz = m.dz;
                x.a = m.a;
                x.quality = m.quality;
            } else
                snprintf(x.reason, sizeof x.reason, "%s", vis_reason_str(m.reason));
        } else
            snprintf(x.reason, sizeof x.reason, "not tracked");
        double tsa = mono();
        store_err se = store_samples_add(sw, &x, why, sizeof why);
        if (mono() - tsa > max_store) max_store = mono() - tsa;
        if (se != STORE_OK) {
            fprintf(stderr, "ribbon-pipeline-bench: store: %s\n", why);
            rc = 1;
            break;
        }
        if (n < cap) lat[n++] = mono() - fi.host_t_s;
    }
    double el = mono() - t0;
    trial_capture_counts k;
    trial_capture_stop(c, &k, why, sizeof why);
    store_samples_end(sw, why, sizeof why);
    store_close(st);
    vis_tracker_free(trk);
    vis_frame_free(fr);
    vis_source_close(src);
    qsort(lat, n, sizeof *lat, cmp);
    double p99 = n ? lat[(size_t)(0.99 * (double)(n - 1))] : NAN, mx = n ? lat[n - 1] : NAN;
    double load = NAN;
    FILE *la = fopen("/proc/loadavg", "r");
    if (la) {
        if (fscanf(la, "%lf", &load) != 1) load = NAN;
        fclose(la);
    }
    printf("{\"bench\":\"live_pipeline\",\"roi\":\"%s\",\"width\":%d,\"height\":%d,\"video_w\":%d,\"video_h\":%d,"
           "\"fps_asked\":%.1f,\"seconds\":%.1f,\"fps_sustained\":%.1f,\"captured\":%ld,\"lost\":%ld,"
           "\"incomplete\":%ld,\"dropped\":%ld,\"skipped\":%ld,\"recorded\":%ld,\"p99_capture_to_stored_ms\":%.2f,"
           "\"max_capture_to_stored_ms\":%.2f,\"tracked\":%ld,\"measured\":%ld,\"track_mean_ms\":%.2f,\"track_max_ms\":%.2f,"
           "\"store_max_ms\":%.2f,\"load1\":%.2f}\n",
           crop ? "auto" : "full", w, h, p.roi.w, p.roi.h, fps, el, k.captured / el, k.captured, k.lost, k.incomplete,
           k.dropped, k.skipped, k.recorded, 1e3 * p99, 1e3 * mx, n_tracked, n_measured, n_tracked ? 1e3 * sum_track / n_tracked : NAN,
           1e3 * max_track, 1e3 * max_store, load);
    fflush(stdout);
    free(lat);
    return rc;
}

int main(int argc, char **argv)
{
    int w = 1280, h = 720;
    double fps = 120.0, seconds = 60.0;
    const char *rig = RIBBON_SOURCE_DIR "/config/rig-rehearsal.ini";
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--seconds")) seconds = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--fps")) fps = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--width")) w = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--height")) h = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--rig")) rig = argv[i + 1];
        else {
            fprintf(stderr, "usage: ribbon-pipeline-bench [--seconds S] [--fps F] [--width W] [--height H] [--rig INI]\n");
            return 2;
        }
    }
    if (!(seconds > 0) || !(fps > 0) || w < 16 || h < 16) {
        fprintf(stderr, "ribbon-pipeline-bench: seconds, fps must be positive, sizes at least 16\n");
        return 2;
    }
    static rig_config cfg;
    cfg_error ce;
    char why[512];
    const char *sets[] = {"rail.compress.port=/dev/null", "rail.shear.port=/dev/null"};
    if (rig_config_load(rig, sets, 2, &cfg, &ce) != CFG_OK) {
        fprintf(stderr, "ribbon-pipeline-bench: %s\n", cfg_error_format(&ce, why, sizeof why));
        return 1;
    }
    rod_scene sc = cfg.scene;
    twin_camera_params cp = twin_camera_params_default();
    cp.width_px = w;
    cp.height_px = h;
    vis_render_params rp;
    vis_calib cal;
    char err[256];
    mock_camera *mc = NULL;
    vis_error ve = {0};
    vis_frame *img = vis_frame_alloc(w, h, 1, &ve);
    double tf;
    if (twin_render_params_for_scene(&sc, &cp, &rp, err, sizeof err) != TWIN_OK ||
        twin_calib_for_scene(&sc, &rp.camera, &cal, err, sizeof err) != TWIN_OK ||
        mock_camera_open(&sc, sc.compression, &cp, 2.0, 0.8, 1u, &mc, err, sizeof err) ||
        mock_camera_grab(mc, 0.0, sc.compression, 0.0, img, &tf, &ve) != VIS_OK) {
        fprintf(stderr, "ribbon-pipeline-bench: twin: %s %s\n", err, ve.message);
        return 1;
    }
    image im = {vis_frame_data(img), w, h, vis_frame_stride(img)};
    char dir[] = "/tmp/ribbon-pipeline-bench.XXXXXX";
    if (!mkdtemp(dir)) return 1;
    ArvGvFakeCamera *gv = arv_gv_fake_camera_new("127.0.0.1", "RIBBONBENCH");
    if (!gv || !arv_gv_fake_camera_is_running(gv)) {
        fprintf(stderr, "ribbon-pipeline-bench: no fake GigE Vision camera on 127.0.0.1\n");
        return 1;
    }
    arv_fake_camera_set_fill_pattern(arv_gv_fake_camera_get_fake_camera(gv), fill, &im);
    int rc = run(&cfg, &cal, w, h, fps, seconds, 0, dir);
    if (!rc) rc = run(&cfg, &cal, w, h, fps, seconds, 1, dir);
    g_object_unref(gv);
    mock_camera_close(mc);
    vis_frame_free(img);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0) fprintf(stderr, "ribbon-pipeline-bench: %s left behind\n", dir);
    return rc;
}
