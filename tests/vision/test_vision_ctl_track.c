/* test_vision_ctl_track.c: `ribbonctl track` end to end on a rendered video.
 *
 * Renders a snapping sequence (320 x 240) with ground truth, runs the real binary with a saved
 * calibration, and checks the --json summary (frames, tracked, mean_quality, snap_frame), the CSV
 * (one row per frame, no NaN) and the overlay video (readable, one frame per input frame). A
 * truncated copy of the video is tracked up to the damage (exit status 1, "damaged": true, the
 * frames before the damage in the CSV); usage errors exit with 2; an image sequence is tracked too;
 * --shear-csv drives the depth correction (Delta Z within 0.2 px with the clamp 30 mm deeper).
 * Without clamp points the clamps are found in the video: with --clamp-spacing-mm (scale from the
 * found points) and with --length-mm alone (scale from the first tracked frame) every frame is
 * tracked, the scale is within 0.5% of the camera's, the heights agree with the --calib run within
 * 0.2 px and --save-calib writes the calibration found; a video without clamp jaws reports every
 * frame as clamp_not_found and exits 1 with the reason. --depth-scene takes the depth from the
 * scene's predicted shapes: on a rendered DER trial filmed from 1 m, A within 0.02 rad RMS where the
 * default profile is off by more than half as much again. --threads 1, 2 and 0 write the same CSV
 * and overlay, byte for byte, with the calibration given and found.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <jansson.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "vis_test_run.h"
#include "vis_test_video.h"

#define NF 12
#define SNAP_AT 6

static char video[600], calib[600], csv[600], overlay[600];

static void gen(vt_shape *s, int i, void *ctx)
{
    (void)ctx;
    const double phi = i < SNAP_AT ? 0.04 * i : M_PI - 0.04 * (NF - i);
    vt_arch(s, 301, 0.2, 0.16, phi, 0.0);
}

static int setup(void **state)
{
    (void)state;
    static vt_shape s;
    vt_arch(&s, 301, 0.2, 0.16, 0.0, 0.0);
    vis_render_params p = vis_render_params_default();
    vis_camera_fit(&p.camera, -0.02, 0.18, -0.07, 0.07, 0.9, NULL);
    vis_calib c = vt_calib(&p, &s);
    snprintf(video, sizeof video, "%s/cli.mkv", vt_tmpdir());
    snprintf(csv, sizeof csv, "%s/cli_truth.csv", vt_tmpdir());
    vis_synth_writer *w = vis_synth_writer_open(video, csv, &p, 25.0, NULL);
    if (!w)
        return -1;
    for (int i = 0; i < NF; i++) {
        gen(&s, i, NULL);
        if (vis_synth_writer_add(w, &s.view, NULL, NULL) != VIS_OK)
            return -1;
    }
    if (vis_synth_writer_close(w, NULL) != VIS_OK)
        return -1;
    snprintf(calib, sizeof calib, "%s/cli_calib.txt", vt_tmpdir());
    snprintf(csv, sizeof csv, "%s/cli_out.csv", vt_tmpdir());
    snprintf(overlay, sizeof overlay, "%s/cli_overlay.mkv", vt_tmpdir());
    return vis_calib_save(&c, calib, NULL) == VIS_OK ? 0 : -1;
}

/* Run a command, capture stdout (up to `cap` bytes), return the exit status. */
static int run(const char *cmd, char *out, size_t cap)
{
    FILE *f = popen(cmd, "r");
    assert_non_null(f);
    size_t n = fread(out, 1, cap - 1, f);
    out[n] = '\0';
    const int st = pclose(f);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

static int count_lines(const char *path, int *has_nan)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char line[512];
    int n = 0;
    *has_nan = 0;
    while (fgets(line, sizeof line, f) && n < 100000) {
        n++;
        if (strstr(line, "nan") || strstr(line, "NaN") || strstr(line, "inf"))
            *has_nan = 1;
    }
    fclose(f);
    return n;
}

