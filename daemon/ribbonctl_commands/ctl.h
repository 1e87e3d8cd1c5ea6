/* ctl.h: the subcommands of `ribbonctl`. Each lives in its own file (ctl_<name>.c) and is one
 * entry of the table in ribbonctl.c: {name, function, one-line help}. A subcommand gets argv
 * starting at its own name and returns the process exit status: 0 success, 1 the operation
 * failed (reason printed), 2 usage error. To add one: declare it here, add a row to the table,
 * add the file to the ribbonctl target (target_sources). */
#ifndef RIBBON_DAEMON_CTL_H
#define RIBBON_DAEMON_CTL_H

int ctl_rail_main(int argc, char **argv);
int ctl_ports_main(int argc, char **argv);
int ctl_track_main(int argc, char **argv);        /* ctl_track.c */
int ctl_vision_bench_main(int argc, char **argv); /* ctl_vision_bench.c */
int ctl_render_main(int argc, char **argv);       /* ctl_render.c (needs sim/ and vision/) */
int ctl_cameras_main(int argc, char **argv);      /* ctl_cameras.c: V4L2 and GenICam cameras */
int ctl_calibrate_camera_main(int argc, char **argv); /* ctl_calibrate_camera.c: clamps in the live camera */
int ctl_transcode_main(int argc, char **argv);    /* ctl_transcode.c: raw video to FFV1, and its bench */

int ctl_trials_main(int argc, char **argv); /* ctl_trials.c: start abort status list show export report
                                            phase-report replay */
int ctl_campaign_main(int argc, char **argv); /* ctl_campaign.c: specimen, queue */
int ctl_rails_main(int argc, char **argv);    /* ctl_rails.c: the daemon's rails: home, confirm-zero */
int ctl_calibrate_main(int argc, char **argv); /* ctl_calibrate.c: one strip fitted to stored trials */
int ctl_check_main(int argc, char **argv);    /* ctl_check.c: is the rig ready (daemon/check/) */
int ctl_phase_main(int argc, char **argv);    /* ctl_phase.c: the lab's phase diagram */
int ctl_plan_main(int argc, char **argv);     /* ctl_plan.c: the next specimens, approval */
int ctl_plan_bench_main(int argc, char **argv); /* ctl_plan_bench.c: the simulated campaign */
int ctl_plan_bench_camera_main(int argc, char **argv); /* ctl_plan_bench_camera.c: plan-bench --camera */

/* ctl_phase.c, shared with ctl_plan.c: the predicted boundary over [phi_lo, phi_hi], from
 * boundary_csv (ribbon-sim boundary's CSV) or, with config (cfg loaded from it), traced from its
 * scene and cached in DB.boundary.csv. *have 0 when neither was given. -1 with the reason printed. */
struct campaign_predicted;
struct rig_config;
int ctl_campaign_predicted(const char *config, const char *boundary_csv, const char *db, double phi_lo, double phi_hi,
                           struct campaign_predicted *pred, struct rig_config *cfg, int *have);
#endif
