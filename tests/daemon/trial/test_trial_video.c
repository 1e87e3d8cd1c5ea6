/* test_trial_video.c: a trial's video notices when its frames do not reach the disk (issue 17,
 * defect 2: with the video on a small file system the video stopped at the file system's size and
 * the trial still ended done, without an event). No mount is needed: a full disk is a reserve
 * larger than the free space (trial_video_set_min_free), and a write the encoder loses is a file
 * size limit (RLIMIT_FSIZE) in a child process. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>
#include <cmocka.h>

#include "trial_video.h"

static char dir[] = "/tmp/ribbon-trial-video-XXXXXX";

static vis_frame *noise_frame(int w, int h, unsigned seed)
{
    vis_frame *f = vis_frame_alloc(w, h, 1, NULL);
    assert_non_null(f);
    uint8_t *d = vis_frame_data(f);
    size_t st = vis_frame_stride(f);
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++) {
            seed = seed * 1103515245u + 12345u;
            d[(size_t)j * st + (size_t)i] = (uint8_t)(seed >> 24);
        }
    return f;
}

static void test_whole_video_closes_with_its_count(void **s)
{
    (void)s;
    char path[256], why[512] = "";
    snprintf(path, sizeof path, "%s/whole.mkv", dir);
    trial_roi roi = {0, 0, 160, 120};
    trial_video *v = trial_video_open(path, roi, 30.0, why, sizeof why);
    assert_non_null(v);
    vis_frame *f = noise_frame(160, 120, 1);
    for (int i = 0; i < 20; i++) assert_int_equal(trial_video_add(v, f, why, sizeof why), 0);
    vis_frame_free(f);
    assert_int_equal(trial_video_close(v, why, sizeof why), 20);
}

static void test_full_disk_fails_the_frame_at_once(void **s)
{
    (void)s;
    char path[256], why[512] = "";
    snprintf(path, sizeof path, "%s/full.mkv", dir);
    trial_roi roi = {0, 0, 160, 120};
    trial_video *v = trial_video_open(path, roi, 30.0, why, sizeof why);
    assert_non_null(v);
    struct statvfs fs;
    assert_int_equal(statvfs(dir, &fs), 0);
    double free_b = (double)fs.f_bavail * (double)fs.f_frsize;
    vis_frame *f = noise_frame(160, 120, 2);
    assert_int_equal(trial_video_add(v, f, why, sizeof why), 0);
    trial_video_set_min_free(v, free_b + 1e12); /* the disk is now "full" */
    assert_int_equal(trial_video_add(v, f, why, sizeof why), -1);
    printf("full disk: %s\n", why);
    assert_non_null(strstr(why, "video disk full"));
    assert_non_null(strstr(why, "at frame 1"));
    vis_frame_free(f);
    trial_video_close(v, why, sizeof why);
}

static void test_lost_writes_make_the_video_incomplete(void **s)
{
    (void)s;
    char path[256];
    snprintf(path, sizeof path, "%s/limited.mkv", dir);
    fflush(NULL);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        /* The child's files may not grow past 96 KiB: ffmpeg's writes beyond fail (EFBIG). */
        signal(SIGXFSZ, SIG_IGN);
        struct rlimit rl = {96 * 1024, 96 * 1024};
        if (setrlimit(RLIMIT_FSIZE, &rl) != 0) _exit(10);
        char why[512] = "";
        trial_roi roi = {0, 0, 160, 120};
        trial_video *v = trial_video_open(path, roi, 30.0, why, sizeof why);
        if (!v) _exit(11);
        vis_frame *f = noise_frame(160, 120, 3);
        for (int i = 0; i < 30; i++)
            if (trial_video_add(v, f, why, sizeof why) != 0) _exit(12);
        vis_frame_free(f);
        long n = trial_video_close(v, why, sizeof why);
        printf("file size limit: %ld, %s\n", n, why);
        fflush(stdout);
        _exit(n == -1 && strstr(why, "video incomplete") ? 0 : 13);
    }
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status));
    assert_int_equal(WEXITSTATUS(status), 0);
}

int main(void)
{
    if (!mkdtemp(dir)) return 1;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_whole_video_closes_with_its_count),
        cmocka_unit_test(test_full_disk_fails_the_frame_at_once),
        cmocka_unit_test(test_lost_writes_make_the_video_incomplete),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0) rc = rc ? rc : 1;
    return rc;
}