static void test_track_video_with_json_csv_overlay(void **state)
{
    (void)state;
    char cmd[3000], out[4096];
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --length-mm 200 --csv '%s' --overlay '%s' --json --quiet",
             RIBBONCTL_PATH, video, calib, csv, overlay);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    printf("%s", out);
    json_error_t je;
    json_t *o = json_loads(out, 0, &je);
    assert_non_null(o);
    assert_int_equal(json_integer_value(json_object_get(o, "frames")), NF);
    assert_int_equal(json_integer_value(json_object_get(o, "tracked")), NF);
    assert_true(json_real_value(json_object_get(o, "mean_quality")) > 0.9);
    assert_int_equal(json_integer_value(json_object_get(o, "snap_frame")), SNAP_AT);
    assert_true(json_is_false(json_object_get(o, "damaged")));
    json_decref(o);
    int nan;
    assert_int_equal(count_lines(csv, &nan), NF + 1);
    assert_false(nan);
    vis_source *src = vis_source_open_video(overlay, NULL);
    assert_non_null(src);
    assert_int_equal(vis_source_frame_count(src), NF);
    vis_source_close(src);
}

static void test_truncated_video_and_usage(void **state)
{
    (void)state;
    char cut[620], cmd[3000], out[4096];
    snprintf(cut, sizeof cut, "%s/cli_cut.mkv", vt_tmpdir());
    assert_int_equal(vt_cut_copy(video, cut, 6, 10), 0);
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --csv '%s' --json --quiet 2>/dev/null",
             RIBBONCTL_PATH, cut, calib, csv);
    assert_int_equal(run(cmd, out, sizeof out), 1);
    printf("%s", out);
    json_error_t je;
    json_t *j = json_loads(out, 0, &je);
    assert_non_null(j);
    const json_int_t frames = json_integer_value(json_object_get(j, "frames"));
    assert_true(frames > 0 && frames < NF);
    assert_true(json_is_true(json_object_get(j, "damaged")));
    assert_non_null(strstr(json_string_value(json_object_get(j, "error")), "damaged"));
    json_decref(j);
    int nan;
    assert_int_equal(count_lines(csv, &nan), (int)frames + 1);

    snprintf(cmd, sizeof cmd, "'%s' track '%s' 2>/dev/null", RIBBONCTL_PATH, video);
    assert_int_equal(run(cmd, out, sizeof out), 2); /* no calibration */
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --px-per-mm 3 --clamp-left 1,2 --clamp-right x 2>/dev/null",
             RIBBONCTL_PATH, video);
    assert_int_equal(run(cmd, out, sizeof out), 2);
    snprintf(cmd, sizeof cmd, "'%s' track /nonexistent.mkv --calib '%s' --quiet 2>/dev/null", RIBBONCTL_PATH,
             calib);
    assert_int_equal(run(cmd, out, sizeof out), 1);
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --px-per-mm 2.88 --clamp-left 10,120 --clamp-right 300,120 --quiet",
             RIBBONCTL_PATH, video);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "frames 12"));
}

static void test_track_image_sequence(void **state)
{
    (void)state;
    char pat[700], name[720], cmd[3000], out[4096];
    snprintf(pat, sizeof pat, "%s/cli_%%03d.png", vt_tmpdir());
    vis_source *src = vis_source_open_video(video, NULL);
    assert_non_null(src);
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    for (int i = 0; i < 4; i++) {
        assert_int_equal(vis_source_read(src, f, NULL, NULL), VIS_OK);
        snprintf(name, sizeof name, pat, i);
        assert_int_equal(vis_frame_save(f, name, NULL), VIS_OK);
    }
    vis_frame_free(f);
    vis_source_close(src);
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --json --quiet", RIBBONCTL_PATH, pat, calib);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    printf("%s", out);
    json_error_t je;
    json_t *o = json_loads(out, 0, &je);
    assert_non_null(o);
    assert_int_equal(json_integer_value(json_object_get(o, "frames")), 4);
    assert_int_equal(json_integer_value(json_object_get(o, "tracked")), 4);
    assert_true(json_is_null(json_object_get(o, "snap_frame")));
    json_decref(o);
}

