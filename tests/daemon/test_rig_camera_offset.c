/* test_rig_camera_offset: the camera's time offset measured at the shear's start (issue 34 C), in
 * real time against ribbon-rigsim with a camera delay (--camera-delay-ms: each image shows the twin
 * that long before its stamp), 60 fps, ribbond on config/rig-rehearsal.ini with
 * camera.time_offset = measure (compression at 20 mm/s: a trial of about 30 s). The camera is
 * pitched 10 deg down (--camera-tilt-deg): level, it sees the shear (along its axis) only by
 * perspective, 3 px over the window, and the offset's standard deviation is 3.5 ms
 * (docs/rig-camera-timing-and-faults.md, "The camera's delay, measured").
 *
 * The truth is the simulator's own: per image sent, the instant it shows is its send time less the
 * delay and less the image's lateness (truth log: camera_delay_s + image_age_s), so the true offset
 * over the fit's window is minus the median of their sum over the images sent in it. The estimate
 * (the trial's camera_offset_s, and its event) must lie within 2 ms of it; its stated standard
 * deviation is printed beside the error. Real time, about 40 s: heavy. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rig_harness.h"

#define RIG RIBBON_SOURCE_DIR "/config/rig-rehearsal.ini"
#define DELAY_MS "20"
#define TILT_DEG "10"

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* From the truth log: minus the median of (delay + lateness) over the images sent from the shear
 * axis's first motion to window_s after it (the fit's window). NaN when the axis never moved. */
static double true_offset(rig_run *r, double window_s, double *spread)
{
    char path[160], line[512];
    snprintf(path, sizeof path, "%s/truth.csv", r->dir);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    static double v[20000];
    size_t n = 0;
    double s_first = NAN, t_move = NAN;
    while (fgets(line, sizeof line, f)) {
        double x[12];
        if (sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &x[0], &x[1], &x[2], &x[3], &x[4], &x[5],
                   &x[6], &x[7], &x[8], &x[9], &x[10], &x[11]) != 12)
            continue;
        if (isnan(s_first)) s_first = x[4];
        if (isnan(t_move) && fabs(x[4] - s_first) > 1e-3) t_move = x[1];
        if (isfinite(t_move) && x[1] <= t_move + window_s && n < 20000) v[n++] = x[11] + x[10];
    }
    fclose(f);
    if (n == 0) return NAN;
    qsort(v, n, sizeof *v, cmp_d);
    *spread = v[n * 9 / 10] - v[n / 10];
    return -v[n / 2];
}

static void test_offset_measured_at_60fps(void **state)
{
    (void)state;
    static const char *const sets[] = {"rail.compress.port=%s/grbl", "rail.shear.port=%s/grbl",
                                       "camera.calibration=%s/camera.calib", "store.path=%s/rig.db",
                                       "camera.video_dir=%s/videos", "trial.compress_speed_mm_s=20",
                                       "camera.time_offset=measure", "camera.transcode=off", NULL};
    static const char *const sim_extra[] = {"--camera-delay-ms", DELAY_MS, "--camera-tilt-deg", TILT_DEG, NULL};
    rig_run r;
    rig_start(&r, RIG, sets, sim_extra);
    int rc = rig_trial(&r, 1);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64], ev[700] = "";
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(max(message),'') from events where trial_id = 1 and message like 'camera time offset%'",
               ev, sizeof ev);
    double est = rig_q_num(db, "select camera_offset_s from trials where id = 1");
    double sd = rig_q_num(db, "select camera_offset_sd_s from trials where id = 1");
    double spread = NAN, truth = true_offset(&r, 4.0, &spread);
    printf("# trial %s (ribbonctl %d)\n# %s\n# estimate %+.2f ms +- %.2f ms, truth %+.2f ms (10-90%% of the images "
           "%.2f ms), error %+.2f ms\n",
           status, rc, ev, 1e3 * est, 1e3 * sd, 1e3 * truth, 1e3 * spread, 1e3 * (est - truth));
    assert_string_equal(status, "done");
    assert_non_null(strstr(ev, "used for this trial's Delta W"));
    assert_true(isfinite(truth));
    assert_true(fabs(est - truth) <= 2e-3);
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_passed();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_offset_measured_at_60fps, rig_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
