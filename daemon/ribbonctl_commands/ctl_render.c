/* ctl_render.c: `ribbonctl render`: a simulated trial filmed by a synthetic side camera, written as
 * a lossless video with its ground truth (the offline half of mock mode, and test material for the
 * tracker).
 *
 *   ribbonctl render --scene F --out OUT.mkv [--set section.key=value ...] [--fps 30]
 *                    [--width 640 --height 480] [--fast] [--noise SIGMA] [--blur SIGMA_PX]
 *                    [--camera-distance-m D] [--post-snap S] [--csv TRUTH.csv]
 *                    [--save-calib FILE] [--shear-csv FILE] [--quiet]
 *
 * Runs rod_predict on the scene (route to the upper state, then shear until the snap plus
 * --post-snap seconds) and films it: frame k shows the state at simulated shear time k / fps,
 * interpolated linearly between the two accepted steps around it (twin_frames.h); frame 0 holds
 * the state after the first step (one dt after the shear starts: rod_predict reports steps, not
 * its starting state). The camera is fixed for the whole trial and frames the box the ribbon can
 * occupy (twin_camera.h); shapes are in the rig's frame (left clamp on y = 0, twin_shape.h), so
 * `ribbonctl track OUT.mkv --calib FILE --shear-csv SHEAR.csv` measures the video as a rig video.
 * Outputs: OUT.mkv (FFV1), the ground truth CSV (default OUT.csv beside it; vis_synth_writer's
 * columns), optionally the calibration and the per-frame shear rail position (frame,shear_mm).
 * stderr: a progress line. stdout: one JSON line: video, truth_csv, frames, fps, width, height,
 * snapped, snap_dw (predicted onset, null without a snap), regime, snap_frame (first frame after
 * the jump in the ground truth's projected Delta Z, by the same rule as `ribbonctl track`'s
 * snap_frame, or null), snap_detect_frame (first frame at or after the simulator's snap
 * detection, or null), sim_time_s, render_ms_per_frame, wall_s.
 * Exit status: 0 done, 1 the scene, the simulation or an output failed (reason on stderr), 2 usage.
 * Outputs are opened before the simulation runs (an unwritable path fails at once); after a later
 * failure the frames written so far stay in the video and the CSV, row k still describing frame k. */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ctl.h"
#include "cfg_number.h"
#include "rod_protocol.h"
#include "scene_file.h"
#include "twin.h"
#include "vision.h"

#define RENDER_MAX_SETS 64
#define RENDER_MAX_FRAMES 1000000 /* about 9 h of simulated time at 30 fps */

typedef struct render_cli {
    const char *scene, *out, *csv, *calib_out, *shear_csv;
    const char *sets[RENDER_MAX_SETS];
    int nsets;
    double fps, noise, blur, distance_m, post_snap;
    int width, height, fast, quiet;
} render_cli;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ribbonctl render --scene F --out OUT.mkv [options]\n"
            "  Simulates the scene's trial (rod_predict: upper state, shear until the snap) and films\n"
            "  it with a fixed synthetic side camera: a lossless FFV1 video plus the ground truth CSV.\n"
            "  Frame k shows simulated shear time k / FPS (states interpolated between solver steps).\n"
            "options:\n"
            "  --set section.key=value  scene override (repeatable), as in ribbon-sim\n"
            "  --fps F                  frames per second of simulated time (30)\n"
            "  --width W --height H     image size, pixels (640 x 480)\n"
            "  --fast                   adaptive time stepping (README \"Fast mode\")\n"
            "  --noise SIGMA            Gaussian noise, grey levels (2)\n"
            "  --blur SIGMA_PX          optical blur, pixels (0.8)\n"
            "  --camera-distance-m D    camera to ribbon plane (default max(5 l, 50 w))\n"
            "  --post-snap S            simulated seconds filmed after the snap is detected (2)\n"
            "  --csv FILE               ground truth CSV (default: OUT with .csv for .mkv)\n"
            "  --save-calib FILE        the matching calibration, for ribbonctl track --calib\n"
            "  --shear-csv FILE         shear rail position per frame (frame,shear_mm), for\n"
            "                           ribbonctl track --shear-csv\n"
            "  --quiet                  no progress line\n"
            "stdout: one JSON line: video, truth_csv, frames, fps, snapped, snap_dw, regime,\n"
            "  snap_frame (jump in the ground truth's Delta Z), snap_detect_frame, sim_time_s,\n"
            "  render_ms_per_frame, wall_s. Exit status: 0 done, 1 failed, 2 usage.\n");
}

