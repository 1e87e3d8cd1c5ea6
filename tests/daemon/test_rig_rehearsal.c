/* test_rig_rehearsal: rig mode end to end in real time against ribbon-rigsim (issue 13 E): the GRBL
 * controller's two axes on a pty, the twin filmed by the GigE Vision camera on 127.0.0.1, ribbond
 * on config/rig-rehearsal.ini (compression at 20 mm/s so a trial takes about 30 s).
 *   - the camera calibrated as a lab must (ribbonctl calibrate-camera: clamps in the live stream
 *     at zero shear), within 1% in scale and 1.5 px of ribbon-rigsim's exact file; ribbond measures
 *     with it (the G-code trial and the Gamma 0.21 one);
 *   - a whole trial: done, the measured snap within the measurement's error of the twin's own
 *     (the rig file's [twin], another strip than the prediction's; ribbon-rigsim's "twin truth"),
 *     the prediction off it by more than that, regimes asymmetric, the compression's last 0.05 of
 *     Delta L tracked with the clamp point moved (Delta Z against the twin's logged truth), no frame lost or dropped, every video frame in the frame-times file, each
 *     frame's stamp against the simulator's true send time (every one within 1 ms), the snap-to-stop latency
 *     stored, PRAGMA integrity_check ok; a calibrated prediction with its band stored, closer to
 *     the measurement than the scene's prediction and the measurement inside its 2-sigma band;
 * Faults come on command (SIGUSR1 / SIGUSR2 to ribbon-rigsim) once the trial is shearing.
 *   (the rails' faults, link lost among them, are test_rig_rails's);
 *   - the camera stops sending mid-shear: failed naming the camera, within 0.5 s;
 *   - the image freezes mid-shear: failed naming it (the rig file's camera.frozen_frames, 20 here),
 *     within 0.5 s, rails stopped;
 *   - GVSP packets lost: counted and noted, the trial done; lost heavily: failed, named, rails stopped;
 *   - bad camera input (no such camera, a region outside the sensor, an exposure and a gain outside
 *     the camera's GenICam bounds, frames not the calibration's size): named, the rails never moved
 *     (the simulator's axes log), nothing stored but the failed trial; `ribbonctl cameras` finds
 *     the camera.
 *   - the same at Gamma 0.21: the twin's truth, the prediction and the measured regime symmetric
 *     (the 0.5 rad pathway rule, sim/rod_regime.h);
 *   - ribbond killed with SIGKILL mid-shear: the shear axis stands within the GRBL driver's bound
 *     (its queued jog segments) as the simulator's truth log shows.
 * The rig is started and stopped by tests/daemon/rig_harness.c, whose teardown kills what a failed
 * test left running. Heavy (real time, a minute or more each): normal build only. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "rig_harness.h"

#define BIN RIBBON_BIN_DIR
#define RIG RIBBON_SOURCE_DIR "/config/rig-rehearsal.ini"

static const char *const rehearsal_sets[] = {"rail.compress.port=%s/grbl", "rail.shear.port=%s/grbl",
                                             "camera.calibration=%s/camera.calib", "store.path=%s/rig.db",
                                             "camera.video_dir=%s/videos", "trial.compress_speed_mm_s=20", NULL};

/* The lab's calibration (issue 34 C): `ribbonctl calibrate-camera` finds the clamps in the
 * simulator's live camera stream with the specimen mounted at Delta L dl, zero shear (the distance
 * 1000 mm as a lab measures it with a tape), and ribbond measures with that file, not with the
 * exact one ribbon-rigsim writes (camera.calib, kept for the comparison). Against the exact file,
 * measured on the rehearsal's level camera at dl 0.2: scale -0.57%, clamp points within 0.94 px
 * (the jaw face's perspective bias, vis_track.h, pulls both points toward the image centre). The
 * bounds asserted: 1% and 1.5 px. */
static double calib_num(const char *path, const char *key, int k)
{
    char line[256];
    double v[2] = {NAN, NAN};
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, key, strlen(key)) && line[strlen(key)] == ' ')
            sscanf(strchr(line, '=') + 1, "%lf , %lf", &v[0], &v[1]);
    fclose(f);
    return v[k];
}

