/* test_vision_video.c: lossless video round-trip and the frame sources' handling of damage.
 *
 * FFV1 in .mkv must read back bit-exact (sub-pixel tracking depends on it); a truncated or
 * corrupted video is read up to the damage and the damage is reported (VIS_ERR_FORMAT), never as a
 * clean end; a file that is not a video is refused at open; image sequences end at the first
 * missing number and report an undecodable image; the synthetic source renders its callback's shapes;
 * a camera that does not exist is an I/O error naming it.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/wait.h>
#include <signal.h>

#include "vis_test_run.h"

#define NF 12

static vt_shape shape;

static void render_frames(vis_frame **frames, vis_render_params *p)
{
    vt_arch(&shape, 201, 0.2, 0.16, 0.0, 0.0);
    *p = vt_render_params(&shape, 320, 240);
    p->noise_sigma = 20.0; /* lots of high-entropy detail: a lossy codec could not keep it */
    vis_renderer *r = vis_renderer_create(p, NULL);
    assert_non_null(r);
    for (int i = 0; i < NF; i++) {
        frames[i] = vis_frame_alloc(8, 8, 1, NULL);
        assert_non_null(frames[i]);
        assert_int_equal(vis_renderer_draw(r, &shape.view, frames[i], NULL, NULL), VIS_OK);
    }
    vis_renderer_free(r);
}

static int same(vis_frame *a, vis_frame *b)
{
    if (vis_frame_width(a) != vis_frame_width(b) || vis_frame_height(a) != vis_frame_height(b))
        return 0;
    for (int y = 0; y < vis_frame_height(a); y++)
        if (memcmp(vis_frame_data(a) + y * vis_frame_stride(a), vis_frame_data(b) + y * vis_frame_stride(b),
                   (size_t)vis_frame_width(a)) != 0)
            return 0;
    return 1;
}

static void write_video(const char *path, vis_frame **frames)
{
    vis_error err;
    vis_video_writer *w = vis_video_writer_open(path, 320, 240, 1, 25.0, &err);
    assert_non_null(w);
    for (int i = 0; i < NF; i++)
        assert_int_equal(vis_video_writer_write(w, frames[i], &err), VIS_OK);
    vis_video_writer_close(w);
}

static void test_ffv1_round_trip_is_bit_exact(void **state)
{
    (void)state;
    vis_frame *frames[NF];
    vis_render_params p;
    render_frames(frames, &p);
    char path[600];
    snprintf(path, sizeof path, "%s/exact.mkv", vt_tmpdir());
    write_video(path, frames);
    vis_error err;
    vis_source *src = vis_source_open_video(path, &err);
    assert_non_null(src);
    assert_int_equal(vis_source_frame_count(src), NF);
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    for (int i = 0; i < NF; i++) {
        double t;
        assert_int_equal(vis_source_read(src, f, &t, &err), VIS_OK);
        assert_true(same(f, frames[i]));
        assert_true(t >= 0);
    }
    assert_int_equal(vis_source_read(src, f, NULL, &err), VIS_ERR_END);
    vis_source_close(src);
    vis_frame_free(f);
    for (int i = 0; i < NF; i++)
        vis_frame_free(frames[i]);
}

static void test_writer_refuses_lossy_name(void **state)
{
    (void)state;
    vis_error err;
    char path[600];
    snprintf(path, sizeof path, "%s/x.mp4", vt_tmpdir());
    assert_null(vis_video_writer_open(path, 320, 240, 1, 25.0, &err));
    assert_int_equal(err.code, VIS_ERR_ARG);
    /* .avi is raw Y800: grey frames only */
    snprintf(path, sizeof path, "%s/x.avi", vt_tmpdir());
    assert_null(vis_video_writer_open(path, 320, 240, 3, 25.0, &err));
    assert_int_equal(err.code, VIS_ERR_ARG);
    assert_null(vis_video_writer_open(NULL, 320, 240, 1, 25.0, &err));
    snprintf(path, sizeof path, "%s/x.mkv", vt_tmpdir());
    assert_null(vis_video_writer_open(path, 320, 240, 2, 25.0, &err));
    assert_null(vis_video_writer_open(path, 320, 240, 1, -1.0, &err));
}

