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
 * may come and go; its state (position, queue) lives across them as a real board's would.
 *
 * As GRBL 1.1 documents itself (doc/markdown/settings.md, commands.md, interface.md and the
 * csv tables of the GRBL project): `$$` lists the settings ($0-$6, $10-$13, $20-$27, $30-$32,
 * $100-$132) with GRBL's documented defaults except where the parameters below say otherwise
 * (rates, accelerations, travels, homing, soft limits, report mask); `$N=V` stores one (error:3
 * unknown setting, error:2 bad number, error:4 negative, error:6 step pulse below 3 us,
 * error:10 soft limits without homing, error:8 unless idle or in alarm; $22=0 also clears
 * $20). $13=1 reports positions, offsets and feeds in inches (4 decimals); $10 bit 0 chooses
 * MPos or WPos, bit 1 the Bf field; $11x clamps feeds and $12x is each axis's acceleration.
 * Soft reset (0x18) at rest keeps the position and prints the banner; in motion it prints
 * ALARM:3 first (ALARM:6 while homing) and stays in alarm. Alarms 1 (hard limit) and 2 (soft
 * limit) are critical: "[MSG:Reset to continue]", and nothing but '?' and a reset is served
 * until a reset. With homing enabled ($22=1) the controller starts (and resets) in alarm with
 * "[MSG:'$H'|'$X' to unlock]"; $H with homing disabled is error:5; a jog beyond the travel is
 * error:15 only with soft limits on ($20=1), as in GRBL. With reset_on_open, a client opening
 * the port resets the board as an Arduino's DTR line does: input is lost for reset_delay_s
 * (the bootloader), then the banner, and the machine position counts from zero where the axes
 * stand. A board powered before any client listens prints no banner to anyone. */
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
    bool soft_limits;                   /* $20=1 (GRBL needs homing for it: start_in_alarm) */
    bool reset_on_open;                 /* a client opening the port resets the board (DTR) */
    double reset_delay_s;               /* s from that reset to the banner (bootloader) */
    char settings[256];                 /* "$N=V ..." stored at power-up over the defaults
                                           (e.g. "$13=1"), each checked as `$N=V` is */
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