static int parse_num(const char *opt, const char *v, double lo, double hi, double *out)
{
    char *end = NULL;
    const double x = v ? cfg_number_strtod(v, &end) : NAN;
    if (!v || end == v || *end || !isfinite(x) || x < lo || x > hi) {
        fprintf(stderr, "ribbonctl render: %s needs a number in [%g, %g], got '%s'\n", opt, lo, hi,
                v ? v : "");
        return -1;
    }
    *out = x;
    return 0;
}

static int parse_int(const char *opt, const char *v, int lo, int hi, int *out)
{
    char *end = NULL;
    const long x = v ? strtol(v, &end, 10) : 0;
    if (!v || end == v || *end || x < lo || x > hi) {
        fprintf(stderr, "ribbonctl render: %s needs an integer in [%d, %d], got '%s'\n", opt, lo, hi,
                v ? v : "");
        return -1;
    }
    *out = (int)x;
    return 0;
}

/* 0 go on, 1 --help printed, -1 usage error (printed). */
static int parse_args(int argc, char **argv, render_cli *c)
{
    memset(c, 0, sizeof *c);
    c->fps = 30.0;
    c->width = 640;
    c->height = 480;
    c->noise = c->blur = c->distance_m = NAN;
    c->post_snap = 2.0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        int used = 1;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 1;
        } else if (!strcmp(a, "--fast")) {
            c->fast = 1;
            used = 0;
        } else if (!strcmp(a, "--quiet")) {
            c->quiet = 1;
            used = 0;
        } else if (!strcmp(a, "--scene")) {
            c->scene = v;
        } else if (!strcmp(a, "--out")) {
            c->out = v;
        } else if (!strcmp(a, "--csv")) {
            c->csv = v;
        } else if (!strcmp(a, "--save-calib")) {
            c->calib_out = v;
        } else if (!strcmp(a, "--shear-csv")) {
            c->shear_csv = v;
        } else if (!strcmp(a, "--set")) {
            if (v && c->nsets >= RENDER_MAX_SETS) {
                fprintf(stderr, "ribbonctl render: more than %d --set overrides\n", RENDER_MAX_SETS);
                return -1;
            }
            if (v) c->sets[c->nsets++] = v;
        } else if (!strcmp(a, "--fps")) {
            if (parse_num(a, v, 0.1, 10000.0, &c->fps)) return -1;
        } else if (!strcmp(a, "--width")) {
            if (parse_int(a, v, 32, 8192, &c->width)) return -1;
        } else if (!strcmp(a, "--height")) {
            if (parse_int(a, v, 32, 8192, &c->height)) return -1;
        } else if (!strcmp(a, "--noise")) {
            if (parse_num(a, v, 0.0, 100.0, &c->noise)) return -1;
        } else if (!strcmp(a, "--blur")) {
            if (parse_num(a, v, 0.0, 50.0, &c->blur)) return -1;
        } else if (!strcmp(a, "--camera-distance-m")) {
            if (parse_num(a, v, 1e-3, 1e4, &c->distance_m)) return -1;
        } else if (!strcmp(a, "--post-snap")) {
            if (parse_num(a, v, 0.0, 1e4, &c->post_snap)) return -1;
        } else if (a[0] == '-') {
            fprintf(stderr, "ribbonctl render: unknown option '%s'\n", a);
            return -1;
        } else {
            fprintf(stderr, "ribbonctl render: unexpected argument '%s'\n", a);
            return -1;
        }
        if (used) {
            if (!v) {
                fprintf(stderr, "ribbonctl render: %s needs a value\n", a);
                return -1;
            }
            i++;
        }
    }
    if (!c->scene || !c->out) {
        fprintf(stderr, "ribbonctl render: --scene FILE and --out OUT.mkv are required\n");
        return -1;
    }
    const size_t len = strlen(c->out);
    if (len < 5 || strcmp(c->out + len - 4, ".mkv") != 0) {
        fprintf(stderr, "ribbonctl render: --out must name a .mkv file (lossless FFV1 in Matroska), got '%s'\n",
                c->out);
        return -1;
    }
    return 0;
}

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Everything the two callbacks share: the simulator's (one per accepted step) and the frame
 * clock's (one per frame). Arrays are sized once before the run. */
