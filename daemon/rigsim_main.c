/* rigsim_main.c: `ribbon-rigsim`, the rig's hardware in one process, in real time (daemon/rigsim/):
 * the rig file's rails (one GRBL controller on a pseudo-terminal linked at their port, or two
 * Modbus TCP drives on the 127.0.0.1 addresses they name), the ribbon as the digital twin stepped
 * with the axes' actual positions, and a GigE Vision camera on 127.0.0.1 filming it. Writes the
 * camera calibration file the rig file names, a truth log of every image sent (time, axis
 * positions) and optionally an axes log. The twin is the rig file's [twin] strip when it has one
 * (else the scene); its parameters are printed at start ("twin: ...") and its own snap once final
 * ("twin truth: ...", twin_truth.h), also into PATH.twin beside the truth log. Prints "ready"
 * once ribbond may start, then serves until
 * SIGINT/SIGTERM or --duration. Faults on a schedule (seconds after start) or on signals. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <signal.h>

#include "cli.h"
#include "rig_config.h"
#include "rigsim.h"
#include "twin.h"

#define PROG "ribbon-rigsim"

/* Faults on command: SIGUSR1 cuts the rails' link, SIGUSR2 stops the camera, SIGRTMIN freezes the
 * image, SIGRTMIN+1 raises an alarm (GRBL: the controller's ALARM:1; Modbus: the shear drive's
 * alarm) (the handler only sets a flag; the main loop applies it). */
static volatile sig_atomic_t cut_link, stop_camera, freeze_image, raise_alarm;
static void on_usr(int sig)
{
    if (sig == SIGUSR1) cut_link = 1;
    if (sig == SIGUSR2) stop_camera = 1;
    if (sig == SIGRTMIN) freeze_image = 1;
    if (sig == SIGRTMIN + 1) raise_alarm = 1;
}
#define MAX_SETS 32

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ribbon-rigsim RIG.INI [options]\n"
            "  --set SECTION.KEY=VALUE  override a rig file key (as ribbond --set; twin.SECTION.KEY=VALUE\n"
            "                        a key of the twin, the strip the camera films)\n"
            "  --start-dl DL         compression the specimen is mounted at (default 0.2)\n"
            "  --serial S            the camera's serial number (default RIBBONSIM)\n"
            "  --truth PATH          truth log of every image sent (CSV); PATH.twin: the twin's\n"
            "                        parameters and its own snap\n"
            "  --axes-log PATH       both axes' actual positions every 5 ms (CSV)\n"
            "  --duration S          exit after S seconds (default: until signalled)\n"
            "  --alarm-after S       the controller raises ALARM:1 (Modbus: the shear drive an alarm)\n"
            "                        S seconds after start\n"
            "  --link-lost-after S   the controller (the drives) stop answering S seconds after start\n"
            "  --stall AXIS:MM       axis X|Y stalls at MM (Modbus: X the compression, Y the shear drive)\n"
            "  --camera-stop-after S the camera stops sending S seconds after start\n"
            "  --freeze-after S      the image freezes S seconds after start\n"
            "  --lost-packets R      the camera drops each GVSP packet with probability R (0..1)\n"
            "  --camera-delay-ms MS  each image shows the twin MS ms before its timestamp (the\n"
            "                        camera's exposure-to-stamp delay; default 0)\n"
            "  --camera-tilt-deg D   the camera looks down D degrees (default 0, level; |D| < 60)\n"
            "rails: one GRBL controller on a pty (both rails driver = gcode, one port) or two Modbus TCP\n"
            "       drives on 127.0.0.1 (both driver = modbus, map = ribbon-sim)\n"
            "signals: SIGUSR1 cuts the rails' link now, SIGUSR2 stops the camera now,\n"
            "         SIGRTMIN freezes the image now, SIGRTMIN+1 raises the alarm now\n"
            "         (GRBL ALARM:1; Modbus: the shear drive's alarm 0x30)\n");
}

/* The twin's own snap on stdout ("twin truth: ...", twin_truth.h) once it is final (2 s of its
 * pathway after the detection), or at exit whatever it is. 1 when said. */
