/* test_rig_rehearsal: rig mode end to end in real time against ribbon-rigsim (issue 13 E): the GRBL
 * controller's two axes on a pty, the twin filmed by the GigE Vision camera on 127.0.0.1, ribbond
 * on config/rig-rehearsal.ini (compression at 20 mm/s so a trial takes about 30 s).
 *   - a whole trial: done, measured snap within 2% of the prediction at the same resolution, the
 *     regimes agree, no frame lost or dropped, every video frame in the frame-times file, each
 *     frame's stamp against the simulator's true send time (every one within 1 ms), the snap-to-stop latency
 *     stored, PRAGMA integrity_check ok;
 * Faults come on command (SIGUSR1 / SIGUSR2 to ribbon-rigsim) once the trial is shearing.
 *   (the rails' faults, link lost among them, are test_rig_rails's);
 *   - the camera stops sending mid-shear: failed naming the camera, within 0.5 s;
 *   - the image freezes mid-shear: failed naming it, within 0.5 s, rails stopped;
 *   - GVSP packets lost: counted and noted, the trial done; lost heavily: failed, named, rails stopped;
 *   - bad camera input (no such camera, a refused frame rate, frames not the calibration's size):
 *     named, nothing moved, nothing stored but the failed trial; `ribbonctl cameras` finds the camera.
 *   - ribbond killed with SIGKILL mid-shear: the shear axis stands within the GRBL driver's bound
 *     (its queued jog segments) as the simulator's truth log shows.
 * Heavy (real time, a minute or more each): normal build only. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define BIN RIBBON_BIN_DIR
#define RIG RIBBON_SOURCE_DIR "/config/rig-rehearsal.ini"
#define FPS 60.0

static double now_real(void)
{
    struct timespec t;
    clock_gettime(CLOCK_REALTIME, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void sleep_s(double s)
{
    struct timespec t = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&t, NULL);
}

typedef struct rehearsal rehearsal;
static rehearsal *current; /* the running rehearsal, stopped by the teardown when a test fails */
static const char *daemon_extra[4]; /* extra --set for ribbond only (bad input), NULL-terminated */
struct rehearsal {
    char dir[64];
    char sets[8][300];
    int n_sets;
    pid_t sim, daemon;
    char url[128];
};