static void test_shear_csv_depth_correction(void **state)
{
    (void)state;
    /* A symmetric arch whose right clamp shears 30 mm away from a camera 400 mm off: without the
     * depth correction the midpoint height would be off by several pixels. */
    static vt_shape s;
    char vid[600], truth[600], shear[600], out_csv[600], cal[600], cmd[3000], out[4096];
    snprintf(vid, sizeof vid, "%s/shear.mkv", vt_tmpdir());
    snprintf(truth, sizeof truth, "%s/shear_truth.csv", vt_tmpdir());
    snprintf(shear, sizeof shear, "%s/shear_mm.csv", vt_tmpdir());
    snprintf(out_csv, sizeof out_csv, "%s/shear_out.csv", vt_tmpdir());
    snprintf(cal, sizeof cal, "%s/shear_calib.txt", vt_tmpdir());
    vt_arch(&s, 301, 0.2, 0.16, 0.0, 0.0);
    vis_render_params p = vis_render_params_default();
    p.camera.distance_m = 0.4;
    vis_camera_fit(&p.camera, -0.02, 0.18, -0.07, 0.07, 0.9, NULL);
    vis_calib c;
    assert_int_equal(vis_calib_from_camera(&c, &p.camera, s.pos, s.pos + 3 * (s.n - 1), NULL), VIS_OK);
    assert_int_equal(vis_calib_save(&c, cal, NULL), VIS_OK);
    vis_synth_writer *w = vis_synth_writer_open(vid, truth, &p, 25.0, NULL);
    assert_non_null(w);
    FILE *sf = fopen(shear, "w");
    assert_non_null(sf);
    fprintf(sf, "frame,shear_mm\n");
    double dz_true[4], px_per_m = 0, len = 0;
    for (int i = 0; i < 4; i++) {
        vt_arch(&s, 301, 0.2, 0.16, 0.0, 0.01 * i);
        vis_render_truth tr;
        assert_int_equal(vis_synth_writer_add(w, &s.view, &tr, NULL), VIS_OK);
        dz_true[i] = tr.truth.dz_cam * tr.truth.length_m;
        px_per_m = tr.px_per_m;
        len = tr.truth.length_m;
        fprintf(sf, "%d,%.6f\n", i, tr.truth.shear_m * 1000.0);
    }
    fclose(sf);
    assert_int_equal(vis_synth_writer_close(w, NULL), VIS_OK);
    (void)len;
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --shear-csv '%s' --length-mm 200 --csv '%s' --quiet",
             RIBBONCTL_PATH, vid, cal, shear, out_csv);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    FILE *f = fopen(out_csv, "r");
    assert_non_null(f);
    char line[512];
    assert_non_null(fgets(line, sizeof line, f));
    for (int i = 0; i < 4; i++) {
        int fr;
        double t, dz, a;
        assert_non_null(fgets(line, sizeof line, f));
        assert_int_equal(sscanf(line, "%d,%lf,%lf,%lf", &fr, &t, &dz, &a), 4);
        const double e = (dz * 0.2 - dz_true[i]) * px_per_m;
        printf("shear %d mm: Delta Z error %.3f px\n", 10 * i, e);
        assert_true(fabs(e) < 0.2);
    }
    fclose(f);
}

/* Column `col` (0-based) of the data rows of a CSV into v (up to n), returns the rows read. */
static int csv_column(const char *path, int col, double *v, char reasons[][32], int n)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return -1;
    char line[512];
    int k = 0;
    if (!fgets(line, sizeof line, f)) {
        fclose(f);
        return 0;
    }
    while (k < n && fgets(line, sizeof line, f)) {
        char *p = line;
        for (int c = 0; c < col && p; c++) {
            p = strchr(p, ',');
            if (p)
                p++;
        }
        v[k] = p && *p != ',' ? atof(p) : NAN;
        const char *r = strrchr(line, ',');
        if (reasons)
            snprintf(reasons[k], 32, "%.*s", r ? (int)strcspn(r + 1, "\r\n") : 0, r ? r + 1 : "");
        k++;
    }
    fclose(f);
    return k;
}

