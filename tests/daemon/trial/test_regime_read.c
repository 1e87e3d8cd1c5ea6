/* test_regime_read: the regime a trial reads from its camera frames against the twin's own
 * (issue 35 D). A twin like the camera campaign's (the mock scene, creases relaxed by 6 deg,
 * compliant hinges 5e-3 N m/rad, creases 1% apart) is simulated (rod_predict, fast mode, followed
 * 2 s after the snap), filmed through mock mode's twin camera (640 x 480, 1 m, noise 2, blur 0.8:
 * config/mock.ini's) at the camera's frame rate, every frame tracked by the trial's tracker
 * (vis_track_params_for_ribbon) and fed to the trial's snap detector with mock.ini's detection;
 * the truth is the twin's own snap (rod_snap_watch on every simulator step: the paper's 3D A over
 * the first swing).
 *
 * The ctest: three twins at N = 31 (docs/trials.md "The measured regime"): an asymmetric passage
 * between 30 fps frames read asymmetric, a symmetric twin read symmetric, a symmetric twin near the
 * threshold at 60 fps read unknown (the peak rule read the first symmetric and the last
 * asymmetric).
 *
 * Measuring modes (not ctests):
 *   probe PHI GAMMA FPS [REL [PHASE_S [N]]]  every frame from Delta W 0.3 (time, Delta W, the
 *       truth's projected Delta Z, 3D A and A_cam at the frame's instant, the tracked Delta Z and A)
 *       and a summary line; REGIME_READ_PNG=DW saves the frame at that Delta W;
 *   table PHI:GAMMA ...  each twin (N = 61, creases REGIME_READ_REL apart, 0.01) filmed at 120 fps
 *       and read at 30 fps (4 phases) and 60 fps (2); REGIME_READ_DUMP=DIR keeps its frames;
 *       REGIME_READ_SETS="K=V ..." sets more scene keys (up to 4, e.g. protocol.compression=0.4);
 *   reread FILE ...  those frames read again, before (the peak rule) and after (the departure);
 *       REGIME_READ_STRIDE=1: the frames as they are, once (a trial's stored frames). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rod_protocol.h"
#include "rod_regime.h"
#include "rod_snap_watch.h"
#include "scene_file.h"
#include "trial.h"
#include "twin.h"
#include "vision.h"

#define SCENE RIBBON_SOURCE_DIR "/config/scenes/mock-gamma013.ini"
#define DW_FROM 0.30

/* One filmed frame: the truth at its instant and what the tracker measured. */
typedef struct frame_rec {
    long index;
    double t, dw;       /* s since the shear started; Delta W */
    double dz_cam, a3, a_cam; /* the twin's projected Delta Z, 3D A and projected A at t */
    double dz, a;       /* measured (valid only) */
    int valid;
} frame_rec;

#define MAX_FRAMES 4096

typedef struct film {
    frame_rec rec[MAX_FRAMES];
    long n;
    rod_scene sc;
    double fps, phase;
    vis_renderer *r;
    vis_frame *f;
    vis_tracker *t;
    twin_frames clock;
    rod_sample prev, cur; /* the simulator steps around the frames being handed out */
    int have_prev;
    rod_snap_watch truth;
    snap_detect det;
    int print;
    int failed;
    long frames, measured;
} film;

/* The trial's detection settings for the twin's scene, with config/mock.ini's [detect]. */
static snap_params mock_detect(const rod_scene *sc)
{
    snap_params sp = snap_params_default();
    sp.snap_speed = sc->snap_speed;
    sp.asym_threshold = sc->asym_threshold;
    sp.dz_jump = 0.02; /* config/mock.ini [detect] */
    return sp;
}

