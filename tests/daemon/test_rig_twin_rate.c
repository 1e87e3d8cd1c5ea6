/* test_rig_twin_rate: ribbon-rigsim's camera films the twin at the camera's own rate through a snap
 * (docs/rig-realtime.md, "One state per frame"). One Modbus trial in real time (the case of the
 * regime flake: test_rig_rails' Modbus trial once read symmetric a snap whose whole passage fell
 * between two renders, frame 852 |A| 0.244, frame 853 0.389), compression at 20 mm/s, about 40 s.
 *
 * From the simulator's truth log, over every image sent while the shear is within 0.02 of the
 * twin's own snap (the snap, its vibration and the hold after it, where the solver is slowest):
 * - no image repeats the previous one's state (the twin time each shows strictly increases: no
 *   silent duplicate when the solver is slow);
 * - each image's timestamp is the instant the state it shows stands for (stamp - camera delay -
 *   shown instant, the column image_age_s, within a frame period: a late state is stamped late,
 *   not passed off as new);
 * and ribbond's stored frame times match those stamps within 1 ms (rig_check_stamps); the measured
 * snap and regime agree with the twin's own, within the bound of the frames' actual spacing. The
 * frames' delivery lateness (send - stamp) and the share of exact states are printed. Heavy. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rig_harness.h"

#define RIG_MODBUS RIBBON_SOURCE_DIR "/config/rig-rehearsal-modbus.ini"
#define FPS 60.0
#define SPAN_DW 0.02 /* the window around the twin's snap, in Delta W */

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* What the truth log says of the images sent near Delta W = snap_dw. */
typedef struct frames_seen {
    long n, repeats, stamp_off;   /* images, repeated states, stamps more than a period off */
    double worst_stamp_s;         /* the largest |stamp - delay - shown| */
    double max_gap_s;             /* the largest step between two images' shown instants */
    double late_med_s, late_max_s; /* send - stamp (delivery lateness), when the log has it */
} frames_seen;

static frames_seen truth_frames(rig_run *r, double snap_dw)
{
    char path[160], line[512];
    snprintf(path, sizeof path, "%s/truth.csv", r->dir);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    static double late[40000];
    frames_seen s = {0};
    size_t nl = 0;
    double prev_t = NAN, prev_shown = NAN;
    while (fgets(line, sizeof line, f)) {
        double v[13];
        const int got = sscanf(line, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3],
                               &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10], &v[11], &v[12]);
        if (got < 12 || v[8] != 0.0 || fabs(v[6] - snap_dw) >= SPAN_DW) {
            prev_t = prev_shown = NAN;
            continue;
        }
        const double shown = v[1] - v[11] - v[10]; /* the instant the image shows (host monotonic) */
        s.n++;
        if (isfinite(prev_t) && !(v[9] > prev_t)) s.repeats++;
        if (isfinite(prev_shown)) s.max_gap_s = fmax(s.max_gap_s, shown - prev_shown);
        s.worst_stamp_s = fmax(s.worst_stamp_s, fabs(v[10]));
        if (fabs(v[10]) > 1.0 / FPS) s.stamp_off++;
        if (got == 13 && nl < 40000) late[nl++] = v[12] - v[1];
        prev_t = v[9];
        prev_shown = shown;
    }
    fclose(f);
    if (nl) {
        qsort(late, nl, sizeof *late, cmp_d);
        s.late_med_s = late[nl / 2];
        s.late_max_s = late[nl - 1];
    }
    return s;
}

static void test_snap_filmed_at_the_camera_rate(void **state)
{
    (void)state;
    char buf[2][64];
    snprintf(buf[0], sizeof buf[0], "rail.compress.address=127.0.0.1:%d", rig_free_port());
    snprintf(buf[1], sizeof buf[1], "rail.shear.address=127.0.0.1:%d", rig_free_port());
    const char *sets[] = {buf[0], buf[1], "camera.calibration=%s/camera.calib", "store.path=%s/rig.db",
                          "camera.video_dir=%s/videos", "trial.compress_speed_mm_s=20", "camera.transcode=off",
                          NULL};
    rig_run r;
    rig_start(&r, RIG_MODBUS, sets, NULL);
    int rc = rig_trial(&r, 1);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512], rm[32], treg[16];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    rig_q_text(db, "select coalesce(regime_measured,'') from trials where id = 1", rm, sizeof rm);
    double meas = rig_q_num(db, "select snap_dw_measured from trials where id = 1");
    double truth = rig_twin_truth(&r, treg, sizeof treg);
    printf("# trial: %s %s (ribbonctl %d); measured %.5f %s, twin truth %.5f %s\n", status, why, rc, meas, rm, truth,
           treg);
    assert_string_equal(status, "done");
    assert_true(isfinite(truth));
    frames_seen s = truth_frames(&r, truth);
    printf("# near the snap (Delta W within %.2f of it): %ld images, %ld repeated the previous state, %ld stamped "
           "more than a frame period from the state they show (worst %.2f ms); largest step between two images' "
           "states %.1f ms; delivery lateness median %.1f ms, max %.1f ms\n",
           SPAN_DW, s.n, s.repeats, s.stamp_off, 1e3 * s.worst_stamp_s, 1e3 * s.max_gap_s, 1e3 * s.late_med_s,
           1e3 * s.late_max_s);
    assert_true(s.n > (long)FPS); /* the snap, its vibration and the hold: over a second of images */
    assert_int_equal(s.repeats, 0);
    assert_int_equal(s.stamp_off, 0);
    /* ribbond got those stamps: every stored frame time within 1 ms of the truth log's instant */
    rig_pipeline pl = rig_pipeline_counts(db);
    rig_check_stamps(&r, pl.recorded);
    /* Measured right: the twin's regime, and its onset within one step between images (the frames'
     * own spacing, no less than a frame period), one twin step and the stamps' 1 ms, of shear. */
    double bound = rig_onset_bound(0.01 / 0.2, 1.0 / fmax(s.max_gap_s, 1.0 / FPS), 1.5e-3, 0.0);
    printf("# measured - twin truth %+.5f (bound %.5f)\n", meas - truth, bound);
    assert_string_equal(treg, "asymmetric");
    assert_string_equal(rm, treg);
    assert_true(fabs(meas - truth) <= bound);
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_passed();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_snap_filmed_at_the_camera_rate, rig_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