static void lab_calibrate(rig_run *r, const char *dl)
{
    char out[160], exact[160], cmd[4096];
    snprintf(out, sizeof out, "%s/camera.lab.calib", r->dir);
    snprintf(exact, sizeof exact, "%s/camera.calib", r->dir);
    int n = snprintf(cmd, sizeof cmd, BIN "/ribbonctl calibrate-camera --config " RIG " --dl %s --camera-distance-mm 1000 --out %s",
                     dl, out);
    for (int k = 0; k < r->n_sets; k++) n += snprintf(cmd + n, sizeof cmd - (size_t)n, " --set '%s'", r->sets[k]);
    assert_true(n < (int)sizeof cmd - 1);
    assert_int_equal(system(cmd), 0);
    const double s_lab = calib_num(out, "px_per_mm", 0), s_ex = calib_num(exact, "px_per_mm", 0);
    double worst = 0.0;
    for (int k = 0; k < 2; k++) {
        worst = fmax(worst, fabs(calib_num(out, "clamp_left", k) - calib_num(exact, "clamp_left", k)));
        worst = fmax(worst, fabs(calib_num(out, "clamp_right", k) - calib_num(exact, "clamp_right", k)));
    }
    printf("# lab calibration against the exact file: scale %.5f px/mm (%+.2f%%), clamp points within %.2f px\n", s_lab,
           100.0 * (s_lab - s_ex) / s_ex, worst);
    assert_true(fabs(s_lab - s_ex) <= 0.01 * s_ex);
    assert_true(worst <= 1.5);
    char set[300];
    snprintf(set, sizeof set, "camera.calibration=%s", out);
    rig_daemon_set(r, set);
}

/* Starts the simulator (with extra args) and ribbond (with daemon_set, when not NULL, for it only). */
static void start_with(rig_run *r, const char *const *sim_extra, const char *daemon_set, int lab_calib)
{
    rig_prepare(r, rehearsal_sets);
    rig_start_sim(r, RIG, sim_extra);
    if (lab_calib) lab_calibrate(r, "0.2");
    if (daemon_set) rig_daemon_set(r, daemon_set);
    rig_start_daemon(r, RIG);
}

static void start(rig_run *r, const char *const *sim_extra) { start_with(r, sim_extra, NULL, 0); }

/* The rehearsal's twin is the rig file's [twin] strip (creases 86 deg, 2.5% unequal, N = 91,
 * dt = 1.5 ms), not the scene the prediction uses: the measured snap is scored against the twin's
 * own (ribbon-rigsim's "twin truth" line) within the measurement's error (rig_onset_bound: one
 * frame at 60 fps or the longest interval between the simulator's images near the snap when it
 * stalled, one twin step, the stamps' 1 ms and the oldest image sent near the snap), the
 * regimes against the twin's, and the prediction is off the truth by more than that error and
 * less than 10% (a different strip). */
static void score_against_twin(rig_run *r, double meas, double pred, const char *rm, const char *rp,
                               const char *want_regime)
{
    char treg[16];
    double truth = rig_twin_truth(r, treg, sizeof treg);
    double age = rig_truth_image_age(r, truth, 0.02), gap = rig_truth_frame_gap(r, truth, 0.005);
    double bound = rig_onset_bound(0.01 / 0.2, 60.0, gap, 1.5e-3, age);
    printf("# twin truth %.5f %s; measured - truth %+.5f (%.2f frames; bound %.5f with images up to %.0f ms old, "
           "%.0f ms apart), predicted - truth %+.5f (%+.2f%%)\n",
           truth, treg, meas - truth, (meas - truth) / (0.05 / 60.0), bound, 1e3 * age, 1e3 * gap, pred - truth,
           100.0 * (pred - truth) / truth);
    assert_true(isfinite(truth));
    assert_string_equal(treg, want_regime);
    assert_true(fabs(meas - truth) <= bound);
    assert_string_equal(rp, want_regime);
    assert_string_equal(rm, want_regime);
    assert_true(fabs(pred - truth) > 3.0 * rig_onset_bound(0.01 / 0.2, 60.0, 0.0, 1.5e-3, 0.0));
    assert_true(fabs(pred - truth) < 0.10 * truth);
    /* The same two lines beside the truth log: what the twin is, and its own snap. */
    char side[160], line[1024];
    snprintf(side, sizeof side, "%s/truth.csv.twin", r->dir);
    assert_true(rig_file_has(side, "twin: N = 91, dt = 0.0015 s; [twin] folds.angle_deg=-86", line, sizeof line));
    assert_true(rig_file_has(side, "twin truth: snap Delta W = ", line, sizeof line));
}

/* The calibrated prediction (issue 32 B and D, docs/calibration.md "In every trial"), made in real
 * time beside the trial: the rig file's twin (creases -87.1 and -84.9 deg, compliant hinges of
 * 5e-3 N m/rad, N = 91) is another strip than the scene's (-90 deg, equal, rigid; N = 61), and the
 * fit (the rig file's sim.fit_hinge: both angles and the creases as hinges from the guess
 * 3.5e-3 N m/rad, each with a prior) learns it from the hold and the shear before the snap (rig
 * mode tracks no compression frames). It must be stored with a band, closer to the measurement
 * than the scene's prediction and inside its own 2-sigma band; the margins are printed. Before
 * (the twin's creases rigid at N = 91, the fit's rigid at N = 61, angles only): 0.41978 +- 0.0027
 * against the measured 0.40575 (+3.46%, 5.2 sigma; the scene +4.09%): a rigid crease's stiffness
 * is one node's, and the fit soaked the meshes' difference into the angles. */