typedef struct render_run {
    twin_frames clock;
    vis_synth_writer *writer;
    FILE *shear;               /* --shear-csv, or NULL */
    const char *shear_path;
    double *dz_cam;            /* ground truth's projected Delta Z per frame */
    unsigned char *valid;      /* all 1: every rendered frame has its truth */
    int cap;                   /* frames the arrays hold */
    double render_s;           /* wall time inside vis_synth_writer_add */
    double snap_speed;         /* 1/s, the scene's snap.speed */
    int detected, have_sample;
    double t_detect, t_prev, dz_prev, dw_last, dz_last;
    int show;
    char failure[700];
} render_run;

static void progress(const render_run *rr, int final)
{
    fprintf(stderr, "\rrender: frame %d, shear time %.2f s, Delta W %.4f, Delta Z %+.4f%s",
            twin_frames_count(&rr->clock), rr->t_prev, rr->dw_last, rr->dz_last, final ? "\n" : "  ");
    fflush(stderr);
}

static int on_frame(void *user, int index, double t_s, const vis_shape *shape)
{
    (void)t_s;
    render_run *rr = user;
    if (index >= rr->cap) {
        snprintf(rr->failure, sizeof rr->failure, "frame %d is beyond the %d frames the run can last", index,
                 rr->cap);
        return 1;
    }
    vis_render_truth truth;
    vis_error ve;
    const double t0 = wall_now();
    if (vis_synth_writer_add(rr->writer, shape, &truth, &ve) != VIS_OK) {
        snprintf(rr->failure, sizeof rr->failure, "frame %d: %s", index, ve.message);
        return 1;
    }
    rr->render_s += wall_now() - t0;
    rr->dz_cam[index] = truth.truth.dz_cam;
    rr->valid[index] = 1;
    if (rr->shear && fprintf(rr->shear, "%d,%.9g\n", index, truth.truth.shear_m * 1000.0) < 0) {
        snprintf(rr->failure, sizeof rr->failure, "cannot write %s", rr->shear_path);
        return 1;
    }
    return 0;
}

static int on_sample(void *user, const rod_sample *s, const rod *r)
{
    render_run *rr = user;
    /* The simulator's snap detection (rod_protocol.h): the first step faster than snap.speed. */
    if (rr->have_sample && !rr->detected && s->t > rr->t_prev &&
        fabs(s->dz - rr->dz_prev) / (s->t - rr->t_prev) > rr->snap_speed) {
        rr->detected = 1;
        rr->t_detect = s->t;
    }
    rr->have_sample = 1;
    rr->t_prev = s->t;
    rr->dz_prev = s->dz;
    rr->dw_last = s->dw;
    rr->dz_last = s->dz;
    char err[300];
    const int before = twin_frames_count(&rr->clock);
    const twin_status st = twin_frames_push(&rr->clock, s->t, r, err, sizeof err);
    if (st == TWIN_STOPPED) return 1; /* on_frame wrote the reason */
    if (st != TWIN_OK) {
        snprintf(rr->failure, sizeof rr->failure, "at shear time %.4f s: %s", s->t, err);
        return 1;
    }
    if (rr->show && twin_frames_count(&rr->clock) / 10 != before / 10) progress(rr, 0);
    return 0;
}

/* OUT.mkv -> OUT.csv */
static void default_csv(const char *out, char *buf, size_t len)
{
    snprintf(buf, len, "%.*s.csv", (int)(strlen(out) - 4), out);
}

/* The scene, the truth CSV's name, and the frame cap the run can need. 0, or the exit status
 * after saying why. */
