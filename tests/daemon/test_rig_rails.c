/* test_rig_rails: the rig's rails faults in real time against ribbon-rigsim (issue 13 E), on the
 * rehearsal rig files (config/rig-rehearsal.ini: GRBL axes X/Y of one controller on a pty;
 * config/rig-rehearsal-modbus.ini: two Modbus TCP drives on 127.0.0.1), compression at 20 mm/s so
 * a trial reaches shearing in about 7 s. Faults come on command once the trial is shearing
 * (SIGUSR1 link cut, SIGRTMIN+1 alarm) or on position (--stall). Each ends the trial failed with a
 * named reason, both rails standing (the simulator's axes log), every captured sample stored
 * (samples_count in the trial row = rows in samples) and PRAGMA integrity_check ok.
 *   - GRBL link lost mid-shear: detected (the fault event's wall time) within 0.5 s of the cut the
 *     simulator logged;
 *   - GRBL controller alarm mid-shear; a stalled shear axis;
 *   - Modbus drive fault mid-shear; Modbus link lost mid-shear (0.5 s too);
 *   - ribbond killed with SIGKILL mid-shear with Modbus rails: the drives' watchdog halts the shear
 *     axis within watchdog_s (0.5 s in the rig file) + its deceleration, from the axes log;
 *   - the whole trial with Modbus rails: measured snap within the measurement's error of the twin's
 *     own (the rig file's [twin]; ribbon-rigsim's "twin truth"), regimes agree,
 *     no frame lost or dropped, every frame's stamp within 1 ms of the simulator's send time, both
 *     rails standing at their start at the end;
 *   - the rig simulator killed mid-shear: the trial fails naming the rail, nothing half-written; the
 *     fault is seen within 0.5 s of the kill and the failure stored within 0.5 s of that (the
 *     in-trial fit's worker is waited for after it), and an abort then is refused (issue 33);
 *   - an abort through the API mid-shear (GRBL and Modbus): both rails stand within the stop
 *     distance plus the abort's latency bound, from the axes log.
 * Heavy (real time, about 20-40 s each): normal build only. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <stdint.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include "rig_harness.h"

#define RIG_GRBL RIBBON_SOURCE_DIR "/config/rig-rehearsal.ini"
#define RIG_MODBUS RIBBON_SOURCE_DIR "/config/rig-rehearsal-modbus.ini"
#define DETECT_BOUND_S 0.5 /* issue 13: a lost rail link is detected within 0.5 s */
#define STORE_FINAL_BOUND_S 0.5 /* a fault seen to the failure stored: the samples' last batch and a
                                   few rows, no waits (test_rigsim_dies_mid_shear) */

static const char *const grbl_sets[] = {"rail.compress.port=%s/grbl", "rail.shear.port=%s/grbl",
                                        "camera.calibration=%s/camera.calib", "store.path=%s/rig.db",
                                        "camera.video_dir=%s/videos", "trial.compress_speed_mm_s=20", NULL};

/* The Modbus rig on two free loopback ports. */
static void modbus_sets(char buf[2][64], const char *sets[8])
{
    snprintf(buf[0], sizeof buf[0], "rail.compress.address=127.0.0.1:%d", rig_free_port());
    snprintf(buf[1], sizeof buf[1], "rail.shear.address=127.0.0.1:%d", rig_free_port());
    const char *rest[] = {"camera.calibration=%s/camera.calib", "store.path=%s/rig.db", "camera.video_dir=%s/videos",
                          "trial.compress_speed_mm_s=20", NULL};
    sets[0] = buf[0];
    sets[1] = buf[1];
    for (int k = 0; k < 5; k++) sets[2 + k] = rest[k];
}

/* Starts the rig and a trial, waits until it is shearing (fails the test with the state reached
 * otherwise), then 0.5 s more: mid-shear, before the snap (Delta W near 0.3 is 3 s of shear). */
static void start_to_shear(rig_run *r, const char *rig, const char *const *sets, const char *const *sim_extra)
{
    rig_start(r, rig, sets, sim_extra);
    assert_int_equal(rig_trial(r, 0), 0);
    char got[700];
    if (rig_wait_state(r, "shearing", 90.0, got, sizeof got)) fail_msg("the trial did not reach shearing: %s", got);
    rig_sleep_s(0.5);
}