static pid_t spawn(const char *const *argv, const char *out_path, const char *err_path)
{
    pid_t p = fork();
    if (p == 0) {
        int o = open(out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        int e = open(err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (o >= 0) dup2(o, 1);
        if (e >= 0) dup2(e, 2);
        execv(argv[0], (char *const *)argv);
        _exit(127);
    }
    return p;
}

static int file_has(const char *path, const char *needle, char *line_out, size_t n)
{
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    char line[1024];
    int found = 0;
    while (fgets(line, sizeof line, f))
        if (strstr(line, needle)) {
            found = 1;
            if (line_out) snprintf(line_out, n, "%s", line);
            break;
        }
    fclose(f);
    return found;
}

/* Starts the simulator (with extra args) and ribbond; fails the test when either does not come up. */
static void start(rehearsal *r, const char *const *sim_extra)
{
    memset(r, 0, sizeof *r);
    current = r;
    snprintf(r->dir, sizeof r->dir, "/tmp/test_rig_rehearsal.XXXXXX");
    assert_non_null(mkdtemp(r->dir));
    const char *fmt[] = {"rail.compress.port=%s/grbl", "rail.shear.port=%s/grbl", "camera.calibration=%s/camera.calib",
                         "store.path=%s/rehearsal.db", "camera.video_dir=%s/videos"};
    for (int k = 0; k < 5; k++) snprintf(r->sets[k], sizeof r->sets[k], fmt[k], r->dir);
    snprintf(r->sets[5], sizeof r->sets[5], "trial.compress_speed_mm_s=20");
    r->n_sets = 6;
    const char *argv[40];
    int n = 0;
    argv[n++] = BIN "/ribbon-rigsim";
    argv[n++] = RIG;
    for (int k = 0; k < r->n_sets; k++) {
        argv[n++] = "--set";
        argv[n++] = r->sets[k];
    }
    char truth[128];
    snprintf(truth, sizeof truth, "%s/truth.csv", r->dir);
    argv[n++] = "--truth";
    argv[n++] = truth;
    for (int k = 0; sim_extra && sim_extra[k]; k++) argv[n++] = sim_extra[k];
    argv[n] = NULL;
    char out[128], err[128];
    snprintf(out, sizeof out, "%s/rigsim.out", r->dir);
    snprintf(err, sizeof err, "%s/rigsim.err", r->dir);
    r->sim = spawn(argv, out, err);
    for (int i = 0; i < 300 && !file_has(out, "ready", NULL, 0); i++) sleep_s(0.1);
    if (!file_has(out, "ready", NULL, 0)) fail_msg("ribbon-rigsim did not start (see %s)", err);
    n = 0;
    argv[n++] = BIN "/ribbond";
    argv[n++] = "--config";
    argv[n++] = RIG;
    for (int k = 0; k < r->n_sets; k++) {
        argv[n++] = "--set";
        argv[n++] = r->sets[k];
    }
    for (int k = 0; daemon_extra[k]; k++) {
        argv[n++] = "--set";
        argv[n++] = daemon_extra[k];
    }
    argv[n] = NULL;
    snprintf(out, sizeof out, "%s/ribbond.out", r->dir);
    snprintf(err, sizeof err, "%s/ribbond.err", r->dir);
    r->daemon = spawn(argv, out, err);
    char line[1024] = "";
    for (int i = 0; i < 300 && !file_has(err, "listening on ", line, sizeof line); i++) sleep_s(0.1);
    char *u = strstr(line, "http://");
    if (!u) fail_msg("ribbond did not start (see %s)", err);
    snprintf(r->url, sizeof r->url, "%s", u);
    r->url[strcspn(r->url, " \n")] = '\0';
}

static void stop(rehearsal *r)
{
    if (r->daemon > 0) {
        kill(r->daemon, SIGTERM);
        waitpid(r->daemon, NULL, 0);
        r->daemon = -1;
    }
    if (r->sim > 0) {
        kill(r->sim, SIGTERM);
        waitpid(r->sim, NULL, 0);
        r->sim = -1;
    }
}

static int teardown(void **state)
{
    (void)state;
    if (current) stop(current);
    current = NULL;
    return 0;
}

/* Runs `ribbonctl start --wait` (or without --wait); returns its exit code. */
static int trial(rehearsal *r, int wait)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "%s/ribbonctl start --url %s --note test%s > %s/trial.txt 2>&1", BIN, r->url,
             wait ? " --wait" : "", r->dir);
    int rc = system(cmd);
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

static sqlite3 *db_open(rehearsal *r)
{
    char p[128];
    snprintf(p, sizeof p, "%s/rehearsal.db", r->dir);
    sqlite3 *db = NULL;
    assert_int_equal(sqlite3_open_v2(p, &db, SQLITE_OPEN_READONLY, NULL), SQLITE_OK);
    sqlite3_busy_timeout(db, 5000);
    return db;
}

static int q_text(sqlite3 *db, const char *sql, char *out, size_t n)
{
    sqlite3_stmt *st = NULL;
    out[0] = '\0';
    if (sqlite3_prepare_v2(db, sql, -1, &st, NULL) != SQLITE_OK) return -1;
    int rc = sqlite3_step(st) == SQLITE_ROW ? 0 : -1;
    if (!rc) snprintf(out, n, "%s", sqlite3_column_text(st, 0) ? (const char *)sqlite3_column_text(st, 0) : "");
    sqlite3_finalize(st);
    return rc;
}

static double q_num(sqlite3 *db, const char *sql)
{
    char t[64];
    return q_text(db, sql, t, sizeof t) ? NAN : atof(t);
}

/* The trial state's wall time (unix s) when a state was entered, from its event. */
static double wall_of(sqlite3 *db, const char *like)
{
    char sql[256], t[64];
    snprintf(sql, sizeof sql,
             "select (julianday(wall_time) - 2440587.5) * 86400.0 from events where message like '%s' order by id limit 1",
             like);
    return q_text(db, sql, t, sizeof t) ? NAN : atof(t);
}

static void check_integrity(sqlite3 *db)
{
    char t[64];
    assert_int_equal(q_text(db, "pragma integrity_check", t, sizeof t), 0);
    assert_string_equal(t, "ok");
}

static double cut_time(rehearsal *r, const char *what)
{
    char out[128], line[1024];
    snprintf(out, sizeof out, "%s/rigsim.out", r->dir);
    if (!file_has(out, what, line, sizeof line)) return NAN;
    const char *at = strstr(line, " at ");
    return at ? atof(at + 4) : NAN;
}

static void test_gcode_trial(void **state)
{
    (void)state;
    rehearsal r;
    start(&r, NULL);
    int rc = trial(&r, 1);
    stop(&r);
    sqlite3 *db = db_open(&r);
    char status[64], why[512];
    q_text(db, "select status from trials where id = 1", status, sizeof status);
    q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    printf("# trial: %s %s (ribbonctl %d)\n", status, why, rc);
    assert_string_equal(status, "done");
    double meas = q_num(db, "select snap_dw_measured from trials where id = 1");
    double pred = q_num(db, "select snap_dw from predictions where trial_id = 1");
    char rm[32], rp[32], pipe[600], lat[400];
    q_text(db, "select regime_measured from trials where id = 1", rm, sizeof rm);
    q_text(db, "select regime from predictions where trial_id = 1", rp, sizeof rp);
    q_text(db, "select message from events where trial_id = 1 and message like 'pipeline:%'", pipe, sizeof pipe);
    q_text(db, "select message from events where trial_id = 1 and message like 'snap-to-stop%'", lat, sizeof lat);
    printf("# measured %.5f predicted %.5f (%s / %s)\n# %s\n# %s\n", meas, pred, rm, rp, pipe, lat);
    assert_true(fabs(meas - pred) <= 0.02 * pred);
    assert_string_equal(rm, rp);
    long cap = -1, lost = -1, inc = -1, drop = -1, rec = -1;
    assert_int_equal(sscanf(pipe, "pipeline: %ld frames captured, %ld lost by the camera or link (id gaps), %ld "
                                  "incomplete buffers, %ld dropped by the pipeline, %ld recorded",
                            &cap, &lost, &inc, &drop, &rec),
                     5);
    assert_true(cap > 0);
    assert_int_equal(lost + inc + drop, 0);
    assert_int_equal(rec, cap);
    assert_non_null(strstr(lat, "stop command"));
    check_integrity(db);
    sqlite3_close(db);
    /* Stamps against the truth: match each frame by the camera's timestamp (the simulator's send
     * time on the real-time clock), compare ribbond's mapped time with the true monotonic time. */
    char path[160];
    snprintf(path, sizeof path, "%s/truth.csv", r.dir);
    FILE *t = fopen(path, "r");
    assert_non_null(t);
    static double real[200000], mono[200000];
    long nt = 0;
    char line[512];
    assert_non_null(fgets(line, sizeof line, t));
    while (nt < 200000 && fgets(line, sizeof line, t)) {
        long k;
        if (sscanf(line, "%ld,%lf,%lf", &k, &mono[nt], &real[nt]) == 3) nt++;
    }
    fclose(t);
    snprintf(path, sizeof path, "%s/videos/trial-1.avi.frames.csv", r.dir);
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    assert_non_null(fgets(line, sizeof line, f));
    static double err[200000];
    long nf = 0, j = 0;
    while (nf < 200000 && fgets(line, sizeof line, f)) {
        long vf, ci;
        unsigned long long id;
        double cam, host, mapped;
        assert_int_equal(sscanf(line, "%ld,%ld,%llu,%lf,%lf,%lf", &vf, &ci, &id, &cam, &host, &mapped), 6);
        assert_int_equal(vf, nf);
        while (j + 1 < nt && fabs(real[j + 1] - cam) < fabs(real[j] - cam)) j++;
        assert_true(fabs(real[j] - cam) < 1e-4); /* the frame is one the simulator sent */
        err[nf++] = fabs(mapped - mono[j]);
    }
    fclose(f);
    assert_int_equal(nf, rec);
    double worst = 0.0;
    long worst_at = -1;
    for (long k = 0; k < nf; k++)
        if (err[k] > worst) {
            worst = err[k];
            worst_at = k;
        }
    long below = 0;
    for (long k = 0; k < nf; k++) below += err[k] < 1e-3;
    printf("# stamps: %ld frames, %ld within 1 ms of the true send time, worst %.3f ms (video frame %ld)\n", nf,
           below, 1e3 * worst, worst_at);
    /* issue 13: every frame's stored time within 1 ms of the simulator's true send time */
    assert_int_equal(below, nf);
}

/* From the truth log: the real time of the last image at which either axis had moved since the
 * image before (NaN: never). */
static double last_axis_move(rehearsal *r)
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

/* Waits (at most 90 s) until trial 1 is shearing; 0 when it is. */
static int wait_shearing(rehearsal *r)
{
    sqlite3 *db = db_open(r);
    double t_end = now_real() + 90.0;
    char st[64] = "";
    while (now_real() < t_end) {
        q_text(db, "select coalesce(state,'') from trials where id = 1", st, sizeof st);
        if (!strcmp(st, "shearing") || !strcmp(st, "failed") || !strcmp(st, "done")) break;
        sleep_s(0.05);
    }
    sqlite3_close(db);
    return strcmp(st, "shearing") ? -1 : 0;
}

/* A fault on command mid-shear (SIGUSR2 camera), then the trial's end. */
static void fault_mid_shear(rehearsal *r, int sig)
{
    start(r, NULL);
    assert_int_equal(trial(r, 0), 0);
    assert_int_equal(wait_shearing(r), 0);
    sleep_s(0.5);
    kill(r->sim, sig);
    /* until the trial has ended */
    sqlite3 *db = db_open(r);
    double t_end = now_real() + 60.0;
    char status[64] = "";
    while (now_real() < t_end) {
        q_text(db, "select status from trials where id = 1", status, sizeof status);
        if (strcmp(status, "running") && strcmp(status, "created")) break;
        sleep_s(0.1);
    }
    sqlite3_close(db);
    stop(r);
}

static void test_camera_stops_mid_shear(void **state)
{
    (void)state;
    rehearsal r;
    fault_mid_shear(&r, SIGUSR2);
    sqlite3 *db = db_open(&r);
    char status[64], why[512];
    q_text(db, "select status from trials where id = 1", status, sizeof status);
    q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    char st[64];
    q_text(db, "select state from events where trial_id = 1 and kind = 'fault' order by id limit 1", st, sizeof st);
    double cut = cut_time(&r, "camera stopped"), seen = wall_of(db, "camera:%");
    printf("# %s in %s: %s; detected %.3f s after the camera stopped\n", status, st, why, seen - cut);
    assert_string_equal(status, "failed");
    assert_string_equal(st, "shearing");
    assert_non_null(strstr(why, "camera"));
    assert_true(seen - cut < 0.5); /* issue 13: within 0.5 s */
    check_integrity(db);
    sqlite3_close(db);
}

/* The image freezes mid-shear (SIGRTMIN): failed, naming the frozen image, within 0.5 s; both rails
 * stopped (the truth log: no axis moves 1 s after the detection), samples stored, integrity ok. */
static void test_frozen_image_mid_shear(void **state)
{
    (void)state;
    rehearsal r;
    fault_mid_shear(&r, SIGRTMIN);
    sqlite3 *db = db_open(&r);
    char status[64], why[512], st[64];
    q_text(db, "select status from trials where id = 1", status, sizeof status);
    q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    q_text(db, "select state from events where trial_id = 1 and kind = 'fault' order by id limit 1", st, sizeof st);
    double cut = cut_time(&r, "image frozen"), seen = wall_of(db, "camera: the image is frozen%");
    double moved = last_axis_move(&r);
    printf("# %s in %s: %s; detected %.3f s after the freeze; last axis motion %.3f s after it\n", status, st, why,
           seen - cut, moved - seen);
    assert_string_equal(status, "failed");
    assert_string_equal(st, "shearing");
    assert_non_null(strstr(why, "frozen"));
    assert_true(seen - cut < 0.5);
    assert_true(!(moved - seen > 1.0));
    assert_true(q_num(db, "select count(*) from samples where trial_id = 1") > 100);
    check_integrity(db);
    sqlite3_close(db);
}

/* GVSP packets lost all along (1e-4 of them: a few frames in a hundred damaged): the trial goes on
 * to done, the losses counted in the pipeline's event and noted as warnings while it ran. */
static void test_lost_packets_trial_goes_on(void **state)
{
    (void)state;
    rehearsal r;
    const char *extra[] = {"--lost-packets", "1e-4", NULL};
    start(&r, extra);
    int rc = trial(&r, 1);
    stop(&r);
    sqlite3 *db = db_open(&r);
    char status[64], why[512], pipe[600], note[400];
    q_text(db, "select status from trials where id = 1", status, sizeof status);
    q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    q_text(db, "select message from events where trial_id = 1 and message like 'pipeline:%'", pipe, sizeof pipe);
    q_text(db, "select message from events where trial_id = 1 and message like 'camera: % lost or incomplete%'", note,
           sizeof note);
    printf("# lost packets: %s %s (ribbonctl %d)\n# %s\n# %s\n", status, why, rc, pipe, note);
    assert_string_equal(status, "done");
    long cap = -1, lost = -1, inc = -1, drop = -1, rec = -1;
    assert_int_equal(sscanf(pipe, "pipeline: %ld frames captured, %ld lost by the camera or link (id gaps), %ld "
                                  "incomplete buffers, %ld dropped by the pipeline, %ld recorded",
                            &cap, &lost, &inc, &drop, &rec),
                     5);
    assert_true(lost + inc > 0);
    assert_int_equal(rec, cap);
    assert_true(note[0] != '\0');
    /* every frame up to the trial's end has its sample (the frames after it are in the video only) */
    double nfs = q_num(db, "select count(*) from samples where trial_id = 1 and kind = 1");
    assert_true(nfs > 0.9 * cap);
    assert_true(nfs == q_num(db, "select max(frame) + 1 from samples where trial_id = 1 and kind = 1"));
    check_integrity(db);
    sqlite3_close(db);
}

/* Packets lost heavily (5e-3: two frames in three damaged): failed with the named quality reason
 * soon after the start, the rails stopped, samples stored, integrity ok. */
static void test_heavy_loss_fails(void **state)
{
    (void)state;
    rehearsal r;
    const char *extra[] = {"--lost-packets", "5e-3", NULL};
    start(&r, extra);
    trial(&r, 1);
    sleep_s(1.5);
    stop(&r);
    sqlite3 *db = db_open(&r);
    char status[64], why[512];
    q_text(db, "select status from trials where id = 1", status, sizeof status);
    q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    double seen = wall_of(db, "%lost or incomplete: %"), moved = last_axis_move(&r);
    printf("# heavy loss: %s: %s; last axis motion %.3f s after the detection\n", status, why, moved - seen);
    assert_string_equal(status, "failed");
    assert_non_null(strstr(why, "lost or incomplete"));
    assert_true(isfinite(seen));
    assert_true(!(moved - seen > 1.0));
    check_integrity(db);
    sqlite3_close(db);
}

/* Bad camera input, each a named error before anything moves: no compression started (no 'start:'
 * event), no sample, no video; and ribbonctl cameras lists the simulator's camera. */
static void bad_input_case(const char *set, const char *needle)
{
    rehearsal r;
    daemon_extra[0] = set;
    daemon_extra[1] = NULL;
    start(&r, NULL);
    daemon_extra[0] = NULL;
    trial(&r, 1);
    stop(&r);
    sqlite3 *db = db_open(&r);
    char status[64], why[512];
    q_text(db, "select status from trials where id = 1", status, sizeof status);
    q_text(db, "select coalesce(reason,'') from trials where id = 1", why, sizeof why);
    printf("# %s: %s: %s\n", set, status, why);
    assert_string_equal(status, "failed");
    assert_non_null(strstr(why, needle));
    assert_true(q_num(db, "select count(*) from events where trial_id = 1 and message like 'start:%'") == 0);
    assert_true(q_num(db, "select count(*) from samples where trial_id = 1") == 0);
    check_integrity(db);
    sqlite3_close(db);
    char v[160];
    snprintf(v, sizeof v, "%s/videos/trial-1.avi", r.dir);
    assert_int_equal(access(v, F_OK), -1);
    snprintf(v, sizeof v, "%s/videos/trial-1.avi.frames.csv", r.dir);
    assert_int_equal(access(v, F_OK), -1);
}

static void test_bad_camera_input(void **state)
{
    (void)state;
    bad_input_case("camera.source=aravis:no-such-camera-4711", "not found");
    bad_input_case("camera.offset_x_px=4000", "OffsetX 4000 refused"); /* the sensor is 2048 wide */
    /* the simulator writes the calibration for 640 x 480; ribbond asks the camera for 320 x 480 */
    bad_input_case("camera.width_px=320", "calibration");
}

static void test_ribbonctl_cameras_finds_the_simulator(void **state)
{
    (void)state;
    rehearsal r;
    start(&r, NULL);
    char cmd[400], path[160], line[1024];
    snprintf(path, sizeof path, "%s/cameras.json", r.dir);
    snprintf(cmd, sizeof cmd, "%s/ribbonctl cameras --json > %s 2>&1", BIN, path);
    int rc = system(cmd);
    stop(&r);
    assert_true(WIFEXITED(rc) && WEXITSTATUS(rc) == 0);
    assert_true(file_has(path, "\"source\":\"aravis:", line, sizeof line));
    printf("# %s", line);
    assert_non_null(strstr(line, "RIBBONSIM")); /* ribbon-rigsim's serial */
    assert_non_null(strstr(line, "GigEVision"));
}

static void test_sigkill_mid_shear(void **state)
{
    (void)state;
    rehearsal r;
    start(&r, NULL);
    assert_int_equal(trial(&r, 0), 0);
    /* wait for the shear to run, then kill ribbond */
    sqlite3 *db = db_open(&r);
    double t_end = now_real() + 60.0;
    char st[64] = "";
    while (now_real() < t_end) {
        q_text(db, "select coalesce(state,'') from trials where id = 1", st, sizeof st);
        if (!strcmp(st, "shearing")) break;
        sleep_s(0.05);
    }
    sqlite3_close(db);
    assert_string_equal(st, "shearing");
    sleep_s(1.0);
    double t_kill = now_real();
    kill(r.daemon, SIGKILL);
    waitpid(r.daemon, NULL, 0);
    r.daemon = -1;
    sleep_s(3.0);
    stop(&r);
    /* From the truth log: the last time the shear axis moved. */
    char path[160], line[512];
    snprintf(path, sizeof path, "%s/truth.csv", r.dir);
    FILE *t = fopen(path, "r");
    assert_non_null(t);
    assert_non_null(fgets(line, sizeof line, t));
    double last_move = NAN, prev = NAN;
    while (fgets(line, sizeof line, t)) {
        long k;
        double mono, real, pc, ps;
        if (sscanf(line, "%ld,%lf,%lf,%lf,%lf", &k, &mono, &real, &pc, &ps) != 5) continue;
        if (isfinite(prev) && fabs(ps - prev) > 1e-4) last_move = real;
        prev = ps;
    }
    fclose(t);
    printf("# SIGKILL mid-shear: the shear axis stood %.3f s after the kill\n", last_move - t_kill);
    /* The GRBL driver keeps at most its queued jog segments ahead (rail_gcode.h: segment_s each,
     * a few queued) plus the deceleration: 1 s bounds it generously at 10 mm/s. */
    assert_true(isfinite(last_move));
    assert_true(last_move - t_kill < 1.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_gcode_trial, teardown),
        cmocka_unit_test_teardown(test_camera_stops_mid_shear, teardown),
        cmocka_unit_test_teardown(test_sigkill_mid_shear, teardown),
        cmocka_unit_test_teardown(test_frozen_image_mid_shear, teardown),
        cmocka_unit_test_teardown(test_lost_packets_trial_goes_on, teardown),
        cmocka_unit_test_teardown(test_heavy_loss_fails, teardown),
        cmocka_unit_test_teardown(test_bad_camera_input, teardown),
        cmocka_unit_test_teardown(test_ribbonctl_cameras_finds_the_simulator, teardown),
    };
    /* REHEARSAL_TESTS=PATTERN runs only the matching tests (cmocka's filter: * and ? wildcards). */
    if (getenv("REHEARSAL_TESTS")) cmocka_set_test_filter(getenv("REHEARSAL_TESTS"));
    return cmocka_run_group_tests(tests, NULL, NULL);
}