static int render_scene(const render_cli *c, rod_scene *sc, char *csv_buf, size_t csv_len,
                        const char **csv, double *cap_d)
{
    cfg_error ce;
    if (cfg_scene_load(c->scene, c->sets, c->nsets, sc, &ce) != CFG_OK) {
        char buf[1200];
        fprintf(stderr, "ribbonctl render: %s\n", cfg_error_format(&ce, buf, sizeof buf));
        return 1;
    }
    *csv = c->csv;
    if (!*csv) {
        if (strlen(c->out) >= csv_len - 1) {
            fprintf(stderr, "ribbonctl render: output name too long\n");
            return 2;
        }
        default_csv(c->out, csv_buf, csv_len);
        *csv = csv_buf;
    }

    /* Frames the run can last: the shear phase (at most shear_max l / rate), the post-snap time,
     * and one longest fast-mode step (100 dt) of overshoot. */
    const double t_max = sc->shear_max * sc->length / sc->shear_rate + c->post_snap + 100.0 * sc->dt;
    *cap_d = ceil(t_max * c->fps) + 2.0;
    if (!(*cap_d <= RENDER_MAX_FRAMES)) {
        fprintf(stderr,
                "ribbonctl render: the trial lasts up to %.0f s of simulated time, %.0f frames at %g fps "
                "(limit %d): lower --fps, raise protocol.shear_rate or lower protocol.shear_max\n",
                t_max, *cap_d, c->fps, RENDER_MAX_FRAMES);
        return 1;
    }
    return 0;
}

/* The twin camera for the scene (size, distance, noise, blur from the options) and the
 * calibration it implies. 0, or 1 after saying why. */
static int render_camera(const render_cli *c, const rod_scene *sc, vis_render_params *rp, vis_calib *cal)
{
    twin_camera_params cp = twin_camera_params_default();
    cp.width_px = c->width;
    cp.height_px = c->height;
    if (isfinite(c->distance_m)) cp.distance_m = c->distance_m;
    char err[512];
    if (twin_render_params_for_scene(sc, &cp, rp, err, sizeof err) != TWIN_OK ||
        twin_calib_for_scene(sc, &rp->camera, cal, err, sizeof err) != TWIN_OK) {
        fprintf(stderr, "ribbonctl render: %s\n", err);
        return 1;
    }
    if (isfinite(c->noise)) rp->noise_sigma = c->noise;
    if (isfinite(c->blur)) rp->blur_sigma_px = c->blur;
    return 0;
}

/* The series, the frame clock and every output, opened before the simulation runs so that an
 * unwritable path fails at once. 0, or 1 with rr->failure set; *clock_ok once the clock is up. */
static int render_open(const render_cli *c, const rod_scene *sc, const char *csv,
                       const vis_render_params *rp, const vis_calib *cal, render_run *rr, int *clock_ok)
{
    char err[512];
    vis_error ve;
    rr->dz_cam = malloc(sizeof *rr->dz_cam * (size_t)rr->cap);
    rr->valid = calloc((size_t)rr->cap, 1);
    if (!rr->dz_cam || !rr->valid) {
        snprintf(rr->failure, sizeof rr->failure, "out of memory for %d frames", rr->cap);
        return 1;
    }
    if (twin_frames_init(&rr->clock, sc, TWIN_Y_RIG, c->fps, on_frame, rr, err, sizeof err) != TWIN_OK) {
        snprintf(rr->failure, sizeof rr->failure, "%s", err);
        return 1;
    }
    *clock_ok = 1;
    rr->writer = vis_synth_writer_open(c->out, csv, rp, c->fps, &ve);
    if (!rr->writer) {
        snprintf(rr->failure, sizeof rr->failure, "%s", ve.message);
        return 1;
    }
    if (c->shear_csv) {
        rr->shear = fopen(c->shear_csv, "w");
        if (!rr->shear || fprintf(rr->shear, "frame,shear_mm\n") < 0) {
            snprintf(rr->failure, sizeof rr->failure, "cannot write %s", c->shear_csv);
            return 1;
        }
    }
    if (c->calib_out && vis_calib_save(cal, c->calib_out, &ve) != VIS_OK) {
        snprintf(rr->failure, sizeof rr->failure, "%s", ve.message);
        return 1;
    }
    return 0;
}

/* The simulated trial, every sample rendered as it comes (on_sample). 0, or 1 with rr->failure. */
static int render_simulate(const render_cli *c, const rod_scene *sc, render_run *rr, rod_prediction *pred)
{
    rod_predict_opts po = rod_predict_opts_default();
    po.adaptive = c->fast;
    po.post_snap_time = c->post_snap;
    po.on_sample = on_sample;
    po.user = rr;
    char serr[512] = "";
    const rod_status st = rod_predict(sc, &po, pred, serr, sizeof serr);
    if (rr->show) progress(rr, 1);
    if (rr->failure[0])
        return 1;
    if (st != ROD_OK) {
        snprintf(rr->failure, sizeof rr->failure, "simulation: %s", serr[0] ? serr : rod_status_message(st));
        return 1;
    }
    if (twin_frames_count(&rr->clock) == 0) {
        snprintf(rr->failure, sizeof rr->failure, "the simulation produced no frame (shear time %.3g s)",
                 pred->sim_time);
        return 1;
    }
    return 0;
}