static void test_track_with_found_clamps(void **state)
{
    (void)state;
    char cmd[3000], out[4096], ref_csv[620], auto_csv[620], cal[620];
    double ref[NF], got[NF];
    snprintf(ref_csv, sizeof ref_csv, "%s/auto_ref.csv", vt_tmpdir());
    snprintf(auto_csv, sizeof auto_csv, "%s/auto.csv", vt_tmpdir());
    snprintf(cal, sizeof cal, "%s/auto_calib.txt", vt_tmpdir());
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --length-mm 200 --csv '%s' --quiet",
             RIBBONCTL_PATH, video, calib, ref_csv);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_int_equal(csv_column(ref_csv, 2, ref, NULL, NF), NF);
    vis_calib truth;
    assert_int_equal(vis_calib_load(&truth, calib, NULL), VIS_OK);
    const char *scale_opt[2] = {"--clamp-spacing-mm 160", ""};
    for (int k = 0; k < 2; k++) {
        snprintf(cmd, sizeof cmd, "'%s' track '%s' %s --length-mm 200 --csv '%s' --save-calib '%s' --json --quiet",
                 RIBBONCTL_PATH, video, scale_opt[k], auto_csv, cal);
        assert_int_equal(run(cmd, out, sizeof out), 0);
        printf("%s", out);
        json_error_t je;
        json_t *o = json_loads(out, 0, &je);
        assert_non_null(o);
        assert_int_equal(json_integer_value(json_object_get(o, "tracked")), NF);
        assert_int_equal(json_integer_value(json_object_get(o, "clamps_frame")), 0);
        assert_int_equal(json_integer_value(json_object_get(o, "snap_frame")), SNAP_AT);
        const double ppmm = json_real_value(json_object_get(o, "px_per_mm"));
        json_decref(o);
        vis_calib found;
        assert_int_equal(vis_calib_load(&found, cal, NULL), VIS_OK);
        printf("%s: scale %.4f px/mm (camera %.4f), left (%.2f, %.2f) vs (%.2f, %.2f), right (%.2f, %.2f) "
               "vs (%.2f, %.2f)\n", k ? "length" : "spacing", found.px_per_mm, truth.px_per_mm,
               found.clamp_left_px[0], found.clamp_left_px[1], truth.clamp_left_px[0], truth.clamp_left_px[1],
               found.clamp_right_px[0], found.clamp_right_px[1], truth.clamp_right_px[0],
               truth.clamp_right_px[1]);
        assert_true(fabs(found.px_per_mm - ppmm) < 1e-9 * ppmm);
        assert_true(fabs(found.px_per_mm / truth.px_per_mm - 1) < 0.005);
        assert_true(fabs(found.clamp_left_px[1] - truth.clamp_left_px[1]) < 0.5);
        assert_true(fabs(found.clamp_right_px[1] - truth.clamp_right_px[1]) < 0.5);
        assert_int_equal(csv_column(auto_csv, 2, got, NULL, NF), NF);
        /* Heights compared in pixels (each run's Delta Z times l in its own scale): the scale from
         * the spacing runs about w / 2D low (the jaws' silhouette faces are their far faces), which
         * changes Delta Z by that fraction, not the pixels measured. */
        double worst = 0, worst_raw = 0;
        for (int i = 0; i < NF; i++) {
            worst = fmax(worst, fabs(got[i] * found.px_per_mm - ref[i] * truth.px_per_mm) * 200.0);
            worst_raw = fmax(worst_raw, fabs(got[i] - ref[i]) * 200.0 * truth.px_per_mm);
        }
        printf("height against the --calib run: worst %.3f px (Delta Z alone: %.3f px)\n", worst, worst_raw);
        assert_true(worst < 0.2);
    }
}

static int same_file(const char *a, const char *b)
{
    FILE *fa = fopen(a, "rb"), *fb = fopen(b, "rb");
    int same = fa && fb;
    while (same) {
        const int ca = fgetc(fa), cb = fgetc(fb);
        same = ca == cb;
        if (ca == EOF || cb == EOF)
            break;
    }
    if (fa)
        fclose(fa);
    if (fb)
        fclose(fb);
    return same;
}