static void score_calibrated(rig_run *r, sqlite3 *db, double meas, double pred)
{
    double cal = rig_q_num(db, "select snap_dw_calibrated from trials where id = 1");
    double sd = rig_q_num(db, "select snap_sd_calibrated from trials where id = 1");
    char reg[32] = "", fail[400] = "", kept[600] = "";
    rig_q_text(db, "select coalesce(regime_calibrated,'') from trials where id = 1", reg, sizeof reg);
    rig_q_text(db, "select coalesce(fit_failure,'') from trials where id = 1", fail, sizeof fail);
    rig_q_text(db, "select message from events where trial_id = 1 and message like 'calibrated prediction stored%'",
               kept, sizeof kept);
    char treg[16];
    double truth = rig_twin_truth(r, treg, sizeof treg);
    printf("# calibrated %.5f +- %.5f %s%s%s; calibrated - measured %+.5f (%+.2f%%, %.2f of the 2-sigma band), "
           "predicted - measured %+.5f (%+.2f%%), |calibrated error| / |scene's| %.2f, calibrated - truth %+.5f\n# %s\n",
           cal, sd, reg, fail[0] ? "; failed: " : "", fail, cal - meas, 100.0 * (cal - meas) / meas,
           fabs(cal - meas) / (2.0 * sd), pred - meas, 100.0 * (pred - meas) / meas, fabs(cal - meas) / fabs(pred - meas),
           cal - truth, kept);
    assert_string_equal(fail, "");
    assert_true(isfinite(cal) && isfinite(sd) && sd > 0.0 && reg[0]);
    assert_non_null(strstr(kept, "calibrated prediction stored"));
    /* Issue 32 D's e2e target. Before the refreshes' cut (every shear frame fitted) it held on a
     * loaded machine (-2.45% to -0.49% against the scene's +6%) and not on a quiet one, whose last
     * refresh fitted the shear to 0.89-0.94 of the way to the snap: +9.35% (1.10 of the 2-sigma
     * band) and +7.12%. A refresh now fits the shear below TRIAL_CALIBRATE_SHEAR_CUT (0.8) of the
     * latest predicted snap: refitted offline, that trial's frames give +0.4% where the shear to
     * 0.9 gave +7.3% (docs/calibration.md "In every trial"). */
    assert_true(fabs(cal - meas) < fabs(pred - meas));
    assert_true(fabs(cal - meas) <= 2.0 * sd);
    /* A stored refresh fitted the shear below its limit only (NaN: fit 0, from the hold). */
    double refresh = rig_q_num(db, "select json_extract(fit_json, '$.refresh') from trials where id = 1");
    double dw_cut = rig_q_num(db, "select json_extract(fit_json, '$.dw_cut') from trials where id = 1");
    double dw_limit = rig_q_num(db, "select json_extract(fit_json, '$.dw_limit') from trials where id = 1");
    printf("# stored fit: refresh %.0f, shear to %.5f (%.2f of the measured snap), limit %.5f\n", refresh, dw_cut,
           dw_cut / meas, dw_limit);
    if (refresh > 0) assert_true(isfinite(dw_limit) && dw_cut <= dw_limit);
}

/* Issue 32 A/B, live: the compression's last part (Delta L from max(0.5 c, c - 0.05) = 0.45 on, c
 * = 0.5; trial_comp_track.h) is tracked with the clamp point moved to where the compression rail
 * puts it, within the live loop's budget (TRIAL_COMP_TRACK_LIVE_BUDGET). Each such measured frame
 * is matched to the image the simulator sent (its capture index -> the frame-times file's camera
 * time -> the truth log's line of that stamp) and its Delta Z compared with the twin's in that
 * image. Before (rig mode left them untracked) none was measured off the compression. The hold's
 * frames are scored the same way, beside them, for the tracker's error where nothing moves. */
typedef struct comp_score {
    long n;               /* compression frames measured (Delta L < c - 0.5 px) */
    double dl_lo, dl_hi;  /* their Delta L */
    double worst, mean;   /* |Delta Z - twin's| over them */
    long n_hold;
    double worst_hold, mean_hold;
    long over;            /* left untracked by the budget */
} comp_score;

