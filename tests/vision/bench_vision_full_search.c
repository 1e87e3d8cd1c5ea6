/* bench_vision_full_search.c: the tracker's fresh acquisition (no previous curve) on the
 * rehearsal scene's twin image at 1280 x 720, one JSON line (issue 13's pipeline bench found it at
 * 0.5-1.2 s per frame; issue 14).
 *
 *   bench_vision_full_search [--frames N] [--width W --height H] [--dl DL] [--dump PNG]
 *
 * The scene is config/scenes/mock-gamma013.ini (the rehearsal's), the camera the twin's for it,
 * the tracker's parameters those the pipeline bench and the live pipeline use (defaults with the
 * known length). Each frame is tracked from scratch (vis_tracker_reset between frames) and then
 * followed once from that curve; prints the mean and worst milliseconds of either, and what the
 * last frame measured. Not a test: speed targets live in benchmarks. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mock_camera.h"
#include "scene_file.h"
#include "twin_camera.h"
#include "vision.h"

static double mono(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
    int frames = 10, w = 1280, h = 720;
    double dl = -1;
    const char *dump = NULL;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--frames"))
            frames = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--width"))
            w = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--height"))
            h = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "--dl"))
            dl = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--dump"))
            dump = argv[i + 1];
        else {
            fprintf(stderr, "usage: bench_vision_full_search [--frames N] [--width W --height H] [--dl DL] [--dump PNG]\n");
            return 2;
        }
    }
    if (frames < 1 || w < 16 || h < 16) {
        fprintf(stderr, "bench_vision_full_search: frames >= 1, sizes >= 16\n");
        return 2;
    }
    rod_scene sc;
    cfg_error ce;
    char buf[1200], err[256];
    if (cfg_scene_load(RIBBON_SOURCE_DIR "/config/scenes/mock-gamma013.ini", NULL, 0, &sc, &ce) != CFG_OK) {
        fprintf(stderr, "bench_vision_full_search: %s\n", cfg_error_format(&ce, buf, sizeof buf));
        return 1;
    }
    if (dl < 0)
        dl = sc.compression;
    twin_camera_params cp = twin_camera_params_default();
    cp.width_px = w;
    cp.height_px = h;
    vis_render_params rp;
    vis_calib cal;
    vis_error ve = {0};
    mock_camera *mc = NULL;
    vis_frame *img = vis_frame_alloc(w, h, 1, &ve);
    double tf;
    if (!img || twin_render_params_for_scene(&sc, &cp, &rp, err, sizeof err) != TWIN_OK ||
        twin_calib_for_scene(&sc, &rp.camera, &cal, err, sizeof err) != TWIN_OK ||
        mock_camera_open(&sc, dl, &cp, 2.0, 0.8, 1u, &mc, err, sizeof err) ||
        mock_camera_grab(mc, 0.0, dl, 0.0, img, &tf, &ve) != VIS_OK) {
        fprintf(stderr, "bench_vision_full_search: twin: %s %s\n", err, ve.message);
        return 1;
    }
    vis_track_params tp = vis_track_params_default();
    tp.length_mm = sc.length * 1000.0;
    vis_tracker *trk = vis_tracker_create(&tp, &cal, &ve);
    if (!trk) {
        fprintf(stderr, "bench_vision_full_search: %s\n", ve.message);
        return 1;
    }
    double sum_fresh = 0, max_fresh = 0, sum_follow = 0, max_follow = 0;
    vis_measure m = {0}, mf = {0};
    for (int k = 0; k < frames; k++) {
        vis_tracker_reset(trk);
        double t0 = mono();
        vis_tracker_process(trk, img, 0.0, &m, &ve);
        const double t1 = mono() - t0;
        t0 = mono();
        vis_tracker_process(trk, img, 0.0, &mf, &ve);
        const double t2 = mono() - t0;
        sum_fresh += t1;
        sum_follow += t2;
        max_fresh = fmax(max_fresh, t1);
        max_follow = fmax(max_follow, t2);
    }
    if (dump) {
        vis_frame *o = vis_frame_alloc(8, 8, 3, &ve);
        if (o && vis_overlay_draw(img, trk, &mf, 0, o, &ve) == VIS_OK)
            (void)vis_frame_save(o, dump, &ve);
        vis_frame_free(o);
    }
    printf("{\"bench\":\"vision_full_search\",\"width\":%d,\"height\":%d,\"frames\":%d,\"fresh_mean_ms\":%.2f,"
           "\"fresh_max_ms\":%.2f,\"follow_mean_ms\":%.3f,\"follow_max_ms\":%.3f,\"reason\":\"%s\",\"dz\":%.5f,"
           "\"a\":%.5f,\"quality\":%.3f,\"follow_reason\":\"%s\"}\n",
           w, h, frames, 1e3 * sum_fresh / frames, 1e3 * max_fresh, 1e3 * sum_follow / frames, 1e3 * max_follow,
           vis_reason_str(m.reason), m.dz, m.a, m.quality, vis_reason_str(mf.reason));
    vis_tracker_free(trk);
    mock_camera_close(mc);
    vis_frame_free(img);
    return 0;
}