/* Copy the first `frac` of file a into b, optionally overwriting a stretch in the middle. */
static long copy_damaged(const char *a, const char *b, double frac, int scramble)
{
    FILE *in = fopen(a, "rb");
    assert_non_null(in);
    fseek(in, 0, SEEK_END);
    const long n = ftell(in);
    fseek(in, 0, SEEK_SET);
    unsigned char *buf = malloc((size_t)n);
    assert_non_null(buf);
    assert_int_equal(fread(buf, 1, (size_t)n, in), (size_t)n);
    fclose(in);
    if (scramble)
        for (long i = n / 2; i < n / 2 + 4000 && i < n; i++)
            buf[i] = (unsigned char)(i * 7919u);
    FILE *out = fopen(b, "wb");
    assert_non_null(out);
    const long m = (long)(frac * n);
    assert_int_equal(fwrite(buf, 1, (size_t)m, out), (size_t)m);
    fclose(out);
    free(buf);
    return m;
}

/* Read until the source stops; returns frames read and the final status. */
static int read_all(const char *path, vis_status *last, vis_error *err)
{
    vis_source *src = vis_source_open_video(path, err);
    if (!src) {
        *last = err->code;
        return -1;
    }
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    int n = 0;
    for (int guard = 0; guard < 10 * NF; guard++) {
        *last = vis_source_read(src, f, NULL, err);
        if (*last != VIS_OK)
            break;
        n++;
    }
    vis_frame_free(f);
    vis_source_close(src);
    return n;
}

static void test_truncated_video_read_up_to_damage(void **state)
{
    (void)state;
    vis_frame *frames[NF];
    vis_render_params p;
    render_frames(frames, &p);
    char a[600], b[600];
    snprintf(a, sizeof a, "%s/full.mkv", vt_tmpdir());
    snprintf(b, sizeof b, "%s/cut.mkv", vt_tmpdir());
    write_video(a, frames);
    copy_damaged(a, b, 0.6, 0);
    vis_error err;
    vis_status last;
    const int n = read_all(b, &last, &err);
    printf("truncated: %d of %d frames, then: %s\n", n, NF, err.message);
    assert_true(n > 0 && n < NF);
    assert_int_equal(last, VIS_ERR_FORMAT);
    assert_non_null(strstr(err.message, "damaged"));
    /* The frames before the damage are intact. */
    vis_source *src = vis_source_open_video(b, &err);
    assert_non_null(src);
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    for (int i = 0; i < n; i++) {
        assert_int_equal(vis_source_read(src, f, NULL, &err), VIS_OK);
        assert_true(same(f, frames[i]));
    }
    vis_frame_free(f);
    vis_source_close(src);

    /* Corruption in the middle: reported, not crashed on. */
    copy_damaged(a, b, 1.0, 1);
    const int m = read_all(b, &last, &err);
    printf("corrupted: %d of %d frames, then: %s\n", m, NF, err.message);
    assert_true(m >= 0 && m <= NF);
    assert_true(last == VIS_ERR_FORMAT || last == VIS_ERR_END);
    for (int i = 0; i < NF; i++)
        vis_frame_free(frames[i]);
}

/* Issue 17, defect 7: a video whose writer was killed (kill -9, a full disk) has no trailer:
 * Matroska's duration and cues are missing, so the container announces no frame count and every
 * frame written before the kill reads back, after which the read used to look like a clean end.
 * Now the end of a file that announced no count is reported as damage (index missing). */
static void test_killed_writer_video_is_damaged(void **state)
{
    (void)state;
    vis_frame *frames[NF];
    vis_render_params p;
    render_frames(frames, &p);
    char path[600];
    snprintf(path, sizeof path, "%s/killed.mkv", vt_tmpdir());
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        vis_error e;
        vis_video_writer *w = vis_video_writer_open(path, 320, 240, 1, 25.0, &e);
        if (!w) _exit(3);
        for (int i = 0; i < 10 * NF; i++) /* enough for ffmpeg to flush most of them to the file */
            if (vis_video_writer_write(w, frames[i % NF], &e) != VIS_OK) _exit(4);
        raise(SIGKILL); /* never closed: no trailer */
        _exit(5);
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFSIGNALED(status));
    vis_error err;
    vis_status last;
    const int n = read_all(path, &last, &err);
    printf("killed writer: %d of %d frames, then: %s\n", n, 10 * NF, err.message);
    assert_true(n > 0 && n <= 10 * NF);
    assert_int_equal(last, VIS_ERR_FORMAT);
    assert_non_null(strstr(err.message, "damaged"));
    for (int i = 0; i < NF; i++)
        vis_frame_free(frames[i]);
}

static void test_not_a_video_is_refused(void **state)
{
    (void)state;
    char path[600];
    snprintf(path, sizeof path, "%s/junk.mkv", vt_tmpdir());
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    for (int i = 0; i < 5000; i++)
        fputc((i * 131) & 0xff, f);
    fclose(f);
    vis_error err;
    assert_null(vis_source_open_video(path, &err));
    assert_int_equal(err.code, VIS_ERR_FORMAT);
    snprintf(path, sizeof path, "%s/missing.mkv", vt_tmpdir());
    assert_null(vis_source_open_video(path, &err));
    assert_int_equal(err.code, VIS_ERR_IO);
}