/* Every frame of two videos bit for bit the same. */
static int same_video(const char *a, const char *b)
{
    vis_source *sa = vis_source_open_video(a, NULL), *sb = vis_source_open_video(b, NULL);
    vis_frame *fa = vis_frame_alloc(8, 8, 3, NULL), *fb = vis_frame_alloc(8, 8, 3, NULL);
    int same = sa && sb && fa && fb, n = 0;
    while (same) {
        const vis_status xa = vis_source_read(sa, fa, NULL, NULL), xb = vis_source_read(sb, fb, NULL, NULL);
        same = xa == xb;
        if (xa != VIS_OK)
            break;
        same = same && vis_frame_width(fa) == vis_frame_width(fb) && vis_frame_height(fa) == vis_frame_height(fb) &&
               !memcmp(vis_frame_data(fa), vis_frame_data(fb), vis_frame_stride(fa) * (size_t)vis_frame_height(fa));
        n++;
    }
    vis_frame_free(fa);
    vis_frame_free(fb);
    vis_source_close(sa);
    vis_source_close(sb);
    return same && n == NF;
}

/* --threads: the CSV and the overlay the same bytes on one core and on several, with a given
 * calibration (the pipe from frame 0) and with the clamps and the scale found in the video (the
 * pipe taking over after the first tracked frame); stretches of 3 frames, so several cores work. */
static void test_threads_same_results(void **state)
{
    (void)state;
    char cmd[3000], out[4096], csv1[620], csvn[620], ov1[620], ovn[620];
    const char *calib_opt[2] = {"--calib", ""};
    for (int k = 0; k < 2; k++) {
        const int threads[3] = {1, 2, 0};
        for (int j = 0; j < 3; j++) {
            char cal_arg[700];
            snprintf(cal_arg, sizeof cal_arg, k == 0 ? "--calib '%s'" : "", calib);
            snprintf(csvn, sizeof csvn, "%s/threads%d_%d.csv", vt_tmpdir(), k, j);
            snprintf(ovn, sizeof ovn, "%s/threads%d_%d.mkv", vt_tmpdir(), k, j);
            snprintf(cmd, sizeof cmd, "'%s' track '%s' %s --length-mm 200 --refresh-frames 3 --threads %d --csv '%s' "
                     "--overlay '%s' --json --quiet", RIBBONCTL_PATH, video, cal_arg, threads[j], csvn, ovn);
            assert_int_equal(run(cmd, out, sizeof out), 0);
            json_error_t je;
            json_t *o = json_loads(out, 0, &je);
            assert_non_null(o);
            const json_int_t used = json_integer_value(json_object_get(o, "tracking_threads"));
            json_decref(o);
            if (threads[j] == 0)
                assert_true(used >= 1);
            else
                assert_int_equal(used, threads[j]); /* --threads 2: two cores did track */
            if (j == 0) {
                snprintf(csv1, sizeof csv1, "%s", csvn);
                snprintf(ov1, sizeof ov1, "%s", ovn);
                continue;
            }
            assert_true(same_file(csv1, csvn));
            assert_true(same_video(ov1, ovn));
        }
        printf("%s: CSV and overlay identical with --threads 1, 2 and 0\n", k ? "found clamps" : calib_opt[0]);
    }
    /* The tracker's error on frame 7 (a shear that puts the clamp behind the camera) ends the run
     * there, however many cores: the same rows, the same message, exit status 1. */
    char shear_csv[620], err_out[2][4096];
    snprintf(shear_csv, sizeof shear_csv, "%s/bad_shear.csv", vt_tmpdir());
    FILE *sf = fopen(shear_csv, "w");
    assert_non_null(sf);
    fprintf(sf, "frame,shear_mm\n0,0\n7,-1e9\n8,0\n");
    fclose(sf);
    for (int j = 0; j < 2; j++) {
        snprintf(csvn, sizeof csvn, "%s/bad_shear_%d.csv", vt_tmpdir(), j);
        snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --shear-csv '%s' --refresh-frames 3 --threads %d "
                 "--csv '%s' --json --quiet 2>/dev/null", RIBBONCTL_PATH, video, calib, shear_csv, j ? 2 : 1, csvn);
        assert_int_equal(run(cmd, err_out[j], sizeof err_out[j]), 1);
        json_error_t je;
        json_t *o = json_loads(err_out[j], 0, &je);
        assert_non_null(o);
        assert_int_equal(json_integer_value(json_object_get(o, "frames")), 7);
        assert_non_null(strstr(json_string_value(json_object_get(o, "error")), "frame 7"));
        assert_true(json_is_false(json_object_get(o, "damaged")));
        json_decref(o);
    }
    snprintf(csv1, sizeof csv1, "%s/bad_shear_0.csv", vt_tmpdir());
    assert_true(same_file(csv1, csvn));
    printf("tracker error at frame 7: %s", err_out[1]);
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --threads 65 2>/dev/null", RIBBONCTL_PATH, video, calib);
    assert_int_equal(run(cmd, out, sizeof out), 2);
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --refresh-frames -1 2>/dev/null", RIBBONCTL_PATH, video,
             calib);
    assert_int_equal(run(cmd, out, sizeof out), 2);
}