static int say_truth(rigsim_camera *cam, const rod_scene *sc, FILE *side, int at_exit)
{
    rod_snap_report r;
    double dw_now = NAN;
    rigsim_camera_twin_truth(cam, &r, &dw_now);
    if (!at_exit && !(r.snapped && r.final)) return 0;
    char line[400];
    twin_truth_snap(&r, sc->shear_rate / sc->length, dw_now, line, sizeof line);
    printf("%s\n", line);
    fflush(stdout);
    if (side) {
        fprintf(side, "%s\n", line);
        fflush(side);
    }
    return 1;
}

static int num(const char *opt, const char *v, double lo, double hi, double *out)
{
    return railsim_cli_num(PROG, opt, v, lo, hi, out);
}

int main(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    const char *rig_path = argv[1], *serial = "RIBBONSIM", *truth = NULL, *axes_log = NULL;
    const char *sets[MAX_SETS];
    int n_sets = 0;
    double start_dl = 0.2, duration = -1.0;
    rigsim_rail_faults rf = {-1.0, -1.0, 0, 0.0};
    rigsim_camera_faults cf = {-1.0, -1.0, 0.0, 0.0, 0.0};
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        int bad = 0;
        if (!v) {
            fprintf(stderr, PROG ": %s needs a value\n", a);
            return 2;
        }
        if (!strcmp(a, "--set")) {
            if (n_sets == MAX_SETS) {
                fprintf(stderr, PROG ": at most %d --set\n", MAX_SETS);
                return 2;
            }
            sets[n_sets++] = v;
        } else if (!strcmp(a, "--start-dl"))
            bad = num(a, v, 0.0, 0.99, &start_dl);
        else if (!strcmp(a, "--serial"))
            serial = v;
        else if (!strcmp(a, "--truth"))
            truth = v;
        else if (!strcmp(a, "--axes-log"))
            axes_log = v;
        else if (!strcmp(a, "--duration"))
            bad = num(a, v, 0.0, 1e7, &duration);
        else if (!strcmp(a, "--alarm-after"))
            bad = num(a, v, 0.0, 1e7, &rf.alarm_after_s);
        else if (!strcmp(a, "--link-lost-after"))
            bad = num(a, v, 0.0, 1e7, &rf.link_lost_after_s);
        else if (!strcmp(a, "--camera-stop-after"))
            bad = num(a, v, 0.0, 1e7, &cf.stop_after_s);
        else if (!strcmp(a, "--freeze-after"))
            bad = num(a, v, 0.0, 1e7, &cf.freeze_after_s);
        else if (!strcmp(a, "--lost-packets"))
            bad = num(a, v, 0.0, 1.0, &cf.lost_packets);
        else if (!strcmp(a, "--camera-tilt-deg")) {
            bad = num(a, v, -60.0, 60.0, &cf.tilt_rad);
            cf.tilt_rad *= M_PI / 180.0;
        } else if (!strcmp(a, "--camera-delay-ms")) {
            bad = num(a, v, 0.0, 1000.0, &cf.delay_s);
            cf.delay_s *= 1e-3;
        }
        else if (!strcmp(a, "--stall")) {
            if ((v[0] != 'X' && v[0] != 'Y' && v[0] != 'Z') || v[1] != ':') {
                fprintf(stderr, PROG ": --stall needs AXIS:MM, e.g. Y:60\n");
                return 2;
            }
            rf.stall_axis = v[0];
            bad = num(a, v + 2, 0.0, 1e5, &rf.stall_at_mm);
        } else {
            fprintf(stderr, PROG ": unknown option '%s'\n", a);
            usage(stderr);
            return 2;
        }
        if (bad) return 2;
        i++;
    }
    static rig_config cfg;
    char why[512] = "";
    cfg_error ce;
    if (rig_config_load(rig_path, sets, n_sets, &cfg, &ce) != CFG_OK) {
        fprintf(stderr, PROG ": %s\n", cfg_error_format(&ce, why, sizeof why));
        return 1;
    }
    if (cfg.mode != RIG_MODE_RIG) {
        fprintf(stderr, PROG ": %s is not a rig-mode file (rig.mode = rig)\n", rig_path);
        return 1;
    }
    /* The strip on the bench: [twin]'s (the scene with its keys, at its own mesh and step), or
     * without [twin] the scene at the prediction's explicit resolution (sim.nodes, sim.dt). */
    rod_scene sc = cfg.scene;
    if (cfg.twin.present) {
        sc = cfg.twin.scene;
    } else if (cfg.sim.explicit_resolution) {
        if (cfg.sim.nodes > 0) sc.nodes = cfg.sim.nodes;
        if (cfg.sim.dt > 0) sc.dt = cfg.sim.dt;
    }
    double c0 = rig_calib_compress_mm(&cfg.calib, sc.length, start_dl);
    rigsim_rails *rails = NULL;
    if (rigsim_rails_start(&cfg, c0, &rf, axes_log, &rails, why, sizeof why)) {
        fprintf(stderr, PROG ": rails: %s\n", why);
        return 1;
    }
    rigsim_camera *cam = NULL;
    if (rigsim_camera_start(&cfg, &sc, start_dl, rails, serial, cfg.camera.calibration[0] ? cfg.camera.calibration : NULL,
                            truth, &cf, &cam, why, sizeof why)) {
        fprintf(stderr, PROG ": camera: %s\n", why);
        rigsim_rails_stop(rails);
        return 1;
    }
    printf("rails thread: %s\n", rigsim_rails_realtime(rails) ? "real-time priority" : "normal priority");
    printf("twin thread: %s\n", rigsim_camera_twin_realtime(cam) ? "real-time priority" : "normal priority");
    const char *keys[RIG_TWIN_KEYS_MAX];
    for (int i = 0; i < cfg.twin.n; i++) keys[i] = cfg.twin.keys[i];
    char params[sizeof cfg.twin.keys + 128];
    twin_truth_params(&sc, keys, cfg.twin.present ? cfg.twin.n : 0, params, sizeof params);
    /* Beside the truth log, what the twin is and (later) its own snap: PATH.twin. */
    FILE *side = NULL;
    if (truth) {
        char side_path[1100];
        snprintf(side_path, sizeof side_path, "%s.twin", truth);
        side = fopen(side_path, "w");
        if (!side) fprintf(stderr, PROG ": %s cannot be written: the twin's truth goes to stdout only\n", side_path);
        else fprintf(side, "%s\n", params);
    }
    printf("rails: %s\ncamera: aravis:127.0.0.1 (serial %s)\ncalibration: %s\n%s\nready\n",
           rigsim_rails_port(rails), serial, cfg.camera.calibration, params);
    fflush(stdout);
    volatile sig_atomic_t *stop = railsim_cli_catch_stop();
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_usr;
    sigaction(SIGUSR1, &sa, NULL);
    sigaction(SIGUSR2, &sa, NULL);
    sigaction(SIGRTMIN, &sa, NULL);
    sigaction(SIGRTMIN + 1, &sa, NULL);
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    int truth_said = 0;
    while (!*stop) {
        struct timespec ts = {0, 10000000};
        nanosleep(&ts, NULL);
        if (cut_link) {
            cut_link = 0;
            rigsim_rails_cut_link(rails);
        }
        if (raise_alarm) {
            raise_alarm = 0;
            rigsim_rails_alarm(rails);
        }
        if (stop_camera) {
            stop_camera = 0;
            rigsim_camera_stop_sending(cam);
        }
        rigsim_rails_flush(rails);
        if (freeze_image) {
            freeze_image = 0;
            rigsim_camera_freeze(cam);
        }
        rigsim_camera_tick(cam);
        if (!truth_said) truth_said = say_truth(cam, &sc, side, 0);
        struct timespec t;
        clock_gettime(CLOCK_MONOTONIC, &t);
        double el = (double)(t.tv_sec - t0.tv_sec) + 1e-9 * (double)(t.tv_nsec - t0.tv_nsec);
        if (duration >= 0.0 && el >= duration) break;
    }
    if (!truth_said) say_truth(cam, &sc, side, 1);
    if (side) fclose(side);
    char rep[400];
    rigsim_camera_report(cam, rep, sizeof rep);
    printf("%s\n", rep);
    rigsim_camera_stop(cam);
    rigsim_rails_stop(rails);
    return 0;
}