static int on_frame(void *user, int index, double t_s, const vis_shape *shape)
{
    film *u = user;
    double ts = t_s - u->phase; /* the simulator's time of this frame */
    double dw = ts * u->sc.shear_rate / u->sc.length;
    if (dw < DW_FROM || ts < 0) return 0;
    double w = u->have_prev && u->cur.t > u->prev.t ? (ts - u->prev.t) / (u->cur.t - u->prev.t) : 1.0;
    double a3 = u->have_prev ? u->prev.a + w * (u->cur.a - u->prev.a) : u->cur.a;
    vis_render_truth truth;
    vis_error err = {0};
    if (vis_renderer_draw(u->r, shape, u->f, &truth, &err) != VIS_OK) {
        print_error("frame %d: %s\n", index, err.message);
        u->failed = 1;
        return 1;
    }
    vis_measure m;
    if (vis_tracker_process(u->t, u->f, truth.truth.shear_m * 1000.0, &m, &err) != VIS_OK) {
        print_error("frame %d: %s\n", index, err.message);
        u->failed = 1;
        return 1;
    }
    u->frames++;
    int valid = m.reason == VIS_REASON_NONE && m.quality >= 0.3;
    if (u->n < MAX_FRAMES)
        u->rec[u->n++] = (frame_rec){index, ts, dw, truth.truth.dz_cam, a3, truth.truth.a_cam, valid ? m.dz : NAN,
                                     valid ? m.a : NAN, valid};
    u->measured += valid;
    snap_phase before = u->det.phase;
    snap_phase ph = snap_detect_add(&u->det, index, ts, dw, m.dz, m.a, valid);
    if (u->print)
        printf("%d,%.5f,%.5f,%.5f,%.4f,%.4f,%s,%s,%d,%s\n", index, ts, dw, truth.truth.dz_cam, a3, truth.truth.a_cam,
               valid ? "" : "-", valid ? "" : vis_reason_str(m.reason), valid, "");
    if (u->print && getenv("REGIME_READ_PNG") && fabs(dw - atof(getenv("REGIME_READ_PNG"))) < 0.5 / u->fps * 0.05) {
        char path[128];
        snprintf(path, sizeof path, "/tmp/rr/frame-%d.png", index);
        vis_frame_save(u->f, path, &err);
    }
    if (u->print && valid) printf("#   measured dz %.5f a %.4f phase %d->%d\n", m.dz, m.a, before, ph);
    return 0;
}

static int on_sample(void *user, const rod_sample *s, const rod *r)
{
    film *u = user;
    u->cur = *s;
    rod_obs o = {.dz = s->dz, .a = s->a, .a_cam = s->a_cam, .dz_cam = s->dz_cam};
    rod_snap_watch_add(&u->truth, s->t, s->dw, &o);
    char err[300];
    twin_status st = twin_frames_push(&u->clock, s->t + u->phase, r, err, sizeof err);
    u->prev = *s;
    u->have_prev = 1;
    if (st == TWIN_STOPPED) return 1;
    if (st != TWIN_OK) {
        print_error("shear time %.4f s: %s\n", s->t, err);
        u->failed = 1;
        return 1;
    }
    return 0;
}

/* The bench's twin at (phi, gamma), creases rel apart, filmed at fps with the frames shifted by phase
 * seconds; N nodes. */
