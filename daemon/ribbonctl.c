/* ribbonctl.c: `ribbonctl`, the bench-top and scripting command line of the rig. This file is
 * only the table of subcommands {name, function, one-line help}, run by cli_dispatch; each subcommand's
 * code is in its own ctl_<name>.c (see ctl.h for how to add one). */
#include <gsl/gsl_errno.h>

#include "cli.h"
#include "ctl.h"

static const cli_command commands[] = {
    {"check", ctl_check_main, "is the rig ready: every part the rig file names, one ok / warn / fail line each"},
    {"rail", ctl_rail_main, "drive one rail: status | home | move-abs MM | move-rel MM | jog MM_S | stop | estop | reset | bench"},
    {"ports", ctl_ports_main, "list serial ports (path, USB VID:PID, serial number)"},
    {"track", ctl_track_main, "measure Delta Z and A in every frame of a video: CSV, overlay, --json summary"},
    {"vision-bench", ctl_vision_bench_main, "speed of the tracker, of decoding and of decode + track, one JSON line"},
    {"calibrate-camera", ctl_calibrate_camera_main, "the camera's calibration from the clamps in its live stream at zero shear: --config RIG --out FILE"},
    {"cameras", ctl_cameras_main, "list cameras: V4L2 devices and GenICam (GigE Vision, USB3 Vision) cameras"},
    {"transcode", ctl_transcode_main, "a raw trial video to lossless FFV1, verified bit for bit; --bench: one JSON line"},
    {"render", ctl_render_main, "simulate a scene's trial and film it: FFV1 video + ground truth CSV, JSON summary"},
    {"start", ctl_trials_main, "ask ribbond to run a trial (--set overrides, --note, --wait to follow it)"},
    {"abort", ctl_trials_main, "abort the running trial (rails stop where they are)"},
    {"status", ctl_trials_main, "the daemon's state and the running trial (JSON)"},
    {"list", ctl_trials_main, "every trial: measured and predicted snap and regime (--json, --db FILE)"},
    {"show", ctl_trials_main, "one trial with its events (--json, --db FILE)"},
    {"export", ctl_trials_main, "samples as CSV: export ID --csv [--out F] | export --all --out DIR (--db FILE)"},
    {"report", ctl_trials_main, "report ID --out FILE.png: Delta Z and A against Delta W, measured and predicted"},
    {"phase-report", ctl_trials_main, "every trial's measured regime on the predicted (Gamma, phi) phase diagram"},
    {"replay", ctl_trials_main, "replay ID: a recorded trial through tracking and snap detection again"},
    {"calibrate", ctl_calibrate_main, "calibrate ID [ID ...]: one strip fitted to stored trials, its snap predicted with a band"},
    {"specimen", ctl_campaign_main, "the store's specimens: add NAME --phi DEG --gamma G ... | list | show NAME | retire NAME"},
    {"phase", ctl_phase_main, "the lab's phase diagram: measured regimes, experimental and predicted boundaries (--out, --csv, --json)"},
    {"plan", ctl_plan_main, "the next specimens to make (--phi LIST --count K), stored; --approve N puts one in the queue"},
    {"plan-bench", ctl_plan_bench_main, "the simulated campaign: the planner against twins it does not know, one line"},
    {"rails", ctl_rails_main, "a rail of the running ribbond: home NAME --confirm | confirm-zero NAME --confirm"},
    {"queue", ctl_campaign_main, "the campaign's queue: add trial|operator|pause | list | show | remove | move | start | stop | confirm"},
};

static const cli_program program = {
    .name = "ribbonctl",
    .usage = "usage: ribbonctl COMMAND [options]   (ribbonctl COMMAND --help for details)\n\n",
    .commands = commands,
    .ncommands = sizeof commands / sizeof commands[0],
};

int main(int argc, char **argv)
{
    /* GSL's default handler aborts; the simulator's callers (render, phase-report) take every GSL
     * failure as a returned status instead. */
    gsl_set_error_handler_off();
    return cli_dispatch(&program, argc, argv);
}
