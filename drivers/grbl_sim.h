/* grbl_sim.h: a GRBL 1.1 subset on a pseudo-terminal, two (or three) axes moving in time.
 *
 * What it speaks: realtime '?', '!', '~', 0x18 (soft reset), 0x85 (jog cancel); lines "$J=..."
 * (G21 G53 G90 G91, axis words, F), "G0"/"G1" moves, "$H"/"$HX"/"$HY", "$X", "$$", "$I", empty
 * lines; replies "ok", "error:N", "ALARM:N", status reports <State|MPos:...|FS:...|Bf:...>.
 * Planner: up to 15 queued blocks, executed one after another; consecutive blocks that carry an
 * axis on in the same direction run without stopping (GRBL's look-ahead), so a stream of short
 * jog segments gives smooth motion and the axis decelerates to rest at the end of the queue.
 * Faults: drop a fraction of requests unanswered, garble a fraction of replies, stall an axis at
 * a position (the controller keeps reporting the motion, feed 0, as an open-loop stepper would),
 * raise an alarm after a time. The simulator keeps the slave side open in raw mode so clients
 * may come and go; its state (position, queue) lives across them as a real board's would. */
#ifndef RIBBON_DRIVERS_GRBL_SIM_H
#define RIBBON_DRIVERS_GRBL_SIM_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>

#include "rail.h"

#define GRBL_SIM_AXES 3

typedef struct grbl_sim_params {
    int n_axes;                         /* 1..3 axes, X Y Z */
    double travel_mm[GRBL_SIM_AXES];    /* mm, machine travel [0, travel] per axis */
    double start_mm[GRBL_SIM_AXES];     /* mm, position at start */
    double accel_mm_s2;                 /* mm/s^2, every axis */
    double max_feed_mm_min;             /* mm/min, feeds above are clamped (GRBL $110..) */
    double home_feed_mm_min;            /* mm/min, homing seek rate */
    bool start_in_alarm;                /* homing enabled: start locked in alarm until $H/$X */
    double drop_prob;                   /* 0..1, requests left unanswered */
    double garble_prob;                 /* 0..1, replies replaced by garbled bytes */
    double stall_at_mm[GRBL_SIM_AXES];  /* mm, NaN = off: the axis stalls there */
    double alarm_after_s;               /* s after start, negative = off: ALARM:alarm_code */
    int alarm_code;                     /* GRBL alarm number for the injected alarm */
    unsigned seed;                      /* fault random stream */
    bool report_wpos;                   /* report WPos (= MPos - wco_mm) with WCO in every 10th
                                           report, as GRBL does with $10=0 */
    double wco_mm[GRBL_SIM_AXES];       /* mm, work coordinate offset for report_wpos */
} grbl_sim_params;

typedef struct grbl_sim grbl_sim;

grbl_sim_params grbl_sim_params_default(void);
rail_err grbl_sim_open(grbl_sim **out, const grbl_sim_params *p, char *why, size_t why_len);
const char *grbl_sim_path(const grbl_sim *s);   /* the slave pty path clients open */
/* The axes' actual positions (mm; a stalled axis where it stalled) as of the last step, and the
 * controller's time (its clock, s) of that step. Not thread-safe against grbl_sim_step. */
void grbl_sim_positions(const grbl_sim *s, double mm[GRBL_SIM_AXES], double *t_s);
/* A fault on command (not thread-safe against grbl_sim_step): ALARM:code now (axes halt, queue
 * flushed, locked until $X), as a limit switch or the board's own fault would. */
void grbl_sim_raise_alarm(grbl_sim *s, int code);
/* One iteration: wait up to max_wait_s for input, handle it, advance the axes. */
rail_err grbl_sim_step(grbl_sim *s, double max_wait_s);
/* Iterate until *stop becomes non-zero (signal flag) or duration_s passes (negative: forever). */
rail_err grbl_sim_run(grbl_sim *s, double duration_s, volatile sig_atomic_t *stop);
void grbl_sim_close(grbl_sim *s);

#endif