static void film_run(film *u, double phi, double gamma, double rel, double fps, double phase, int nodes)
{
    char a[64], g[64], r[64], n[64];
    snprintf(a, sizeof a, "folds.angle_deg=%.9g", -(phi - 6.0));
    snprintf(g, sizeof g, "folds.position=%.9g", gamma);
    snprintf(r, sizeof r, "imperfection.fold_angle_rel=%.9g", rel);
    snprintf(n, sizeof n, "mesh.nodes=%d", nodes);
    const char *sets[10] = {a, g, r, n, "folds.hinge_stiffness=5e-3", "solver.dt=2e-3"};
    int nsets = 6;
    /* REGIME_READ_SETS="K=V K=V": more scene keys for the measuring modes (e.g. the camera
       campaign's mount, protocol.compression=0.4) */
    char extra[256] = "";
    if (getenv("REGIME_READ_SETS")) snprintf(extra, sizeof extra, "%s", getenv("REGIME_READ_SETS"));
    for (char *save = NULL, *tok = strtok_r(extra, " ", &save); tok && nsets < 10; tok = strtok_r(NULL, " ", &save))
        sets[nsets++] = tok;
    cfg_error ce;
    char buf[1200];
    if (cfg_scene_load(SCENE, sets, (size_t)nsets, &u->sc, &ce) != CFG_OK)
        fail_msg("%s", cfg_error_format(&ce, buf, sizeof buf));
    u->fps = fps;
    u->phase = phase;
    twin_camera_params cp = twin_camera_params_default();
    vis_render_params rp;
    vis_calib cal;
    char err[512];
    assert_int_equal(twin_render_params_for_scene(&u->sc, &cp, &rp, err, sizeof err), TWIN_OK);
    assert_int_equal(twin_calib_for_scene(&u->sc, &rp.camera, &cal, err, sizeof err), TWIN_OK);
    rp.noise_sigma = 2.0;
    rp.blur_sigma_px = 0.8;
    vis_error ve = {0};
    vis_track_params tp = vis_track_params_for_ribbon(u->sc.width * 1000.0, cal.px_per_mm);
    tp.length_mm = u->sc.length * 1000.0;
    u->t = vis_tracker_create(&tp, &cal, &ve);
    assert_non_null(u->t);
    u->r = vis_renderer_create(&rp, &ve);
    assert_non_null(u->r);
    u->f = vis_frame_alloc(rp.camera.width_px, rp.camera.height_px, 1, &ve);
    assert_non_null(u->f);
    rod_snap_watch_init(&u->truth, u->sc.snap_speed, u->sc.asym_threshold, 2.0);
    snap_params sp = mock_detect(&u->sc);
    snap_detect_init(&u->det, &sp);
    assert_int_equal(twin_frames_init(&u->clock, &u->sc, TWIN_Y_RIG, fps, on_frame, u, err, sizeof err), TWIN_OK);
    rod_predict_opts po = rod_predict_opts_default();
    po.adaptive = 1;
    po.post_snap_time = 2.0;
    po.on_sample = on_sample;
    po.user = u;
    rod_prediction pred;
    memset(&pred, 0, sizeof pred);
    rod_status rs = rod_predict(&u->sc, &po, &pred, err, sizeof err);
    twin_frames_release(&u->clock);
    vis_tracker_free(u->t);
    vis_renderer_free(u->r);
    vis_frame_free(u->f);
    if (rs != ROD_OK && !u->failed) fail_msg("rod_predict: %s", err);
    assert_false(u->failed);
}

static void film_summary(const film *u, double phi, double gamma, double rel)
{
    const rod_snap_report *t = &u->truth.r;
    printf("phi %g Gamma %.4f rel %g fps %g phase %.4f: truth %s at %.5f (3D peak |A| %.3f first swing, %.3f over "
           "2 s, A_cam %.3f over 2 s); measured %s at %.5f (peak |A_cam| %.3f), frames %ld measured %ld\n",
           phi, gamma, rel, u->fps, u->phase, rod_snap_report_regime(t), t->snap_dw, t->peak_abs_a, t->peak_abs_a_post,
           t->peak_abs_a_cam, snap_detect_regime(&u->det), snap_detect_dw(&u->det), u->det.peak_abs_a, u->frames,
           u->measured);
}

/* The trial's detector over the frames taken every stride-th from offset (a camera at fps / stride
 * with another frame phase), with mock.ini's detection. */
static snap_detect read_frames(const film *u, int stride, int offset)
{
    snap_params sp = mock_detect(&u->sc);
    snap_detect d;
    snap_detect_init(&d, &sp);
    for (long k = offset; k < u->n; k += stride) {
        const frame_rec *f = &u->rec[k];
        if (snap_detect_add(&d, f->index / stride, f->t, f->dw, f->dz, f->a, f->valid) == SNAP_DONE) break;
    }
    return d;
}

static film *film_new(void)
{
    film *u = calloc(1, sizeof *u);
    assert_non_null(u);
    return u;
}