static comp_score score_compression(rig_run *r, sqlite3 *db)
{
    comp_score cs = {0, INFINITY, -INFINITY, 0.0, 0.0, 0, 0.0, 0.0, 0};
    char path[160], line[512];
    /* capture index -> camera time (frames.csv), camera time -> twin's Delta Z (truth.csv) */
    static double cam_of[20000], real[200000], tdz[200000];
    for (long k = 0; k < 20000; k++) cam_of[k] = NAN;
    snprintf(path, sizeof path, "%s/videos/trial-1.avi.frames.csv", r->dir);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(line, sizeof line, f));
    while (fgets(line, sizeof line, f)) {
        long vf, ci;
        unsigned long long id;
        double cam, host, mapped;
        if (sscanf(line, "%ld,%ld,%llu,%lf,%lf,%lf", &vf, &ci, &id, &cam, &host, &mapped) == 6 && ci >= 0 && ci < 20000)
            cam_of[ci] = cam;
    }
    fclose(f);
    snprintf(path, sizeof path, "%s/truth.csv", r->dir);
    f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(line, sizeof line, f));
    long nt = 0;
    while (nt < 200000 && fgets(line, sizeof line, f)) {
        long k;
        double mono, pc, ps, dl, dw;
        if (sscanf(line, "%ld,%lf,%lf,%lf,%lf,%lf,%lf,%lf", &k, &mono, &real[nt], &pc, &ps, &dl, &dw, &tdz[nt]) == 8) nt++;
    }
    fclose(f);
    assert_true(nt > 0);
    const double c = 0.5, tol_dl = 0.5 / 2.49 / 200.0; /* half a pixel at the rehearsal's 2.49 px/mm */
    sqlite3_stmt *q;
    assert_int_equal(sqlite3_prepare_v2(db,
                                        "select frame, dl, dz, coalesce(reason,'') from samples where trial_id = 1 and "
                                        "kind = 1 and dw < 1e-4 and t_s < (select min(t_s) from samples where "
                                        "trial_id = 1 and kind = 1 and dw > 1e-3) order by seq",
                                        -1, &q, NULL),
                     SQLITE_OK);
    long j = 0;
    while (sqlite3_step(q) == SQLITE_ROW) {
        const long fr = sqlite3_column_int64(q, 0);
        const double dl = sqlite3_column_double(q, 1);
        const char *why = (const char *)sqlite3_column_text(q, 3);
        if (why && strstr(why, "tracking budget")) cs.over++;
        if (sqlite3_column_type(q, 2) == SQLITE_NULL || fr < 0 || fr >= 20000 || !isfinite(cam_of[fr])) continue;
        const double dz = sqlite3_column_double(q, 2), cam = cam_of[fr];
        j = 0;
        for (long lo = 0, hi = nt - 1; lo <= hi;) { /* truth lines are in send order: the nearest stamp */
            long mid = (lo + hi) / 2;
            if (real[mid] < cam) lo = mid + 1;
            else hi = mid - 1;
            j = lo < nt ? lo : nt - 1;
        }
        if (j > 0 && fabs(real[j - 1] - cam) < fabs(real[j] - cam)) j--;
        assert_true(fabs(real[j] - cam) < 1e-4); /* an image the simulator sent */
        const double e = fabs(dz - tdz[j]);
        if (dl < c - tol_dl) {
            assert_true(dl > 0.45 - 1e-9); /* the window only: earlier frames stay untracked */
            cs.n++;
            cs.dl_lo = fmin(cs.dl_lo, dl);
            cs.dl_hi = fmax(cs.dl_hi, dl);
            cs.worst = fmax(cs.worst, e);
            cs.mean += e;
        } else {
            cs.n_hold++;
            cs.worst_hold = fmax(cs.worst_hold, e);
            cs.mean_hold += e;
        }
    }
    sqlite3_finalize(q);
    if (cs.n) cs.mean /= (double)cs.n;
    if (cs.n_hold) cs.mean_hold /= (double)cs.n_hold;
    printf("# compression frames: %ld measured at Delta L %.4f to %.4f (%ld left untracked by the budget), |Delta Z - "
           "twin's| mean %.5f, worst %.5f; the hold's %ld frames: mean %.5f, worst %.5f\n",
           cs.n, cs.dl_lo, cs.dl_hi, cs.over, cs.mean, cs.worst, cs.n_hold, cs.mean_hold, cs.worst_hold);
    return cs;
}

static void test_gcode_trial(void **state)
{
    (void)state;
    rig_run r;
    start_with(&r, NULL, NULL, 1); /* the lab's calibration from the clamps in the live stream */
    int rc = rig_trial(&r, 1);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    printf("# trial: %s %s (ribbonctl %d)\n", status, why, rc);
    assert_string_equal(status, "done");
    double meas = rig_q_num(db, "select snap_dw_measured from trials where id = 1");
    double pred = rig_q_num(db, "select snap_dw from predictions where trial_id = 1");
    char rm[32], rp[32], lat[400];
    rig_q_text(db, "select regime_measured from trials where id = 1", rm, sizeof rm);
    rig_q_text(db, "select regime from predictions where trial_id = 1", rp, sizeof rp);
    rig_q_text(db, "select message from events where trial_id = 1 and message like 'snap-to-stop latency%'", lat, sizeof lat);
    printf("# measured %.5f predicted %.5f (%s / %s)\n# %s\n", meas, pred, rm, rp, lat);
    score_against_twin(&r, meas, pred, rm, rp, "asymmetric"); /* Gamma 0.13: the pitchfork first */
    score_calibrated(&r, db, meas, pred);
    comp_score cs = score_compression(&r, db);
    /* Measured (load 25 on 2 cores): 30 of 30 frames at Delta L 0.4508 to 0.4989, |Delta Z - twin's|
     * mean 0.00150, worst 0.00158, against the hold's 0.00150 and 0.00153 (the lab calibration's
     * bias); the fresh tracker 3.7 ms a frame, 10.5 ms at most, nothing over the budget. Bounds: at
     * least 5 frames over 0.02 of Delta L, none further from the twin than the hold's worst plus
     * 0.001, nor than the runner test's 0.005. */
    assert_true(cs.n >= 5);
    assert_true(cs.dl_hi - cs.dl_lo > 0.02);
    assert_true(cs.worst < cs.worst_hold + 0.001);
    assert_true(cs.worst < 0.005);
    rig_pipeline pl = rig_pipeline_counts(db);
    assert_true(pl.captured > 0);
    assert_int_equal(pl.lost + pl.incomplete + pl.dropped, 0);
    assert_int_equal(pl.recorded, pl.captured);
    assert_non_null(strstr(lat, "stop command"));
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_check_stamps(&r, pl.recorded);
    rig_passed();
}

