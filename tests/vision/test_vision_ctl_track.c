/* test_vision_ctl_track.c: `ribbonctl track` end to end on a rendered video.
 *
 * Renders a snapping sequence (320 x 240) with ground truth, runs the real binary with a saved
 * calibration, and checks the --json summary (frames, tracked, mean_quality, snap_frame), the CSV
 * (one row per frame, no NaN) and the overlay video (readable, one frame per input frame). A
 * truncated copy of the video is tracked up to the damage (exit status 1, "damaged": true, the
 * frames before the damage in the CSV); usage errors exit with 2; an image sequence is tracked too.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>

#include "vis_test_run.h"

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
    FILE *in = fopen(video, "rb"), *o = fopen(cut, "wb");
    assert_non_null(in);
    assert_non_null(o);
    fseek(in, 0, SEEK_END);
    const long n = ftell(in);
    fseek(in, 0, SEEK_SET);
    for (long i = 0; i < n * 6 / 10; i++)
        fputc(fgetc(in), o);
    fclose(in);
    fclose(o);
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_track_video_with_json_csv_overlay),
        cmocka_unit_test(test_truncated_video_and_usage),
        cmocka_unit_test(test_track_image_sequence),
    };
    return cmocka_run_group_tests(tests, setup, NULL);
}
