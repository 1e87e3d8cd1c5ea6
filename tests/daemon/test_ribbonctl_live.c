/* test_ribbonctl_live: the real programs together, as a lab user runs them. ribbond is started
 * on config/mock.ini (any free port) with NOTIFY_SOCKET pointing at a datagram socket of the test,
 * as systemd would; ribbonctl is run as a separate process for every command.
 *   1. ribbond reports READY=1 on the notify socket once it listens;
 *   2. ribbonctl start --wait --out runs a whole trial, prints measured and predicted and the
 *      `database:` line, and writes the report PNG; status, list --json, show --json, export --csv
 *      and report ask the daemon; an unknown trial and an abort while idle exit non-zero;
 *   3. start then abort: the trial ends aborted;
 *   4. start then SIGTERM to ribbond: it sends STOPPING=1, exits 0, and the trial is stored
 *      aborted with the signal as its reason (read offline with --db);
 *   5. offline with --db: phase-report draws its PNG, replay reproduces the measured snap.
 * Labelled heavy (three mock trials through two processes). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <jansson.h>

static char dir[64], db[128], url[128], sock_path[96];
static int notify_fd = -1;
static pid_t daemon_pid = -1;

static void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&ts, NULL);
}

/* Reads a whole small file (malloc'ed, NUL-terminated); NULL if it cannot be read. */
static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 4096, n = 0;
    char *b = malloc(cap);
    size_t got;
    while (b && (got = fread(b + n, 1, cap - n - 1, f)) > 0) {
        n += got;
        if (n + 1 == cap) {
            char *nb = realloc(b, 2 * cap);
            if (!nb) {
                free(b);
                b = NULL;
                break;
            }
            b = nb;
            cap *= 2;
        }
    }
    fclose(f);
    if (b) b[n] = 0;
    return b;
}

/* Runs ribbonctl with the arguments (NULL-terminated); stdout into *out (malloc'ed), stderr into
 * *err; returns the exit status (or -1). */
static int ribbonctl(char **out, char **err, ...)
{
    const char *argv[32];
    int n = 0;
    argv[n++] = RIBBON_BIN_DIR "/ribbonctl";
    va_list ap;
    va_start(ap, err);
    const char *a;
    while (n < 31 && (a = va_arg(ap, const char *)) != NULL) argv[n++] = a;
    va_end(ap);
    argv[n] = NULL;
    char o[160], e[160];
    snprintf(o, sizeof o, "%s/ctl.out", dir);
    snprintf(e, sizeof e, "%s/ctl.err", dir);
    pid_t pid = fork();
    if (pid == 0) {
        int fo = open(o, O_WRONLY | O_CREAT | O_TRUNC, 0644), fe = open(e, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fo < 0 || fe < 0) _exit(126);
        dup2(fo, 1);
        dup2(fe, 2);
        execv(argv[0], (char *const *)argv);
        _exit(127);
    }
    int ws = 0;
    if (pid < 0 || waitpid(pid, &ws, 0) != pid) return -1;
    char *so = slurp(o), *se = slurp(e);
    if (out) *out = so; else free(so);
    if (err) *err = se; else free(se);
    return WIFEXITED(ws) ? WEXITSTATUS(ws) : -1;
}

/* Receives one datagram from the notify socket within max_s; returns 1 and the text in buf. */
static int notify_recv(char *buf, size_t n, double max_s)
{
    for (double t = 0; t < max_s; t += 0.05) {
        ssize_t k = recv(notify_fd, buf, n - 1, MSG_DONTWAIT);
        if (k >= 0) {
            buf[k] = 0;
            return 1;
        }
        sleep_s(0.05);
    }
    return 0;
}