/* Gamma 0.21 (the symmetric case) in real time: the same scoring, and the measured regime
 * symmetric under the pathway rule (sim/rod_regime.h; see test_ribbond_e2e.c
 * GAMMA021_MEASURED_REGIME: the old fixed 0.05 rad rule read it asymmetric). Mounted at Delta L
 * 0.25 (the route to the upper state does not converge at 0.2 at this Gamma). */
#define GAMMA021_MEASURED_REGIME "symmetric"

static void test_gcode_trial_gamma021(void **state)
{
    (void)state;
    static const char *const sets[] = {"rail.compress.port=%s/grbl", "rail.shear.port=%s/grbl",
                                       "camera.calibration=%s/camera.calib", "store.path=%s/rig.db",
                                       "camera.video_dir=%s/videos", "trial.compress_speed_mm_s=20",
                                       "folds.position=0.21",
                                       /* rigid creases as before: the rig file's compliant twin
                                          left this trial's onset bound (rig-rehearsal.ini); and
                                          the fit's creases rigid too, as the twin's (the hinge
                                          guess is for compliant strips, calibration.md) */
                                       "twin.folds.hinge_stiffness=rigid", "sim.fit_hinge=0",
                                       "sim.fit_keys=folds.angle_left_deg,folds.angle_right_deg", NULL};
    static const char *const sim_extra[] = {"--start-dl", "0.25", NULL};
    rig_run r;
    rig_prepare(&r, sets);
    rig_start_sim(&r, RIG, sim_extra);
    /* The lab's calibration here too. Measured: alone on the machine (load 3.5-5) -0.00029 and
     * -0.00020 against the truth (bounds 0.00213, 0.00347); at load 10, while other sessions' rig tests
     * ran on the machine (seen beside at least one run; one GigE Vision port), +0.01132 and +0.00793 (bound 0.0018) beside
     * -0.00062, as the exact file there (+0.00337, bound 0.00238, beside +0.00007): run it alone. */
    lab_calibrate(&r, "0.25");
    rig_start_daemon(&r, RIG);
    int rc = rig_trial(&r, 1);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512], rm[32], rp[32];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    printf("# Gamma 0.21 trial: %s %s (ribbonctl %d)\n", status, why, rc);
    assert_string_equal(status, "done");
    double meas = rig_q_num(db, "select snap_dw_measured from trials where id = 1");
    double pred = rig_q_num(db, "select snap_dw from predictions where trial_id = 1");
    rig_q_text(db, "select regime_measured from trials where id = 1", rm, sizeof rm);
    rig_q_text(db, "select regime from predictions where trial_id = 1", rp, sizeof rp);
    printf("# measured %.5f %s, predicted %.5f %s\n", meas, rm, pred, rp);
    char treg[16];
    double truth = rig_twin_truth(&r, treg, sizeof treg);
    double age = rig_truth_image_age(&r, truth, 0.02), gap = rig_truth_frame_gap(&r, truth, 0.005);
    double bound = rig_onset_bound(0.01 / 0.2, 60.0, gap, 1.5e-3, age);
    printf("# twin truth %.5f %s; measured - truth %+.5f (bound %.5f: images up to %.0f ms old, %.0f ms apart), "
           "predicted - truth %+.2f%%\n",
           truth, treg, meas - truth, bound, 1e3 * age, 1e3 * gap, 100.0 * (pred - truth) / truth);
    assert_true(isfinite(truth));
    assert_string_equal(treg, "symmetric");
    assert_string_equal(rp, "symmetric");
    assert_string_equal(rm, GAMMA021_MEASURED_REGIME);
    assert_true(fabs(meas - truth) <= bound);
    assert_true(fabs(pred - truth) < 0.10 * truth);
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_passed();
}

/* From the truth log: the real time of the last image at which either axis had moved since the
 * image before (NaN: never). */
