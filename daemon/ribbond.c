/* ribbond.c: the rig daemon's main: load the rig file, open the store and the rails, serve the
 * control API, and stop cleanly on SIGTERM / SIGINT (the running trial is aborted, the rails
 * stopped, samples flushed; exit 0). Under systemd (Type=notify) it reports READY=1 once the API
 * listens and STOPPING=1 when it begins to stop. `ribbond bench` measures the store's sample rate
 * and the wall time of a complete mock trial, on one machine-readable line. SIGHUP runs the rig's
 * readiness checks again (rig_daemon_check). */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>
#include <systemd/sd-daemon.h>

#include "rig_daemon.h"
#include "store.h"
#include "trial.h"

static void log_line(const char *line)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    struct tm tm;
    gmtime_r(&ts.tv_sec, &tm);
    char stamp[32];
    strftime(stamp, sizeof stamp, "%H:%M:%S", &tm);
    fprintf(stderr, "ribbond %s %s\n", stamp, line);
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ribbond --config RIG.ini [--set section.key=value ...]\n"
            "       ribbond bench [--config RIG.ini] [--samples N] [--json]\n"
            "\n"
            "Runs snap-through trials on the rig named by the rig file (mode rig, mock or replay), serves\n"
            "the control API (HTTP+JSON, [api] listen and port; a token is required off loopback) and keeps\n"
            "every trial, its samples, events, video and prediction in the SQLite store ([store] path).\n"
            "Drive it with ribbonctl (start, abort, status, list, show, report, ...).\n"
            "At start-up, trials left running by a dead daemon are marked interrupted; motion is never\n"
            "resumed. SIGTERM or SIGINT aborts the running trial, stops the rails and exits 0.\n"
            "It runs the rig's readiness checks (as ribbonctl check) at start: while one fails it serves\n"
            "status and the page with the reasons and refuses trials; SIGHUP or POST /checks runs them again\n"
            "(in rig mode, rails that did not open are opened then).\n"
            "One daemon per store and per rail device: ribbond locks STORE.lock beside the store and each\n"
            "serial port or Modbus drive of the rig file (in $RIBBON_LOCK_DIR, else /run/lock) before it\n"
            "touches anything; a second one refuses to start, naming the first (pid, since when).\n"
            "\n"
            "bench: prints one JSON line: samples_per_s (batched SQLite writes, target >= 50000) and\n"
            "mock_trial_wall_s (a complete mock trial of config/mock.ini, or --config).\n");
}

/* ---- bench --------------------------------------------------------------------------------- */