/* table PHI:GAMMA ...: each twin filmed at 120 fps, read at 30 fps (4 phases) and 60 fps (2). */
static int table(int argc, char **argv)
{
    printf("phi,gamma,truth,peak_a3,peak_a3_2s,peak_acam_2s,fps,phase,read,read_peak,read_dw,truth_dw\n");
    for (int i = 2; i < argc; i++) {
        double phi, gamma;
        if (sscanf(argv[i], "%lf:%lf", &phi, &gamma) != 2) return 2;
        film *u = film_new();
        double rel = getenv("REGIME_READ_REL") ? atof(getenv("REGIME_READ_REL")) : 0.01;
        film_run(u, phi, gamma, rel, 120.0, 0.0, 61);
        const rod_snap_report *t = &u->truth.r;
        if (getenv("REGIME_READ_DUMP")) {
            char path[256];
            snprintf(path, sizeof path, "%s/frames-%g-%.4f-%g.csv", getenv("REGIME_READ_DUMP"), phi, gamma, rel);
            FILE *fp = fopen(path, "w");
            if (fp) {
                fprintf(fp, "# truth %s %.5f %.4f %.4f %.4f\n", rod_snap_report_regime(t), t->snap_dw, t->peak_abs_a,
                        t->peak_abs_a_post, t->peak_abs_a_cam);
                for (long k = 0; k < u->n; k++) {
                    const frame_rec *f = &u->rec[k];
                    fprintf(fp, "%ld,%.6f,%.6f,%.5f,%.5f,%.5f,%.5f,%.5f,%d\n", f->index, f->t, f->dw, f->dz_cam, f->a3,
                            f->a_cam, f->dz, f->a, f->valid);
                }
                fclose(fp);
            }
        }
        for (int s = 4; s >= 2; s /= 2)
            for (int o = 0; o < s; o++) {
                snap_detect d = read_frames(u, s, o);
                printf("%g,%.4f,%s,%.3f,%.3f,%.3f,%g,%d,%s,%.3f,%.5f,%.5f\n", phi, gamma, rod_snap_report_regime(t),
                       t->peak_abs_a, t->peak_abs_a_post, t->peak_abs_a_cam, 120.0 / s, o, snap_detect_regime(&d),
                       d.peak_abs_a, snap_detect_dw(&d), t->snap_dw);
            }
        fflush(stdout);
        free(u);
    }
    return 0;
}

/* The regime before issue 35 D: the peak |A| from the onset until the snap settled. */
static const char *read_before(const snap_detect *d)
{
    if (!snap_detect_snapped(d)) return "no snap";
    return rod_regime_asymmetric(d->peak_abs_a, d->p.asym_threshold) ? "asymmetric" : "symmetric";
}

/* reread FILE...: the frames a table run dumped (REGIME_READ_DUMP), read at 30 fps (4 phases) and
 * 60 fps (2) before and after; one line per reading. */
static int reread(int argc, char **argv)
{
    printf("file,truth,peak_a3,fps,phase,before,after,departure,departure_dz,swing_dz,peak_swing,peak_settle\n");
    for (int i = 2; i < argc; i++) {
        FILE *fp = fopen(argv[i], "r");
        if (!fp) return 2;
        film *u = film_new();
        u->sc = rod_scene_default();
        u->sc.snap_speed = 1.0;
        u->sc.asym_threshold = 0.5;
        char line[512], treg[32] = "";
        double tdw, p3, p3p, pc;
        if (!fgets(line, sizeof line, fp) || sscanf(line, "# truth %31s %lf %lf %lf %lf", treg, &tdw, &p3, &p3p, &pc) != 5)
            return 2;
        while (fgets(line, sizeof line, fp) && u->n < MAX_FRAMES) {
            frame_rec *f = &u->rec[u->n];
            if (sscanf(line, "%ld,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%d", &f->index, &f->t, &f->dw, &f->dz_cam, &f->a3,
                       &f->a_cam, &f->dz, &f->a, &f->valid) == 9)
                u->n++;
        }
        fclose(fp);
        int s_min = getenv("REGIME_READ_STRIDE") ? atoi(getenv("REGIME_READ_STRIDE")) : 2;
        for (int s = s_min > 1 ? 4 : 1; s >= s_min && s >= 1; s /= 2)
            for (int o = 0; o < s; o++) {
                snap_detect d = read_frames(u, s, o);
                snap_reading r;
                snap_detect_read(&d, &r);
                if (getenv("REGIME_READ_PASSAGE")) /* the passage's kept frames: Delta Z travel, A - A_onset */
                    for (int k = 0; k < d.pass_n; k++)
                        fprintf(stderr, "%s %d/%d %d %.4f %+.4f %.5f\n", argv[i], s, o, 1,
                                fabs(d.pass_dz[k] - d.pass_dz[0]), d.pass_a[k] - d.pass_a[0], d.pass_far);
                printf("%s,%s,%.3f,%g,%d,%s,%s,%.2f,%.4f,%.4f,%.3f,%.3f\n", argv[i], treg, p3, 120.0 / s, o,
                       read_before(&d), snap_detect_regime(&d), r.departure, r.departure_dz, r.swing_dz, r.peak_swing,
                       d.peak_abs_a);
            }
        free(u);
    }
    return 0;
}