static double last_axis_move(rig_run *r)
{
    char path[160], line[512];
    snprintf(path, sizeof path, "%s/truth.csv", r->dir);
    FILE *t = fopen(path, "r");
    assert_non_null(t);
    assert_non_null(fgets(line, sizeof line, t));
    double last = NAN, pc0 = NAN, ps0 = NAN;
    while (fgets(line, sizeof line, t)) {
        long k;
        double mono, real, pc, ps;
        if (sscanf(line, "%ld,%lf,%lf,%lf,%lf", &k, &mono, &real, &pc, &ps) != 5) continue;
        if (isfinite(pc0) && (fabs(pc - pc0) > 1e-4 || fabs(ps - ps0) > 1e-4)) last = real;
        pc0 = pc;
        ps0 = ps;
    }
    fclose(t);
    return last;
}

/* A fault on command mid-shear (SIGUSR2 camera, SIGRTMIN frozen image), then the trial's end. */
/* The overloaded loop (issue 34 F): each tracked frame takes RIBBON_TEST_TRACK_DELAY_S = 1.0 s (60
 * frame periods at 60 fps), so the loop tracks about one frame a second and stores the rest
 * untracked; the snap's own frames fall in such a gap and the speed across it (a Delta Z jump of
 * about 0.55 over about a second) is diluted below snap.speed: before the gap rule the shear ran to
 * its limit ("shear limit reached, no snap", largest Delta W 0.6214; at 0.5 s per frame the old
 * rule still caught it). The snap must be detected (across the
 * gap, said in the event) and the shear stopped by it, not run on to its limit. */
#define OVERLOAD_TRACK_DELAY_S "1.0"

static void test_overloaded_loop_still_stops_at_snap(void **state)
{
    (void)state;
    rig_run r;
    setenv("RIBBON_TEST_TRACK_DELAY_S", OVERLOAD_TRACK_DELAY_S, 1);
    start(&r, NULL);
    unsetenv("RIBBON_TEST_TRACK_DELAY_S");
    int rc = rig_trial(&r, 1);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512], det[400] = "", lim[200] = "";
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    rig_q_text(db, "select coalesce(max(message),'') from events where trial_id = 1 and message like 'snap detected%'",
               det, sizeof det);
    rig_q_text(db, "select coalesce(max(message),'') from events where trial_id = 1 and message like 'shear limit%'",
               lim, sizeof lim);
    double skipped = rig_q_num(db, "select count(*) from samples where trial_id = 1 and reason like 'not tracked%'");
    double meas = rig_q_num(db, "select coalesce(snap_dw_measured, -1) from trials where id = 1");
    double dw_max = rig_q_num(db, "select max(dw) from samples where trial_id = 1");
    printf("# overloaded loop (%s s per tracked frame): %s %s (ribbonctl %d); %.0f frames untracked; largest "
           "Delta W %.4f\n# %s\n# %s\n",
           OVERLOAD_TRACK_DELAY_S, status, why, rc, skipped, dw_max, det, lim);
    assert_string_equal(status, "done");
    assert_true(skipped > 0);
    assert_string_equal(lim, "");
    assert_non_null(strstr(det, "snap detected"));
    assert_true(meas > 0.0);
    /* The shear limit is Delta W 0.6; the snap (twin) is near 0.37-0.40 and the stop comes about
     * a gap plus a tracking time (2 x 1.0 s = 0.1 in Delta W at this rate) plus the braking after
     * it: 0.5245 measured, short of the limit (1.5 s per frame: 0.5665). */
    assert_true(dw_max < 0.58);
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_passed();
}

static void fault_mid_shear(rig_run *r, int sig, const char *daemon_set)
{
    /* The shipped config: the in-trial fit on (its refreshes run during the shear on SCHED_IDLE
     * threads, which never take CPU from the loop, the capture and the poller; docs/rig-realtime.md). */
    rig_prepare(r, rehearsal_sets);
    rig_start_sim(r, RIG, NULL);
    if (daemon_set) rig_daemon_set(r, daemon_set);
    rig_start_daemon(r, RIG);
    assert_int_equal(rig_trial(r, 0), 0);
    char got[700];
    if (rig_wait_state(r, "shearing", 90.0, got, sizeof got)) fail_msg("the trial did not reach shearing: %s", got);
    rig_sleep_s(0.5);
    kill(r->sim, sig);
    assert_int_equal(rig_wait_end(r, 60.0), 0);
    rig_stop(r);
}

static void test_camera_stops_mid_shear(void **state)
{
    (void)state;
    rig_run r;
    fault_mid_shear(&r, SIGUSR2, NULL);
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    char st[64];
    rig_q_text(db, "select state from events where trial_id = 1 and kind = 'fault' order by id limit 1", st, sizeof st);
    double cut = rig_sim_fault_time(&r, "camera stopped"), seen = rig_event_wall(db, "camera:%");
    printf("# %s in %s: %s; detected %.3f s after the camera stopped\n", status, st, why, seen - cut);
    assert_string_equal(status, "failed");
    assert_string_equal(st, "shearing");
    assert_non_null(strstr(why, "camera"));
    assert_true(seen - cut < 0.5); /* issue 13: within 0.5 s */
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_passed();
}