static void test_image_sequence(void **state)
{
    (void)state;
    vis_frame *frames[NF];
    vis_render_params p;
    render_frames(frames, &p);
    char pat[600], name[620];
    snprintf(pat, sizeof pat, "%s/seq_%%03d.png", vt_tmpdir());
    for (int i = 0; i < 3; i++) {
        snprintf(name, sizeof name, pat, i);
        assert_int_equal(vis_frame_save(frames[i], name, NULL), VIS_OK);
    }
    vis_error err;
    vis_source *src = vis_source_open_images(pat, 0, &err);
    assert_non_null(src);
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    for (int i = 0; i < 3; i++) {
        assert_int_equal(vis_source_read(src, f, NULL, &err), VIS_OK);
        assert_true(same(f, frames[i]));
    }
    assert_int_equal(vis_source_read(src, f, NULL, &err), VIS_ERR_END);
    vis_source_close(src);
    /* An undecodable image in the middle is damage, named in the message. */
    snprintf(name, sizeof name, pat, 1);
    FILE *fp = fopen(name, "wb");
    assert_non_null(fp);
    fputs("not a png", fp);
    fclose(fp);
    src = vis_source_open_images(pat, 0, &err);
    assert_non_null(src);
    assert_int_equal(vis_source_read(src, f, NULL, &err), VIS_OK);
    assert_int_equal(vis_source_read(src, f, NULL, &err), VIS_ERR_FORMAT);
    assert_non_null(strstr(err.message, "seq_001.png"));
    vis_source_close(src);
    /* Bad patterns are refused. */
    assert_null(vis_source_open_images("frame_%s.png", 0, &err));
    assert_int_equal(err.code, VIS_ERR_ARG);
    assert_null(vis_source_open_images("frame_%d_%d.png", 0, &err));
    vis_frame_free(f);
    for (int i = 0; i < NF; i++)
        vis_frame_free(frames[i]);
}

static int synth_cb(void *user, int index, vis_shape *out)
{
    int *calls = user;
    (*calls)++;
    if (index >= 3)
        return 1;
    vt_arch(&shape, 201, 0.2, 0.16, 0.1 * index, 0.0);
    *out = shape.view;
    return 0;
}

static void test_synthetic_source(void **state)
{
    (void)state;
    vt_arch(&shape, 201, 0.2, 0.16, 0.0, 0.0);
    vis_render_params p = vt_render_params(&shape, 160, 120);
    int calls = 0;
    vis_error err;
    vis_source *src = vis_source_open_synthetic(&p, 50.0, synth_cb, &calls, &err);
    assert_non_null(src);
    vis_frame *f = vis_frame_alloc(8, 8, 1, NULL);
    double t = -1;
    for (int i = 0; i < 3; i++) {
        assert_int_equal(vis_source_read(src, f, &t, &err), VIS_OK);
        assert_int_equal(vis_frame_width(f), 160);
        assert_true(t > i / 50.0 - 1e-9 && t < i / 50.0 + 1e-9);
    }
    assert_int_equal(vis_source_read(src, f, NULL, &err), VIS_ERR_END);
    assert_int_equal(calls, 4);
    vis_source_close(src);
    vis_frame_free(f);
}

static void test_missing_camera_is_reported(void **state)
{
    (void)state;
    vis_camera_settings cs = vis_camera_settings_default();
    cs.path = "/dev/ribbon-no-such-camera";
    cs.width_px = 640;
    cs.height_px = 480;
    cs.fps = 30;
    memcpy(cs.fourcc, "MJPG", 5);
    vis_error err;
    assert_null(vis_source_open_camera(&cs, &err));
    assert_int_equal(err.code, VIS_ERR_IO);
    assert_non_null(strstr(err.message, "ribbon-no-such-camera"));
    assert_null(vis_source_open_camera(NULL, &err));
    assert_int_equal(err.code, VIS_ERR_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ffv1_round_trip_is_bit_exact),
        cmocka_unit_test(test_writer_refuses_lossy_name),
        cmocka_unit_test(test_truncated_video_read_up_to_damage),
        cmocka_unit_test(test_killed_writer_video_is_damaged),
        cmocka_unit_test(test_not_a_video_is_refused),
        cmocka_unit_test(test_image_sequence),
        cmocka_unit_test(test_synthetic_source),
        cmocka_unit_test(test_missing_camera_is_reported),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
