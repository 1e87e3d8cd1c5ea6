/* rig_harness.h: the rig on loopback for the real-time rig tests: ribbon-rigsim and ribbond started
 * on one rig file in a temporary directory (the same --set overrides for both), a trial through
 * ribbonctl, the store read back, the simulator's truth (its "fault: ... at UNIX-TIME" lines and
 * truth log). Both programs run at nice -10 when the test runs as root, as `make rehearsal` runs
 * them (REHEARSAL_NICE): the machine is shared with compilers. Failures end the test (cmocka). */
#ifndef RIBBON_TESTS_RIG_HARNESS_H
#define RIBBON_TESTS_RIG_HARNESS_H

#include <sqlite3.h>
#include <stddef.h>
#include <sys/types.h>

#define RIG_HARNESS_SETS 16

typedef struct rig_run {
    char dir[64];
    char sets[RIG_HARNESS_SETS][300];
    int n_sets;
    char daemon_sets[4][300]; /* overrides for ribbond only (rig_daemon_set) */
    int n_daemon_sets;
    pid_t sim, daemon;
    char url[128];
} rig_run;

double rig_now_real(void);
void rig_sleep_s(double s);
/* A free TCP port on 127.0.0.1 (bound and released; loopback only). */
int rig_free_port(void);

/* Prepares r (a temporary directory; the store, videos and calibration go there) with the rig
 * file's overrides `sets` (NULL-terminated, "%s" in a value is replaced by the directory). */
void rig_prepare(rig_run *r, const char *const *sets);
/* An override for ribbond only (bad input the simulator must not see), before rig_start_daemon. */
void rig_daemon_set(rig_run *r, const char *set);
/* Starts ribbon-rigsim on rig (with sim_extra arguments) and waits for "ready". */
void rig_start_sim(rig_run *r, const char *rig, const char *const *sim_extra);
/* Starts ribbond on rig and waits for its URL. */
void rig_start_daemon(rig_run *r, const char *rig);
/* Both, the simulator first. */
void rig_start(rig_run *r, const char *rig, const char *const *sets, const char *const *sim_extra);
/* SIGTERM to ribbond, then the simulator; SIGKILL to one that has not exited 5 s later. */
void rig_stop(rig_run *r);
/* The teardown for cmocka: kills every process the harness started that is still running. It
 * keeps their ids itself (not in the test's rig_run, which a failed assertion's longjmp leaves on a
 * dead stack frame), so a failing test never leaves a simulator serving port 3956 to the next. */
int rig_teardown(void **state);
/* Called at the end of a test that passed: its teardown then removes the directories it prepared
 * (test_dir.h: a failed test's are kept and named, and every test's with RIBBON_TEST_KEEP=1). */
void rig_passed(void);

/* `ribbonctl start` (with --wait when wait); its exit code. */
int rig_trial(rig_run *r, int wait);
/* Waits at most timeout_s until trial 1's state is `state` (or final); 0 when it is. On failure
 * the state and reason reached are in got. */
int rig_wait_state(rig_run *r, const char *state, double timeout_s, char *got, size_t got_len);
/* Waits at most timeout_s until trial 1 is no longer created or running; 0 when it ended. */
int rig_wait_end(rig_run *r, double timeout_s);

sqlite3 *rig_db_open(rig_run *r);
int rig_q_text(sqlite3 *db, const char *sql, char *out, size_t n);
double rig_q_num(sqlite3 *db, const char *sql);
/* Unix time of the first event whose message is LIKE `like`, NaN if none. */
double rig_event_wall(sqlite3 *db, const char *like);
void rig_check_integrity(sqlite3 *db);
/* The unix time in the simulator's line "fault: WHAT at T", NaN if none. */
double rig_sim_fault_time(rig_run *r, const char *what);
/* 1 when `needle` is in the file at path (its line copied to line_out). */
int rig_file_has(const char *path, const char *needle, char *line_out, size_t n);

/* The pipeline event's counts ("pipeline: N frames captured, ..."); fails the test when absent. */
typedef struct rig_pipeline {
    long captured, lost, incomplete, dropped, recorded;
} rig_pipeline;
rig_pipeline rig_pipeline_counts(sqlite3 *db);
/* Each video frame's stored time (trial-1.avi.frames.csv) against the simulator's true send time
 * of the same image (the truth log, matched by the camera's timestamp): asserts every frame is one
 * the simulator sent, there are `recorded` of them, and every one is within 1 ms (issue 13 E). */
void rig_check_stamps(rig_run *r, long recorded);

/* From the simulator's truth log: the last real (unix) time axis `col` (0 compression, 1 shear)
 * moved by more than 1e-4 mm between two images; NaN if it never did. */
double rig_truth_last_move(rig_run *r, int col);

/* The twin's own snap from ribbon-rigsim's "twin truth: snap Delta W = X, regime R (...)" line
 * (twin_truth.h; printed once final, or at exit: call after rig_stop): X, with R in regime; NaN
 * (regime "no snap" or "") when it did not snap or said nothing. */
double rig_twin_truth(rig_run *r, char *regime, size_t n);
/* From the truth log: the oldest image (s, column image_age_s) the simulator sent while Delta W
 * was within span of dw; 0 if none. */
double rig_truth_image_age(rig_run *r, double dw, double span);
/* From the truth log: the longest interval (s) between two images the simulator sent while Delta W
 * was within span of dw, on the way there (the shear's first pass); 0 if none. Where the simulator
 * stalled (a busy machine) the frames are that far apart and the onset, a frame, no closer. */
double rig_truth_frame_gap(rig_run *r, double dw, double span);
/* How far the measured snap may lie from the twin's own (docs/trials.md "The twin and its truth"):
 * one frame period of shear (at fps, or the longer frame_gap_s the frames had near the snap:
 * rig_truth_frame_gap), one twin step, the frame stamps' 1 ms and the oldest image sent near
 * the snap, all times the shear rate (Delta W per second). */
double rig_onset_bound(double rate, double fps, double frame_gap_s, double twin_dt, double image_age_s);

#endif