/* The image freezes mid-shear (SIGRTMIN): failed, naming the frozen image, within 0.5 s; both rails
 * stopped (the truth log: no axis moves 1 s after the detection), samples stored, integrity ok. */
static void test_frozen_image_mid_shear(void **state)
{
    (void)state;
    rig_run r;
    fault_mid_shear(&r, SIGRTMIN, "camera.frozen_frames=20");
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512], st[64];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    rig_q_text(db, "select state from events where trial_id = 1 and kind = 'fault' order by id limit 1", st, sizeof st);
    double cut = rig_sim_fault_time(&r, "image frozen"), seen = rig_event_wall(db, "camera: the image is frozen%");
    double moved = last_axis_move(&r);
    printf("# %s in %s: %s; detected %.3f s after the freeze; last axis motion %.3f s after it\n", status, st, why,
           seen - cut, moved - seen);
    assert_string_equal(status, "failed");
    assert_string_equal(st, "shearing");
    assert_non_null(strstr(why, "frozen"));
    /* the rig file's camera.frozen_frames (20 here, not the default 12) is the rule applied */
    assert_non_null(strstr(why, "20 identical frames"));
    assert_true(seen - cut < 0.5);
    assert_true(!(moved - seen > 1.0));
    assert_true(rig_q_num(db, "select count(*) from samples where trial_id = 1") > 100);
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_passed();
}

/* GVSP packets lost all along (1e-4 of them: a few frames in a hundred damaged): the trial goes on
 * to done, the losses counted in the pipeline's event and noted as warnings while it ran. */
static void test_lost_packets_trial_goes_on(void **state)
{
    (void)state;
    rig_run r;
    const char *extra[] = {"--lost-packets", "1e-4", NULL};
    start(&r, extra);
    int rc = rig_trial(&r, 1);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512], note[400];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    rig_q_text(db, "select message from events where trial_id = 1 and message like 'camera: % lost or incomplete%'",
               note, sizeof note);
    printf("# lost packets: %s %s (ribbonctl %d)\n# %s\n", status, why, rc, note);
    assert_string_equal(status, "done");
    rig_pipeline pl = rig_pipeline_counts(db);
    assert_true(pl.lost + pl.incomplete > 0);
    assert_int_equal(pl.recorded, pl.captured);
    assert_true(note[0] != '\0');
    const long cap = pl.captured;
    /* every frame up to the trial's end has its sample (the frames after it are in the video only) */
    double nfs = rig_q_num(db, "select count(*) from samples where trial_id = 1 and kind = 1");
    assert_true(nfs > 0.9 * cap);
    assert_true(nfs == rig_q_num(db, "select max(frame) + 1 from samples where trial_id = 1 and kind = 1"));
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_passed();
}

/* Packets lost heavily (5e-3: two frames in three damaged): failed with the named quality reason
 * soon after the start, the rails stopped, samples stored, integrity ok. */
static void test_heavy_loss_fails(void **state)
{
    (void)state;
    rig_run r;
    const char *extra[] = {"--lost-packets", "5e-3", NULL};
    start(&r, extra);
    rig_trial(&r, 1);
    rig_sleep_s(1.5);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512];
    rig_q_text(db, "select status from trials where id = 1", status, sizeof status);
    rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    double seen = rig_event_wall(db, "%lost or incomplete: %"), moved = last_axis_move(&r);
    printf("# heavy loss: %s: %s; last axis motion %.3f s after the detection\n", status, why, moved - seen);
    assert_string_equal(status, "failed");
    assert_non_null(strstr(why, "lost or incomplete"));
    assert_true(isfinite(seen));
    assert_true(!(moved - seen > 1.0));
    rig_check_integrity(db);
    sqlite3_close(db);
    rig_passed();
}

/* Bad camera input, each a named error before anything moves: either ribbond's start-up checks
 * (daemon/check/) find it and the start is refused (409) naming it, with no trial row, or the trial
 * is created and fails by name with no compression started (no 'start:' event), no sample and no
 * video; either way no axis step in the simulator's axes log. ribbonctl cameras lists the
 * simulator's camera. */