static void test_video_without_clamps(void **state)
{
    (void)state;
    static vt_shape s;
    char vid[600], truth[600], out_csv[600], cmd[3000], out[4096], reasons[4][32];
    double dz[4];
    snprintf(vid, sizeof vid, "%s/noclamp.mkv", vt_tmpdir());
    snprintf(truth, sizeof truth, "%s/noclamp_truth.csv", vt_tmpdir());
    snprintf(out_csv, sizeof out_csv, "%s/noclamp_out.csv", vt_tmpdir());
    vt_arch(&s, 301, 0.2, 0.16, 0.2, 0.0);
    vis_render_params p = vis_render_params_default();
    vis_camera_fit(&p.camera, -0.02, 0.18, -0.07, 0.07, 0.9, NULL);
    p.clamp_length_m = 0.0;
    vis_synth_writer *w = vis_synth_writer_open(vid, truth, &p, 25.0, NULL);
    assert_non_null(w);
    for (int i = 0; i < 4; i++)
        assert_int_equal(vis_synth_writer_add(w, &s.view, NULL, NULL), VIS_OK);
    assert_int_equal(vis_synth_writer_close(w, NULL), VIS_OK);
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --clamp-spacing-mm 160 --csv '%s' --json --quiet 2>/dev/null",
             RIBBONCTL_PATH, vid, out_csv);
    assert_int_equal(run(cmd, out, sizeof out), 1);
    printf("%s", out);
    json_error_t je;
    json_t *o = json_loads(out, 0, &je);
    assert_non_null(o);
    assert_int_equal(json_integer_value(json_object_get(o, "frames")), 4);
    assert_int_equal(json_integer_value(json_object_get(o, "tracked")), 0);
    assert_true(json_is_null(json_object_get(o, "clamp_left")));
    assert_non_null(strstr(json_string_value(json_object_get(o, "error")), "no clamp pair found"));
    json_decref(o);
    assert_int_equal(csv_column(out_csv, 2, dz, reasons, 4), 4);
    for (int i = 0; i < 4; i++) {
        assert_true(isnan(dz[i]));
        assert_string_equal(reasons[i], "clamp_not_found");
    }
    /* One clamp point without the other is a usage error. */
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --clamp-spacing-mm 160 --clamp-left 1,2 2>/dev/null",
             RIBBONCTL_PATH, vid);
    assert_int_equal(run(cmd, out, sizeof out), 2);
}