/* After a fault: the trial ended failed in shearing naming `what`, every sample stored, integrity
 * ok, both axes standing (their last move in the axes log more than 0.3 s before the end, which
 * is after the fault). Returns the fault event's wall time. */
static double check_failed(rig_run *r, const char *what, double t_fault)
{
    assert_int_equal(rig_wait_end(r, 60.0), 0);
    rig_sleep_s(1.0);
    double t_end = rig_now_real();
    rig_stop(r);
    sqlite3 *db = rig_db_open(r);
    char status[64], why[512], st[64];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    rig_q_text(db, "select state from events where trial_id = 1 and kind = 'fault' order by id limit 1", st, sizeof st);
    double seen = rig_event_wall(db, "rail fault%");
    printf("# %s in %s: %s\n", status, st, why);
    assert_string_equal(status, "failed");
    assert_string_equal(st, "shearing");
    assert_non_null(strstr(why, what));
    double stored = rig_q_num(db, "select count(*) from samples where trial_id = 1");
    double counted = rig_q_num(db, "select samples_count from trials where id = 1");
    printf("# samples: %.0f stored, %.0f counted in the trial\n", stored, counted);
    assert_true(stored > 100);
    assert_true(stored == counted);
    rig_check_integrity(db);
    sqlite3_close(db);
    double lc = rig_truth_last_move(r, 0), ls = rig_truth_last_move(r, 1);
    printf("# axes: compression last moved %.3f s, shear %.3f s after the fault\n", lc - t_fault, ls - t_fault);
    assert_true(!isfinite(lc) || lc < t_end - 0.3);
    assert_true(isfinite(ls) && ls < t_end - 0.3);
    return seen;
}

static void link_lost(const char *rig, const char *const *sets, const char *what)
{
    rig_run r;
    start_to_shear(&r, rig, sets, NULL);
    kill(r.sim, SIGUSR1);
    rig_sleep_s(0.2);
    double cut = rig_sim_fault_time(&r, "link lost");
    assert_true(isfinite(cut));
    double seen = check_failed(&r, what, cut);
    printf("# link lost: detected %.3f s after the cut (bound %.1f s)\n", seen - cut, DETECT_BOUND_S);
    assert_true(seen - cut > 0.0);
    assert_true(seen - cut <= DETECT_BOUND_S);
}

static void test_grbl_link_lost_mid_shear(void **state)
{
    (void)state;
    link_lost(RIG_GRBL, grbl_sets, "rail");
    rig_passed();
}

static void test_modbus_link_lost_mid_shear(void **state)
{
    (void)state;
    char buf[2][64];
    const char *sets[8] = {0};
    modbus_sets(buf, sets);
    link_lost(RIG_MODBUS, sets, "rail");
    rig_passed();
}

/* An alarm on command mid-shear (SIGRTMIN+1): GRBL's ALARM:1 of the controller, or the shear drive's
 * alarm 0x30 (a drive fault). */
static void alarm_mid_shear(const char *rig, const char *const *sets, const char *sim_fault, const char *what)
{
    rig_run r;
    start_to_shear(&r, rig, sets, NULL);
    kill(r.sim, SIGRTMIN + 1);
    rig_sleep_s(0.2);
    double t = rig_sim_fault_time(&r, sim_fault);
    assert_true(isfinite(t));
    double seen = check_failed(&r, what, t);
    printf("# %s: detected %.3f s after it was raised\n", sim_fault, seen - t);
    assert_true(seen - t <= DETECT_BOUND_S);
}

static void test_grbl_alarm_mid_shear(void **state)
{
    (void)state;
    alarm_mid_shear(RIG_GRBL, grbl_sets, "controller alarm", "GRBL alarm 1");
    rig_passed();
}

static void test_modbus_drive_fault_mid_shear(void **state)
{
    (void)state;
    char buf[2][64];
    const char *sets[8] = {0};
    modbus_sets(buf, sets);
    alarm_mid_shear(RIG_MODBUS, sets, "drive alarm", "rail shear");
    rig_passed();
}

/* The shear axis stalls 20 mm into the shear (2 s at 10 mm/s, before the snap near 84 mm):
 * GRBL's open loop sees no progress for stall_timeout_s (1 s); the Modbus drive raises its
 * position-deviation alarm. */