static void start_daemon(void)
{
    char log[160], set_store[200], set_video[200];
    snprintf(log, sizeof log, "%s/ribbond.log", dir);
    snprintf(set_store, sizeof set_store, "store.path=%s", db);
    snprintf(set_video, sizeof set_video, "camera.video_dir=%s/videos", dir);
    daemon_pid = fork();
    assert_true(daemon_pid >= 0);
    if (daemon_pid == 0) {
        int fl = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fl < 0) _exit(126);
        dup2(fl, 2);
        setenv("NOTIFY_SOCKET", sock_path, 1);
        execl(RIBBON_BIN_DIR "/ribbond", "ribbond", "--config", RIBBON_SOURCE_DIR "/config/mock.ini", "--set",
              set_store, "--set", set_video, "--set", "api.port=0", "--set", "sim.nodes=61", (char *)NULL);
        _exit(127);
    }
    /* The URL from its log, READY=1 from its notify socket. */
    url[0] = 0;
    for (int k = 0; k < 600 && !url[0]; k++) {
        char *t = slurp(log);
        const char *p = t ? strstr(t, "listening on ") : NULL;
        if (p) sscanf(p + 13, "%127s", url);
        free(t);
        if (!url[0]) sleep_s(0.1);
    }
    if (!url[0]) {
        char *t = slurp(log);
        fprintf(stderr, "ribbond log:\n%s\n", t ? t : "(none)");
        free(t);
    }
    assert_true(url[0] != 0);
    char msg[512];
    assert_true(notify_recv(msg, sizeof msg, 10));
    printf("notify: %s\n", msg);
    assert_non_null(strstr(msg, "READY=1"));
}

static int setup(void **state)
{
    (void)state;
    snprintf(dir, sizeof dir, "/tmp/ribbonctl-live-XXXXXX");
    assert_non_null(mkdtemp(dir));
    snprintf(db, sizeof db, "%s/trials.db", dir);
    snprintf(sock_path, sizeof sock_path, "%s/notify.sock", dir);
    notify_fd = socket(AF_UNIX, SOCK_DGRAM, 0);
    assert_true(notify_fd >= 0);
    struct sockaddr_un sa;
    memset(&sa, 0, sizeof sa);
    sa.sun_family = AF_UNIX;
    snprintf(sa.sun_path, sizeof sa.sun_path, "%.90s", sock_path);
    assert_int_equal(bind(notify_fd, (struct sockaddr *)&sa, sizeof sa), 0);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    if (daemon_pid > 0) {
        kill(daemon_pid, SIGKILL);
        waitpid(daemon_pid, NULL, 0);
    }
    close(notify_fd);
    char cmd[160];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    return system(cmd) == 0 ? 0 : -1;
}

static json_t *parse_json(const char *text)
{
    json_error_t je;
    json_t *j = text ? json_loads(text, 0, &je) : NULL;
    if (!j) fprintf(stderr, "not JSON (%s): %.500s\n", text ? je.text : "no output", text ? text : "");
    assert_non_null(j);
    return j;
}

static int is_png(const char *path)
{
    FILE *f = fopen(path, "rb");
    unsigned char m[4] = {0};
    int ok = f && fread(m, 1, 4, f) == 4 && !memcmp(m, "\x89PNG", 4);
    if (f) fclose(f);
    struct stat sb;
    return ok && stat(path, &sb) == 0 && sb.st_size > 1000;
}

/* Polls `ribbonctl status` until the daemon is idle. */
static void wait_idle(double max_s)
{
    for (double t = 0; t < max_s; t += 0.25) {
        char *out = NULL;
        assert_int_equal(ribbonctl(&out, NULL, "status", "--url", url, NULL), 0);
        json_t *s = parse_json(out);
        free(out);
        int idle = !strcmp(json_string_value(json_object_get(s, "state")), "idle");
        json_decref(s);
        if (idle) return;
        sleep_s(0.25);
    }
    fail_msg("ribbond still running a trial after %.0f s", max_s);
}

/* Starts a trial without waiting; returns its id once it is shearing or later (so abort and
 * SIGTERM meet moving rails). */