/* The summary line (JSON) of a successful render. */
static void render_print(const render_cli *c, const char *csv, const render_run *rr,
                         const rod_prediction *pred, int frames, double wall0)
{
    const int snap = vis_snap_find(rr->dz_cam, rr->valid, (size_t)frames, 0.02, 0.3);
    const int detect = rr->detected ? (int)ceil(rr->t_detect * c->fps - 1e-9) : -1;
    const char *regime = !pred->snapped ? "none" : pred->asymmetric ? "asymmetric" : "symmetric";
    json_t *o = json_object();
    json_object_set_new(o, "video", json_string(c->out));
    json_object_set_new(o, "truth_csv", json_string(csv));
    json_object_set_new(o, "frames", json_integer(frames));
    json_object_set_new(o, "fps", json_real(c->fps));
    json_object_set_new(o, "width", json_integer(c->width));
    json_object_set_new(o, "height", json_integer(c->height));
    json_object_set_new(o, "snapped", json_boolean(pred->snapped));
    json_object_set_new(o, "snap_dw", pred->snapped ? json_real(pred->snap_dw) : json_null());
    json_object_set_new(o, "regime", json_string(regime));
    json_object_set_new(o, "snap_frame", snap >= 0 ? json_integer(snap) : json_null());
    json_object_set_new(o, "snap_detect_frame",
                        detect >= 0 && detect < frames ? json_integer(detect) : json_null());
    json_object_set_new(o, "sim_time_s", json_real(pred->sim_time));
    json_object_set_new(o, "render_ms_per_frame", json_real(frames ? 1e3 * rr->render_s / frames : 0.0));
    json_object_set_new(o, "wall_s", json_real(wall_now() - wall0));
    char *s = json_dumps(o, JSON_COMPACT | JSON_REAL_PRECISION(10));
    printf("%s\n", s ? s : "{}");
    free(s);
    json_decref(o);
}

int ctl_render_main(int argc, char **argv)
{
    render_cli c;
    const int pa = parse_args(argc, argv, &c);
    if (pa > 0) return 0;
    if (pa < 0) {
        usage(stderr);
        return 2;
    }
    const double wall0 = wall_now();
    rod_scene sc;
    char csv_buf[4096];
    const char *csv = NULL;
    double cap_d = 0.0;
    int rc = render_scene(&c, &sc, csv_buf, sizeof csv_buf, &csv, &cap_d);
    if (rc) return rc;
    vis_render_params rp;
    vis_calib cal;
    if (render_camera(&c, &sc, &rp, &cal)) return 1;

    render_run rr;
    memset(&rr, 0, sizeof rr);
    rr.cap = (int)cap_d;
    rr.snap_speed = sc.snap_speed;
    rr.show = !c.quiet;
    rr.shear_path = c.shear_csv;
    int clock_ok = 0;
    vis_error ve;
    rod_prediction pred;
    memset(&pred, 0, sizeof pred);
    rc = render_open(&c, &sc, csv, &rp, &cal, &rr, &clock_ok) || render_simulate(&c, &sc, &rr, &pred);

    const int frames = clock_ok ? twin_frames_count(&rr.clock) : 0;
    if (rr.writer && vis_synth_writer_close(rr.writer, &ve) != VIS_OK && !rc) {
        snprintf(rr.failure, sizeof rr.failure, "%s", ve.message);
        rc = 1;
    }
    if (rr.shear && fclose(rr.shear) != 0 && !rc) {
        snprintf(rr.failure, sizeof rr.failure, "cannot write %s", c.shear_csv);
        rc = 1;
    }
    if (clock_ok) twin_frames_release(&rr.clock);
    if (rr.failure[0]) fprintf(stderr, "ribbonctl render: %s\n", rr.failure);
    if (!rc) render_print(&c, csv, &rr, &pred, frames, wall0);
    free(rr.dz_cam);
    free(rr.valid);
    return rc;
}