static void stall_mid_shear(const char *rig, const char *const *sets, const char *what)
{
    rig_run r;
    const char *extra[] = {"--stall", "Y:70", NULL};
    rig_start(&r, rig, sets, extra);
    assert_int_equal(rig_trial(&r, 0), 0);
    char got[700];
    if (rig_wait_state(&r, "shearing", 90.0, got, sizeof got)) fail_msg("the trial did not reach shearing: %s", got);
    double t = rig_now_real();
    check_failed(&r, what, t);
}

static void test_grbl_stall_mid_shear(void **state)
{
    (void)state;
    stall_mid_shear(RIG_GRBL, grbl_sets, "stall");
    rig_passed();
}

static void test_modbus_stall_mid_shear(void **state)
{
    (void)state;
    char buf[2][64];
    const char *sets[8] = {0};
    modbus_sets(buf, sets);
    stall_mid_shear(RIG_MODBUS, sets, "rail shear");
    rig_passed();
}

/* ribbond killed mid-shear with Modbus rails: nobody talks to the drives, whose watchdog
 * (watchdog_s = 0.5 in the rig file) halts the shear axis: from the simulator's axes log. */
static void test_modbus_sigkill_mid_shear(void **state)
{
    (void)state;
    char buf[2][64];
    const char *sets[8] = {0};
    modbus_sets(buf, sets);
    rig_run r;
    start_to_shear(&r, RIG_MODBUS, sets, NULL);
    double t_kill = rig_now_real();
    kill(r.daemon, SIGKILL);
    waitpid(r.daemon, NULL, 0);
    r.daemon = -1;
    rig_sleep_s(2.0);
    rig_stop(&r);
    double ls = rig_truth_last_move(&r, 1);
    printf("# SIGKILL mid-shear (Modbus): the shear axis stood %.3f s after the kill (watchdog 0.5 s)\n",
           ls - t_kill);
    assert_true(isfinite(ls));
    assert_true(ls - t_kill > 0.0);
    /* The watchdog counts from the last request, which came before the kill; the drive halts at
     * once (mb_sim's alarm 0x85); the axes log has 5 ms lines and the drive thread a 1 ms step. */
    assert_true(ls - t_kill <= 0.5 + 0.05);
    /* and it did not stop by itself before the watchdog: the shear was running when killed */
    assert_true(ls - t_kill > 0.3);
    rig_passed();
}

/* From the simulator's axes log: axis col's position at real time t (the last line at or before
 * it) and at the end of the log. */
static void axis_at(rig_run *r, int col, double t, double *at_t, double *at_end)
{
    char path[160], line[512];
    snprintf(path, sizeof path, "%s/axes.csv", r->dir);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(line, sizeof line, f));
    *at_t = *at_end = NAN;
    while (fgets(line, sizeof line, f)) {
        double mono, real, pc, ps;
        if (sscanf(line, "%lf,%lf,%lf,%lf", &mono, &real, &pc, &ps) != 4) continue;
        double v = col ? ps : pc;
        if (real <= t) *at_t = v;
        *at_end = v;
    }
    fclose(f);
}

/* POST /trials/current/abort mid-shear: the abort's stop. Against the
 * simulator's axes log (its truth, not the daemon's view): the trial ends aborted, the
 * compression rail (holding) does not move after the abort, and the shear rail, moving at v, comes
 * to rest within v^2 / (2 a) (a = 200 mm/s^2, the rig file's and the controller's) plus v times
 * the abort's latency bound, and within that latency plus v / a of the abort. The latency bound,
 * 0.25 s, covers the request, the runner's next look (one frame at 60 fps) and the rails' lock
 * (one poll in flight). */
#define ABORT_LATENCY_S 0.25
/* POST /trials/current/abort from this process (no client program to start: its start-up under
 * load took 0.6 s here, which is not the daemon's latency); returns the HTTP status. */