static void bad_input_case(const char *set, const char *needle)
{
    rig_run r;
    start_with(&r, NULL, set, 0);
    int rc = rig_trial(&r, 1);
    rig_stop(&r);
    sqlite3 *db = rig_db_open(&r);
    char status[64], why[512];
    if (rig_q_text(db, "select status from trials where id = 1", status, sizeof status) != 0) {
        /* refused at the start: ribbonctl said why and exited non-zero */
        char p[128], out[2048] = "";
        snprintf(p, sizeof p, "%s/trial.txt", r.dir);
        FILE *f = fopen(p, "r");
        assert_non_null(f);
        size_t n = fread(out, 1, sizeof out - 1, f);
        out[n] = '\0';
        fclose(f);
        printf("# %s: refused at start (ribbonctl %d): %s", set, rc, out);
        assert_true(rc != 0);
        assert_non_null(strstr(out, "check"));
        assert_non_null(strstr(out, needle));
    } else {
        rig_q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
        printf("# %s: %s: %s\n", set, status, why);
        assert_string_equal(status, "failed");
        assert_non_null(strstr(why, needle));
        assert_true(rig_q_num(db, "select count(*) from events where trial_id = 1 and message like 'start:%'") == 0);
        assert_true(rig_q_num(db, "select count(*) from samples where trial_id = 1") == 0);
    }
    rig_check_integrity(db);
    sqlite3_close(db);
    char v[160];
    snprintf(v, sizeof v, "%s/videos/trial-1.avi", r.dir);
    assert_int_equal(access(v, F_OK), -1);
    snprintf(v, sizeof v, "%s/videos/trial-1.avi.frames.csv", r.dir);
    assert_int_equal(access(v, F_OK), -1);
    /* the rails never moved (the simulator's axes log: no step of either axis) */
    assert_true(isnan(rig_truth_last_move(&r, 0)));
    assert_true(isnan(rig_truth_last_move(&r, 1)));
}

static void test_bad_camera_input(void **state)
{
    (void)state;
    bad_input_case("camera.source=aravis:no-such-camera-4711", "not found");
    bad_input_case("camera.offset_x_px=4000", "OffsetX 4000 refused"); /* the sensor is 2048 wide */
    /* Aravis's fake camera declares ExposureTime 10..1e7 us and Gain 0..10 dB (and would take any
     * value written): outside them, refused by name with the bounds */
    bad_input_case("camera.exposure_us=5", "ExposureTime 5 us refused: the camera allows 10..1e+07 us");
    bad_input_case("camera.gain_db=50", "Gain 50 dB refused: the camera allows 0..10 dB");
    /* the simulator writes the calibration for 640 x 480; ribbond asks the camera for 320 x 480 */
    bad_input_case("camera.width_px=320", "calibration");
    rig_passed();
}

static void test_ribbonctl_cameras_finds_the_simulator(void **state)
{
    (void)state;
    rig_run r;
    start(&r, NULL);
    char cmd[400], path[160], line[1024];
    snprintf(path, sizeof path, "%s/cameras.json", r.dir);
    snprintf(cmd, sizeof cmd, "%s/ribbonctl cameras --json > %s 2>&1", BIN, path);
    int rc = system(cmd);
    rig_stop(&r);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 0);
    assert_true(rig_file_has(path, "\"source\":\"aravis:", line, sizeof line));
    printf("# %s", line);
    assert_non_null(strstr(line, "RIBBONSIM")); /* ribbon-rigsim's serial */
    assert_non_null(strstr(line, "GigEVision"));
    rig_passed();
}

static void test_sigkill_mid_shear(void **state)
{
    (void)state;
    rig_run r;
    start(&r, NULL);
    assert_int_equal(rig_trial(&r, 0), 0);
    char got[700];
    if (rig_wait_state(&r, "shearing", 60.0, got, sizeof got)) fail_msg("the trial did not reach shearing: %s", got);
    rig_sleep_s(1.0);
    double t_kill = rig_now_real();
    kill(r.daemon, SIGKILL);
    waitpid(r.daemon, NULL, 0);
    r.daemon = -1;
    rig_sleep_s(3.0);
    rig_stop(&r);
    /* From the simulator's axes log (it goes on when nobody streams): the shear axis's last move. */
    double last_move = rig_truth_last_move(&r, 1);
    printf("# SIGKILL mid-shear: the shear axis stood %.3f s after the kill\n", last_move - t_kill);
    /* The GRBL driver keeps at most its queued jog segments ahead (rail_gcode.h: segment_s each,
     * a few queued) plus the deceleration: 1 s bounds it generously at 10 mm/s. */
    assert_true(isfinite(last_move));
    assert_true(last_move - t_kill < 1.0);
    rig_passed();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_gcode_trial, rig_teardown),
        cmocka_unit_test_teardown(test_gcode_trial_gamma021, rig_teardown),
        cmocka_unit_test_teardown(test_camera_stops_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_overloaded_loop_still_stops_at_snap, rig_teardown),
        cmocka_unit_test_teardown(test_sigkill_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_frozen_image_mid_shear, rig_teardown),
        cmocka_unit_test_teardown(test_lost_packets_trial_goes_on, rig_teardown),
        cmocka_unit_test_teardown(test_heavy_loss_fails, rig_teardown),
        cmocka_unit_test_teardown(test_bad_camera_input, rig_teardown),
        cmocka_unit_test_teardown(test_ribbonctl_cameras_finds_the_simulator, rig_teardown),
    };
    /* REHEARSAL_TESTS=PATTERN runs only the matching tests (cmocka's filter: * and ? wildcards). */
    if (getenv("REHEARSAL_TESTS")) cmocka_set_test_filter(getenv("REHEARSAL_TESTS"));
    return cmocka_run_group_tests(tests, NULL, NULL);
}