/* A PNG of only its signature and IHDR chunk (CRC included) claiming w x h pixels. */
static void write_png_header(const char *path, uint32_t w, uint32_t h)
{
    unsigned char b[33] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R'};
    for (int k = 0; k < 4; k++) {
        b[16 + k] = (unsigned char)(w >> (24 - 8 * k));
        b[20 + k] = (unsigned char)(h >> (24 - 8 * k));
    }
    b[24] = 8; /* depth 8, grey, no interlace */
    uint32_t crc = 0xFFFFFFFFu;
    for (int i = 12; i < 29; i++) {
        crc ^= b[i];
        for (int k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    crc ^= 0xFFFFFFFFu;
    for (int k = 0; k < 4; k++) b[29 + k] = (unsigned char)(crc >> (24 - 8 * k));
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(b, 1, sizeof b, f), sizeof b);
    fclose(f);
}

/* Issue 17: defect 8 (a 100000 x 100000 PNG read as 0 frames with error null; a 16000 x 16000
 * one was decoded to 2 GB first) and item 12 (`track /dev/zero` and `track DIR` said "no such
 * file"). Now: refused from the header with the named error, and the real reason. */
static void test_hostile_inputs_named(void **state)
{
    (void)state;
    static const struct {
        uint32_t w, h;
    } sizes[] = {{100000, 100000}, {2147483647u, 2147483647u}, {16000, 16000}, {16385, 8}};
    char path[600], cmd[1400], out[8192];
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        snprintf(path, sizeof path, "%s/huge%zu.png", vt_tmpdir(), i);
        write_png_header(path, sizes[i].w, sizes[i].h);
        snprintf(cmd, sizeof cmd, "%s track %s --px-per-mm 2 --json --quiet 2>/dev/null", RIBBONCTL_PATH, path);
        assert_int_equal(run(cmd, out, sizeof out), 1);
        printf("%u x %u: %s", sizes[i].w, sizes[i].h, out);
        assert_non_null(strstr(out, "image too large"));
        assert_non_null(strstr(out, "refused before decoding"));
    }
    snprintf(cmd, sizeof cmd, "%s track /dev/zero --px-per-mm 2 --json --quiet 2>/dev/null", RIBBONCTL_PATH);
    assert_int_equal(run(cmd, out, sizeof out), 1);
    assert_non_null(strstr(out, "not a regular file (a character device)"));
    snprintf(cmd, sizeof cmd, "%s track %s --px-per-mm 2 --json --quiet 2>/dev/null", RIBBONCTL_PATH, vt_tmpdir());
    assert_int_equal(run(cmd, out, sizeof out), 1);
    assert_non_null(strstr(out, "not a regular file (a directory)"));
    snprintf(cmd, sizeof cmd, "%s track %s/none.mkv --px-per-mm 2 --json --quiet 2>/dev/null", RIBBONCTL_PATH,
             vt_tmpdir());
    assert_int_equal(run(cmd, out, sizeof out), 1);
    assert_non_null(strstr(out, "No such file"));
    /* The image reader of a frame sequence checks each header too. */
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    vis_error err;
    snprintf(path, sizeof path, "%s/huge0.png", vt_tmpdir());
    assert_int_equal(vis_frame_load(f, path, &err), VIS_ERR_TOO_LARGE);
    vis_frame_free(f);
}

/* Per-frame errors of a track CSV against ribbonctl render's truth CSV (dz_cam, a_cam, px_per_m
 * columns 6, 7, 14): RMS of Delta Z (px) and A (rad) over the measured frames, and the count of
 * frames more than 2 px or 0.1 rad off. Returns the frames compared. */
static int errors_vs_truth(const char *track_csv, const char *truth_csv, double *dz_rms, double *a_rms, int *wrong)
{
    enum { N = 400 };
    static double dz[N], a[N], tdz[N], ta[N], ppm[N];
    const int n = csv_column(track_csv, 2, dz, NULL, N);
    assert_int_equal(csv_column(track_csv, 3, a, NULL, N), n);
    assert_int_equal(csv_column(truth_csv, 6, tdz, NULL, N), n);
    assert_int_equal(csv_column(truth_csv, 7, ta, NULL, N), n);
    assert_int_equal(csv_column(truth_csv, 14, ppm, NULL, N), n);
    double sz = 0, sa = 0;
    int m = 0;
    *wrong = 0;
    for (int i = 0; i < n; i++) {
        if (!isfinite(dz[i]))
            continue;
        const double ez = (dz[i] - tdz[i]) * 0.2 * ppm[i], ea = a[i] - ta[i];
        sz += ez * ez;
        sa += ea * ea;
        *wrong += fabs(ez) > 2.0 || fabs(ea) > 0.1;
        m++;
    }
    *dz_rms = m ? sqrt(sz / m) : NAN;
    *a_rms = m ? sqrt(sa / m) : NAN;
    return m;
}

/* --depth-scene: a DER trial of the lab strip rendered by `ribbonctl render` with the twin's own
 * camera (1 m), tracked with the default depth profile and with the scene's predicted shapes.
 * Measured (46 frames, 640 x 480): A 0.0254 rad RMS (max 0.087) with the default, 0.0108 with the
 * prediction's depth; Delta Z 0.42 and 0.45 px RMS (at N = 31 the polygon, not the
 * depth, dominates it). Then the option's errors: --depth-set alone, a scene that does not load. */
