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
int ctl_transcode_main(int argc, char **argv);    /* ctl_transcode.c: raw video to FFV1, and its bench */

int ctl_trials_main(int argc, char **argv); /* ctl_trials.c: start abort status list show export report
                                            phase-report replay */
int ctl_campaign_main(int argc, char **argv); /* ctl_campaign.c: specimen, queue */
int ctl_rails_main(int argc, char **argv);    /* ctl_rails.c: the daemon's rails: home, confirm-zero */
#endif