static int post_abort(const char *url)
{
    int port = 0;
    assert_int_equal(sscanf(url, "http://127.0.0.1:%d", &port), 1);
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    assert_true(fd >= 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    assert_int_equal(connect(fd, (struct sockaddr *)&a, sizeof a), 0);
    const char req[] = "POST /trials/current/abort HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 0\r\n"
                       "Connection: close\r\n\r\n";
    assert_int_equal(write(fd, req, sizeof req - 1), (ssize_t)(sizeof req - 1));
    struct timeval tv = {5, 0};
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    char buf[512] = "";
    ssize_t n = read(fd, buf, sizeof buf - 1);
    close(fd);
    int status = 0;
    if (n > 0 && sscanf(buf, "HTTP/1.%*d %d", &status) != 1) status = 0;
    return status;
}

static void abort_mid_shear(const char *rig, const char *const *sets)
{
    rig_run r;
    start_to_shear(&r, rig, sets, NULL);
    double t0 = rig_now_real();
    assert_int_equal(post_abort(r.url), 200);
    assert_int_equal(rig_wait_end(&r, 30.0), 0);
    rig_sleep_s(1.0);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_check_integrity(db);
    sqlite3_close(db);
    assert_string_equal(status, "aborted");
    double c0, c1, s0, s1, s_before, dummy;
    axis_at(&r, 0, t0, &c0, &c1);
    axis_at(&r, 1, t0, &s0, &s1);
    axis_at(&r, 1, t0 - 0.2, &s_before, &dummy);
    double v = (s0 - s_before) / 0.2, a = 200.0;
    double bound_mm = v * v / (2.0 * a) + fabs(v) * ABORT_LATENCY_S;
    double ls = rig_truth_last_move(&r, 1), lc = rig_truth_last_move(&r, 0);
    printf("# abort mid-shear: shear at %.2f mm/s stood %.3f mm and %.3f s after the abort (bounds %.3f mm, "
           "%.3f s); compression moved %.4f mm after it\n",
           v, s1 - s0, ls - t0, bound_mm, ABORT_LATENCY_S + fabs(v) / a, c1 - c0);
    assert_true(fabs(v) > 1.0); /* the shear was moving when aborted */
    assert_true(fabs(s1 - s0) <= bound_mm);
    assert_true(ls - t0 <= ABORT_LATENCY_S + fabs(v) / a + 0.01); /* + the axes log's 5 ms lines */
    assert_true(fabs(c1 - c0) <= 1e-3);
    assert_true(!isfinite(lc) || lc <= t0 + ABORT_LATENCY_S);
}

static void test_grbl_abort_mid_shear(void **state)
{
    (void)state;
    abort_mid_shear(RIG_GRBL, grbl_sets);
    rig_passed();
}

static void test_modbus_abort_mid_shear(void **state)
{
    (void)state;
    char buf[2][64];
    const char *sets[8] = {0};
    modbus_sets(buf, sets);
    abort_mid_shear(RIG_MODBUS, sets);
    rig_passed();
}

/* The rig simulator itself killed mid-shear: the GRBL pty hangs up (and the camera goes silent):
 * the trial fails with a named reason, the store is whole. */
static void test_rigsim_dies_mid_shear(void **state)
{
    (void)state;
    rig_run r;
    start_to_shear(&r, RIG_GRBL, grbl_sets, NULL);
    double t_kill = rig_now_real();
    kill(r.sim, SIGKILL);
    waitpid(r.sim, NULL, 0);
    r.sim = -1;
    assert_int_equal(rig_wait_end(&r, 30.0), 0);
    double t_ended = rig_now_real();
    /* Issue 33, item 13: the trial read "running" 12 s after the fault was seen (the dead camera's
     * close came before the final status), and an abort then answered 200 "requested". */
    char cmd[600], out[600] = "";
    snprintf(cmd, sizeof cmd, "%s/ribbonctl abort --url %s > %s/abort.txt 2>&1", RIBBON_BIN_DIR, r.url, r.dir);
    int abort_rc = system(cmd);
    snprintf(cmd, sizeof cmd, "%s/abort.txt", r.dir);
    rig_file_has(cmd, "", out, sizeof out);
    printf("# rig simulator killed: the store read the trial ended %.2f s after the kill; abort then: exit %d, %s\n",
           t_ended - t_kill, WIFEXITED(abort_rc) ? WEXITSTATUS(abort_rc) : -1, out);
    assert_true(WIFEXITED(abort_rc) && WEXITSTATUS(abort_rc) != 0);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    /* What the time from the kill to the stored failure is made of: the fault seen (the pty's
     * hang-up, the camera's silence: DETECT_BOUND_S, issue 13), then the record closed (the
     * samples' last batch, the result and the final status: rows, not waits). The in-trial fit's
     * worker is not in it: it is cancelled and waited for after the final status (its prediction
     * cannot be interrupted; before, the final status waited for it: 2.43 s of 2.91 s measured
     * at load 20, and 3.39 s in all under load). */
    double t_fault = rig_event_wall(db, "rail fault in shearing%");
    double t_stored = rig_q_num(db, "select (julianday(ended_at) - 2440587.5) * 86400.0 from trials where id = 1");
    double t_fit = rig_event_wall(db, "calibrated prediction fit % landed%");
    printf("# rig simulator killed: fault seen %.3f s after the kill, failure stored %.3f s after the fault; the "
           "fit beside the trial %s\n", t_fault - t_kill, t_stored - t_fault,
           !isfinite(t_fit) ? "never landed" : t_fit > t_fault ? "landed after the fault" : "landed before the fault");
    assert_true(t_fault - t_kill <= DETECT_BOUND_S);
    assert_true(t_stored - t_fault <= STORE_FINAL_BOUND_S);
    /* The whole, as the harness sees it: both bounds and its 0.1 s poll. */
    assert_true(t_ended - t_kill < DETECT_BOUND_S + STORE_FINAL_BOUND_S + 0.1);
    char status[64], why[512];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    printf("# rig simulator killed: %s: %s\n", status, why);
    assert_string_equal(status, "failed");
    /* The controller's pty hung up: the rail is named (the camera's silence may follow it). */
    assert_non_null(strstr(why, "rail"));
    double stored = rig_q_num(db, "select count(*) from samples where trial_id = 1");
    double counted = rig_q_num(db, "select samples_count from trials where id = 1");
    assert_true(stored > 100);
    assert_true(stored == counted);
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_passed();
}

/* The whole trial with Modbus TCP rails: done, the measured snap within the measurement's error of
 * the twin's own snap, the regimes agree, no frame lost, incomplete or dropped, every video frame's
 * stamp within 1 ms of the simulator's true send time, both rails standing where they started. */
static void test_modbus_trial(void **state)
{
    (void)state;
    char buf[2][64];
    const char *sets[8] = {0};
    modbus_sets(buf, sets);
    rig_run r;
    rig_start(&r, RIG_MODBUS, sets, NULL);
    int rc = rig_trial(&r, 1);
    rig_sleep_s(1.0);
    double t_end = rig_now_real();
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512], rm[32], rp[32], lat[400], path_show[160];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    printf("# trial: %s %s (ribbonctl %d)\n", status, why, rc);
    assert_string_equal(status, "done");
    double meas = rig_q_num(db, "select snap_dw_measured from trials where id = 1");
    double pred = rig_q_num(db, "select snap_dw from predictions where trial_id = 1");
    rig_q_text(db, "select regime_measured from trials where id = 1", rm, sizeof rm);
    rig_q_text(db, "select regime from predictions where trial_id = 1", rp, sizeof rp);
    rig_q_text(db, "select message from events where trial_id = 1 and message like 'snap-to-stop latency%'", lat, sizeof lat);
    printf("# measured %.5f predicted %.5f (%+.2f%%; %s / %s)\n# %s\n", meas, pred, 100.0 * (meas - pred) / pred, rm,
           rp, lat);
    /* What the camera showed near the snap: the twin's image age at each send (truth log column
     * 11). An image older than a frame period shows the ribbon where it was, not where it is. */
    char tpath[160], tl[512];
    snprintf(tpath, sizeof tpath, "%s/truth.csv", r.dir);
    FILE *tf = fopen(tpath, "r");
    assert_non_null(tf);
    double age_max = 0.0;
    while (fgets(tl, sizeof tl, tf)) {
        double v[11];
        if (sscanf(tl, "%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], &v[1], &v[2], &v[3], &v[4], &v[5], &v[6],
                   &v[7], &v[8], &v[9], &v[10]) == 11 &&
            fabs(v[6] - pred) < 0.02)
            age_max = fmax(age_max, v[10]);
    }
    fclose(tf);
    printf("# the twin's images near the snap were at most %.0f ms old when sent\n", 1e3 * age_max);
    /* The twin is the rig file's [twin] strip, not the prediction's: scored against its own snap
     * (ribbon-rigsim's "twin truth") within the measurement's error (rig_onset_bound). */
    char treg[16];
    double truth = rig_twin_truth(&r, treg, sizeof treg);
    double age = rig_truth_image_age(&r, truth, 0.02);
    double gap = rig_truth_frame_gap(&r, truth, 0.005);
    double bound = rig_onset_bound(0.01 / 0.2, 60.0, gap, 1.5e-3, age);
    printf("# twin truth %.5f %s; measured - truth %+.5f (bound %.5f, frames up to %.0f ms apart), predicted - truth "
           "%+.2f%%\n",
           truth, treg, meas - truth, bound, 1e3 * gap, 100.0 * (pred - truth) / truth);
    assert_true(isfinite(truth));
    assert_true(fabs(meas - truth) <= bound);
    assert_string_equal(treg, "asymmetric");
    assert_string_equal(rm, treg);
    assert_string_equal(rp, treg);
    assert_true(fabs(pred - truth) < 0.10 * truth);
    /* no frame lost or dropped, every one recorded, each stamp within 1 ms of its true send time */
    rig_pipeline pl = rig_pipeline_counts(db);
    assert_true(pl.captured > 0);
    assert_int_equal(pl.lost + pl.incomplete + pl.dropped, 0);
    assert_int_equal(pl.recorded, pl.captured);
    rig_check_stamps(&r, pl.recorded);
    /* The snap-to-stop latency is stored with the trial (the event's numbers, ms to 0.1) and shown. */
    double lc_s = rig_q_num(db, "select stop_cmd_latency_s from trials where id = 1");
    double ls_s = rig_q_num(db, "select stop_stand_latency_s from trials where id = 1");
    double ev_c = NAN;
    const char *arrow = strstr(lat, "stop command ");
    if (arrow) ev_c = atof(arrow + strlen("stop command ")) / 1e3;
    printf("# stored latency: %.1f ms to the stop command, %.1f ms to the rail standing\n", 1e3 * lc_s, 1e3 * ls_s);
    assert_true(isfinite(lc_s) && lc_s >= 0.0 && lc_s < 1.0);
    assert_true(fabs(lc_s - ev_c) < 1e-4);
    assert_true(isnan(ls_s) || ls_s >= lc_s);
    char cmd[400], shown[400];
    snprintf(cmd, sizeof cmd, "%s/ribbonctl show 1 --db %s/rig.db > %s/show.txt 2>&1", RIBBON_BIN_DIR, r.dir, r.dir);
    assert_int_equal(system(cmd), 0);
    snprintf(path_show, sizeof path_show, "%s/show.txt", r.dir);
    assert_true(rig_file_has(path_show, "snap-to-stop latency", shown, sizeof shown));
    printf("# ribbonctl show: %s", shown);
    rig_check_integrity(db);
    sqlite3_close(db);
    /* Both axes standing at the end, at their start (the shear at its zero, 50 mm). */
    /* The start: the axes log's first line, before the trial (the first stored rail reading may
     * come after the compression began: 90.161 mm was seen under load). */
    char path[160], line[256], first[256] = "", last[256] = "";
    snprintf(path, sizeof path, "%s/axes.csv", r.dir);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(line, sizeof line, f)); /* the header */
    while (fgets(line, sizeof line, f)) {
        if (!first[0]) snprintf(first, sizeof first, "%s", line);
        snprintf(last, sizeof last, "%s", line);
    }
    fclose(f);
    double mono, real, pc, ps, start_c, start_s;
    assert_int_equal(sscanf(first, "%lf,%lf,%lf,%lf", &mono, &real, &start_c, &start_s), 4);
    assert_int_equal(sscanf(last, "%lf,%lf,%lf,%lf", &mono, &real, &pc, &ps), 4);
    double lc = rig_truth_last_move(&r, 0), ls = rig_truth_last_move(&r, 1);
    printf("# end: compression at %.3f mm (started %.3f), shear at %.3f mm; last moves %.1f s and %.1f s before "
           "the end\n",
           pc, start_c, ps, t_end - lc, t_end - ls);
    assert_true(fabs(pc - start_c) < 0.05);
    assert_true(fabs(ps - 50.0) < 0.05);
    assert_true(lc < t_end - 0.5 && ls < t_end - 0.5);
    rig_passed();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_grbl_link_lost_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_modbus_link_lost_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_grbl_alarm_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_modbus_drive_fault_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_grbl_stall_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_modbus_stall_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_modbus_sigkill_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_rigsim_dies_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_grbl_abort_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_modbus_abort_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_modbus_trial, rig_teardown),
    };
    /* RIG_TEST_FILTER=PATTERN runs only the matching tests (cmocka's filter, * wildcards). */
    if (getenv("RIG_TEST_FILTER")) cmocka_set_test_filter(getenv("RIG_TEST_FILTER"));
    return cmocka_run_group_tests(tests, NULL, NULL);
}
