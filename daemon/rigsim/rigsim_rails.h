/* rigsim_rails.h: the rig simulator's rails, stepped in real time on their own thread: either one
 * GRBL 1.1 controller (drivers/grbl_sim.c) on a pseudo-terminal with the rig file's two axes, or
 * two Modbus TCP drives (drivers/mb_sim.c, the ribbon-sim register map) on the 127.0.0.1
 * addresses the rig file names.
 *
 * GRBL: both rails must be axes of one gcode controller; the pty's path is linked at the port the
 * rig file names, so ribbond opens it as it would open the USB serial port. Modbus: both rails
 * driver = modbus, map = ribbon-sim, TCP on 127.0.0.1 (or localhost), each drive on its own port
 * (a real drive is one axis on one address). The axes' ACTUAL positions (a stalled axis where it
 * stalled, a drive its watchdog halted where it halted) are readable from any thread: they are
 * the ribbon's boundary conditions and what the truth logs record.
 * The thread runs at a real-time priority when the process may (rigsim_rails_realtime): it stands
 * for a controller that never shares its CPU.
 * Faults: an alarm after a time and a stalled axis are the controller's or the drive's own; an
 * alarm (GRBL ALARM:1, hard limit; Modbus: drive alarm 0x30 on the shear drive) on command;
 * "link lost" from a time or on command: GRBL stops answering the pty (the board is gone, its axes
 * halt where they are, as a board that lost power would); a Modbus drive stops answering but goes
 * on moving until its communication watchdog halts it, as a drive with a cut cable does. */
#ifndef RIBBON_RIGSIM_RAILS_H
#define RIBBON_RIGSIM_RAILS_H

#include <stddef.h>

#include "rig_config.h"

typedef struct rigsim_rails rigsim_rails;

typedef struct rigsim_rail_faults {
    double alarm_after_s;     /* s after start, < 0 = off */
    double link_lost_after_s; /* s after start, < 0 = off */
    char stall_axis;          /* 'X', 'Y' or 0 = off (GRBL axes; Modbus: X the compression drive, Y the shear) */
    double stall_at_mm;
} rigsim_rail_faults;

/* Starts the controller (or the drives) for cfg's rails: axis positions start at the compression
 * rail's compress_start_mm and the shear rail's zero. axes_log: a CSV of both axes' actual
 * positions every 5 ms (mono_s,real_s,compress_mm,shear_mm), NULL = none. */
int rigsim_rails_start(const rig_config *cfg, double compress_start_mm, const rigsim_rail_faults *f,
                       const char *axes_log, rigsim_rails **out, char *why, size_t why_len);
/* Actual positions (mm) of the compression and the shear axis, and the host monotonic time of
 * the step they are from. */
void rigsim_rails_positions(rigsim_rails *r, double *compress_mm, double *shear_mm, double *t_s);
/* What ribbond connects to: the GRBL port, or "modbus 127.0.0.1:P (compress), 127.0.0.1:Q (shear)". */
const char *rigsim_rails_port(const rigsim_rails *r);
/* 1 when the rails' thread got a real-time priority (SCHED_FIFO; needs root or CAP_SYS_NICE), 0
 * when it runs at the process's own. */
int rigsim_rails_realtime(const rigsim_rails *r);
/* Faults on command (thread-safe; each prints "fault: ... at UNIX-TIME"): the link is cut from
 * now on; the controller (GRBL) or the shear drive (Modbus) raises an alarm now. */
void rigsim_rails_cut_link(rigsim_rails *r);
void rigsim_rails_alarm(rigsim_rails *r);
/* Writes what the rails' thread buffered (the axes log's lines, "fault: ..." notes on stdout):
 * call it from the main loop; the thread itself never blocks on a file. One caller at a time. */
void rigsim_rails_flush(rigsim_rails *r);
void rigsim_rails_stop(rigsim_rails *r);

#endif