static void test_depth_from_scene(void **state)
{
    (void)state;
    char vid[600], truth[600], shear[600], cal[600], def[600], dep[600], cmd[4000], out[4096];
    snprintf(vid, sizeof vid, "%s/depth.mkv", vt_tmpdir());
    snprintf(truth, sizeof truth, "%s/depth_truth.csv", vt_tmpdir());
    snprintf(shear, sizeof shear, "%s/depth_shear.csv", vt_tmpdir());
    snprintf(cal, sizeof cal, "%s/depth_calib.txt", vt_tmpdir());
    snprintf(def, sizeof def, "%s/depth_default.csv", vt_tmpdir());
    snprintf(dep, sizeof dep, "%s/depth_scene.csv", vt_tmpdir());
    const char *scene = RIBBON_SOURCE_DIR "/config/scenes/pet-200x5.ini";
    snprintf(cmd, sizeof cmd,
             "'%s' render --scene '%s' --set mesh.nodes=31 --set protocol.compression=0.5 --set protocol.shear_rate=0.01 "
             "--set folds.hinge_stiffness=rigid " /* the bars were measured on rigid creases */
             "--fast --fps 5 --post-snap 1 --out '%s' --csv '%s' --save-calib '%s' --shear-csv '%s' --quiet",
             RIBBONCTL_PATH, scene, vid, truth, cal, shear);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --shear-csv '%s' --length-mm 200 --csv '%s' --json --quiet",
             RIBBONCTL_PATH, vid, cal, shear, def);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    assert_non_null(strstr(out, "\"depth_shapes\":null"));
    snprintf(cmd, sizeof cmd,
             "'%s' track '%s' --calib '%s' --shear-csv '%s' --length-mm 200 --csv '%s' --json --quiet --depth-scene '%s' "
             "--depth-set mesh.nodes=31 --depth-set protocol.compression=0.5 --depth-set protocol.shear_rate=0.01 "
             "--depth-set folds.hinge_stiffness=rigid",
             RIBBONCTL_PATH, vid, cal, shear, dep, scene);
    assert_int_equal(run(cmd, out, sizeof out), 0);
    json_error_t je;
    json_t *o = json_loads(out, 0, &je);
    assert_non_null(o);
    const json_int_t shapes = json_integer_value(json_object_get(o, "depth_shapes"));
    json_decref(o);
    double z0, a0, z1, a1;
    int w0, w1;
    const int n0 = errors_vs_truth(def, truth, &z0, &a0, &w0), n1 = errors_vs_truth(dep, truth, &z1, &a1, &w1);
    printf("default depth: %d frames, Delta Z %.3f px RMS, A %.4f rad RMS, %d wrong; from the scene (%lld shapes): "
           "%d frames, %.3f px, %.4f rad, %d wrong\n",
           n0, z0, a0, w0, (long long)shapes, n1, z1, a1, w1);
    assert_true(shapes > 100);
    assert_true(n1 >= n0 && n1 >= 40);
    assert_int_equal(w1, 0);
    assert_true(a1 <= 0.02);
    assert_true(a0 >= 1.5 * a1); /* the default's depth costs A at this distance */
    assert_true(z1 <= z0 + 0.1);
    /* Usage and scene errors. */
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --depth-set mesh.nodes=31 2>&1", RIBBONCTL_PATH, vid, cal);
    assert_int_equal(run(cmd, out, sizeof out), 2);
    assert_non_null(strstr(out, "--depth-set needs --depth-scene"));
    snprintf(cmd, sizeof cmd, "'%s' track '%s' --calib '%s' --depth-scene '%s' --depth-set mesh.nodes=2 2>&1",
             RIBBONCTL_PATH, vid, cal, scene);
    assert_int_equal(run(cmd, out, sizeof out), 1);
    assert_non_null(strstr(out, "--depth-scene"));
    printf("refused: %s", out);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_track_video_with_json_csv_overlay),
        cmocka_unit_test(test_truncated_video_and_usage),
        cmocka_unit_test(test_track_image_sequence),
        cmocka_unit_test(test_shear_csv_depth_correction),
        cmocka_unit_test(test_track_with_found_clamps),
        cmocka_unit_test(test_threads_same_results),
        cmocka_unit_test(test_video_without_clamps),
        cmocka_unit_test(test_hostile_inputs_named),
        cmocka_unit_test(test_depth_from_scene),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