static int probe(int argc, char **argv)
{
    if (argc < 5) {
        fprintf(stderr, "usage: test_regime_read probe PHI GAMMA FPS [REL [PHASE_S [N]]]\n");
        return 2;
    }
    film *up = film_new();
    up->print = 1;
    double phi = atof(argv[2]), gamma = atof(argv[3]), fps = atof(argv[4]);
    double rel = argc > 5 ? atof(argv[5]) : 0.01, phase = argc > 6 ? atof(argv[6]) : 0.0;
    int nodes = argc > 7 ? atoi(argv[7]) : 61;
    printf("frame,t,dw,dz_cam,a3,a_cam,reason,valid\n");
    film_run(up, phi, gamma, rel, fps, phase, nodes);
    film_summary(up, phi, gamma, rel);
    free(up);
    return 0;
}

/* The ctests' twin (N = 31, no frame phase) at (phi, gamma), creases rel apart, filmed at fps and
 * read by the trial's detector: the film (the caller frees it), its reading in r, and the truth
 * that it snapped (every ctest's twin does). */
static film *film_read(double phi, double gamma, double rel, double fps, snap_reading *r)
{
    film *u = film_new();
    film_run(u, phi, gamma, rel, fps, 0.0, 31);
    film_summary(u, phi, gamma, rel);
    snap_detect_read(&u->det, r);
    assert_true(u->truth.r.snapped);
    return u;
}

/* The phi 120 twin below its boundary at 30 fps (N = 31 to keep it short): the asymmetric
 * passage's sharpest frames fall between frames, so the frames' peak |A| stays under the threshold
 * (the peak rule read symmetric); the departure reads asymmetric. */
static void twin_passage_between_frames_read_asymmetric(void **state)
{
    (void)state;
    snap_reading r;
    film *u = film_read(120, 0.165, 0.01, 30.0, &r);
    const rod_snap_report *t = &u->truth.r;
    assert_true(t->snapped && t->asymmetric);
    assert_true(t->peak_abs_a > 2.0 * u->sc.asym_threshold); /* a clear truth */
    assert_true(snap_detect_snapped(&u->det));
    assert_false(rod_regime_asymmetric(r.peak_swing, u->sc.asym_threshold)); /* the passage unseen */
    assert_int_equal(r.by_departure, 1);
    assert_true(r.departure >= u->det.p.depart_asym);
    assert_string_equal(snap_detect_regime(&u->det), "asymmetric");
    free(u);
}

/* A symmetric twin at phi 90 at 30 fps reads symmetric by its departure. */
static void twin_symmetric_read_symmetric(void **state)
{
    (void)state;
    snap_reading r;
    film *u = film_read(90, 0.20, 0.01, 30.0, &r);
    const rod_snap_report *t = &u->truth.r;
    assert_true(t->snapped && !t->asymmetric);
    assert_true(t->peak_abs_a < 0.5 * u->sc.asym_threshold);
    assert_int_equal(r.by_departure, 1);
    assert_true(r.departure <= u->det.p.depart_sym);
    assert_string_equal(snap_detect_regime(&u->det), "symmetric");
    free(u);
}

/* A symmetric twin near the threshold (creases 2% apart: 3D peak 0.33) at 60 fps: a passage frame's
 * projected |A| is 0.71, which the peak rule read asymmetric; its departure lies between the two
 * thresholds, so the frames cannot tell: unknown, not a wrong regime. */
static void twin_near_threshold_read_unknown(void **state)
{
    (void)state;
    snap_reading r;
    film *u = film_read(90, 0.19, 0.02, 60.0, &r);
    const rod_snap_report *t = &u->truth.r;
    assert_true(t->snapped && !t->asymmetric);
    assert_true(rod_regime_asymmetric(r.peak_swing, u->sc.asym_threshold)); /* the peak rule: asymmetric */
    assert_int_equal(r.by_departure, 1);
    assert_true(r.departure > u->det.p.depart_sym && r.departure < u->det.p.depart_asym);
    assert_string_equal(snap_detect_regime(&u->det), "unknown");
    free(u);
}

int main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "probe")) return probe(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "table")) return table(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "reread")) return reread(argc, argv);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(twin_passage_between_frames_read_asymmetric),
        cmocka_unit_test(twin_symmetric_read_symmetric),
        cmocka_unit_test(twin_near_threshold_read_unknown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