static int bench(int argc, char **argv)
{
    const char *config = "config/mock.ini";
    long samples = 200000;
    for (int i = 0; i < argc; i++) {
        if (!strcmp(argv[i], "--config") && i + 1 < argc)
            config = argv[++i];
        else if (!strcmp(argv[i], "--samples") && i + 1 < argc)
            samples = strtol(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--json"))
            continue;
        else {
            fprintf(stderr, "ribbond bench: unknown argument %s\n", argv[i]);
            return 2;
        }
    }
    char dir[] = "/tmp/ribbond-bench-XXXXXX";
    if (!mkdtemp(dir)) {
        fprintf(stderr, "ribbond bench: no temporary directory: %s\n", strerror(errno));
        return 1;
    }
    char db[256], why[512];
    snprintf(db, sizeof db, "%s/samples.db", dir);
    double rate = 0.0;
    if (store_bench_samples(db, samples, &rate, why, sizeof why) != STORE_OK) {
        fprintf(stderr, "ribbond bench: store: %s\n", why);
        return 1;
    }
    /* A complete mock trial into a store of its own. */
    char store_set[300], video_set[300];
    snprintf(store_set, sizeof store_set, "store.path=%s/trial.db", dir);
    snprintf(video_set, sizeof video_set, "camera.video_dir=%s", dir);
    const char *ov[2] = {store_set, video_set};
    rig_daemon d;
    if (rig_daemon_open(&d, config, ov, 2, NULL, why, sizeof why)) {
        fprintf(stderr, "ribbond bench: %s\n", why);
        return 1;
    }
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    trial_session *s = NULL;
    int64_t id = 0;
    if (trial_session_start_tx(&d.cfg, d.overrides, d.n_overrides, d.compress, d.shear, "bench", NULL, NULL, NULL, &s,
                               &id, why, sizeof why)) {
        fprintf(stderr, "ribbond bench: %s\n", why);
        rig_daemon_close(&d, "bench");
        return 1;
    }
    trial_result r;
    trial_session_join(s, &r);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double wall = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    rig_daemon_close(&d, "bench");
    printf("{\"bench\":\"ribbond\",\"samples\":%ld,\"samples_per_s\":%.0f,\"mock_trial_wall_s\":%.2f,"
           "\"mock_trial_status\":\"%s\",\"mock_trial_frames\":%ld,\"snap_dw_measured\":%.5f,\"regime\":\"%s\"}\n",
           samples, rate, wall, trial_state_name(r.final), r.frames, r.snapped ? r.snap_dw : 0.0, r.regime);
    return r.final == TRIAL_DONE ? 0 : 1;
}

/* ---- daemon ---------------------------------------------------------------------------------- */

int main(int argc, char **argv)
{
    /* GSL's default handler aborts the process; every GSL failure is a returned status here. */
    gsl_set_error_handler_off();
    if (argc > 1 && !strcmp(argv[1], "bench")) return bench(argc - 2, argv + 2);
    const char *config = NULL;
    const char *ov[RIG_DAEMON_MAX_OVERRIDES];
    int nov = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(argv[i], "--config") && i + 1 < argc) {
            config = argv[++i];
        } else if (!strcmp(argv[i], "--set") && i + 1 < argc) {
            if (nov >= RIG_DAEMON_MAX_OVERRIDES) {
                fprintf(stderr, "ribbond: at most %d --set\n", RIG_DAEMON_MAX_OVERRIDES);
                return 2;
            }
            ov[nov++] = argv[++i];
        } else {
            fprintf(stderr, "ribbond: unknown argument %s\n", argv[i]);
            usage(stderr);
            return 2;
        }
    }
    if (!config) {
        fprintf(stderr, "ribbond: --config RIG.ini is required (config/mock.ini runs anywhere)\n");
        return 2;
    }
    /* Signals are taken by sigwait in this thread only: block them before any thread starts. */
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &set, NULL);
    signal(SIGPIPE, SIG_IGN);

    rig_daemon d;
    char why[1024];
    if (rig_daemon_open(&d, config, ov, nov, log_line, why, sizeof why)) {
        fprintf(stderr, "ribbond: %s\n", why);
        return 1;
    }
    unsigned port = 0;
    if (rig_daemon_serve(&d, &port, why, sizeof why)) {
        fprintf(stderr, "ribbond: API: %s\n", why);
        rig_daemon_close(&d, "start-up failed");
        return 1;
    }
    char line[600];
    snprintf(line, sizeof line, "%s mode, store %.400s, listening on http://%s:%u", rig_mode_name(d.cfg.mode),
             d.cfg.store_path, strchr(d.cfg.api.listen, ':') ? "[::1]" : d.cfg.api.listen, port);
    log_line(line);
    sd_notifyf(0, "READY=1\nSTATUS=%s", line);

    int sig = 0;
    for (int stop = 0; !stop;) {
        if (sigwait(&set, &sig) != 0) continue;
        stop = sig != SIGHUP;
        if (!stop && rig_daemon_check(&d, NULL, why, sizeof why)) { /* SIGHUP: the checks again */
            snprintf(line, sizeof line, "SIGHUP: checks not run: %.500s", why);
            log_line(line);
        }
    }
    snprintf(line, sizeof line, "signal %s: stopping (running trial aborted, rails stopped)", strsignal(sig));
    log_line(line);
    sd_notify(0, "STOPPING=1");
    char reason[64];
    snprintf(reason, sizeof reason, "daemon stopped by %s", strsignal(sig));
    rig_daemon_close(&d, reason);
    log_line("stopped");
    return 0;
}