static long start_and_get_going(void)
{
    char *out = NULL;
    assert_int_equal(ribbonctl(&out, NULL, "start", "--url", url, "--json", NULL), 0);
    json_t *t = parse_json(out);
    free(out);
    long id = (long)json_integer_value(json_object_get(t, "id"));
    json_decref(t);
    assert_true(id > 0);
    for (int k = 0; k < 400; k++) {
        assert_int_equal(ribbonctl(&out, NULL, "status", "--url", url, NULL), 0);
        json_t *s = parse_json(out);
        free(out);
        const char *st = json_string_value(json_object_get(json_object_get(s, "trial"), "state"));
        int going = st && (!strcmp(st, "compressing") || !strcmp(st, "holding") || !strcmp(st, "checking") ||
                           !strcmp(st, "shearing"));
        json_decref(s);
        if (going) break;
        sleep_s(0.05);
    }
    return id;
}

static void live_daemon(void **state)
{
    (void)state;
    start_daemon();
    printf("ribbond at %s\n", url);

    /* 2. A whole trial through ribbonctl. */
    char report[160];
    snprintf(report, sizeof report, "%s/report.png", dir);
    char *out = NULL, *err = NULL;
    int rc = ribbonctl(&out, &err, "start", "--url", url, "--note", "live", "--wait", "--out", report, NULL);
    if (rc) fprintf(stderr, "start --wait: %s\n%s\n", out ? out : "", err ? err : "");
    assert_int_equal(rc, 0);
    printf("%s", out);
    assert_non_null(strstr(out, "measured"));
    assert_non_null(strstr(out, "predicted"));
    /* The twin's own snap (mock.ini [twin]: another strip than the prediction's) with both
     * differences: the measurement is scored against it, within one frame of shear (30 fps) and one
     * twin step (docs/trials.md "The twin and its truth"). */
    double truth = NAN;
    const char *tt = strstr(out, "twin truth snap Delta W = ");
    assert_non_null(tt);
    assert_int_equal(sscanf(tt, "twin truth snap Delta W = %lf", &truth), 1);
    assert_non_null(strstr(out, "measured - twin truth"));
    assert_non_null(strstr(out, "predicted - twin truth"));
    char want[200];
    snprintf(want, sizeof want, "database: %s", db);
    assert_non_null(strstr(out, want));
    free(out);
    free(err);
    assert_true(is_png(report));

    assert_int_equal(ribbonctl(&out, NULL, "list", "--url", url, "--json", NULL), 0);
    json_t *list = parse_json(out);
    free(out);
    assert_int_equal(json_array_size(list), 1);
    json_t *t0 = json_array_get(list, 0);
    const char *keys[] = {"id", "mode", "status", "snap_dw_measured", "snap_dw_predicted", "regime_measured",
                          "regime_predicted", "samples"};
    for (size_t k = 0; k < sizeof keys / sizeof *keys; k++) assert_non_null(json_object_get(t0, keys[k]));
    assert_string_equal(json_string_value(json_object_get(t0, "status")), "done");
    double meas = json_number_value(json_object_get(t0, "snap_dw_measured"));
    double pred = json_number_value(json_object_get(t0, "snap_dw_predicted"));
    assert_true(fabs(meas - truth) <= 0.05 / 30.0 + 0.05 * 1e-3 + 1e-9);
    assert_true(pred > 0 && fabs(pred - truth) / truth < 0.10);
    json_decref(list);

    assert_int_equal(ribbonctl(&out, NULL, "show", "1", "--url", url, "--json", NULL), 0);
    json_t *t = parse_json(out);
    free(out);
    assert_int_equal(json_integer_value(json_object_get(t, "id")), 1);
    assert_true(json_array_size(json_object_get(t, "events")) >= 7);
    json_decref(t);

    char csv[160];
    snprintf(csv, sizeof csv, "%s/samples.csv", dir);
    assert_int_equal(ribbonctl(NULL, NULL, "export", "1", "--csv", "--out", csv, "--url", url, NULL), 0);
    char *text = slurp(csv);
    assert_non_null(text);
    long lines = 0;
    for (const char *p = text; *p; p++) lines += *p == '\n';
    printf("export: %ld lines, header %.60s\n", lines, text);
    assert_true(lines > 100);
    free(text);

    snprintf(report, sizeof report, "%s/report2.png", dir);
    assert_int_equal(ribbonctl(NULL, NULL, "report", "1", "--out", report, "--url", url, NULL), 0);
    assert_true(is_png(report));

    /* Errors exit non-zero with the reason. */
    assert_int_not_equal(ribbonctl(NULL, &err, "show", "99", "--url", url, NULL), 0);
    assert_non_null(strstr(err, "404"));
    free(err);
    assert_int_not_equal(ribbonctl(NULL, &err, "abort", "--url", url, NULL), 0);
    assert_non_null(strstr(err, "409"));
    free(err);

    /* 3. Start, then abort. */
    long id = start_and_get_going();
    assert_int_equal(ribbonctl(NULL, NULL, "abort", "--url", url, NULL), 0);
    wait_idle(120);
    char ids[16];
    snprintf(ids, sizeof ids, "%ld", id);
    assert_int_equal(ribbonctl(&out, NULL, "show", ids, "--url", url, "--json", NULL), 0);
    t = parse_json(out);
    free(out);
    printf("trial %ld after abort: %s (%s)\n", id, json_string_value(json_object_get(t, "status")),
           json_string_value(json_object_get(t, "reason")));
    assert_string_equal(json_string_value(json_object_get(t, "status")), "aborted");
    json_decref(t);

    /* 4. Start, then SIGTERM the daemon. */
    id = start_and_get_going();
    assert_int_equal(kill(daemon_pid, SIGTERM), 0);
    int ws = 0;
    assert_int_equal(waitpid(daemon_pid, &ws, 0), daemon_pid);
    daemon_pid = -1;
    assert_true(WIFEXITED(ws));
    assert_int_equal(WEXITSTATUS(ws), 0);
    char msg[512];
    assert_true(notify_recv(msg, sizeof msg, 5));
    printf("notify: %s\n", msg);
    assert_non_null(strstr(msg, "STOPPING=1"));
    snprintf(ids, sizeof ids, "%ld", id);
    assert_int_equal(ribbonctl(&out, NULL, "show", ids, "--db", db, "--json", NULL), 0);
    t = parse_json(out);
    free(out);
    printf("trial %ld after SIGTERM: %s (%s)\n", id, json_string_value(json_object_get(t, "status")),
           json_string_value(json_object_get(t, "reason")));
    assert_string_equal(json_string_value(json_object_get(t, "status")), "aborted");
    assert_non_null(strstr(json_string_value(json_object_get(t, "reason")), "daemon stopped by"));
    json_decref(t);

    /* 5. Offline: phase report and replay. */
    char phase[160];
    snprintf(phase, sizeof phase, "%s/phase.png", dir);
    rc = ribbonctl(NULL, &err, "phase-report", "--db", db, "--out", phase, "--scene",
                   RIBBON_SOURCE_DIR "/config/scenes/mock-gamma013.ini", "--phi", "60:120:2", "--gamma",
                   "0.1:0.25:2", NULL);
    if (rc) fprintf(stderr, "phase-report: %s\n", err ? err : "");
    free(err);
    assert_int_equal(rc, 0);
    assert_true(is_png(phase));
    assert_int_equal(ribbonctl(&out, NULL, "replay", "1", "--db", db, "--json", NULL), 0);
    t = parse_json(out);
    free(out);
    double again = json_number_value(json_object_get(t, "snap_dw_measured"));
    printf("replay of trial 1: %.5f (measured %.5f)\n", again, meas);
    assert_true(fabs(again - meas) <= 0.01 / 30.0 / 0.2 + 1e-9);
    assert_int_equal(json_integer_value(json_object_get(t, "source_trial")), 1);
    json_decref(t);
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    const struct CMUnitTest tests[] = {cmocka_unit_test(live_daemon)};
    return cmocka_run_group_tests(tests, setup, teardown);
}
